"""An audit of the commands other than match and batch: show, transfer, evaluate, texture, fmap,
embed, bench and cache. Each test is a defect found by using the command as a new user would:
bad input or option values get one line and the exit code of the README, outputs never replace
an input, an interrupted run leaves no output, long work says how far it is.
"""

import json

import numpy as np
import pytest
import trimesh

from meshcorr import datasets as ds
from meshcorr.cli import EXIT_INPUT, EXIT_INTERRUPTED, EXIT_USAGE, main


def _save(path, vertices, faces):
    trimesh.Trimesh(vertices, faces, process=False).export(path)
    return str(path)


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    """A tube, a rigid re-indexed copy, the true map; a target of two pieces and its map."""
    folder = tmp_path_factory.mktemp("audit")
    shape = ds.tube(n_along=22, n_around=10)
    copy, truth = ds.rigid_copy(shape, scale=0.5, random_state=2)
    n = shape.n_vertices
    two = _save(folder / "two_pieces.off", np.vstack([copy.vertices, copy.vertices + 10.0]),
                np.vstack([copy.faces, copy.faces + n]))
    paths = {
        "src": _save(folder / "source.off", shape.vertices, shape.faces),
        "tgt": _save(folder / "target.off", copy.vertices, copy.faces),
        "two": two,
        "map": str(folder / "map.txt"),
        "off_by_one": str(folder / "off_by_one.txt"),
        "unmapped": str(folder / "unmapped.txt"),
    }
    np.savetxt(paths["map"], truth, fmt="%d")
    np.savetxt(paths["off_by_one"], (truth + 1) % n, fmt="%d")
    np.savetxt(paths["unmapped"], np.full(n, -1), fmt="%d")
    return folder, paths, truth


def _run(args, capsys):
    code = main(args)
    out, err = capsys.readouterr()
    assert "Traceback" not in err and "internal error" not in err
    return code, out, err


# ---------------------------------------------------------------- show and embed: pictures


def test_show_refuses_to_write_over_a_ground_truth_file(files, tmp_path, capsys):
    _, p, _ = files
    truth = tmp_path / "truth.png"  # a ground-truth file that happens to be named like a picture
    truth.write_text(open(p["map"]).read())
    before = truth.read_bytes()
    code, _, err = _run(["show", p["src"], p["tgt"], p["map"], "--gt", str(truth), "-o", str(truth)], capsys)
    assert code == EXIT_USAGE and "is the input --gt" in err
    assert truth.read_bytes() == before


@pytest.mark.parametrize("command", ["show", "embed"])
def test_pictures_are_png_files_and_dpi_is_checked(files, tmp_path, capsys, command):
    _, p, _ = files
    inputs = [p["src"], p["tgt"], p["map"]] if command == "show" else [p["src"]]
    code, _, err = _run([command, *inputs, "-o", str(tmp_path / "picture.jpg")], capsys)
    assert code == EXIT_USAGE and "give a file name ending in .png" in err
    assert not (tmp_path / "picture.jpg").exists()  # was a PNG under a .jpg name
    for dpi in ("0", "-5", "100000"):  # were an internal error, and 'out of memory ... n x n matrices'
        with pytest.raises(SystemExit) as exit_:
            main([command, *inputs, "-o", str(tmp_path / "picture.png"), "--dpi", dpi])
        assert exit_.value.code == EXIT_USAGE
        assert "argument --dpi: expected dots per inch from 10 to 1000" in capsys.readouterr().err


def test_show_with_truth_on_a_target_of_two_pieces_names_a_fix_it_has(files, tmp_path, capsys):
    _, p, truth = files
    code, _, err = _run(["show", p["src"], p["two"], p["map"], "--gt", p["map"],
                         "-o", str(tmp_path / "s.png")], capsys)
    assert code == EXIT_INPUT and "is not one connected surface" in err and "without --gt" in err
    assert "--largest-component" not in err  # show has no such option


def test_embed_largest_component_memory_and_small_mesh(files, tmp_path, capsys):
    _, p, _ = files
    out = tmp_path / "e.png"
    code, _, err = _run(["embed", p["two"], "-o", str(out)], capsys)
    assert code == EXIT_INPUT and "--largest-component" in err  # the advice names an option embed has
    code, _, err = _run(["embed", p["two"], "-o", str(out), "--largest-component"], capsys)
    assert code == 0 and out.is_file() and "largest piece" in err
    code, _, err = _run(["embed", p["src"], "-o", str(tmp_path / "m.png"), "--max-memory", "1MiB"], capsys)
    assert code == EXIT_USAGE and "Decimate the mesh" in err and not (tmp_path / "m.png").exists()
    tiny = _save(tmp_path / "tet.off", np.eye(4, 3), np.array([[0, 1, 2], [0, 3, 1], [0, 2, 3], [1, 3, 2]]))
    code, _, err = _run(["embed", tiny, "-o", str(out)], capsys)
    assert code == EXIT_INPUT and err.startswith(f"meshcorr: error: {tiny} has 4 vertices")  # was 'mesh'


