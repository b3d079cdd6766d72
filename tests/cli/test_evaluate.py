"""``meshcorr evaluate`` and ``meshcorr bench``: outputs, resume, failures, exit codes."""

import csv
import json
import time

import numpy as np
import pytest
import trimesh

import meshcorr.evaluation.benchmark as benchmark
from meshcorr import datasets as ds
from meshcorr.cli import main
from meshcorr.errors import ParameterError
from meshcorr.maps.result import Correspondence


def save_off(path, shape):
    trimesh.Trimesh(shape.vertices, shape.faces, process=False).export(path)
    return str(path)


@pytest.fixture(scope="module")
def tube_files_for_evaluation(tmp_path_factory):
    """A tube and a rigid, re-indexed copy; truth[i] = copy's vertex of vertex i."""
    folder = tmp_path_factory.mktemp("eval")
    shape = ds.tube(n_along=16, n_around=8)
    copy, truth = ds.rigid_copy(shape, scale=0.5, random_state=3)
    src, tgt = save_off(folder / "a.off", shape), save_off(folder / "b.off", copy)
    np.savetxt(folder / "truth.txt", truth, fmt="%d")
    (folder / "a.vts").write_text("".join(f"{i + 1}\n" for i in range(len(truth))))
    (folder / "b.vts").write_text("".join(f"{t + 1}\n" for t in truth))
    shifted = truth[(np.arange(len(truth)) + 8) % len(truth)]  # a wrong map: next ring's vertex
    np.savetxt(folder / "shifted.txt", shifted, fmt="%d")
    (folder / "b.sym.vts").write_text("".join(f"{t + 1}\n" for t in shifted))
    np.savetxt(folder / "short.txt", truth[:127], fmt="%d")
    return folder, src, tgt


def test_evaluate_perfect_map_text(tube_files_for_evaluation, capsys):
    folder, src, tgt = tube_files_for_evaluation
    assert main(["evaluate", src, tgt, str(folder / "truth.txt"), "--gt", str(folder / "truth.txt")]) == 0
    out = capsys.readouterr().out
    assert "mean geodesic error:   0.0000" in out and "100.0 % / 100.0 % / 100.0 %" in out


def test_evaluate_json_with_vts_and_sym(tube_files_for_evaluation, capsys):
    folder, src, tgt = tube_files_for_evaluation
    code = main(["evaluate", src, tgt, str(folder / "shifted.txt"), "--gt", str(folder / "a.vts"),
                 "--gt", str(folder / "b.vts"), "--sym", str(folder / "b.sym.vts"), "--json",
                 "--thresholds", "0.5,1"])
    assert code == 0
    report = json.loads(capsys.readouterr().out)
    assert report["flipped"] is True and report["sym_mean_error"] == 0.0
    assert report["mean_error"] > 0.01 and set(report["under"]) == {"0.5", "1"}
    # The next ring's vertex is close (< 0.2), but for the 8 vertices of the last ring, sent
    # to the far end: 144 of the 152 points are under either threshold.
    assert report["under"] == {"0.5": pytest.approx(144 / 152), "1": pytest.approx(144 / 152)}
    assert report["n_points"] == ds.tube(n_along=16, n_around=8).n_vertices == 152
    assert report["total_error"] == pytest.approx(report["mean_error"] * 152 * report["sqrt_area"])


def test_evaluate_curve_png(tube_files_for_evaluation, tmp_path):
    pytest.importorskip("matplotlib")
    folder, src, tgt = tube_files_for_evaluation
    png = tmp_path / "curve.png"
    assert main(["evaluate", src, tgt, str(folder / "shifted.txt"), "--gt", str(folder / "truth.txt"),
                 "--curve", str(png)]) == 0
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and png.stat().st_size < 150_000


@pytest.mark.parametrize("change, message, code", [
    (lambda f: [str(f / "missing.txt"), "--gt", "identity"], "No such file", 3),
    (lambda f: [str(f / "short.txt"), "--gt", str(f / "truth.txt")], "has 127 entries", 3),
    (lambda f: [str(f / "truth.txt"), "--gt", str(f / "a.vts")], "indexes one mesh only", 3),
    (lambda f: [str(f / "truth.txt"), "--gt", str(f / "a.vts"), "--gt", str(f / "nope.vts")],
     "No such ground-truth", 3),
    (lambda f: [str(f / "truth.txt"), "--gt", "identity", "--thresholds", "x"], "--thresholds", 2),
])
def test_evaluate_errors_exit_2_or_3_with_one_line(tube_files_for_evaluation, capsys, change, message, code):
    """Bad usage exits 2, bad input data 3."""
    folder, src, tgt = tube_files_for_evaluation
    assert main(["evaluate", src, tgt, *change(folder)]) == code
    err = capsys.readouterr().err
    assert err.startswith("meshcorr: error:") and message in err and err.count("\n") == 1


