"""meshcorr batch on a real local Dask cluster: same maps, failures recorded, resumable (issue 13)."""

from __future__ import annotations

import builtins
import threading
import json
from pathlib import Path

import numpy as np
import pytest
import trimesh

import meshcorr
from meshcorr.evaluation import cuts as cuts
from meshcorr import datasets as ds
from meshcorr.collection.batch import batch
from meshcorr.collection.pairs import all_pairs, map_name, read_pair_list, template_pairs
from meshcorr.cli import main
from meshcorr.collection.consistency import (choose_hub, cycle_errors, invert, sample_triples, shape_dna, spectral_medoid,
                                  through_hub)
from meshcorr.errors import ParameterError
from meshcorr.io import read_map

distributed = pytest.importorskip("distributed", reason="the batch tests need meshcorr[dask] (dask[distributed])")

POSES = ("rest", "bent", "curled", 0.4)


@pytest.fixture(scope="module")
def cluster():
    """A scheduler and two single-threaded worker processes on loopback, started once for the module."""
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                                  dashboard_address=":0") as local, distributed.Client(local) as client:
        yield client


@pytest.fixture(scope="module")
def shapes(tmp_path_factory):
    folder = tmp_path_factory.mktemp("shapes")
    paths = []
    for i, pose in enumerate(POSES):
        shape = ds.creature(resolution=1, pose=pose)  # same vertices and faces: the truth is the identity
        path = folder / f"c{i}.off"
        trimesh.Trimesh(shape.vertices, shape.faces, process=False).export(path)
        paths.append(str(path))
    bad = folder / "bad.off"
    bad.write_text("OFF\n3 1 0\n0 0 0\n1 0 0\n")  # a vertex line missing
    return paths, str(bad)


def test_all_pairs_batch_gives_the_per_pair_maps(cluster, shapes, tmp_path):
    paths, _ = shapes
    seen = []
    assert meshcorr.batch is batch
    records = batch(all_pairs(paths), tmp_path, client=cluster, ground_truth="identity",
                    progress=lambda *a: seen.append(a))
    assert len(records) == 12 and all(r["status"] == "ok" for r in records)
    for record in records:
        direct = meshcorr.match(record["source"], record["target"])
        np.testing.assert_array_equal(read_map(record["map"]), direct.map)
        assert record["seconds"] > 0 and 0 <= record["mean_error"] < 0.05  # poses of one shape
    assert seen[0] == (0, 12, 0, None) and seen[-1][:3] == (12, 12, 0) and seen[-1][3] == 0
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["n_pairs"] == 12 and summary["n_failed"] == 0
    assert (tmp_path / "summary.csv").read_text().splitlines()[0] == \
        "source,target,map,status,seconds,cpu_seconds,mean_error,error,via,made"
    # Consistency over the collection: the cycle error of the direct maps and of the hub's.
    names = [Path(p).stem for p in paths]
    maps = {(Path(r["source"]).stem, Path(r["target"]).stem): read_map(r["map"]) for r in records}
    meshes = {n: meshcorr.as_mesh(p) for n, p in zip(names, paths)}
    triples = sample_triples(names, maps, 10)
    assert len(triples) == 10 and len(set(triples)) == 10
    errors = cycle_errors(maps, meshes, triples)
    assert np.all(errors >= 0) and errors.mean() < 0.05
    hub = choose_hub(maps, meshes)
    composed = through_hub(maps, hub)
    a, b = [n for n in names if n != hub][:2]
    np.testing.assert_array_equal(composed[a, b], maps[hub, b][maps[a, hub]])
    np.testing.assert_array_equal(composed[a, hub], maps[a, hub])
    # A map composed with the identity maps: a collection of copies is exactly consistent.
    identity = {key: np.arange(500) for key in maps}
    np.testing.assert_array_equal(cycle_errors(identity, meshes, triples), 0.0)


