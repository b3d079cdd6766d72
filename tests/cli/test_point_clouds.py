"""Point clouds on the command line and in the batch: .xyz, .npy and PLY of points (issue 15, item 1)."""

from __future__ import annotations

import json

import numpy as np
import pytest
import trimesh

import meshcorr
from meshcorr import datasets as ds
from meshcorr.cli import main
from meshcorr.io import read_mesh

FAST = ["--no-refine", "--no-extremities", "--mode", "scalable"]


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    """The creature's vertices as .xyz (with comments and extra columns), its rigid copy as .npy and as
    a PLY of points, and the copy's mesh; with the truth (copy index of each source point)."""
    folder = tmp_path_factory.mktemp("clouds")
    shape = ds.creature(resolution=2)
    copy, truth = ds.rigid_copy(shape, scale=1.5, random_state=4)
    xyz = folder / "source.xyz"
    normals = np.tile([0.0, 0.0, 1.0], (shape.n_vertices, 1))
    with open(xyz, "w") as file:
        file.write("# x y z nx ny nz: the normals are ignored\n")
        np.savetxt(file, np.hstack([shape.vertices, normals]), fmt="%.10f")
    npy = folder / "target.npy"
    np.save(npy, copy.vertices)
    ply = folder / "target_points.ply"
    trimesh.PointCloud(copy.vertices).export(ply)
    mesh = folder / "copy_mesh.off"
    trimesh.Trimesh(copy.vertices, copy.faces, process=False).export(mesh)
    return dict(xyz=str(xyz), npy=str(npy), ply=str(ply), mesh=str(mesh), truth=truth, folder=folder)


def test_the_point_formats_read_as_clouds(files):
    for key in ("xyz", "npy", "ply"):
        vertices, faces = read_mesh(files[key])
        assert faces.shape == (0, 3) and vertices.shape == (1000, 3)
    np.testing.assert_allclose(read_mesh(files["ply"])[0], read_mesh(files["npy"])[0], atol=1e-5)  # PLY: float32


@pytest.mark.parametrize("target", ["npy", "ply", "mesh"])
def test_match_reads_xyz_npy_and_point_ply(files, target, tmp_path):
    out = tmp_path / "map.txt"
    assert main(["match", files["xyz"], files[target], "-o", str(out), "-q", *FAST]) == 0
    mapping = np.loadtxt(out, dtype=np.int64)
    assert np.mean(mapping == files["truth"]) >= (0.95 if target != "mesh" else 0.6)


def test_evaluate_show_and_transfer_take_clouds(files, tmp_path, capsys):
    out = tmp_path / "map.txt"
    assert main(["match", files["xyz"], files["npy"], "-o", str(out), "-q", *FAST]) == 0
    truth = tmp_path / "truth.txt"
    truth.write_text("".join(f"{i} {j}\n" for i, j in enumerate(files["truth"])))
    capsys.readouterr()
    assert main(["evaluate", files["xyz"], files["npy"], str(out), "--gt", str(truth), "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["mean_error"] < 0.01 and 0.5 < summary["coverage"] <= 1.0
    pytest.importorskip("matplotlib")
    picture = tmp_path / "show.png"
    assert main(["show", files["xyz"], files["mesh"], str(out), "-o", str(picture), "--dpi", "40", "-q"]) == 0
    assert picture.stat().st_size > 1000
    coloured = tmp_path / "colours.ply"
    assert main(["transfer", files["xyz"], files["mesh"], str(out), "--attribute", "parts", "-o", str(coloured),
                 "-q"]) == 0
    cloud = trimesh.load(coloured)
    assert isinstance(cloud, trimesh.PointCloud) and len(cloud.vertices) == 1000
    assert main(["transfer", files["xyz"], files["mesh"], str(out), "--attribute", "parts", "-o",
                 str(tmp_path / "c.obj"), "-q"]) == 2
    assert "point cloud" in capsys.readouterr().err


def test_cloud_errors_on_the_command_line(files, tmp_path, capsys):
    out = str(tmp_path / "map.txt")
    assert main(["match", files["xyz"], files["npy"], "-o", out, "--geodesic", "fmm"]) == 2
    assert "needs triangles" in capsys.readouterr().err
    bad = tmp_path / "bad.xyz"
    bad.write_text("0 0 0\n1 2\n")
    assert main(["match", str(bad), files["npy"], "-o", out]) == 3
    assert "bad.xyz, line 2: expected 'x y z'" in capsys.readouterr().err
    few = tmp_path / "few.npy"
    np.save(few, np.random.default_rng(0).random((10, 3)))
    assert main(["match", str(few), files["npy"], "-o", out]) == 3
    assert "point cloud of 10 points" in capsys.readouterr().err
    wrong = tmp_path / "wrong.npy"
    np.save(wrong, np.zeros((40, 4)))
    assert main(["match", str(wrong), files["npy"], "-o", out]) == 3
    assert "(n, 3) array" in capsys.readouterr().err


def test_batch_and_the_cache_take_clouds(files, tmp_path):
    distributed = pytest.importorskip("distributed")
    pairs = [(files["xyz"], files["npy"]), (files["xyz"], files["mesh"])]
    options = dict(refine=False, extremities=False, mode="scalable")
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=False,
                                  dashboard_address=":0") as cluster, distributed.Client(cluster) as client:
        records = meshcorr.batch(pairs, tmp_path / "out", client=client, cache=tmp_path / "cache", **options)
    assert [r["status"] for r in records] == ["ok", "ok"]
    direct = meshcorr.match(files["xyz"], files["npy"], **options)
    written = np.loadtxt(tmp_path / "out" / "maps" / "source__target.txt", dtype=np.int64)
    np.testing.assert_array_equal(written, direct.map)
    assert len(list((tmp_path / "cache").glob("*.npz"))) == 3  # one cloud source, a cloud and a mesh target