# ---------------------------------------------------------------- bench


@pytest.fixture()
def dataset(tmp_path):
    """Two classes, each a tube and a rigid, re-indexed copy, in the TOSCA layout."""
    root = tmp_path / "data"
    (root / "corres").mkdir(parents=True)
    for cls, shape in (("tube", ds.tube(n_along=22, n_around=10)),
                       ("fig", ds.tube(n_along=20, n_around=10, random_state=1))):
        copy, truth = ds.rigid_copy(shape, scale=0.5, random_state=2)
        for name, mesh, vts in ((f"{cls}0", shape, np.arange(shape.n_vertices)), (f"{cls}1", copy, truth)):
            save_off(root / f"{name}.off", mesh)
            (root / "corres" / f"{name}.vts").write_text("".join(f"{i + 1}\n" for i in vts))
    (root / "test_pairs.txt").write_text("tube0 tube1\nfig0\tfig1\ntube1 tube0\n")
    return root


def fake_method(calls, fail_on=()):
    def run(name, source, target, *, random_state=0, progress=None, **options):
        calls.append((source.name, target.name, name, options))
        if source.name in fail_on:
            raise RuntimeError("boom\nsecond line")
        return Correspondence(map=np.arange(source.n_vertices), method=name)
    return run


def test_bench_writes_tables_and_resumes(dataset, tmp_path, monkeypatch, capsys):
    calls = []
    monkeypatch.setattr(benchmark, "run_method", fake_method(calls, fail_on={"fig0"}))
    out = tmp_path / "out"
    args = ["bench", str(dataset), "--out", str(out), "--no-plot", "-k", "5", "--set", "spectral:reorder='greedy'"]
    assert main(args) == 4  # one run failed
    captured = capsys.readouterr()
    assert "| spectral | 2 | 1 |" in captured.out and "warning" not in captured.err and "1 (pair, method) runs failed" in captured.err
    rows = list(csv.DictReader((out / "results.csv").open()))
    assert [(r["source"], r["status"]) for r in rows] == [("tube0", "ok"), ("fig0", "failed"), ("tube1", "ok")]
    assert rows[1]["error"] == "RuntimeError: boom second line"
    assert calls[0][3] == {"k": 5, "reorder": "greedy"}
    assert (out / "maps" / "spectral" / "tube0-tube1.npy").is_file()
    assert (out / "summary.csv").is_file() and "tube" in (out / "summary.md").read_text()

    before = (out / "results.csv").read_text()
    calls.clear()
    assert main(args) == 4  # restart: nothing recomputed, rows unchanged, the failure still counted
    assert calls == [] and (out / "results.csv").read_text() == before
    assert main(args + ["--retry-failed"]) == 4
    assert [c[0] for c in calls] == ["fig0"]
    assert main(["bench", str(dataset), "--out", str(out), "--no-plot", "-q"]) == 2  # other settings
    assert "other settings" in capsys.readouterr().err


def test_bench_real_spectral_run_and_curves(dataset, tmp_path, capsys):
    pytest.importorskip("matplotlib")
    out = tmp_path / "real"
    start = time.perf_counter()
    assert main(["bench", str(dataset), "--out", str(out), "--pairs", "2", "-q",
                 "--set", "spectral:reorder='greedy'", "--set", "spectral:icp_iterations=2"]) == 0
    seconds = time.perf_counter() - start
    rows = list(csv.DictReader((out / "results.csv").open()))
    assert {r["class"] for r in rows} == {"tube", "fig"} and all(r["status"] == "ok" for r in rows)
    assert all(float(r["mean_error"]) == 0.0 for r in rows)
    assert max(float(r["seconds"]) for r in rows) <= seconds  # each pair's time, in seconds
    png = out / "curves.png"
    assert png.read_bytes()[:4] == b"\x89PNG" and png.stat().st_size < 150_000


def test_stratified_sample_covers_classes():
    pairs = [(f"{c}{i}", f"{c}{i + 1}") for c in "abcd" for i in range(5)]
    sample = benchmark.stratified_sample(pairs, 8, random_state=0)
    assert len(sample) == 8 and sorted({benchmark.shape_class(s) for s, _ in sample}) == list("abcd")
    assert sample == benchmark.stratified_sample(pairs, 8, random_state=0)
    assert benchmark.stratified_sample(pairs, None) == pairs
    assert benchmark.shape_class("david10") == "david"