def test_a_batch_through_a_hub_matches_the_hub_pairs_and_composes_the_others(cluster, shapes, tmp_path, capsys):
    paths, _ = shapes
    hub = paths[1]
    records = batch(all_pairs(paths), tmp_path, client=cluster, ground_truth="identity", hub=hub)
    assert len(records) == 12 and all(r["status"] == "ok" for r in records)
    maps = {(r["source"], r["target"]): read_map(r["map"]) for r in records}
    hub_points = meshcorr.as_mesh(hub).vertices
    for record in records:
        a, b = record["source"], record["target"]
        assert record["mean_error"] < 0.05  # poses of one shape
        if b == hub:  # matched: the per-pair map
            assert not record.get("via") and record["made"] == "match"
            np.testing.assert_array_equal(maps[a, b], meshcorr.match(a, b).map)
        elif a == hub:  # the inverse of b's map onto the hub
            assert record["via"] == hub and record["made"] == "inverse"
            np.testing.assert_array_equal(maps[a, b], invert(maps[b, hub], hub_points))
        else:  # composed: source -> hub -> target
            assert record["via"] == hub and record["made"] == "composition"
            np.testing.assert_array_equal(maps[a, b], maps[hub, b][maps[a, hub]])
    assert [r["made"] for r in records].count("match") == 3  # n - 1 matches for n (n - 1) maps
    # A rerun skips every pair, composed ones included; a composed map whose file is gone is composed again.
    Path(maps_path := records[1]["map"]).unlink()
    totals = []
    again = batch(all_pairs(paths), tmp_path, client=cluster, ground_truth="identity", hub=hub,
                  progress=lambda d, t, f, left: totals.append(t))
    assert records[1]["via"] == hub and totals[0] == 1 and all(r["status"] == "ok" for r in again)
    np.testing.assert_array_equal(read_map(maps_path), maps[records[1]["source"], records[1]["target"]])
    # The CLI: the automatic hub is the spectral medoid of the four poses, and the summary says so.
    dna = {p: shape_dna(meshcorr.as_mesh(p)) for p in paths}
    medoid = spectral_medoid(dna)
    assert main(["batch", "--all-pairs", *paths, "--hub", "auto", "--out", str(tmp_path / "auto"),
                 "--scheduler", cluster.scheduler.address]) == 0
    assert f"12 of 12 pairs mapped into {tmp_path / 'auto'} (9 made through {medoid})" in capsys.readouterr().err
    summary = json.loads((tmp_path / "auto" / "summary.json").read_text())["pairs"]
    assert {r["via"] for r in summary if r.get("via")} == {medoid}
    with pytest.raises(ParameterError, match="holds results made with other settings"):
        batch(all_pairs(paths), tmp_path / "auto", client=cluster, hub=paths[0])


def test_a_hub_batch_of_shapes_with_holes_maps_their_own_vertices(cluster, tmp_path):
    # The same holes in three poses (one vertex numbering: the truth is the identity); the hub's holes
    # are closed while it is matched, and its inverse maps cover its own vertices only.
    rest = ds.creature(resolution=1)
    _, kept = cuts.punch_holes(meshcorr.as_mesh((rest.vertices, rest.faces)), n_holes=4, hole_area=0.01,
                               random_state=0)
    keep = np.isin(rest.faces, kept).all(axis=1)  # the faces left: the same in every pose
    paths = []
    for i, pose in enumerate(POSES[:3]):
        shape = ds.creature(resolution=1, pose=pose)
        holed, _ = cuts.submesh(meshcorr.as_mesh((shape.vertices, shape.faces)), keep)
        paths.append(str(tmp_path / f"h{i}.off"))
        trimesh.Trimesh(holed.vertices, holed.faces, process=False).export(paths[-1])
    records = batch(all_pairs(paths), tmp_path / "out", client=cluster, ground_truth="identity", hub=paths[1])
    assert len(records) == 6 and all(r["status"] == "ok" for r in records)
    for record in records:
        mapping = read_map(record["map"])
        assert mapping.shape == (len(kept),) and 0 <= mapping.min() and mapping.max() < len(kept)
        assert record["mean_error"] < 0.05


def test_a_hub_pair_that_fails_fails_the_maps_composed_through_it(cluster, shapes, tmp_path):
    paths, bad = shapes
    shapes_with_bad = [paths[0], paths[1], bad]
    records = batch(all_pairs(shapes_with_bad), tmp_path, client=cluster, hub=paths[0])
    status = {(r["source"], r["target"]): r for r in records}
    assert status[paths[0], paths[1]]["status"] == "ok" and status[paths[1], paths[0]]["status"] == "ok"
    failed = status[bad, paths[1]]
    assert failed["status"] == "failed" and failed["via"] == paths[0]
    assert "Composed through the hub: its map bad.off -> c0.off failed" in failed["error"]
    assert "Composed through the hub: its map c0.off -> bad.off failed" in status[paths[1], bad]["error"]
    assert "Inverted from the map bad.off -> c0.off, which failed" in status[paths[0], bad]["error"]
    # The automatic hub is never a shape that could not be prepared.
    records = batch(all_pairs(shapes_with_bad), tmp_path / "auto", client=cluster, hub="auto")
    assert {r.get("via") for r in records} - {None} <= {paths[0], paths[1]}


