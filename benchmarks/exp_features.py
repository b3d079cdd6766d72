"""Feature-point experiment (Jain & Zhang 2006, its Figure 5 measure).

Percentage of sparse ground-truth feature points matched correctly, per
method: a point counts when its predicted vertex lies within a geodesic
tolerance (0.05 or 0.1 x sqrt(target area)) of the true one. Data: the
Sumner cat/lion meshes in ``../shared/data/sumner/``:

- lion-reference -> cat-reference, truth = the 55 hand-placed cat<->lion
  markers (a non-isometric pair, as the paper's cow-lion / lion-horse);
- lion-reference -> lion-01 / lion-05 and cat-reference -> cat-01: the same
  markers on one animal in another pose (truth = identity at the markers).

Usage::

    nice -n 10 python benchmarks/exp_features.py [--methods spectral,icp,...]
        [--pairs lion-cat,lion-01,lion-05,cat-01] [--out benchmarks/exp_features]

Writes ``OUT.md`` (table + command) and ``OUT.png`` (cumulative curves over
the feature points of all pairs). Skips with a message when the data is
absent.
"""

from __future__ import annotations

import argparse
import os
import platform
import re
import sys
import time
from pathlib import Path

import numpy as np

import meshcorr
from meshcorr.evaluation.benchmark import check_methods, run_method
from meshcorr.evaluation.metrics import GeodesicCache, cumulative_curve, evaluate_map
from meshcorr.evaluation.ground_truth import GroundTruth
from meshcorr.io import atomic_write
from meshcorr.core.mesh import Mesh, as_mesh
from meshcorr.viz.plots import plot_cumulative_curves

HERE = Path(__file__).resolve().parent
DEFAULT_DATA = HERE.parents[1] / "shared" / "data" / "sumner"
TOLERANCES = (0.05, 0.1)


def read_markers(path: Path) -> np.ndarray:
    """(m, 2) int: 0-based (cat vertex, lion vertex) pairs of ``markers-cat-lion.yml``."""
    pairs = re.findall(r'^\s*-\s*"(\d+):(\d+)"', path.read_text(), flags=re.MULTILINE)
    return np.array(pairs, dtype=np.int64)


def pair_specs(data: Path, markers: np.ndarray) -> dict:
    """name -> (source path, target path, GroundTruth at the markers)."""
    cat, lion = markers[:, 0], markers[:, 1]
    specs = {"lion-cat": (data / "lion-poses/lion-reference.obj", data / "cat-poses/cat-reference.obj",
                          GroundTruth(lion, cat, "cat-lion markers"))}
    for pose in ("01", "05"):
        specs[f"lion-{pose}"] = (data / "lion-poses/lion-reference.obj", data / f"lion-poses/lion-{pose}.obj",
                                 GroundTruth(lion, lion, "lion markers, identity"))
    specs["cat-01"] = (data / "cat-poses/cat-reference.obj", data / "cat-poses/cat-01.obj",
                       GroundTruth(cat, cat, "cat markers, identity"))
    return specs


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--data", type=Path, default=DEFAULT_DATA)
    parser.add_argument("--methods", default="spectral")
    parser.add_argument("--pairs", default="lion-cat,lion-01,lion-05,cat-01")
    parser.add_argument("--out", type=Path, default=HERE / "exp_features")
    args = parser.parse_args()
    marker_file = args.data / "markers-cat-lion.yml"
    if not marker_file.is_file():
        print(f"{marker_file} not found (the shared data is absent); nothing to do.", file=sys.stderr)
        return 0
    methods = check_methods(args.methods.split(","))
    specs = pair_specs(args.data, read_markers(marker_file))
    names = args.pairs.split(",")
    unknown = [n for n in names if n not in specs]
    if unknown:
        parser.error(f"unknown pairs {unknown}; choose from {', '.join(specs)}")

    cache = GeodesicCache("heat", max_meshes=1)
    rows, errors = [], {m: [] for m in methods}
    for name in names:
        source_path, target_path, truth = specs[name]
        source = as_mesh(source_path, name=source_path.stem)
        target = as_mesh(target_path, name=target_path.stem)
        for method in methods:
            start = time.perf_counter()
            try:
                # fresh copies: no method reuses geodesics another one cached on the meshes
                result = run_method(method, Mesh(source.vertices, source.faces, name=source.name),
                                    Mesh(target.vertices, target.faces, name=target.name), random_state=0)
            except Exception as exc:  # noqa: BLE001 - record the failure, go on
                rows.append({"pair": name, "method": method, "failed": f"{type(exc).__name__}: {exc}"[:120]})
                print(f"{name} {method}: FAILED {exc}", file=sys.stderr)
                continue
            seconds = time.perf_counter() - start
            report = evaluate_map(target, result.map, truth, thresholds=TOLERANCES, cache=cache)
            errors[method].append(report["errors"])
            rows.append({"pair": name, "method": method, "n": len(truth), "seconds": seconds,
                         "mean": report["mean_error"],
                         **{f"{t:g}": report["under"][f"{t:g}"] for t in TOLERANCES}})
            print(f"{name} {method}: {100 * report['under']['0.05']:.0f} % within 0.05, "
                  f"{seconds:.1f} s", file=sys.stderr)

    curves = {m: cumulative_curve(np.concatenate(e)) for m, e in errors.items() if e}
    if curves:
        plot_cumulative_curves(args.out.with_suffix(".png"), curves,
                               title=f"Feature points within each tolerance ({', '.join(names)})")
    command = "nice -n 10 python benchmarks/exp_features.py " + " ".join(sys.argv[1:])
    lines = [
        "## Feature points matched correctly (Sumner cat / lion)",
        "",
        f"Command: `{command.strip()}`  ",
        f"Measured {time.strftime('%Y-%m-%d')} on {platform.machine()}, {os.cpu_count()} cores, "
        f"meshcorr {meshcorr.__version__}, default options, heat geodesics. A feature point is correct "
        "when its predicted vertex is within the tolerance (geodesic distance / sqrt(target area)) of "
        "the true one. lion-cat: 55 hand-placed markers; lion-XX / cat-XX: the same markers, reference "
        "pose -> pose XX (truth = identity).",
        "",
        "| pair | method | points | % within 0.05 | % within 0.1 | mean error | seconds |",
        "|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        if "failed" in r:
            lines.append(f"| {r['pair']} | {r['method']} | - | failed: {r['failed']} | | | |")
        else:
            lines.append(f"| {r['pair']} | {r['method']} | {r['n']} | {100 * r['0.05']:.1f} | "
                         f"{100 * r['0.1']:.1f} | {r['mean']:.4f} | {r['seconds']:.1f} |")
    lines += ["", "Mean over pairs:", "", "| method | % within 0.05 | % within 0.1 |", "|---|---|---|"]
    for method in methods:
        ok = [r for r in rows if r["method"] == method and "failed" not in r]
        if ok:
            lines.append(f"| {method} | {100 * np.mean([r['0.05'] for r in ok]):.1f} | "
                         f"{100 * np.mean([r['0.1'] for r in ok]):.1f} |")
    lines += ["", f"Figure: `{args.out.with_suffix('.png').name}`.", ""]
    text = "\n".join(lines)
    atomic_write(args.out.with_suffix(".md"), lambda f: f.write(text.encode()))
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
