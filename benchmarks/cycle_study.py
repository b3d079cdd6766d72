"""Does the map the other way round tell a wrong global choice? (issue 34, the confidence of the choice)

For each pair of ``benchmarks/robustness.py``'s sets: ``meshcorr.match(A, B)`` and
``meshcorr.match(B, A)`` with default settings, the first map's error against the truth
(as ``robustness.py`` scores it), and the **cycle error**: over 200 seeded vertices i of A,
the mean geodesic distance on A between i and T_BA(T_AB(i)), over sqrt(area(A)). Where the
two choices turned the shapes differently (one front to back, the other not), the cycle
sends a vertex to the other side of A; where both are right, or both turned alike, it stays
near. Rows go to a CSV (resumable); ``confidence_threshold.py``-style halves are in the
report. Usage::

    python benchmarks/cycle_study.py --sets shrec07-human shrec07-fourleg --out /tmp/cycle.csv
"""

from __future__ import annotations

import argparse
import csv
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

import robustness as rb  # noqa: E402
import meshcorr  # noqa: E402
from meshcorr.core.mesh import as_mesh  # noqa: E402
from meshcorr.evaluation.metrics import GeodesicCache  # noqa: E402

FIELDS = ["set", "source", "target", "mean_error", "flipped", "partial", "margin", "cycle_error"]


def cycle_error(a, forward: np.ndarray, backward: np.ndarray, cache: GeodesicCache, n: int = 200) -> float:
    """Mean geodesic distance on ``a`` between seeded vertices and their images through the cycle."""
    rng = np.random.default_rng(0)
    sample = rng.choice(a.n_vertices, size=min(n, a.n_vertices), replace=False)
    back = backward[forward[sample]]
    return float(np.mean(cache.pair_distances(a, sample, back)) / np.sqrt(a.area))


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--sets", nargs="+", required=True)
    parser.add_argument("--half", choices=("a", "b"), default=None)
    parser.add_argument("--out", type=Path, required=True)
    args = parser.parse_args(argv)
    if not rb.DATA.is_dir():
        print(f"cycle_study: {rb.DATA} is absent; skipping.", file=sys.stderr)
        return 0
    done = set()
    if args.out.is_file():
        done = {(r["set"], r["source"], r["target"]) for r in csv.DictReader(args.out.open())}
    sets = rb.build_sets(False)
    new = not args.out.is_file()
    with args.out.open("a", newline="") as handle:
        writer = csv.DictWriter(handle, fieldnames=FIELDS)
        if new:
            writer.writeheader()
        for name in args.sets:
            for index, pair in enumerate(sets[name]):
                if args.half is not None and index % 2 != "ab".index(args.half):
                    continue
                if (name, pair.source_name, pair.target_name) in done:
                    continue
                a, b = as_mesh(pair.source_path), as_mesh(pair.target_path)
                forward = meshcorr.match(a, b)
                backward = meshcorr.match(b, a)
                cache = GeodesicCache("heat")
                scored = rb.score(pair, b, forward.map, cache)
                row = dict(set=name, source=pair.source_name, target=pair.target_name,
                           mean_error=scored["mean_error"], flipped=scored["flipped"], partial=scored["partial"],
                           margin=(forward.confidence or {}).get("margin"),
                           cycle_error=cycle_error(a, forward.map, backward.map, cache))
                writer.writerow(row)
                handle.flush()
                print(f"{name} {pair.source_name}->{pair.target_name}: error {row['mean_error']:.3f} "
                      f"cycle {row['cycle_error']:.3f}", file=sys.stderr, flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