def test_the_time_left_counts_matches_at_their_pace_and_compositions_at_theirs(monkeypatch):
    from meshcorr.collection import batch as collection

    clock = iter([0.0, 5.0, 10.0, 10.0, 15.0, 20.0, 20.0, 21.0])
    monkeypatch.setattr(collection.time, "perf_counter", lambda: next(clock))
    eta = collection._Estimate(4, 3, collection.time.perf_counter())  # start at 0 s
    eta.finished(True)  # a match at 5 s
    eta.finished(True)  # another at 10 s
    assert eta.seconds_left() == 10.0  # two matches left at 5 s each, compositions not counted
    eta.finished(True)  # 15 s
    eta.finished(True)  # 20 s: the last match
    assert eta.seconds_left() == 0.0 * 3  # no composition done yet: nothing to go by (20 - 20 s)
    eta.finished(False)  # two compositions, then asked at 21 s
    eta.finished(False)
    assert eta.seconds_left() == 1.0 / 2 * 1  # 1 s since the last match for 2 compositions, 1 left


def test_hub_error_paths(shapes, tmp_path, capsys):
    paths, _ = shapes
    with pytest.raises(ParameterError, match="is not one of the shapes of the batch"):
        batch(all_pairs(paths[:3]), tmp_path, hub=paths[3])
    with pytest.raises(ParameterError, match="needs every ordered pair of at least three shapes"):
        batch(all_pairs(paths[:3])[:-1], tmp_path, hub=paths[0])
    with pytest.raises(ParameterError, match="needs every ordered pair of at least three shapes"):
        batch(all_pairs(paths[:2]), tmp_path, hub="auto")
    assert main(["batch", "--template", paths[0], *paths[1:3], "--hub", "auto", "--out", str(tmp_path)]) == 2
    assert "--hub needs --all-pairs" in capsys.readouterr().err
    with pytest.raises(ParameterError, match="does not go with partial"):
        batch(all_pairs(paths[:3]), tmp_path, hub="auto", partial="source")
    with pytest.raises(ParameterError, match="at least one shape"):
        spectral_medoid({})
    from meshcorr.collection.consistency import _positive

    for values in ([0.0], [0.0, -1.0], [0.0, np.nan]):
        with pytest.raises(ParameterError, match="Shape-DNA needs"):
            _positive(np.array(values))
    # Scale-free: a shape three times larger has the same Shape-DNA; the medoid of three spectra
    # on a line is the middle one.
    shape = ds.creature(resolution=1)
    small, large = (shape_dna(meshcorr.Mesh(scale * shape.vertices, shape.faces), 12) for scale in (1.0, 3.0))
    assert len(small) == 11
    np.testing.assert_allclose(large, small, rtol=1e-6)
    line = {"a": np.array([1.0, 2.0]), "b": np.array([2.0, 4.0]), "c": np.array([4.0, 8.0])}
    assert spectral_medoid(line) == "b" and spectral_medoid({"only": np.array([1.0])}) == "only"


def test_a_corrupt_mesh_fails_its_pairs_and_the_others_finish(cluster, shapes, tmp_path, capsys):
    paths, bad = shapes
    pairs = [(paths[0], paths[1]), (bad, paths[0]), (paths[1], paths[0]), (paths[2], bad)]
    records = batch(pairs, tmp_path, client=cluster)
    assert [r["status"] for r in records] == ["ok", "failed", "ok", "failed"]
    assert "bad.off" in records[1]["error"] and "truncated" in records[1]["error"]
    assert not (tmp_path / "maps" / map_name(bad, paths[0])).exists()
    # The CLI on the same cluster: exit code 4 when a pair failed, 0 once every pair is mapped.
    pairs_file = tmp_path / "pairs.txt"
    pairs_file.write_text(f"# source target\n{paths[0]} {paths[1]}\n\n{bad} {paths[0]}\n")
    address = cluster.scheduler.address
    assert main(["batch", "--pairs", str(pairs_file), "--out", str(tmp_path / "cli"), "--scheduler", address]) == 4
    err = capsys.readouterr().err
    assert "1 of 2 pairs mapped" in err and "1 failed" in err and "[batch]" in err
    pairs_file.write_text(f"{paths[0]} {paths[1]}\n")
    assert main(["batch", "--pairs", str(pairs_file), "--out", str(tmp_path / "cli"), "--scheduler", address,
                 "-q"]) == 0