# ---------------------------------------------------------------- evaluate


def test_evaluate_curve_never_replaces_a_truth_file(files, tmp_path, capsys):
    _, p, _ = files
    for option in ("--gt", "--sym"):
        truth = tmp_path / f"truth{option}.png"
        truth.write_text(open(p["map"]).read())
        before = truth.read_bytes()
        extra = ["--gt", p["map"], "--sym", str(truth)] if option == "--sym" else ["--gt", str(truth)]
        code, _, err = _run(["evaluate", p["src"], p["tgt"], p["map"], *extra, "--curve", str(truth)], capsys)
        assert code == EXIT_USAGE and f"is the input {option}" in err
        assert truth.read_bytes() == before
    code, _, err = _run(["evaluate", p["src"], p["tgt"], p["map"], "--gt", p["map"],
                         "--curve", str(tmp_path / "c.pdf")], capsys)
    assert code == EXIT_USAGE and ".png" in err


def test_evaluate_a_map_that_maps_nothing_is_bad_data(files, capsys):
    _, p, _ = files
    code, _, err = _run(["evaluate", p["src"], p["tgt"], p["unmapped"], "--gt", p["map"]], capsys)
    assert code == EXIT_INPUT and "maps no SOURCE vertex" in err


def test_evaluate_json_is_strict_json_when_no_truth_point_is_mapped(files, tmp_path, capsys):
    _, p, truth = files
    partial = tmp_path / "partial.txt"
    np.savetxt(partial, np.where(np.arange(truth.size) < 3, -1, truth), fmt="%d")
    sparse = tmp_path / "sparse.txt"
    sparse.write_text("".join(f"{i} {truth[i]}\n" for i in range(3)))  # only the unmapped vertices
    code, out, _ = _run(["evaluate", p["src"], p["tgt"], str(partial), "--gt", str(sparse), "--json"], capsys)
    assert code == 0 and "NaN" not in out  # NaN is no JSON: jq and browsers refused the report
    report = json.loads(out, parse_constant=lambda name: pytest.fail(f"{name} in the JSON"))
    assert report["n_unmapped"] == 3 and report["mean_error"] is None


def test_evaluate_largest_component(files, capsys):
    _, p, truth = files
    args = ["evaluate", p["src"], p["two"], p["map"], "--gt", p["map"]]
    code, _, err = _run(args, capsys)
    assert code == EXIT_INPUT and "pass --largest-component" in err
    code, out, err = _run(args + ["--largest-component", "--json"], capsys)
    assert code == 0 and "largest piece" in err
    report = json.loads(out)
    assert report["n_points"] == truth.size and report["mean_error"] == pytest.approx(0.0)


def test_evaluate_reports_progress_of_the_geodesic_solves(files, capsys):
    _, p, _ = files
    code, _, err = _run(["evaluate", p["src"], p["tgt"], p["off_by_one"], "--gt", p["map"], "-v"], capsys)
    assert code == 0 and "[geodesic errors] 100%" in err
    code, _, err = _run(["evaluate", p["src"], p["tgt"], p["off_by_one"], "--gt", p["map"], "-q"], capsys)
    assert code == 0 and err == ""


def test_evaluate_interrupted_leaves_no_curve(files, tmp_path, capsys, monkeypatch):
    pytest.importorskip("matplotlib")
    import meshcorr.evaluation.metrics

    _, p, _ = files

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(meshcorr.evaluation.metrics, "map_quality", interrupted)
    curve = tmp_path / "curve.png"
    code, _, err = _run(["evaluate", p["src"], p["tgt"], p["map"], "--gt", p["map"], "--curve", str(curve)],
                        capsys)
    assert code == EXIT_INTERRUPTED and err.strip() == "meshcorr: interrupted"
    assert not curve.exists()


# ---------------------------------------------------------------- transfer


def test_transfer_attribute_file_of_text_is_one_line(files, tmp_path, capsys):
    _, p, truth = files
    text = tmp_path / "words.npy"
    np.save(text, np.array(["a"] * truth.size))  # was an internal error (exit 1)
    out = tmp_path / "t.ply"
    code, _, err = _run(["transfer", p["src"], p["tgt"], p["map"], "--attribute", str(text), "-o", str(out)],
                        capsys)
    assert code == 3 and "not a table of numbers" in err  # an attribute file that cannot be used: bad data
    assert not out.exists()


# ---------------------------------------------------------------- texture and fmap


