"""The smooth shells' schedule and the landmarks' distances, compared on the robustness sets (issue 12).

For 10 pairs of each chosen set of ``benchmarks/robustness.py`` (spread evenly), runs
``meshcorr.match`` with each variant of the final smooth-shell stage and reports the mean error
(flips counted and forgiven), full flips and partial swaps per set and variant:

- ``adopted``: the library as it is: every candidate that keeps the orientation aligned on
  :data:`meshcorr.stages.shells.SCALES` (6, 8, ..., 40), the user's landmark distances in the landmark
  candidate's product space;
- ``no-descriptors``: adopted without the landmark distances (differs only with landmarks);
- ``coarse``: the candidates on the former coarse schedule (8, 12, 16, 24, 32, 40).

The former default (``coarse`` followed by 16, 18, ..., 40 on the chosen map alone) is commit
82c3a90; its full-set figures are in ``RESULTS-robustness.md``.

Usage::

    nice -n 5 python benchmarks/shell_schedule.py [--sets tosca-noniso tosca-noniso+5 ...] \\
        [--variants adopted coarse ...] [--pairs 10] [--workers 2]

Each pair runs in a worker process (``--workers``). Needs ``../shared/data``; exits with a message
when it is absent.
"""

from __future__ import annotations

import argparse
import sys
import time
from concurrent.futures import ProcessPoolExecutor

import numpy as np

import meshcorr
import meshcorr.pipeline.run as pipeline
import meshcorr.choice.selection as selection
import meshcorr.stages.shells as shells
from meshcorr.evaluation.metrics import GeodesicCache
from meshcorr.core.mesh import as_mesh
from robustness import DATA, _spread, build_sets, score, truth_landmarks

VARIANTS = ("adopted", "no-descriptors", "coarse")
COARSE = (8, 12, 16, 24, 32, 40)


def apply(variant: str) -> None:
    """Patch this worker process's meshcorr into ``variant`` (module docstring)."""
    original = shells.shell_refine

    def patched(source, target, mapping, **kwargs):
        if variant == "coarse":
            kwargs["scales"] = COARSE
        if variant == "no-descriptors":
            kwargs["descriptors"] = None
        return original(source, target, mapping, **kwargs)

    pipeline.shell_refine = patched
    selection.shell_refine = patched


def run(job: tuple[str, int, str]) -> dict:
    set_name, index, variant = job
    apply(variant)
    pair = build_sets(quick=False)[set_name][index]
    source = as_mesh(pair.source_path, name=pair.source_name)
    target = as_mesh(pair.target_path, name=pair.target_name)
    extra = {"landmarks": truth_landmarks(pair, source)} if set_name.endswith("+5") else {}
    start = time.perf_counter()
    mapping = meshcorr.match(source, target, **extra).map
    seconds = time.perf_counter() - start
    return dict(set=set_name, variant=variant, seconds=seconds,
                **score(pair, target, mapping, GeodesicCache("heat")))


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sets", nargs="+", default=["tosca5k", "tosca-noniso", "tosca-noniso+5",
                                                      "shrec07-human", "shrec07-fourleg"])
    parser.add_argument("--variants", nargs="+", choices=VARIANTS, default=list(VARIANTS))
    parser.add_argument("--pairs", type=int, default=10, help="pairs of each set, spread evenly")
    parser.add_argument("--workers", type=int, default=2)
    args = parser.parse_args(argv)
    if not DATA.is_dir():
        print(f"skipped: {DATA} is absent (the shared data sits beside the repository)")
        return 0
    sets = build_sets(quick=False)
    jobs = []
    for name in args.sets:
        chosen = _spread(list(range(len(sets[name]))), args.pairs)
        jobs += [(name, i, v) for v in args.variants for i in chosen]
    print("| set | variant | pairs | mean error | forgiving flips | full flips | partial swaps | median s |")
    print("|---|---|---|---|---|---|---|---|")
    with ProcessPoolExecutor(args.workers) as pool:
        rows = list(pool.map(run, jobs))
    for name in args.sets:
        for variant in args.variants:
            got = [r for r in rows if r["set"] == name and r["variant"] == variant]
            print(f"| {name} | {variant} | {len(got)} | {np.mean([r['mean_error'] for r in got]):.4f} | "
                  f"{np.mean([r['forgiven_error'] for r in got]):.4f} | {sum(r['flipped'] for r in got)} | "
                  f"{sum(r['partial'] for r in got)} | {np.median([r['seconds'] for r in got]):.2f} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