def test_an_interrupted_batch_resumes(cluster, shapes, tmp_path):
    paths, _ = shapes
    pairs = template_pairs(paths[0], paths)

    def stop_after_two(done, total, failed, left):
        if done == 2:
            raise KeyboardInterrupt  # Ctrl-C, or a kill after the second pair

    with pytest.raises(KeyboardInterrupt):
        batch(pairs, tmp_path, client=cluster, progress=stop_after_two)
    first = json.loads((tmp_path / "summary.json").read_text())["pairs"]
    assert len(first) == 2 and all(r["status"] == "ok" for r in first)
    written = {r["map"]: Path(r["map"]).stat().st_mtime_ns for r in first}
    (tmp_path / "maps" / ".c0__c3.txt.0123.tmp").write_text("left by a killed worker")
    totals = []
    records = batch(pairs, tmp_path, client=cluster, progress=lambda d, t, f, s: totals.append(t))
    assert totals[0] == 1  # only the pair not done yet ran
    assert [r["status"] for r in records] == ["ok"] * 3, [r.get("error") for r in records]
    assert {m: Path(m).stat().st_mtime_ns for m in written} == written  # done maps untouched
    for record in records:
        np.testing.assert_array_equal(read_map(record["map"]),
                                      meshcorr.match(record["source"], record["target"]).map)
    with pytest.raises(ParameterError, match="holds results made with other settings"):
        batch(pairs, tmp_path, client=cluster, random_state=1)


def test_a_finished_batch_reruns_without_starting_a_cluster(cluster, shapes, tmp_path, monkeypatch):
    paths, _ = shapes
    pairs = template_pairs(paths[0], paths[:3])
    batch(pairs, tmp_path, client=cluster)

    def no_cluster(*args, **kwargs):
        raise AssertionError("a cluster was started for nothing to do")

    monkeypatch.setattr(distributed, "LocalCluster", no_cluster)
    totals = []
    records = batch(pairs, tmp_path, progress=lambda d, t, f, s: totals.append(t))
    assert totals == [0] and [r["status"] for r in records] == ["ok", "ok"]


def test_a_rerun_redoes_the_pairs_of_a_changed_mesh_and_keeps_the_others_records(cluster, shapes, tmp_path):
    import shutil

    paths, _ = shapes
    local = []
    for path in paths[:3]:  # copies: one of them is changed below
        local.append(str(tmp_path / Path(path).name))
        shutil.copy(path, local[-1])
    pairs = template_pairs(local[0], local)
    out = tmp_path / "out"
    batch(pairs, out, client=cluster)
    # A run of one pair into the same folder keeps the other pairs' records.
    batch(pairs[:1], out, client=cluster)
    assert len(json.loads((out / "summary.json").read_text())["pairs"]) == 2
    # The third shape's file now holds another pose: its pair is matched again, the other not.
    shutil.copy(paths[1], local[2])
    totals = []
    records = batch(pairs, out, client=cluster, progress=lambda d, t, f, s: totals.append(t))
    assert totals[0] == 1 and [r["status"] for r in records] == ["ok", "ok"]
    np.testing.assert_array_equal(read_map(records[1]["map"]), meshcorr.match(local[0], local[2]).map)
    # Scoring asked for on a finished folder scores (the pairs run again with the truth).
    records = batch(pairs, out, client=cluster, ground_truth="identity")
    assert all(r["mean_error"] is not None for r in records)


