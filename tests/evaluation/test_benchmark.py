"""``meshcorr bench``: run.json records the dataset, and a rerun on another (or changed) one is refused.

Before, ``bench A --out DIR`` then ``bench B --out DIR`` reused A's finished records and reported
them as B's results (a silent wrong answer).
"""

import csv
import json
import shutil

import numpy as np
import pytest
import trimesh

import meshcorr.evaluation.benchmark as benchmark
from meshcorr import datasets as ds
from meshcorr.cli import EXIT_USAGE, main
from meshcorr.maps.result import Correspondence

SHAPE = ds.tube(n_along=10, n_around=6)


def make_dataset(root, shift=0):
    """One pair, a tube onto itself; the truth maps vertex i onto vertex i + shift (0: the identity)."""
    (root / "corres").mkdir(parents=True)
    n = SHAPE.n_vertices
    for name in ("tube0", "tube1"):
        trimesh.Trimesh(SHAPE.vertices, SHAPE.faces, process=False).export(root / f"{name}.off")
    (root / "corres" / "tube0.vts").write_text("".join(f"{i + 1}\n" for i in range(n)))
    (root / "corres" / "tube1.vts").write_text("".join(f"{(i + shift) % n + 1}\n" for i in range(n)))
    (root / "test_pairs.txt").write_text("tube0 tube1\n")
    return root


@pytest.fixture()
def calls(monkeypatch):
    """Every method is the identity map (fast); the calls are recorded."""
    made = []

    def identity(name, source, target, *, random_state=0, progress=None, **options):
        made.append((source.name, target.name, name))
        return Correspondence(map=np.arange(source.n_vertices), method=name)

    monkeypatch.setattr(benchmark, "run_method", identity)
    return made


def bench(dataset, out):
    return main(["bench", str(dataset), "--out", str(out), "--no-plot", "-q"])


def mean_error(out):
    rows = list(csv.DictReader((out / "results.csv").open()))
    assert len(rows) == 1 and rows[0]["status"] == "ok"
    return float(rows[0]["mean_error"])


def test_bench_refuses_another_dataset_in_the_same_out(tmp_path, calls, capsys):
    a, b = make_dataset(tmp_path / "A"), make_dataset(tmp_path / "B", shift=20)
    out = tmp_path / "out"
    assert bench(a, out) == 0 and mean_error(out) == 0.0
    before = (out / "results.csv").read_text(), (out / "run.json").read_text()
    capsys.readouterr()
    calls.clear()
    assert bench(b, out) == EXIT_USAGE  # was 0, with A's 0.0000 shown as B's result
    err = capsys.readouterr().err
    assert err.startswith("meshcorr: error:") and err.count("\n") == 1, err
    for text in (str(a.resolve()), str(b.resolve()), "corres/tube1.vts", "another --out",
                 str(out / "run.json")):
        assert text in err, text
    assert calls == [] and ((out / "results.csv").read_text(), (out / "run.json").read_text()) == before
    # B's true error, in a folder of its own.
    assert bench(b, tmp_path / "out-b") == 0 and mean_error(tmp_path / "out-b") > 0.1


@pytest.mark.parametrize("change, named", [
    (lambda root: trimesh.Trimesh(SHAPE.vertices * 1.5, SHAPE.faces, process=False).export(root / "tube1.off"),
     "tube1.off"),
    (lambda root: (root / "corres" / "tube1.vts").write_text(
        "".join(f"{(i + 6) % SHAPE.n_vertices + 1}\n" for i in range(SHAPE.n_vertices))), "corres/tube1.vts"),
    (lambda root: (root / "test_pairs.txt").write_text("tube0 tube1\ntube1 tube0\n"),
     "pair list (1 pair recorded, 2 pairs now)"),
])
def test_bench_refuses_the_same_folder_after_its_files_changed(tmp_path, calls, capsys, change, named):
    data, out = make_dataset(tmp_path / "data"), tmp_path / "out"
    assert bench(data, out) == 0
    capsys.readouterr()
    calls.clear()
    change(data)
    assert bench(data, out) == EXIT_USAGE
    err = capsys.readouterr().err
    assert named in err and "changed since" in err and str(data.resolve()) in err and err.count("\n") == 1, err
    assert calls == []


def test_bench_resumes_from_a_copy_of_the_same_dataset(tmp_path, calls, capsys):
    """Only the content counts: the same files in another folder are the same dataset."""
    data, out = make_dataset(tmp_path / "data"), tmp_path / "out"
    assert bench(data, out) == 0
    calls.clear()
    assert bench(shutil.copytree(data, tmp_path / "copy"), out) == 0 and calls == []


def test_bench_resumes_a_run_json_without_the_dataset_and_records_it(tmp_path, calls, capsys):
    """A run.json of the previous version (no "dataset") resumes, and is then checked next time."""
    data, out = make_dataset(tmp_path / "data"), tmp_path / "out"
    assert bench(data, out) == 0
    settings = json.loads((out / "run.json").read_text())
    identity = settings.pop("dataset")
    assert identity == benchmark.dataset_identity(benchmark.load_dataset(data))
    assert identity["path"] == str(data.resolve()) and set(identity["files"]) == {
        "tube0.off", "tube1.off", "corres/tube0.vts", "corres/tube1.vts"}
    (out / "run.json").write_text(json.dumps(settings))  # as the previous version wrote it
    calls.clear()
    assert bench(data, out) == 0 and calls == []  # resumed: nothing ran again
    assert json.loads((out / "run.json").read_text()) == dict(settings, dataset=identity)
    capsys.readouterr()
    assert bench(make_dataset(tmp_path / "other", shift=20), out) == EXIT_USAGE
    assert "another dataset" in capsys.readouterr().err
    # Other settings are still refused as before, whatever run.json holds.
    (out / "run.json").write_text(json.dumps(settings))
    assert main(["bench", str(data), "--out", str(out), "--no-plot", "-q", "--seed", "3"]) == EXIT_USAGE
    assert "other settings" in capsys.readouterr().err and calls == []
