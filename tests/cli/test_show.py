"""Pictures (`meshcorr show`, `meshcorr embed`) and attribute transfer (`meshcorr transfer`)."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("matplotlib")

from meshcorr import datasets  # noqa: E402
from meshcorr.cli import main  # noqa: E402
from meshcorr.errors import ParameterError  # noqa: E402
from meshcorr.io import write_map, write_mesh  # noqa: E402
from meshcorr.transfer import check_map, pull_back, read_attribute  # noqa: E402
from meshcorr.maps.colors import part_colors, scalar_colors  # noqa: E402


def _read_png(path) -> np.ndarray:
    from matplotlib.image import imread

    return imread(str(path))[:, :, :3]


def _ink(image: np.ndarray) -> float:
    """Fraction of pixels that are not (near) white background."""
    return float((image.min(axis=2) < 0.9).mean())


def _differing(image: np.ndarray) -> float:
    """Fraction of pixels where the left and right halves of a picture differ visibly."""
    half = image.shape[1] // 2
    return float((np.abs(image[:, :half] - image[:, half:2 * half]).max(axis=2) > 0.1).mean())


@pytest.fixture(scope="module")
def bent_tube_files(tmp_path_factory):
    """A straight tube, a bent and re-indexed copy and the true map (not the identity), as files.

    Also the bent tube in its own vertex order ("bent") with its map onto the re-indexed copy
    ("same_map"): two meshes of one pose, so a right map draws the same picture twice.
    """
    folder = tmp_path_factory.mktemp("viz")
    source = datasets.tube(n_along=14, n_around=8, bend=0.0)
    bent = datasets.tube(n_along=14, n_around=8, bend=1.5)
    target, same_map = datasets.rigid_copy(bent, rotation=np.eye(3), translation=np.zeros(3),
                                           random_state=0)
    truth = datasets.ground_truth(source, target)
    assert np.mean(truth == np.arange(len(truth))) < 0.05
    paths = {"source": folder / "source.off", "target": folder / "target.off",
             "map": folder / "map.txt", "gt": folder / "gt.txt", "folder": folder,
             "bent": folder / "bent.off", "same_map": folder / "same_map.txt"}
    write_mesh(paths["source"], source.vertices, source.faces)
    write_mesh(paths["target"], target.vertices, target.faces)
    write_mesh(paths["bent"], bent.vertices, bent.faces)
    write_map(paths["map"], truth)
    write_map(paths["gt"], truth)
    write_map(paths["same_map"], same_map)
    paths.update(n_source=len(source.vertices), n_target=len(target.vertices),
                 target_shape=target, truth=truth, same_map_array=same_map)
    return paths


def _args(bent_tube_files, *extra):
    return [str(bent_tube_files["source"]), str(bent_tube_files["target"]), str(bent_tube_files["map"]),
            *map(str, extra)]


def test_show_draws_both_meshes(bent_tube_files, tmp_path):
    out = tmp_path / "show.png"
    assert main(["show", *_args(bent_tube_files, "-o", out)]) == 0
    image = _read_png(out)
    half = image.shape[1] // 2
    # Each half holds a mesh: a good share of coloured pixels, and several colours (parts).
    for part in (image[:, :half], image[:, half:]):
        assert _ink(part) > 0.05
        assert len(np.unique(np.round(part.reshape(-1, 3) * 8), axis=0)) > 20
    # One pose in two vertex orders: through the right map the source is drawn in the
    # target's colours at the same places, so the halves agree but for the titles.
    # Measured: 1.7 % of pixels differ through the map, 24 % when the map is ignored.
    same = tmp_path / "same.png"
    assert main(["show", str(bent_tube_files["bent"]), str(bent_tube_files["target"]), str(bent_tube_files["same_map"]),
                 "-o", str(same)]) == 0
    assert _differing(_read_png(same)) < 0.05


def test_show_with_truth_adds_a_row_and_error_mode(bent_tube_files, tmp_path, capsys):
    one = tmp_path / "one.png"
    two = tmp_path / "two.png"
    err = tmp_path / "err.png"
    assert main(["show", *_args(bent_tube_files, "-o", one)]) == 0
    assert main(["show", *_args(bent_tube_files, "-o", two, "--gt", bent_tube_files["gt"])]) == 0
    assert "mean 0.0000" in capsys.readouterr().err  # the map is the truth
    assert _read_png(two).shape[0] > 1.7 * _read_png(one).shape[0]
    bottom = _read_png(two)[_read_png(two).shape[0] // 2:]
    assert _ink(bottom[:, : bottom.shape[1] // 2]) > 0.05
    assert main(["show", *_args(bent_tube_files, "-o", err, "--gt", bent_tube_files["gt"], "--error")]) == 0
    assert _ink(_read_png(err)) > 0.05
    # A wrong map (reversed) with the true one: only the ground-truth row draws the source
    # in the target's colours at the same places.
    wrong = tmp_path / "wrong.txt"
    write_map(wrong, bent_tube_files["same_map_array"][::-1])
    rows = tmp_path / "rows.png"
    assert main(["show", str(bent_tube_files["bent"]), str(bent_tube_files["target"]), str(wrong), "-o", str(rows),
                 "--gt", str(bent_tube_files["same_map"])]) == 0
    assert "mean 0.0000" not in capsys.readouterr().err.splitlines()[-1]  # status lines go to stderr
    image = _read_png(rows)
    middle = image.shape[0] // 2
    assert _differing(image[:middle]) > 0.1
    assert _differing(image[middle:]) < 0.05


def test_error_mode_colours_follow_the_error(bent_tube_files, tmp_path):
    # Error colours run from blue (0) to red (largest), every level a different colour.
    ramp = scalar_colors(np.linspace(0.0, 1.0, 11), "error").astype(int)
    assert np.all(ramp[:4, 2] > ramp[:4, 0] + 50) and np.all(ramp[-4:, 0] > ramp[-4:, 2] + 100)
    assert len(np.unique(ramp, axis=0)) == 11
    # A map right on one end of the tube and sent far away on the other end.
    truth = bent_tube_files["truth"]
    params = bent_tube_files["target_shape"].params
    wrong = truth.copy()
    far_end = int(np.argmax(params[:, 0]))
    near = datasets.tube(n_along=14, n_around=8, bend=0.0).params[:, 0] < 0.5
    wrong[near] = far_end
    bad = tmp_path / "bad.txt"
    write_map(bad, wrong)
    out = tmp_path / "err.png"
    argv = [str(bent_tube_files["source"]), str(bent_tube_files["target"]), str(bad), "-o", str(out),
            "--gt", str(bent_tube_files["gt"]), "--error"]
    assert main(["show", *argv]) == 0
    image = _read_png(out)
    source_half = image[: int(0.85 * image.shape[0]), : image.shape[1] // 2]  # above the colour bar
    drawn = source_half.min(axis=2) < 0.9
    red = drawn & (source_half[:, :, 0] > source_half[:, :, 2] + 0.15)
    blue = drawn & (source_half[:, :, 2] > source_half[:, :, 0] + 0.15)
    assert red.mean() > 0.01 and blue.mean() > 0.01, (red.mean(), blue.mean())


def test_show_errors_are_one_line(bent_tube_files, tmp_path, capsys):
    short = tmp_path / "short.txt"
    write_map(short, np.zeros(bent_tube_files["n_source"] - 1, dtype=int))
    far = tmp_path / "far.txt"
    write_map(far, np.full(bent_tube_files["n_source"], bent_tube_files["n_target"]))
    cases = [
        ([str(bent_tube_files["source"]), str(bent_tube_files["target"]), str(short), "-o", str(tmp_path / "a.png")],
         "entries but the source mesh has"),
        ([str(bent_tube_files["source"]), str(bent_tube_files["target"]), str(far), "-o", str(tmp_path / "b.png")],
         "outside the target's vertex range"),
        (_args(bent_tube_files, "-o", tmp_path / "missing" / "c.png"), "does not exist"),
        (_args(bent_tube_files, "-o", tmp_path / "d.png", "--error"), "--gt"),
        (_args(bent_tube_files, "-o", tmp_path / "e.png", "--geodesic", "fmm"), "--geodesic fmm chooses the solver"),
    ]
    for number, (argv, message) in enumerate(cases):
        assert main(["show", *argv]) == (3 if number < 2 else 2)  # a map file that does not fit is bad data
        err = capsys.readouterr().err
        assert err.startswith("meshcorr: error:") and message in err and "Traceback" not in err
        assert err.count("\n") == 1
    assert not list(tmp_path.glob("*.png"))


def test_pull_back_and_check_map():
    values = np.array([[1, 2, 3], [4, 5, 6], [7, 8, 9]], dtype=np.uint8)
    pulled = pull_back(values, np.array([2, -1, 0]), fill=np.array([0, 0, 0], dtype=np.uint8))
    np.testing.assert_array_equal(pulled, [[7, 8, 9], [0, 0, 0], [1, 2, 3]])
    assert np.isnan(pull_back(np.array([1.0, 2.0]), np.array([-1, 1]))[0])
    with pytest.raises(ParameterError, match="1-D array of integer"):
        check_map(np.zeros(3), 3, 3)
    with pytest.raises(ParameterError, match=r"entry 1 is -2, outside the target's vertex range 0\.\.3 "):
        check_map(np.array([0, -2, 1]), 3, 4)
    with pytest.raises(ParameterError, match=r"entry 2 is 9, outside the target's vertex range 0\.\.3 "):
        check_map(np.array([0, 3, 9]), 3, 4)


def test_colorings_are_valid():
    shape = datasets.tube(n_along=10, n_around=6)
    colors = part_colors(shape.vertices, shape.faces, n_parts=4)
    assert colors.shape == (len(shape.vertices), 3) and colors.dtype == np.uint8
    assert len(np.unique(colors, axis=0)) > 10  # smooth: many blended colours
    ends = scalar_colors(np.array([0.0, 1.0, np.nan]), "viridis")
    np.testing.assert_array_equal(ends, [[68, 1, 84], [253, 231, 37], [170, 170, 170]])


def test_a_cloud_is_coloured_by_parts_like_its_mesh():
    # A cloud has no edges: its parts used to be all grey but for the seeds.
    shape = datasets.creature(resolution=1)
    mesh_colors = part_colors(shape.vertices, shape.faces)
    cloud_colors = part_colors(shape.vertices, np.zeros((0, 3), dtype=int))
    grey = np.all(cloud_colors == cloud_colors[:, :1], axis=1)
    assert grey.mean() < 0.05
    assert len(np.unique(cloud_colors, axis=0)) > 50
    # The same seeds: each vertex's colour is near its mesh colour for most of the shape.
    close = np.linalg.norm(cloud_colors.astype(float) - mesh_colors, axis=1) < 60
    assert close.mean() > 0.8


def _ply_colors(path) -> np.ndarray:
    import trimesh

    mesh = trimesh.load(path, process=False, force="mesh")
    return np.asarray(mesh.visual.vertex_colors)[:, :3]


def test_transfer_colours_follow_the_map(bent_tube_files, tmp_path):
    rng = np.random.default_rng(0)
    target = bent_tube_files["target_shape"]
    colors = rng.integers(0, 256, size=(bent_tube_files["n_target"], 3))
    mapping = rng.integers(0, bent_tube_files["n_target"], size=bent_tube_files["n_source"])
    mapping[:3] = -1
    map_file, color_file = tmp_path / "m.txt", tmp_path / "c.txt"
    write_map(map_file, mapping)
    np.savetxt(color_file, colors, fmt="%d")
    coloured_target = tmp_path / "t.ply"
    write_mesh(coloured_target, target.vertices, target.faces, vertex_colors=colors.astype(np.uint8))
    for attribute in (str(color_file), "colors"):
        out = tmp_path / "out.ply"
        assert main(["transfer", str(bent_tube_files["source"]), str(coloured_target), str(map_file),
                     "--attribute", attribute, "-o", str(out)]) == 0
        got = _ply_colors(out)
        np.testing.assert_array_equal(got[3:], colors[mapping[3:]])
        np.testing.assert_array_equal(got[:3], np.full((3, 3), 170))


def test_read_attribute_tables(bent_tube_files, tmp_path):
    n = bent_tube_files["n_target"]
    target = bent_tube_files["target_shape"]
    rng = np.random.default_rng(1)
    field = rng.normal(size=n)
    np.save(tmp_path / "column.npy", field[:, None])  # one column: a scalar field
    np.testing.assert_array_equal(read_attribute(str(tmp_path / "column.npy"), None, target.vertices,
                                                 target.faces), field)
    rgba = rng.integers(0, 256, size=(n, 4))
    np.savetxt(tmp_path / "rgba.txt", rgba, fmt="%d")  # the alpha channel is dropped
    got = read_attribute(str(tmp_path / "rgba.txt"), None, target.vertices, target.faces)
    assert got.dtype == np.uint8
    np.testing.assert_array_equal(got, rgba[:, :3])
    np.savetxt(tmp_path / "two.txt", rgba[:, :2], fmt="%d")  # neither a field nor colours
    with pytest.raises(ParameterError, match=r"has shape \(\d+, 2\); expected one row per target vertex"):
        read_attribute(str(tmp_path / "two.txt"), None, target.vertices, target.faces)
    for bad in (-1, 256):
        rgba[5, 1] = bad
        np.savetxt(tmp_path / "bad.txt", rgba, fmt="%d")
        with pytest.raises(ParameterError, match="colour channels must lie in 0..255"):
            read_attribute(str(tmp_path / "bad.txt"), None, target.vertices, target.faces)


def test_transfer_scalar_field(bent_tube_files, tmp_path):
    field = np.linspace(0.0, 1.0, bent_tube_files["n_target"])
    field_file, values_out, out = tmp_path / "f.npy", tmp_path / "v.npy", tmp_path / "s.ply"
    np.save(field_file, field)
    assert main(["transfer", *_args(bent_tube_files, "--attribute", field_file, "-o", out,
                                    "--values-out", values_out)]) == 0
    np.testing.assert_allclose(np.load(values_out), field[bent_tube_files["truth"]], atol=0)
    got = _ply_colors(out)
    np.testing.assert_array_equal(got, scalar_colors(field[bent_tube_files["truth"]], vmin=0.0, vmax=1.0))


def test_transfer_errors_are_one_line(bent_tube_files, tmp_path, capsys):
    wrong = tmp_path / "wrong.txt"
    np.savetxt(wrong, np.zeros(bent_tube_files["n_target"] + 1))
    rgb = tmp_path / "rgb.npy"
    np.save(rgb, np.full((bent_tube_files["n_target"], 3), 200))
    cases = [  # (arguments, exit code: 2 usage, 3 an attribute file that cannot be used, message)
        (_args(bent_tube_files, "--attribute", wrong, "-o", tmp_path / "a.ply"), 3, "one row per target vertex"),
        (_args(bent_tube_files, "--attribute", tmp_path / "nope.txt", "-o", tmp_path / "b.ply"), 2, "no such file"),
        (_args(bent_tube_files, "--attribute", "foo", "-o", tmp_path / "b.ply"), 2, "not a known attribute"),
        (_args(bent_tube_files, "--attribute", tmp_path, "-o", tmp_path / "b.ply"), 3, "cannot be read"),
        (_args(bent_tube_files, "--attribute", "colors", "-o", tmp_path / "c.ply"), 2, "no per-vertex colours"),
        (_args(bent_tube_files, "--attribute", "parts", "-o", tmp_path / "d.off"), 2, ".ply or .obj"),
        (_args(bent_tube_files, "--attribute", "xyz", "-o", tmp_path / "no" / "e.ply"), 2, "does not exist"),
        (_args(bent_tube_files, "--attribute", "parts", "-o", tmp_path / "g.ply", "--cmap", "coolwarm"), 2,
         "--cmap coolwarm colours a scalar field, and --attribute parts gives colours"),
        (_args(bent_tube_files, "--attribute", rgb, "-o", tmp_path / "h.ply", "--cmap", "error"), 2,
         "holds colours (3 or 4 columns)"),
    ]
    for argv, code, message in cases:
        assert main(["transfer", *argv]) == code
        err = capsys.readouterr().err
        assert err.startswith("meshcorr: error:") and message in err, err
    far = tmp_path / "far.txt"  # a map file that does not fit the meshes: bad input data
    write_map(far, np.full(bent_tube_files["n_source"], bent_tube_files["n_target"]))
    assert main(["transfer", str(bent_tube_files["source"]), str(bent_tube_files["target"]), str(far), "--attribute", "xyz",
                 "-o", str(tmp_path / "f.ply")]) == 3
    assert "outside the target's vertex range" in capsys.readouterr().err
    assert not list(tmp_path.glob("*.ply"))


def test_colours_move_between_clouds(tmp_path, capsys):
    # A cloud target's colours: a PLY of coloured points is read as a cloud; a .npy has none.
    import trimesh

    points = np.asarray(datasets.creature(resolution=1).vertices)
    colours = np.random.default_rng(0).integers(0, 256, size=(len(points), 3)).astype(np.uint8)
    trimesh.PointCloud(points, colors=colours).export(tmp_path / "target.ply")
    np.save(tmp_path / "target.npy", points)
    np.savetxt(tmp_path / "source.xyz", points)
    order = np.random.default_rng(1).permutation(len(points))
    np.savetxt(tmp_path / "map.txt", order, fmt="%d")
    base = [str(tmp_path / "source.xyz")]
    assert main(["transfer", *base, str(tmp_path / "target.ply"), str(tmp_path / "map.txt"),
                 "--attribute", "colors", "-o", str(tmp_path / "out.ply"), "-q"]) == 0
    moved = trimesh.load(tmp_path / "out.ply", process=False)
    np.testing.assert_array_equal(np.asarray(moved.colors)[:, :3], colours[order])
    assert main(["transfer", *base, str(tmp_path / "target.npy"), str(tmp_path / "map.txt"),
                 "--attribute", "colors", "-o", str(tmp_path / "none.ply")]) == 2
    assert "target.npy has no per-vertex colours" in capsys.readouterr().err


def test_embed_draws_eigenvectors(bent_tube_files, tmp_path, capsys):
    out = tmp_path / "embed.png"
    assert main(["embed", str(bent_tube_files["source"]), "-o", str(out), "-n", "2"]) == 0
    line = capsys.readouterr().err
    values = [float(v) for v in line.split("eigenvalues:")[1].split(",")]
    assert len(values) == 2 and values[0] >= values[1] > 0
    image = _read_png(out)
    quarter = image.shape[1] // 4
    # Four panels (mesh, embedding, u1, u2) in one row, each drawn.
    for column in range(4):
        assert _ink(image[:, column * quarter:(column + 1) * quarter]) > 0.03


def test_embed_errors_are_one_line(bent_tube_files, tmp_path, capsys):
    assert main(["embed", str(bent_tube_files["source"]), "-o", str(tmp_path / "a.png"), "-n", "0"]) == 2
    assert "n_eigenvectors" in capsys.readouterr().err
    assert main(["embed", str(tmp_path / "none.off"), "-o", str(tmp_path / "b.png")]) == 3  # bad input data
    assert capsys.readouterr().err.startswith("meshcorr: error:")