def test_batch_checks_its_input_before_any_work(shapes, tmp_path):
    paths, _ = shapes
    for options, message in [({"k": 1}, "'k' parameter must be an int >= 2"),
                             ({"symmetry": "x"}, "'symmetry' parameter must be one of"),
                             ({"method": "icp"}, "spectral method only"),
                             ({"colour": 1}, "Unknown option of meshcorr.batch"),
                             ({"landmarks": [(0, 0)]}, "User landmarks belong to one pair")]:
        with pytest.raises(ParameterError, match=message):
            batch(all_pairs(paths[:2]), tmp_path, **options)
    with pytest.raises(ParameterError, match="has no pairs"):
        batch([], tmp_path)
    with pytest.raises(ParameterError, match="give absolute paths"):  # a cluster's workers run elsewhere
        batch([("shapes/a.off", "/abs/b.off")], tmp_path, client=object())
    with pytest.raises(ParameterError, match=r"same map file c0__c1\.\w+ \(.*c0.off -> .*c1.off and .*c0.off -> "
                                             r".*x/c1.off\)"):
        batch([(paths[0], paths[1]), (paths[0], str(tmp_path / "x" / "c1.off"))], tmp_path)
    with pytest.raises(ParameterError, match="'identity' or a folder of SHAPE.vts"):
        batch(all_pairs(paths[:2]), tmp_path, ground_truth="truth.txt")
    (tmp_path / "truth").mkdir()
    (tmp_path / "truth" / "c0.vts").write_text("1\n")
    with pytest.raises(ParameterError, match="folder .*truth has no c1.vts: every shape needs"):
        batch(all_pairs(paths[:2]), tmp_path / "out", ground_truth=str(tmp_path / "truth"))
    assert not (tmp_path / "out").exists()
    with pytest.raises(ParameterError, match="at least 2 distinct mesh files"):
        all_pairs([paths[0], paths[0]])
    assert template_pairs(paths[0], paths[:3]) == [(paths[0], paths[1]), (paths[0], paths[2])]
    (tmp_path / "pairs.txt").write_text("a.off b.off c.off\n")
    with pytest.raises(ParameterError, match="line 1: expected two mesh paths"):
        read_pair_list(tmp_path / "pairs.txt")
    (tmp_path / "pairs.txt").write_text("# nothing\n")
    with pytest.raises(ParameterError, match="lists no pairs"):
        read_pair_list(tmp_path / "pairs.txt")
    with pytest.raises(ParameterError, match="does not exist"):
        read_pair_list(tmp_path / "none.txt")
    (tmp_path / "pairs.txt").write_text("a.off /abs/b.off\n")
    assert read_pair_list(tmp_path / "pairs.txt") == [(str(tmp_path / "a.off"), "/abs/b.off")]


def test_cli_usage_errors(shapes, tmp_path, capsys, monkeypatch):
    paths, _ = shapes
    monkeypatch.setattr("meshcorr.collection.cluster.CONNECT_TIMEOUT", 1)
    assert main(["batch", "--all-pairs", *paths[:2], "--out", str(tmp_path), "--set", "nokey"]) == 2
    assert "--set takes KEY=VALUE" in capsys.readouterr().err
    assert main(["batch", "--pairs", "p.txt", paths[0], "--out", str(tmp_path)]) == 2
    assert "SHAPES of --template" in capsys.readouterr().err
    assert main(["batch", "--template", paths[0], paths[1], "--consistency", "--out", str(tmp_path)]) == 2
    assert "--consistency needs --all-pairs" in capsys.readouterr().err
    assert main(["batch", "--all-pairs", *paths[:2], "--out", str(tmp_path), "--scheduler",
                 "tcp://127.0.0.1:9"]) == 2
    assert "No Dask scheduler answered at tcp://127.0.0.1:9" in capsys.readouterr().err
    # Refused before any work: --set for an option with a flag, too few shapes for cycles, no workers,
    # an output folder that cannot be made, a damaged run.json.
    assert main(["batch", "--all-pairs", *paths[:2], "--out", str(tmp_path), "--set", "k=8"]) == 2
    assert "--set k=8: k has its own option here, -k." in capsys.readouterr().err
    assert main(["batch", "--all-pairs", *paths[:2], "--consistency", "--out", str(tmp_path)]) == 2
    assert "--consistency needs at least three shapes" in capsys.readouterr().err
    assert main(["batch", "--all-pairs", *paths[:2], "--workers", "-3", "--out", str(tmp_path)]) == 2
    assert "whole number >= 1 (--workers N); got -3" in capsys.readouterr().err
    assert main(["batch", "--all-pairs", *paths[:2], "--workers", "2", "--scheduler", "tcp://127.0.0.1:9",
                 "--out", str(tmp_path)]) == 2
    assert "leave out one of them" in capsys.readouterr().err
    assert main(["batch", "--template", paths[0], "--cache", *paths[1:3], "--out", str(tmp_path)]) == 2
    assert f"--cache took {paths[1]} as its folder" in capsys.readouterr().err
    assert main(["batch", "--template", paths[0], "--out", str(tmp_path)]) == 2
    assert "No mesh files were given: list at least 1 (after --template T)" in capsys.readouterr().err
    (tmp_path / "a_file").write_text("x")
    assert main(["batch", "--all-pairs", *paths[:2], "--out", str(tmp_path / "a_file")]) == 2
    assert "Cannot create the output folder" in capsys.readouterr().err
    (tmp_path / "old").mkdir()
    (tmp_path / "old" / "run.json").write_text("{damaged")
    assert main(["batch", "--all-pairs", *paths[:2], "--out", str(tmp_path / "old")]) == 3
    assert "run.json is damaged (not JSON)" in capsys.readouterr().err
    assert not (tmp_path / "old" / "summary.json").exists()


