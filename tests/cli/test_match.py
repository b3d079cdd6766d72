"""The meshcorr command line: outputs, exit codes and error messages."""

import json
import os
import re
import subprocess
import sys
import threading

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


@pytest.mark.parametrize("option", ["--alternative-out", "--report"])
def test_an_output_other_than_the_map_is_not_written_to_a_file_named_dash(tube_files_with_truth, tmp_path,
                                                                          capsys, monkeypatch, option):
    # it wrote a file named '-' (issue 31, item 6); only -o goes to stdout
    src, tgt, _ = tube_files_with_truth
    monkeypatch.chdir(tmp_path)
    assert main(["match", src, tgt, "-o", "m.txt", option, "-", "--reorder", "greedy"]) == 2
    err = capsys.readouterr().err
    assert f"Cannot write {option} to stdout" in err and "./-" in err
    assert os.listdir(tmp_path) == []


@pytest.mark.parametrize("output", ["newdir/", "file.txt/", "folder/", "folder"])
def test_an_output_naming_a_folder_is_refused_and_nothing_written(tube_files_with_truth, tmp_path, capsys,
                                                                  monkeypatch, output):
    # 'newdir/' wrote a file 'newdir', 'file.txt/' replaced file.txt (issue 31, item 6)
    src, tgt, _ = tube_files_with_truth
    monkeypatch.chdir(tmp_path)
    (tmp_path / "file.txt").write_text("mine\n")
    (tmp_path / "folder").mkdir()
    for flag in ("-o", "--alternative-out", "--report"):
        args = ["-o", output] if flag == "-o" else ["-o", "m.txt", flag, output]
        assert main(["match", src, tgt, *args, "--reorder", "greedy"]) == 2
        err = capsys.readouterr().err
        assert "folder" in err and output in err and "Traceback" not in err
        assert sorted(os.listdir(tmp_path)) == ["file.txt", "folder"] and not os.listdir(tmp_path / "folder")
        assert (tmp_path / "file.txt").read_text() == "mine\n"


@pytest.mark.parametrize("name", ["m.txt", "m.npy"])
def test_a_full_disk_is_said_with_the_path_and_exit_3(tube_files_with_truth, tmp_path, capsys, monkeypatch, name):
    # it was "internal error ... report it", exit 1 (issue 31, item 11)
    import errno

    src, tgt, _ = tube_files_with_truth
    out = tmp_path / name

    def full(fd):
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    monkeypatch.setattr(os, "fsync", full)
    code = main(["match", src, tgt, "-o", str(out), "--reorder", "greedy", "-q"])
    err = capsys.readouterr().err
    assert code == 3 and "internal error" not in err and "Traceback" not in err
    assert f"Cannot write {out}: the disk is full" in err
    assert os.listdir(tmp_path) == []


@pytest.mark.skipif(not os.path.exists("/dev/full"), reason="needs /dev/full (Linux)")
@pytest.mark.parametrize("output", [["--json"], ["-o", "-"]])
def test_stdout_on_a_full_disk_is_said_and_exit_3(tube_files_with_truth, output):
    src, tgt, _ = tube_files_with_truth
    with open("/dev/full", "w") as full:
        proc = subprocess.run([sys.executable, "-m", "meshcorr", "match", src, tgt, *output, "-q",
                               "--reorder", "greedy"], stdout=full, stderr=subprocess.PIPE, text=True, timeout=120)
    assert proc.returncode == 3, proc.stderr
    assert "Cannot write stdout" in proc.stderr and "the disk is full" in proc.stderr
    assert "Traceback" not in proc.stderr and "Exception ignored" not in proc.stderr


def _no_work(monkeypatch):
    """Make the match itself fail loudly: what is tested must be found before it."""
    import meshcorr
    import meshcorr.pipeline.run

    def no_work(*args, **kwargs):
        raise AssertionError("match ran")

    monkeypatch.setattr(meshcorr, "match", no_work)  # first: see tests/cli/test_reliability.py
    monkeypatch.setattr(meshcorr.pipeline.run, "match", no_work)


#: What each bad file holds, by problem and by kind (a text file of pairs, a .vts file).
BAD_FILES = {"no permission": {".txt": b"1 2\n", ".vts": b"1\n"}, "not text": {".txt": b"1 \xff\n", ".vts": b"\xff\n"},
             "out of range": {".txt": b"1 999999\n"}}


#: (option, problem) cases; landmarks out of range are the pipeline's to refuse (tests/cli/test_match_landmarks.py).
UNREADABLE_CASES = [(option, problem) for option in (["--landmarks", "{f}"], ["--landmarks-vts", "{f}", "{v}"],
                                                     ["--report", "{r}", "--gt", "{f}"])
                    for problem in ("no permission", "a folder", "not text", "out of range")
                    if problem != "out of range" or option[0] == "--report"]