@pytest.fixture(scope="module")
def textured(files):
    """TARGET as an OBJ with UVs, written by trimesh: material.obj names material.mtl and material_0.png."""
    from PIL import Image

    folder, p, _ = files
    copy = trimesh.load(p["tgt"], process=False)
    uv = (copy.vertices[:, :2] - copy.vertices[:, :2].min(axis=0)) / np.ptp(copy.vertices[:, :2], axis=0)
    (folder / "tex").mkdir()
    obj = folder / "tex" / "target.obj"
    trimesh.Trimesh(copy.vertices, copy.faces, process=False,
                    visual=trimesh.visual.TextureVisuals(uv=uv, image=Image.new("RGB", (8, 8), (9, 90, 200)))
                    ).export(obj)
    assert (folder / "tex" / "material.mtl").is_file()
    return obj


def test_texture_never_replaces_the_targets_material_file(files, textured, capsys):
    _, p, _ = files
    mtl = textured.parent / "material.mtl"
    before = mtl.read_bytes()
    code, _, err = _run(["texture", p["src"], str(textured), p["map"], "-o", str(textured.parent / "material.obj"),
                         "-k", "10"], capsys)
    assert code == EXIT_USAGE and "is the input TARGET's material" in err
    assert mtl.read_bytes() == before and not (textured.parent / "material.obj").exists()


def test_texture_writes_all_three_files_or_none(files, textured, tmp_path, capsys, monkeypatch):
    import meshcorr.io
    from meshcorr.errors import OutputError

    _, p, _ = files
    real = meshcorr.io.atomic_write
    calls = []

    def third_write_fails(path, writer):
        calls.append(path)
        if len(calls) == 3:
            raise OutputError(f"Cannot write {path}: no space left on device.")
        return real(path, writer)

    monkeypatch.setattr("meshcorr.io.atomic_write", third_write_fails)
    code, _, err = _run(["texture", p["src"], str(textured), p["map"], "-o", str(tmp_path / "out.obj"), "-k", "10"],
                        capsys)
    assert code == EXIT_USAGE and len(calls) == 3 and "no space left" in err
    assert sorted(f.name for f in tmp_path.iterdir()) == []  # the image and the .mtl were left behind
    monkeypatch.undo()
    code, _, err = _run(["texture", p["src"], str(textured), p["map"], "-o", str(tmp_path / "out.obj"), "-k", "10"],
                        capsys)
    assert code == 0 and "wrote" in err and len(list(tmp_path.iterdir())) == 3


def test_texture_refuses_a_point_cloud_source(files, textured, tmp_path, capsys):
    _, p, _ = files
    cloud = tmp_path / "source.xyz"
    np.savetxt(cloud, trimesh.load(p["src"], process=False).vertices)
    code, _, err = _run(["texture", str(cloud), str(textured), p["map"], "-o", str(tmp_path / "t.obj"), "-k", "10"],
                        capsys)
    assert code == EXIT_INPUT and "is a point cloud: a texture needs a surface" in err  # wrote an OBJ of points
    assert not (tmp_path / "t.obj").exists()


@pytest.mark.parametrize("command", ["fmap", "texture"])
def test_map_commands_refuse_a_map_that_maps_nothing_and_name_their_own_fix(files, textured, tmp_path, capsys,
                                                                             command):
    _, p, _ = files
    target = str(textured) if command == "texture" else p["tgt"]
    out = str(tmp_path / ("o.npz" if command == "fmap" else "o.obj"))
    code, _, err = _run([command, p["src"], target, p["unmapped"], "-o", out, "-k", "10"], capsys)
    assert code == EXIT_INPUT and "maps no SOURCE vertex" in err  # was a zero matrix / UVs all (0, 0)
    two = [p["src"], p["two"], p["map"]] if command == "fmap" else [p["two"], target, p["map"]]
    code, _, err = _run([command, *two, "-o", out, "-k", "10"], capsys)
    assert code == EXIT_INPUT and "is not one connected surface" in err and "--largest-component" not in err
    assert not list(tmp_path.iterdir())