def test_bench_input_errors(dataset, tmp_path, capsys):
    assert main(["bench", str(tmp_path / "nowhere"), "--no-plot"]) == 2
    assert "No such dataset folder" in capsys.readouterr().err
    (dataset / "corres" / "fig1.vts").unlink()
    assert main(["bench", str(dataset), "--out", str(tmp_path / "o"), "--no-plot"]) == 2
    assert "fig1.vts is missing" in capsys.readouterr().err
    assert main(["bench", str(dataset), "--methods", "magic", "--no-plot"]) == 2
    assert "Unknown method 'magic'" in capsys.readouterr().err
    assert main(["bench", str(dataset), "--set", "spectral-k", "--no-plot"]) == 2
    assert "METHOD:KEY=VALUE" in capsys.readouterr().err
    (dataset / "test_pairs.txt").write_text("tube0 tube1 extra\n")
    with pytest.raises(ParameterError, match="line 1: expected two shape names"):
        benchmark.load_dataset(dataset)


def test_evaluate_refuses_a_truth_with_two_targets_for_a_vertex_and_a_wrapped_uint64_map(
        tube_files_for_evaluation, tmp_path, capsys):
    # both were taken: 129 points scored on a 128-vertex source; 2**64 - 1 read as -1 (issue 31, item 7)
    folder, src, tgt = tube_files_for_evaluation
    truth = np.loadtxt(folder / "truth.txt", dtype=np.int64)
    pairs = [f"{i} {t}" for i, t in enumerate(truth)]
    (tmp_path / "pairs.txt").write_text("\n".join(pairs + [f"5 {truth[6]}"]) + "\n")
    assert main(["evaluate", src, tgt, str(folder / "truth.txt"), "--gt", str(tmp_path / "pairs.txt")]) == 3
    err = capsys.readouterr().err
    assert f"pairs.txt, line {len(truth) + 1}: source vertex 5 already has the true target {truth[5]} on line 6" in err
    huge = truth.astype(np.uint64)
    huge[3] = np.uint64(2 ** 64 - 1)
    np.save(tmp_path / "huge.npy", huge)
    assert main(["evaluate", src, tgt, str(tmp_path / "huge.npy"), "--gt", str(folder / "truth.txt")]) == 3
    err = capsys.readouterr().err
    assert "huge.npy: entry 3 is 18446744073709551615, too large for a vertex index" in err
    assert err.count("\n") == 1


@pytest.mark.parametrize("which", ["MAP", "--gt", "--sym"])
def test_evaluate_says_an_unreadable_map_or_truth_with_exit_3(tube_files_for_evaluation, tmp_path, capsys,
                                                              no_read_permission, which):
    # no read permission was an internal error, exit 1 (issue 31, item 13)
    folder, src, tgt = tube_files_for_evaluation
    locked = tmp_path / "locked.txt"
    locked.write_text((folder / "truth.txt").read_text())
    no_read_permission("locked.txt")
    truth = str(folder / "truth.txt")
    args = {"MAP": [str(locked), "--gt", truth], "--gt": [truth, "--gt", str(locked)],
            "--sym": [truth, "--gt", truth, "--sym", str(locked)]}[which]
    assert main(["evaluate", src, tgt, *args]) == 3
    err = capsys.readouterr().err
    assert err.startswith("meshcorr: error: Cannot read the") and str(locked) in err and "Permission denied" in err
    assert err.count("\n") == 1


def test_evaluate_progress_names_each_phase_and_only_rises(tube_files_for_evaluation, tmp_path, capsys, monkeypatch):
    """Issue 31: the truth's and the mirrored truth's solves ran 39 -> 100 -> 66 -> 100 % under one label."""
    import meshcorr.cli.match as cli_match

    folder, src, tgt = tube_files_for_evaluation
    truth = np.loadtxt(folder / "truth.txt", dtype=np.int64)
    rolled = tmp_path / "shuffled.txt"  # a map off both truths: each needs its own solves
    np.savetxt(rolled, np.random.default_rng(0).permutation(truth), fmt="%d")
    reports = []
    monkeypatch.setattr(cli_match, "progress_for", lambda args, label, plan=None: lambda *r: reports.append(r))
    assert main(["evaluate", src, tgt, str(rolled), "--gt", str(folder / "a.vts"), "--gt", str(folder / "b.vts"),
                 "--sym", str(folder / "b.sym.vts"), "--json"]) == 0
    capsys.readouterr()
    labels = list(dict.fromkeys(stage for stage, _, _ in reports))
    assert labels == ["geodesic errors", "geodesic errors (mirrored truth)"]
    for label in labels:
        shares = [done / total for stage, done, total in reports if stage == label]
        assert shares == sorted(shares) and shares[-1] == 1.0, (label, shares)
