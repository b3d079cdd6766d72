"""Time per map over a shape collection (issue 13): fresh processes vs ``meshcorr batch`` vs pyFM.

On one TOSCA-5k class (default: the first ``--shapes`` michael shapes), all
ordered pairs:

(a) ``meshcorr match`` in a fresh process per pair (what a shell loop
    does), on a seeded sample of ``--fresh-pairs`` pairs: seconds per map;
    their maps are compared with (b)'s vertex for vertex;
(b) ``meshcorr batch --all-pairs`` on the local Dask cluster, end to end
    (cluster start, preparation, every pair, summary), with 2 and then 1
    worker processes: wall seconds and seconds per map;
(c) pyFM's automatic pipeline (``benchmarks/tosca_symmetry.py::pyfm_map``) on
    ``--pyfm-pairs`` sampled pairs, in this process: seconds per map;
(d) ``meshcorr batch --all-pairs --hub auto`` on 2 workers: the n-1 maps onto
    the spectral medoid matched, the others made from them (inverted, then
    composed; :mod:`meshcorr.collection.consistency`): wall seconds per map and the
    maps' error;
(e) ``meshcorr batch --all-pairs --no-shells`` on 2 workers: every pair
    matched without the smooth-shell stage (the option that trades accuracy
    for time): wall seconds per map and the maps' error.

Also: seconds to prepare one shape and to match one prepared pair, with and
without the smooth shells (medians, in this process), the mean geodesic error against TOSCA's ground truth of
(b)'s maps, of the maps composed through the hub (:mod:`meshcorr.collection.consistency`)
and of pyFM's (on ``--gt-points`` sampled truth points per pair), and the
cycle-consistency error of both sets of maps.

Usage::

    nice -n 10 python benchmarks/shape_collections.py [--class michael] [--shapes 10] [--out /tmp/coll]

Needs the TOSCA data beside the repository (``../shared/data/tosca5k``) and
exits with a message when it is absent; pyFM (``pip install pyfmaps``) is
optional (``--pyfm-pairs 0``). Not named ``collections.py``: a script of that
name would shadow the standard library's ``collections`` module.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import re
import shutil
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

DEFAULT_DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "tosca5k"


def _shapes(data: Path, name: str, n: int) -> list[Path]:
    found = [p for p in data.glob(f"{name}*.off") if re.fullmatch(rf"{name}\d+", p.stem)]
    return sorted(found, key=lambda p: int(p.stem[len(name):]))[:n]


def _sample(pairs: list, n: int, seed: int) -> list:
    rng = np.random.default_rng(seed)
    return [pairs[i] for i in np.sort(rng.choice(len(pairs), size=min(n, len(pairs)), replace=False))]


def _batch_cli(shapes: list[Path], out: Path, workers: int, *extra: str) -> float:
    shutil.rmtree(out, ignore_errors=True)
    start = time.perf_counter()
    subprocess.run([sys.executable, "-m", "meshcorr", "batch", "--all-pairs", *map(str, shapes), "--out", str(out),
                    "--workers", str(workers), "-q", *extra], check=True)
    return time.perf_counter() - start


def _truth_errors(maps: dict, shapes: dict, data: Path, n_points: int, seed: int) -> dict:
    """Mean geodesic error / sqrt(target area) of each map on a seeded sample of truth points."""
    from meshcorr.evaluation.metrics import GeodesicCache
    from meshcorr.evaluation.ground_truth import read_vts

    vts = {name: read_vts(data / "corres" / f"{name}.vts") - 1 for name in shapes}
    n_truth = min(len(v) for v in vts.values())
    points = np.sort(np.random.default_rng(seed).choice(n_truth, size=min(n_points, n_truth), replace=False))
    cache = GeodesicCache("heat", max_meshes=len(shapes))
    for name, mesh in shapes.items():  # rows from the true target points, shared by every map onto the shape
        cache.precompute(mesh, vts[name][points])
    errors = {}
    for (a, b), mapping in maps.items():
        predicted, truth = mapping[vts[a][points]], vts[b][points]
        errors[a, b] = float(cache.pair_distances(shapes[b], predicted, truth).mean() / np.sqrt(shapes[b].area))
    return errors


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--data", type=Path, default=DEFAULT_DATA)
    parser.add_argument("--class", dest="name", default="michael")
    parser.add_argument("--shapes", type=int, default=10)
    parser.add_argument("--fresh-pairs", type=int, default=16)
    parser.add_argument("--pyfm-pairs", type=int, default=6)
    parser.add_argument("--gt-points", type=int, default=500)
    parser.add_argument("--rounds", type=int, default=5, help="repeats of the prepare / prepared-pair timings")
    parser.add_argument("--out", type=Path, default=Path("/tmp/meshcorr-collections"))
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    if not args.data.is_dir():
        print(f"TOSCA-5k not found at {args.data}: nothing to measure.", file=sys.stderr)
        return 0

    import meshcorr
    from meshcorr.collection.pairs import all_pairs, map_name
    from meshcorr.collection.consistency import choose_hub, cycle_errors, sample_triples, through_hub
    from meshcorr.io import read_map

    paths = _shapes(args.data, args.name, args.shapes)
    names = [p.stem for p in paths]
    pairs = all_pairs([str(p) for p in paths])
    args.out.mkdir(parents=True, exist_ok=True)
    report: dict = {"machine": f"{platform.machine()}, {os.cpu_count()} cores, Python {platform.python_version()}",
                    "date": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()), "shapes": names,
                    "n_maps": len(pairs), "load_average_start": os.getloadavg()[0]}

    # (b) meshcorr batch on the local cluster, 2 then 1 worker processes.
    for workers in (2, 1):
        wall = _batch_cli(paths, args.out / f"batch{workers}", workers)
        summary = json.loads((args.out / f"batch{workers}" / "summary.json").read_text())
        cpu = [r["cpu_seconds"] for r in summary["pairs"] if r["cpu_seconds"] is not None]
        report[f"batch_{workers}_workers"] = {"wall_s": wall, "per_map_s": wall / len(pairs),
                                              "mean_pair_s": summary["mean_seconds"],
                                              "mean_pair_cpu_s": float(np.mean(cpu)),
                                              "failed": summary["n_failed"], "load_average": os.getloadavg()[0]}
        print(f"batch, {workers} workers: {wall:.1f} s, {wall / len(pairs):.3f} s per map", file=sys.stderr)
    # (d) the same collection through the automatic hub.
    wall = _batch_cli(paths, args.out / "hub", 2, "--hub", "auto")
    summary = json.loads((args.out / "hub" / "summary.json").read_text())
    hub_auto = {Path(r["via"]).stem for r in summary["pairs"] if r.get("via")}
    report["batch_hub_auto_2_workers"] = {"wall_s": wall, "per_map_s": wall / len(pairs), "hub": sorted(hub_auto),
                                          "failed": summary["n_failed"]}
    print(f"batch through the hub {sorted(hub_auto)}, 2 workers: {wall:.1f} s, {wall / len(pairs):.3f} s per map",
          file=sys.stderr)
    # (e) every pair matched without the smooth shells (the option that trades accuracy for time).
    wall = _batch_cli(paths, args.out / "noshells", 2, "--no-shells")
    report["batch_no_shells_2_workers"] = {"wall_s": wall, "per_map_s": wall / len(pairs)}
    print(f"batch --no-shells, 2 workers: {wall:.1f} s, {wall / len(pairs):.3f} s per map", file=sys.stderr)
    batch_dir = args.out / "batch2" / "maps"
    same_12 = all(np.array_equal(read_map(batch_dir / map_name(a, b)),
                                 read_map(args.out / "batch1" / "maps" / map_name(a, b))) for a, b in pairs)
    report["same_maps_1_vs_2_workers"] = same_12

    # (a) fresh meshcorr match processes on a sample of pairs.
    fresh_pairs = _sample(pairs, args.fresh_pairs, args.seed)
    seconds, same = [], []
    for a, b in fresh_pairs:
        out = args.out / "fresh.txt"
        start = time.perf_counter()
        subprocess.run([sys.executable, "-m", "meshcorr", "match", a, b, "-o", str(out), "-q"], check=True)
        seconds.append(time.perf_counter() - start)
        same.append(bool(np.array_equal(read_map(out), read_map(batch_dir / map_name(a, b)))))
    report["fresh_process"] = {"n_pairs": len(fresh_pairs), "per_map_s": float(np.mean(seconds)),
                               "median_s": float(np.median(seconds)), "same_maps_as_batch": f"{sum(same)}/{len(same)}"}
    print(f"fresh processes: {np.mean(seconds):.2f} s per map, same maps {sum(same)}/{len(same)}", file=sys.stderr)

    # Prepare one shape vs match one prepared pair (in this process).
    prep, pair_s, pair_plain_s = [], [], []
    for r in range(args.rounds):
        a, b = paths[r % len(paths)], paths[(r + 1) % len(paths)]
        start = time.perf_counter()
        shape_a = meshcorr.prepare(a)
        prep.append(time.perf_counter() - start)
        shape_b = meshcorr.prepare(b)
        start = time.perf_counter()
        meshcorr.match(shape_a, shape_b)
        pair_s.append(time.perf_counter() - start)
        start = time.perf_counter()
        meshcorr.match(shape_a, shape_b, shells=False)
        pair_plain_s.append(time.perf_counter() - start)
    report["prepare_one_shape_s"] = float(np.median(prep))
    report["match_prepared_pair_s"] = float(np.median(pair_s))
    report["match_prepared_pair_no_shells_s"] = float(np.median(pair_plain_s))
    print(f"prepare {np.median(prep):.3f} s, prepared pair {np.median(pair_s):.3f} s "
          f"({np.median(pair_plain_s):.3f} s without the shells)", file=sys.stderr)

    # (c) pyFM on a sample of pairs.
    pyfm_maps = {}
    if args.pyfm_pairs:
        sys.path.insert(0, str(Path(__file__).resolve().parent))
        from tosca_symmetry import pyfm_map

        pyfm_s = []
        for a, b in _sample(pairs, args.pyfm_pairs, args.seed + 1):
            source, target = meshcorr.as_mesh(a), meshcorr.as_mesh(b)
            start = time.perf_counter()
            pyfm_maps[Path(a).stem, Path(b).stem] = pyfm_map(source, target)
            pyfm_s.append(time.perf_counter() - start)
        report["pyfm"] = {"n_pairs": len(pyfm_s), "per_map_s": float(np.mean(pyfm_s))}
        print(f"pyFM: {np.mean(pyfm_s):.2f} s per map", file=sys.stderr)

    # Accuracy and consistency.
    meshes = {p.stem: meshcorr.as_mesh(p) for p in paths}
    maps = {(Path(a).stem, Path(b).stem): read_map(batch_dir / map_name(a, b)) for a, b in pairs}
    hub = choose_hub(maps, meshes)
    consistent = through_hub(maps, hub)
    errors = _truth_errors(maps, meshes, args.data, args.gt_points, args.seed)
    hub_errors = _truth_errors(consistent, meshes, args.data, args.gt_points, args.seed)
    off_hub = [key for key in maps if hub not in key]
    report["hub"] = hub
    report["mean_error_direct"] = float(np.mean([errors[k] for k in off_hub]))
    report["mean_error_hub"] = float(np.mean([hub_errors[k] for k in off_hub]))
    report["mean_error_all_direct"] = float(np.mean(list(errors.values())))
    report["pairs_hub_better"] = int(sum(hub_errors[k] < errors[k] for k in off_hub))
    report["pairs_off_hub"] = len(off_hub)
    if pyfm_maps:
        pyfm_errors = _truth_errors(pyfm_maps, meshes, args.data, args.gt_points, args.seed)
        report["pyfm"]["mean_error"] = float(np.mean(list(pyfm_errors.values())))
        report["pyfm"]["meshcorr_mean_error_same_pairs"] = float(np.mean([errors[k] for k in pyfm_maps]))
    triples = sample_triples(names, maps, 40, args.seed)
    hub_maps = {(Path(a).stem, Path(b).stem): read_map(args.out / "hub" / "maps" / map_name(a, b)) for a, b in pairs}
    report["batch_hub_auto_2_workers"]["mean_error"] = float(np.mean(list(
        _truth_errors(hub_maps, meshes, args.data, args.gt_points, args.seed).values())))
    report["cycle_error_hub_auto"] = float(cycle_errors(hub_maps, meshes, triples).mean())
    plain_maps = {(Path(a).stem, Path(b).stem): read_map(args.out / "noshells" / "maps" / map_name(a, b))
                  for a, b in pairs}
    report["batch_no_shells_2_workers"]["mean_error"] = float(np.mean(list(
        _truth_errors(plain_maps, meshes, args.data, args.gt_points, args.seed).values())))
    report["cycle_error_direct"] = float(cycle_errors(maps, meshes, triples).mean())
    report["cycle_error_hub"] = float(cycle_errors(consistent, meshes, triples).mean())
    report["n_triples"] = len(triples)
    report["load_average_end"] = os.getloadavg()[0]
    (args.out / "report.json").write_text(json.dumps(report, indent=1))
    print(json.dumps(report, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