@pytest.mark.parametrize("option, problem", UNREADABLE_CASES)
def test_unreadable_landmarks_and_truth_are_input_errors_before_the_work(tube_files_with_truth, tmp_path, capsys,
                                                                         monkeypatch, no_read_permission, option,
                                                                         problem):
    # exit 1 (internal error) for an unreadable file; a bad --gt was said only after the whole match (issue 31,
    # item 13).
    src, tgt, _ = tube_files_with_truth
    _no_work(monkeypatch)
    suffix = ".vts" if "--landmarks-vts" in option else ".txt"
    bad = tmp_path / f"bad{suffix}"
    if problem == "a folder":
        bad.mkdir()
    else:
        bad.write_bytes(BAD_FILES[problem][suffix])
    if problem == "no permission":
        no_read_permission(bad.name)
    (tmp_path / "good.vts").write_text("1\n")
    args = [arg.format(f=bad, v=tmp_path / "good.vts", r=tmp_path / "r.html") for arg in option]
    code = main(["match", src, tgt, "-o", str(tmp_path / "m.txt"), *args])
    err = capsys.readouterr().err
    assert code == 3, err
    assert str(bad) in err and "Traceback" not in err and "internal error" not in err
    assert not (tmp_path / "m.txt").exists() and not (tmp_path / "r.html").exists()


def _percentages(err):
    return [int(m) for m in re.findall(r"\] \[[#-]+\] +(\d+)%", err)]


def test_match_progress_is_one_line_for_the_run_that_only_rises(tube_files_with_truth, tmp_path, capsys):
    src, tgt, _ = tube_files_with_truth
    assert main(["match", src, tgt, "-o", str(tmp_path / "m.txt"), "-v"]) == 0
    err = capsys.readouterr().err
    shares = _percentages(err)
    assert len(shares) > 5 and shares == sorted(shares) and shares[-1] == 100, err
    lines = err.splitlines()
    assert any(line.startswith("meshcorr: source.off -> target.ply [shells] [") for line in lines)
    done = [line for line in lines if "[done]" in line]
    assert len(done) == 1 and done[0].startswith("meshcorr: source.off -> target.ply [done] [" + "#" * 24 + "] 100%")
    assert not [t for t in threading.enumerate() if t.name == "meshcorr-progress"]


def test_no_progress_thread_is_left_after_an_error_or_ctrl_c(tube_files_with_truth, tmp_path, capsys, monkeypatch):
    import meshcorr.cli.match as cli_match
    from meshcorr.runtime.progress import StderrProgress

    src, tgt, _ = tube_files_with_truth
    bad = tmp_path / "fan.off"
    V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [0, -1, 0.5]], float)
    trimesh.Trimesh(V, np.array([[0, 1, 2], [0, 1, 3], [0, 1, 4]]), process=False).export(bad)
    assert main(["match", str(bad), tgt, "-o", str(tmp_path / "a.txt"), "-v"]) != 0  # fails in "load"
    assert "[load]" in capsys.readouterr().err
    assert not [t for t in threading.enumerate() if t.name == "meshcorr-progress"]

    class Interrupting(StderrProgress):
        def __call__(self, stage, done, total):
            super().__call__(stage, done, total)
            assert self._ticker is not None and self._ticker.is_alive()
            if stage == "reorder":
                raise KeyboardInterrupt

    monkeypatch.setattr(cli_match, "progress_for", lambda args, label, plan=None: Interrupting(
        sys.stderr, label=label, delay=0.0, plan=plan, tick=0.01))
    assert main(["match", src, tgt, "-o", str(tmp_path / "b.txt")]) == 130
    assert "meshcorr: interrupted" in capsys.readouterr().err
    assert not [t for t in threading.enumerate() if t.name == "meshcorr-progress"]
    assert not (tmp_path / "b.txt").exists()


def test_match_refuses_large_files_from_their_headers_in_python(tmp_path):
    # The library call does the same check as the command line, before the files are read.
    import meshcorr
    from meshcorr.errors import MemoryLimitError

    header = "OFF\n1280000 2560000 0\n"  # no data: reading would fail, the refusal comes first
    for name in ("a.off", "b.off"):
        (tmp_path / name).write_text(header)
    with pytest.raises(MemoryLimitError, match="meshes of up to 732096 vertices each fit"):
        meshcorr.match(str(tmp_path / "a.off"), tmp_path / "b.off", max_memory="2GiB")


def test_large_meshes_that_would_not_fit_are_refused_before_they_are_read(tmp_path, capsys):
    # headers declaring 1.28M vertices and no data: reading them would fail, the refusal comes first
    header = "ply\nformat binary_little_endian 1.0\nelement vertex 1280000\nproperty float x\nproperty float y\n" \
             "property float z\nelement face 2560000\nproperty list uchar int vertex_indices\nend_header\n"
    for name in ("a.ply", "b.ply"):
        (tmp_path / name).write_text(header)
    out = tmp_path / "m.txt"
    assert main(["match", str(tmp_path / "a.ply"), str(tmp_path / "b.ply"), "-o", str(out),
                 "--max-memory", "2GiB"]) == 2
    err = capsys.readouterr().err
    assert "1280000 and 1280000 vertices needs about 3.12 GiB but may use 2.00 GiB" in err
    assert "meshes of up to 732096 vertices each fit" in err and not out.exists()
    # the same files with room to spare go on to be read (and are refused for what they are)
    assert main(["match", str(tmp_path / "a.ply"), str(tmp_path / "b.ply"), "-o", str(out),
                 "--max-memory", "8GiB"]) != 0
    assert "vertices each fit" not in capsys.readouterr().err
