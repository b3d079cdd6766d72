"""``meshcorr evaluate`` map measures, ``meshcorr texture`` and ``meshcorr fmap`` (issue 14)."""

import json

import numpy as np
import pytest
import trimesh
from PIL import Image

from meshcorr import datasets as ds
from meshcorr.cli import main
from meshcorr.maps.texture import read_textured_obj


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    folder = tmp_path_factory.mktemp("maps")
    shape = ds.figure()
    copy, truth = ds.rigid_copy(shape, random_state=1)
    trimesh.Trimesh(shape.vertices, shape.faces, process=False).export(folder / "a.off")
    uv = (copy.vertices[:, :2] - copy.vertices[:, :2].min(axis=0)) / np.ptp(copy.vertices[:, :2], axis=0)
    image = Image.new("RGB", (16, 16), (200, 30, 30))
    trimesh.Trimesh(copy.vertices, copy.faces, process=False,
                    visual=trimesh.visual.TextureVisuals(uv=uv, image=image)).export(folder / "b.obj")
    np.savetxt(folder / "map.txt", truth, fmt="%d")
    return folder, truth, uv


def test_evaluate_reports_coverage_bijectivity_continuity(files, capsys):
    folder, truth, _ = files
    args = [str(folder / "a.off"), str(folder / "b.obj"), str(folder / "map.txt"), "--gt", str(folder / "map.txt")]
    assert main(["evaluate", *args, "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["coverage"] == pytest.approx(1.0) and report["bijectivity"] == pytest.approx(1.0)
    assert report["continuity"] == pytest.approx(1.0, abs=1e-6)
    assert main(["evaluate", *args]) == 0
    assert "coverage:              100.0 %" in capsys.readouterr().out


def test_texture_command_writes_obj_mtl_png(files):
    folder, truth, uv = files
    out = folder / "a_textured.obj"
    assert main(["texture", str(folder / "a.off"), str(folder / "b.obj"), str(folder / "map.txt"),
                 "-o", str(out)]) == 0
    written = read_textured_obj(out)
    np.testing.assert_allclose(written.vertex_uv(), uv[truth], atol=1e-3)
    assert (folder / "a_textured.mtl").exists() and (folder / "a_textured_texture.png").exists()


def test_texture_command_refuses_to_replace_an_input(files, capsys):
    folder, _, _ = files
    assert main(["texture", str(folder / "a.off"), str(folder / "b.obj"), str(folder / "map.txt"),
                 "-o", str(folder / "b.obj")]) == 2
    assert "is the input TARGET: writing there would replace it" in capsys.readouterr().err


def test_fmap_export_and_import_round_trip(files, capsys):
    folder, truth, _ = files
    a, b = str(folder / "a.off"), str(folder / "b.obj")
    assert main(["fmap", a, b, str(folder / "map.txt"), "-k", "25", "-o", str(folder / "fmap.npz")]) == 0
    with np.load(folder / "fmap.npz") as data:
        assert data["C"].shape == (25, 25)
    assert main(["fmap", a, b, "--to-map", str(folder / "fmap.npz"), "-o", str(folder / "back.txt")]) == 0
    np.testing.assert_array_equal(np.loadtxt(folder / "back.txt", dtype=np.int64), truth)
    assert main(["fmap", a, b, "-o", str(folder / "x.npz")]) == 2
    assert "Give either MAP" in capsys.readouterr().err
    assert main(["fmap", a, b, str(folder / "map.txt"), "-o", str(folder / "x.txt")]) == 2
    assert "written as .npz" in capsys.readouterr().err
    small = folder / "small.off"
    tube = ds.tube(n_along=8, n_around=6)
    trimesh.Trimesh(tube.vertices, tube.faces, process=False).export(small)
    assert main(["fmap", str(small), b, "--to-map", str(folder / "fmap.npz"), "-o", str(folder / "z.txt")]) == 3
    assert "was written for meshes of" in capsys.readouterr().err


def test_fmap_to_map_refuses_k_and_seed_it_would_ignore(files, capsys):
    folder, _, _ = files
    a, b = str(folder / "a.off"), str(folder / "b.obj")
    assert main(["fmap", a, b, str(folder / "map.txt"), "-o", str(folder / "f2.npz")]) == 0
    with np.load(folder / "f2.npz") as data:
        assert data["C"].shape == (30, 30)  # the default basis size is unchanged
    for extra, named in ((["-k", "25"], "-k 25"), (["--seed", "3"], "--seed 3"),
                         (["-k", "25", "--seed", "3"], "-k 25 and --seed 3")):
        out = folder / "refused.txt"
        assert main(["fmap", a, b, "--to-map", str(folder / "f2.npz"), "-o", str(out), *extra]) == 2
        err = capsys.readouterr().err
        assert named in err and "--to-map" in err and "ignored" in err and not out.exists()