def test_without_dask_the_batch_names_the_extra(shapes, tmp_path, monkeypatch, capsys):
    real_import = builtins.__import__

    def no_dask(name, *args, **kwargs):
        if name.split(".")[0] in ("distributed", "dask"):
            raise ImportError(f"No module named {name!r}")
        return real_import(name, *args, **kwargs)

    monkeypatch.setattr(builtins, "__import__", no_dask)
    paths, _ = shapes
    with pytest.raises(ParameterError, match=r'pip install "meshcorr\[dask\]"'):
        batch(all_pairs(paths[:2]), tmp_path)
    assert main(["batch", "--all-pairs", *paths[:2], "--out", str(tmp_path)]) == 2
    assert 'meshcorr[dask]' in capsys.readouterr().err


def test_meshcorr_threads_1_runs_the_thread_pools_in_the_calling_thread(monkeypatch):
    from meshcorr.runtime.threads import parallel_map

    monkeypatch.setenv("MESHCORR_THREADS", "1")  # what each worker process of the local cluster gets
    assert parallel_map(lambda _: threading.get_ident(), [0, 1, 2]) == [threading.get_ident()] * 3


def test_an_inverse_map_sends_each_vertex_to_the_source_of_its_nearest_image():
    points = np.array([[0.0, 0, 0], [1, 0, 0], [2, 0, 0], [np.nan, np.nan, np.nan], [3, 0, 0]])
    # Sources 0 and 1 hit vertex 0, source 2 hits vertex 2, source 3 is unmapped; vertex 3 is missing.
    inverse = invert(np.array([0, 0, 2, -1]), points)
    np.testing.assert_array_equal(inverse, [0, 0, 2, -1, 2])  # 1 -> nearest image (0, source 0); 4 -> 2
    np.testing.assert_array_equal(invert(np.array([-1, -1]), points), [-1] * 5)
    # A bijection inverts exactly.
    order = np.random.default_rng(0).permutation(5)
    line = np.arange(15.0).reshape(5, 3)
    np.testing.assert_array_equal(invert(order, line)[order], np.arange(5))


def test_composed_maps_keep_unmapped_vertices_unmapped(shapes):
    # -1 (a vertex dropped by largest_component, or outside a part) must not index B's last vertex.
    from meshcorr.collection.consistency import compose

    np.testing.assert_array_equal(compose(np.array([2, -1, 0]), np.array([5, -1, 7])), [7, -1, 5])
    np.testing.assert_array_equal(compose(np.array([-1, -1]), np.array([], dtype=int)), [-1, -1])
    paths, _ = shapes
    mesh = meshcorr.as_mesh(paths[0])
    meshes = {"a": mesh, "b": mesh, "c": mesh}
    half = np.where(np.arange(500) < 250, np.arange(500), -1)
    maps = {("a", "b"): half, ("b", "c"): np.arange(500), ("a", "c"): np.arange(500)}
    np.testing.assert_array_equal(through_hub(maps, "b")[("a", "c")], half)
    assert cycle_errors(maps, meshes, [("a", "b", "c")])[0] == 0.0  # the unmapped half does not count
    maps["a", "b"] = np.full(500, -1)
    assert np.isnan(cycle_errors(maps, meshes, [("a", "b", "c")])[0])


def test_consistency_error_paths(shapes, tmp_path):
    paths, _ = shapes
    mesh = meshcorr.as_mesh(paths[0])
    meshes = {"a": mesh, "b": mesh, "c": mesh}
    one_way = {("a", "b"): np.arange(500), ("b", "c"): np.arange(500), ("a", "c"): np.arange(500)}
    with pytest.raises(ParameterError, match="No shape has maps to and from every other shape"):
        choose_hub(one_way, meshes)
    with pytest.raises(ParameterError, match="'n_points' parameter must be an int >= 1"):
        cycle_errors(one_way, meshes, [("a", "b", "c")], n_points=0)
    from meshcorr.collection.consistency import consistency_report

    records = [{"source": paths[0], "target": paths[1], "status": "failed", "map": ""}]
    with pytest.raises(ParameterError, match="needs three shapes whose maps all succeeded"):
        consistency_report(tmp_path, paths[:3], records)
    # A shape whose pairs all failed (a damaged mesh) is left out of the report, not read again.
    broken = tmp_path / "broken.off"
    broken.write_text("OFF\n3 1 0\n0 0")
    records = []
    for a in paths[:3] + [str(broken)]:
        for b in paths[:3] + [str(broken)]:
            if a != b:
                ok = str(broken) not in (a, b)
                name = tmp_path / f"{Path(a).stem}__{Path(b).stem}.txt"
                if ok:
                    np.savetxt(name, np.arange(500), fmt="%d")
                records.append({"source": a, "target": b, "status": "ok" if ok else "failed", "map": str(name)})
    report = consistency_report(tmp_path, paths[:3] + [str(broken)], records)
    assert report["n_triples"] > 0 and "broken" not in {s for t in report["triples"] for s in t}


