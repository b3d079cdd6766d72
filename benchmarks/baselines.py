"""The paper's baselines against the spectral method on TOSCA-5k pairs (issue 3).

For each pair, runs every method of :data:`meshcorr.baselines.METHODS` with
default options and reports the mean geodesic error (distance on the target
between predicted and true vertex, divided by sqrt(target area); ground truth
``vtsA[k]-1 <-> vtsB[k]-1``), the mean error against the mirrored truth
(``.sym.vts``: a low value there means a left/right flip) and the seconds.

The spatial methods (tps-rpm, icp, shape-context) run twice:
``auto``: the library's automatic pre-alignment (``prealign=True``: centre,
unit RMS radius, principal axes, axis signs by Chamfer distance);
``oracle``: the source first moved by the least-squares similarity onto the
target fitted on the ground-truth pairs (Umeyama), then ``prealign=False``,
a stand-in for the paper's hand alignment (it uses the answer, so it is an
upper bound on what alignment by hand could give).

Usage::

    nice -n 10 python benchmarks/baselines.py [--data ../shared/data/tosca5k] \
        [--pairs cat0-cat1,david0-david1,horse0-horse10] [--methods icp,shape-context]

Needs the TOSCA data beside the repository (``../shared/data``); exits with a
message when it is absent. Prints a Markdown table on stdout, progress on stderr.
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
import time
from pathlib import Path

import numpy as np

import meshcorr
from meshcorr.baselines import METHODS, SPATIAL_METHODS, run_method
from meshcorr.baselines.rigid_icp import umeyama
from meshcorr.evaluation.metrics import GeodesicCache, geodesic_errors
from meshcorr.core.mesh import as_mesh

DEFAULT_DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "tosca5k"
DEFAULT_PAIRS = "cat0-cat1,david0-david1,horse0-horse10"


def load_vts(path: Path) -> np.ndarray:
    return np.loadtxt(path, dtype=np.int64) - 1


def runs(methods: list[str]):
    """(method, alignment) pairs: spatial methods with both alignments."""
    for name in methods:
        if name in SPATIAL_METHODS:
            yield name, "auto"
            yield name, "oracle"
        else:
            yield name, "-"


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--data", type=Path, default=DEFAULT_DATA)
    parser.add_argument("--pairs", default=DEFAULT_PAIRS, help=f"comma-separated A-B (default: {DEFAULT_PAIRS})")
    parser.add_argument("--methods", default=",".join(METHODS), help="comma-separated (default: all)")
    args = parser.parse_args()
    if not (args.data / "corres").is_dir():
        print(f"TOSCA data not found at {args.data}; nothing to do.", file=sys.stderr)
        return 0
    methods = args.methods.split(",")
    pairs = [pair.split("-") for pair in args.pairs.split(",")]
    missing = [f"{name}{ext}" for pair in pairs for name in pair for ext in (".off", ".vts")
               if not (args.data / ("corres" if ext == ".vts" else "") / f"{name}{ext}").exists()]
    if missing:
        print(f"Not in {args.data}: {', '.join(missing)}.", file=sys.stderr)
        return 1
    rows = []
    for a, b in pairs:
        pair = f"{a}-{b}"
        va, vb = load_vts(args.data / "corres" / f"{a}.vts"), load_vts(args.data / "corres" / f"{b}.vts")
        vb_sym = load_vts(args.data / "corres" / f"{b}.sym.vts")
        target_for_errors = as_mesh(args.data / f"{b}.off", name=b)
        cache = GeodesicCache("heat")
        cache.precompute(target_for_errors, np.union1d(vb, vb_sym))
        source_raw = as_mesh(args.data / f"{a}.off", name=a)
        oracle = umeyama(source_raw.vertices[va], target_for_errors.vertices[vb])
        for name, alignment in runs(methods):
            # fresh meshes each run: no geodesics cached from an earlier method
            source = as_mesh(args.data / f"{a}.off", name=a)
            target = as_mesh(args.data / f"{b}.off", name=b)
            options = {}
            if alignment == "oracle":
                source = (oracle.apply(source.vertices), source.faces)
                options["prealign"] = False
            start = time.perf_counter()
            result = run_method(name, source, target, **options)
            seconds = time.perf_counter() - start
            predicted = result.map[va]
            err = geodesic_errors(target_for_errors, predicted, vb, cache=cache).mean()
            err_sym = geodesic_errors(target_for_errors, predicted, vb_sym, cache=cache).mean()
            rows.append((pair, name, alignment, err, err_sym, seconds))
            print(f"{pair} {name} ({alignment}): error {err:.4f}, vs mirrored truth {err_sym:.4f}, "
                  f"{seconds:.1f} s", file=sys.stderr, flush=True)

    print(f"Measured {time.strftime('%Y-%m-%d')} on {platform.machine()}, {os.cpu_count()} cores, "
          f"meshcorr {meshcorr.__version__}, default options of every method.\n")
    print("| pair | method | alignment | mean error | vs mirrored truth | seconds |")
    print("|---|---|---|---|---|---|")
    for pair, name, alignment, err, err_sym, seconds in rows:
        print(f"| {pair} | {name} | {alignment} | {err:.4f} | {err_sym:.4f} | {seconds:.1f} |")
    print("\nMean over the pairs:\n")
    print("| method | alignment | mean error | min(error, mirrored) | seconds | seconds / spectral |")
    print("|---|---|---|---|---|---|")
    spectral = [r[5] for r in rows if r[1] == "spectral"]
    for name, alignment in runs(methods):
        sel = [r for r in rows if r[1] == name and r[2] == alignment]
        seconds = np.mean([r[5] for r in sel])
        ratio = f"{seconds / np.mean(spectral):.2f}" if spectral else "-"
        print(f"| {name} | {alignment} | {np.mean([r[3] for r in sel]):.4f} | "
              f"{np.mean([min(r[3], r[4]) for r in sel]):.4f} | {seconds:.1f} | {ratio} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
