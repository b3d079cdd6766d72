"""The meshcorr command line: outputs, exit codes and error messages."""

import json
import os
import subprocess
import sys

import numpy as np
import pytest
import trimesh

from meshcorr import __version__
from meshcorr import datasets as ds
from meshcorr.cli import main


def test_match_writes_one_index_per_line(tube_files_with_truth, tmp_path, capsys):
    src, tgt, truth = tube_files_with_truth
    out = tmp_path / "map.txt"
    assert main(["match", src, tgt, "-o", str(out), "--reorder", "greedy"]) == 0
    mapping = np.loadtxt(out, dtype=np.int64)
    np.testing.assert_array_equal(mapping, truth)
    assert "wrote" in capsys.readouterr().err


def test_match_npy_and_json_summary(tube_files_with_truth, tmp_path, capsys):
    src, tgt, truth = tube_files_with_truth
    out = tmp_path / "map.npy"
    code = main(["match", src, tgt, "-o", str(out), "--json", "-k", "5", "--reorder", "greedy",
                 "--no-eigenvalue-scaling", "--anchors", "2", "--alpha", "0.5", "--seed", "4",
                 "--geodesic", "fmm", "--icp-iterations", "3"])
    assert code == 0
    np.testing.assert_array_equal(np.load(out), truth)
    summary = json.loads(capsys.readouterr().out)
    assert summary["params"]["k"] == 5 and summary["params"]["scale_eigenvalues"] is False
    assert summary["params"]["geodesic"] == "fmm" and summary["params"]["random_state"] == 4
    assert len(summary["anchors"]) == 2 and summary["icp"]["iterations"] <= 3
    assert set(summary["timings"]) >= {"geodesics", "embedding", "reorder", "icp", "matching"}
    assert summary["configuration"]["perm"] and summary["runner_up"]["cost"] >= summary["configuration"]["cost"]


def test_version_and_help(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["--version"])
    assert exc.value.code == 0 and __version__ in capsys.readouterr().out
    with pytest.raises(SystemExit):
        main(["match", "--help"])
    text = capsys.readouterr().out
    for option in ("--reorder", "--geodesic", "--bijective", "--seed", "--no-eigenvalue-scaling", "--json"):
        assert option in text
    assert main([]) == 2


def _fail(args, capsys):
    code = main(args)
    err = capsys.readouterr().err
    assert code != 0
    assert "Traceback" not in err
    return err


def test_missing_file_is_a_clean_error(tube_files_with_truth, tmp_path, capsys):
    _, tgt, _ = tube_files_with_truth
    out = tmp_path / "map.txt"
    err = _fail(["match", str(tmp_path / "nope.off"), tgt, "-o", str(out)], capsys)
    assert "meshcorr: error:" in err and "nope.off" in err
    assert not out.exists()


def test_non_manifold_mesh_is_a_clean_error(tube_files_with_truth, tmp_path, capsys):
    _, tgt, _ = tube_files_with_truth
    bad = tmp_path / "fan.off"
    V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [0, -1, 0.5]], float)
    F = np.array([[0, 1, 2], [0, 1, 3], [0, 1, 4]])  # one edge shared by three faces
    trimesh.Trimesh(V, F, process=False).export(bad)
    err = _fail(["match", str(bad), tgt, "-o", str(tmp_path / "m.txt")], capsys)
    assert "non-manifold" in err


def test_bad_k_and_missing_output_folder(tube_files_with_truth, tmp_path, capsys):
    src, tgt, _ = tube_files_with_truth
    err = _fail(["match", src, tgt, "-o", str(tmp_path / "m.txt"), "-k", "1"], capsys)
    assert "'k' parameter must be an int >= 2" in err
    err = _fail(["match", src, tgt, "-o", str(tmp_path / "missing" / "m.txt")], capsys)
    assert "does not exist" in err


@pytest.mark.parametrize("extra, named", [
    (["--mode", "dense", "--samples", "30"], ("(--samples)", "--mode dense")),
    (["--no-refine", "--refine-k", "20"], ("(--refine-k)", "--no-refine")),
    (["--icp-iterations", "0", "--control-points", "40"], ("(--control-points)", "--icp-iterations 0")),
    (["--mode", "scalable", "--max-memory", "4GiB"], ("(--max-memory)", "--mode scalable")),
])
def test_an_option_another_makes_ignored_is_a_usage_error(tube_files_with_truth, tmp_path, capsys, extra, named):
    src, tgt, _ = tube_files_with_truth
    out = tmp_path / "m.txt"
    assert main(["match", src, tgt, "-o", str(out), *extra]) == 2
    err = capsys.readouterr().err
    assert all(name in err for name in named) and "ignored" in err and not out.exists()


def test_bijective_with_unequal_counts_leaves_no_file(tmp_path, capsys):
    a, b = ds.tube(n_along=20, n_around=10), ds.tube(n_along=22, n_around=10)
    pa, pb = tmp_path / "a.off", tmp_path / "b.off"
    trimesh.Trimesh(a.vertices, a.faces, process=False).export(pa)
    trimesh.Trimesh(b.vertices, b.faces, process=False).export(pb)
    out = tmp_path / "m.txt"
    err = _fail(["match", str(pa), str(pb), "-o", str(out), "--bijective"], capsys)
    assert "same number of vertices" in err
    assert os.listdir(tmp_path) == sorted(["a.off", "b.off"]) or not out.exists()
    assert not [f for f in os.listdir(tmp_path) if f.endswith(".tmp")]


def test_console_script_runs_as_a_process(tube_files_with_truth, tmp_path):
    src, tgt, truth = tube_files_with_truth
    out = tmp_path / "map.txt"
    proc = subprocess.run([sys.executable, "-m", "meshcorr", "match", src, tgt, "-o", str(out), "-q"],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    np.testing.assert_array_equal(np.loadtxt(out, dtype=np.int64), truth)
    bad = subprocess.run([sys.executable, "-m", "meshcorr", "match", src, "nope.obj", "-o", str(out)],
                         capture_output=True, text=True, timeout=120)
    assert bad.returncode == 3 and "Traceback" not in bad.stderr  # bad input data