def test_a_damaged_summary_and_a_partial_target_are_reported(shapes, tmp_path):
    from meshcorr.collection.tasks import mean_error
    from meshcorr.pipeline.prepare import prepare

    paths, _ = shapes
    (tmp_path / "summary.json").write_text("{")
    with pytest.raises(ParameterError, match="is not a batch summary"):
        batch(all_pairs(paths[:2]), tmp_path)
    shape = ds.creature(resolution=1)
    two = (np.concatenate([shape.vertices, shape.vertices + 10]),
           np.concatenate([shape.faces, shape.faces + shape.n_vertices]))
    partial = prepare(two, largest_component=True)
    with pytest.raises(ParameterError, match="needs the whole target mesh"):
        mean_error(partial, partial, np.arange(partial.n_vertices), "a.off", "b.off", "identity", "heat")


def test_cli_batch_cache_and_ctrl_c(cluster, shapes, tmp_path, monkeypatch, capsys):
    paths, _ = shapes
    address = cluster.scheduler.address
    cache = tmp_path / "cache"
    assert main(["batch", "--template", paths[0], paths[1], "--out", str(tmp_path / "o"), "--scheduler", address,
                 "--cache", str(cache), "-q"]) == 0
    assert len(list(cache.glob("*.npz"))) == 2  # both shapes prepared into the cache by the workers

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr("meshcorr.collection.batch.batch", interrupted)
    assert main(["batch", "--template", paths[0], paths[1], "--out", str(tmp_path / "o2"), "-q"]) == 130
    assert "interrupted" in capsys.readouterr().err