def test_fmap_seed_stdout_and_bad_functional_map_files(files, tmp_path, capsys):
    _, p, truth = files
    a, b = p["src"], p["tgt"]
    with pytest.raises(SystemExit) as exit_:  # was an internal error
        main(["fmap", a, b, p["map"], "-o", str(tmp_path / "f.npz"), "--seed", "-1"])
    assert exit_.value.code == EXIT_USAGE and "--seed: expected an integer >= 0" in capsys.readouterr().err
    good = tmp_path / "f.npz"
    code, _, err = _run(["fmap", a, b, p["map"], "-o", str(good), "-k", "20"], capsys)
    assert code == 0 and "wrote" in err
    code, out, _ = _run(["fmap", a, b, "--to-map", str(good), "-o", "-"], capsys)
    assert code == 0 and np.array_equal(np.array(out.split(), dtype=np.int64), truth)
    assert not (tmp_path / "-").exists()  # was a file named '-'
    arrays = dict(np.load(good))
    npy = tmp_path / "plain.npz"
    np.save(tmp_path / "plain.npy", arrays["C"])
    (tmp_path / "plain.npy").rename(npy)  # a .npy under a .npz name: was an internal error
    np.savez(tmp_path / "nan.npz", **{**arrays, "C": arrays["C"] * np.nan})  # was a usage error (exit 2)
    np.savez(tmp_path / "text.npz", **{**arrays, "C": np.full(arrays["C"].shape, "x")})  # an internal error
    for bad, message in ((npy, "it is no .npz archive"), (tmp_path / "nan.npz", "NaN"),
                         (tmp_path / "text.npz", "could not convert"), (p["src"], "it is no .npz archive")):
        code, _, err = _run(["fmap", a, b, "--to-map", str(bad), "-o", str(tmp_path / "m.txt")], capsys)
        assert code == EXIT_INPUT and message in err and "allow_pickle" not in err
        assert not (tmp_path / "m.txt").exists()


# ---------------------------------------------------------------- bench and cache


@pytest.fixture()
def dataset(tmp_path):
    """One class: a tube and a rigid, re-indexed copy, in the TOSCA layout."""
    root = tmp_path / "data"
    (root / "corres").mkdir(parents=True)
    shape = ds.tube(n_along=12, n_around=8)
    copy, truth = ds.rigid_copy(shape, scale=0.5, random_state=2)
    for name, mesh, vts in (("tube0", shape, np.arange(shape.n_vertices)), ("tube1", copy, truth)):
        _save(root / f"{name}.off", mesh.vertices, mesh.faces)
        (root / "corres" / f"{name}.vts").write_text("".join(f"{i + 1}\n" for i in vts))
    (root / "test_pairs.txt").write_text("tube0 tube1\n")
    return root


def test_bench_refuses_bad_method_options_before_any_run(dataset, tmp_path, capsys, monkeypatch):
    import meshcorr.evaluation.benchmark

    def no_run(*args, **kwargs):
        raise AssertionError("a method ran")

    monkeypatch.setattr(meshcorr.evaluation.benchmark, "run_method", no_run)
    out = tmp_path / "out"
    base = ["bench", str(dataset), "--out", str(out), "--no-plot", "-q"]
    for option, message in ((["--set", "spectral:method=icp"], "use --methods"),  # ran icp, named spectral
                            (["--set", "spectral:random_state=1"], "use --seed"),  # every pair failed
                            (["--set", "spectral:nonsense=1"], "has no option 'nonsense'"),  # every pair failed
                            (["--methods", "icp", "--set", "icp:k=5"], "has no option 'k'")):
        code, _, err = _run([*base, *option], capsys)
        assert code == EXIT_USAGE and message in err, err
    for k in ("0", "11"):  # every pair failed, and the folder kept k as its setting
        with pytest.raises(SystemExit) as exit_:
            main([*base, "-k", k])
        assert exit_.value.code == EXIT_USAGE and "-k: expected an integer from 2 to 10" in capsys.readouterr().err
    assert not out.exists()
    code, _, err = _run(["bench", str(dataset), "--out", str(dataset), "--no-plot", "-q"], capsys)
    assert code == EXIT_USAGE and "is the dataset folder" in err
    assert sorted(p.name for p in dataset.iterdir()) == ["corres", "test_pairs.txt", "tube0.off", "tube1.off"]


def test_cache_clear_that_cannot_remove_a_file_is_one_line(tmp_path, capsys, monkeypatch):
    from pathlib import Path

    (tmp_path / ("a" * 64 + ".npz")).write_bytes(b"x")

    def refused(self, missing_ok=False):
        raise PermissionError(13, "Permission denied", str(self))

    monkeypatch.setattr(Path, "unlink", refused)
    code, _, err = _run(["cache", "clear", "--dir", str(tmp_path)], capsys)
    assert code == EXIT_USAGE and "Cannot clear the cache folder" in err and "Permission denied" in err
    monkeypatch.undo()
    code, out, _ = _run(["cache", "info", "--dir", str(tmp_path / "none")], capsys)
    assert code == 0 and "does not exist yet" in out


@pytest.mark.parametrize("command, expected", [
    ("cache", "info: print the folder"),  # the action had no help
    ("transfer", "one row per SOURCE vertex"),  # said values were written for a scalar field only
    ("show", "errors against --gt (default: heat)"),  # said --error only; --gt uses it too
    ("embed", "--max-memory"),
    ("bench", "2..10"),
])
def test_help_explains_the_options(capsys, command, expected):
    with pytest.raises(SystemExit):
        main([command, "--help"])
    assert expected in " ".join(capsys.readouterr().out.split())