def test_ctrl_c_in_a_terminal_stops_the_local_cluster_without_worker_tracebacks(shapes, tmp_path):
    # A terminal sends SIGINT to the whole process group: the worker processes too.
    import os
    import signal
    import subprocess
    import sys

    paths, _ = shapes
    # preexec_fn: the default SIGINT, even where pytest was started with it ignored (a background job).
    run = subprocess.Popen([sys.executable, "-m", "meshcorr", "batch", "--all-pairs", *paths,
                            "--out", str(tmp_path / "out"), "--workers", "2"],
                           stderr=subprocess.PIPE, text=True, start_new_session=True,
                           preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    for line in run.stderr:  # the first progress line: the cluster runs and the pairs are submitted
        if line.startswith("[batch]"):
            break
    os.killpg(run.pid, signal.SIGINT)
    rest = run.stderr.read()
    assert run.wait(timeout=60) == 130
    assert "Traceback" not in rest and rest.strip().splitlines()[-1] == "meshcorr: interrupted", rest


def test_cli_consistency_report_names_what_it_compares(cluster, shapes, tmp_path, capsys):
    paths, _ = shapes
    assert main(["batch", "--all-pairs", *paths[:3], "--consistency", "--out", str(tmp_path / "o"),
                 "--scheduler", cluster.scheduler.address, "-q"]) == 0
    err = capsys.readouterr().err
    assert "cycle-consistency error" in err and "(the batch's maps)" in err and "all composed through" in err
    assert (tmp_path / "o" / "consistency.json").is_file()


class _CrashingClient:
    """A stand-in client whose pair tasks fail in the scheduler (as when a pair kills its worker)."""

    class Future:
        def __init__(self, key):
            self.key = key

        def result(self):
            raise RuntimeError(f"KilledWorker: attempted to run task {self.key} on 3 different workers")

        def release(self):
            pass

    def submit(self, function, *args, key):
        return self.Future(key)


def test_a_pair_that_crashes_its_worker_is_recorded(shapes, tmp_path, monkeypatch):
    paths, _ = shapes
    monkeypatch.setattr(distributed, "as_completed", lambda futures: iter(futures))
    records = batch(all_pairs(paths[:2]), tmp_path, client=_CrashingClient())
    assert [r["status"] for r in records] == ["failed", "failed"]
    assert "KilledWorker" in records[0]["error"] and records[0]["map"].endswith("c0__c1.txt")
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["n_failed"] == 2


def test_a_rerun_redoes_a_mesh_changed_in_place_and_a_damaged_map(cluster, shapes, tmp_path):
    # Issue 31, item 3: the pairs are known by their files' content, and a map file must be whole.
    import os
    import shutil

    paths, _ = shapes
    local = []
    for path in paths[:3]:
        local.append(str(tmp_path / Path(path).name))
        shutil.copy(path, local[-1])
    pairs = template_pairs(local[0], local)
    out = tmp_path / "out"
    first = batch(pairs, out, client=cluster)
    assert all(r["map_length"] == 500 for r in json.loads((out / "summary.json").read_text())["pairs"])
    # Another digit in a vertex of the third shape: the same size, and its modification time put back.
    changed = Path(local[2])
    before, text = changed.stat(), changed.read_text()
    line = text.splitlines()[2]
    digit = next(i for i, c in enumerate(line) if c in "12345678")
    edited = line[:digit] + str(int(line[digit]) + 1) + line[digit + 1:]
    changed.write_text(text.replace(line, edited, 1))
    os.utime(changed, ns=(before.st_atime_ns, before.st_mtime_ns))
    assert changed.stat().st_size == before.st_size and changed.stat().st_mtime_ns == before.st_mtime_ns
    totals = []
    records = batch(pairs, out, client=cluster, progress=lambda d, t, f, s: totals.append(t))
    assert totals[0] == 1 and [r["status"] for r in records] == ["ok", "ok"]
    np.testing.assert_array_equal(read_map(records[1]["map"]), meshcorr.match(local[0], local[2]).map)
    # A map file cut short (a full disk, a killed copy), here within a line, or emptied: matched again.
    whole = Path(first[0]["map"]).read_text()
    for damaged in (whole[:len(whole) // 2 + 1], ""):
        Path(first[0]["map"]).write_text(damaged)
        totals.clear()
        records = batch(pairs, out, client=cluster, progress=lambda d, t, f, s: totals.append(t))
        assert totals[0] == 1 and records[0]["status"] == "ok"
        assert Path(first[0]["map"]).read_text() == whole


def test_a_second_batch_into_a_folder_in_use_is_refused(shapes, tmp_path, capsys):
    # Issue 31, item 4: both ran, and the summary kept the records of the last one to write it.
    from meshcorr.collection.folder import output_lock
    from meshcorr.errors import OutputError

    paths, _ = shapes
    (tmp_path / "maps").mkdir()
    with output_lock(tmp_path):  # another batch runs into the folder
        with pytest.raises(OutputError, match="Another meshcorr batch is writing into"):
            batch(all_pairs(paths[:2]), tmp_path)
        assert main(["batch", "--all-pairs", *paths[:2], "--out", str(tmp_path)]) == 2
        assert "Another meshcorr batch is writing into" in capsys.readouterr().err
    assert not (tmp_path / "summary.json").exists() and not (tmp_path / "run.json").exists()
    with output_lock(tmp_path):  # released by the refused runs, and by the one that held it
        pass


def test_an_interrupted_batch_leaves_no_map_its_summary_does_not_list(cluster, shapes, tmp_path):
    # Issue 31, item 5: the pairs still running on the cluster's workers when the batch is interrupted
    # finished there later and wrote maps that the summary, already written, did not list.
    import time

    paths, _ = shapes
    pairs = template_pairs(paths[0], paths)

    def stop_after_one(done, total, failed, left):
        if done == 1:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        batch(pairs, tmp_path, client=cluster, progress=stop_after_one)
    deadline = time.monotonic() + 60  # until the workers are idle: what was running has finished
    while sum(cluster.run(lambda dask_worker: dask_worker.state.executing_count).values()) and \
            time.monotonic() < deadline:
        time.sleep(0.2)
    time.sleep(0.5)
    recorded = {Path(r["map"]).name for r in json.loads((tmp_path / "summary.json").read_text())["pairs"]
                if r["status"] == "ok"}
    assert len(recorded) == 1
    assert sorted(p.name for p in (tmp_path / "maps").iterdir()) == sorted(recorded)


def test_a_cache_folder_that_cannot_be_written_warns_once_and_the_pairs_are_mapped(cluster, shapes, tmp_path):
    # Issue 31, item 12: every pair failed (its shapes could not be stored).
    from meshcorr.shapes.cache import CacheWarning

    paths, _ = shapes
    (tmp_path / "file").write_text("x")
    with pytest.warns(CacheWarning, match="batch runs without the cache") as caught:
        records = batch(template_pairs(paths[0], paths[:3]), tmp_path / "out", client=cluster,
                        cache=tmp_path / "file" / "cache")
    assert len([w for w in caught if issubclass(w.category, CacheWarning)]) == 1
    assert [r["status"] for r in records] == ["ok", "ok"]
