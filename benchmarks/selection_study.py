"""The whole-map choice studied offline: every candidate of every pair, scored and dumped once.

For pairs of each set of ``benchmarks/robustness.py``, runs ``meshcorr.match``
with both ways of turning a tip assignment into a dense map
(``meshcorr.pipeline.run.EXTREMITY_STARTS = ("oriented", "distances")``) and
records, per candidate map, its scores (orientation, distortion, curvature,
regional orientation) and its errors against the truth (flips counted and
forgiven, flipped, partly swapped), and saves the candidate maps themselves
beside the CSV (``<out>.maps/<set>__<source>__<target>.npz``, one array per
origin), so that new energies can be studied without running the pairs again. ``--rules`` then replays choice rules on
the dump without running anything again: which map each rule would keep,
and its mean error per set. ``--shells`` refines the default rule's pick (and
the best candidate) by :mod:`meshcorr.stages.shells` and reports the errors before
and after, from the same starts.

Usage::

    nice -n 10 python benchmarks/selection_study.py --out benchmarks/cache/candidates.csv [--per-set 20]
    python benchmarks/selection_study.py --out benchmarks/cache/candidates.csv --rules
    python benchmarks/selection_study.py --out benchmarks/cache/candidates.csv --shells

This hooks ``meshcorr.pipeline.run.score_candidates`` to see the candidate maps
(a study tool, not an API). Needs ``../shared/data``; exits with a message
when it is absent.
"""

from __future__ import annotations

import argparse
import csv
import sys
from pathlib import Path

import numpy as np

import meshcorr
import meshcorr.pipeline.run as pipeline
from meshcorr.evaluation.metrics import GeodesicCache
from meshcorr.core.mesh import as_mesh
from meshcorr.choice.selection import ORIENTATION_MIN
from robustness import DATA, _spread, build_sets, score

FIELDS = ["set", "source", "target", "origin", "chosen", "orientation", "distortion", "curvature",
          "regional_orientation", "mean_error", "forgiven_error", "flipped", "partial"]


def dump(per_set: int, out: Path) -> None:
    """Run the pairs and append one row per candidate map to ``out`` (resumable)."""
    seen = set()
    if out.is_file():
        with out.open() as handle:
            seen = {(r["set"], r["source"], r["target"]) for r in csv.DictReader(handle)}
    captured: list = []
    original = pipeline.score_candidates

    def capture(candidates, *args, **kwargs):
        captured.append(candidates)
        return original(candidates, *args, **kwargs)

    pipeline.score_candidates = capture
    pipeline.EXTREMITY_STARTS = ("oriented", "distances")
    new_file = not out.is_file()
    with out.open("a", newline="") as handle:
        writer = csv.DictWriter(handle, fieldnames=FIELDS)
        if new_file:
            writer.writeheader()
        for name, pairs in build_sets(quick=False).items():
            if name.endswith("+5"):
                continue
            for pair in _spread(pairs, per_set):
                if (name, pair.source_name, pair.target_name) in seen:
                    continue
                source = as_mesh(pair.source_path, name=pair.source_name)
                target = as_mesh(pair.target_path, name=pair.target_name)
                captured.clear()
                result = meshcorr.match(source, target)
                chosen = {c["origin"] for c in result.map_candidates if c["chosen"]}
                cache = GeodesicCache("heat")
                maps_dir = out.with_suffix(".maps")
                maps_dir.mkdir(exist_ok=True)
                # The candidate maps themselves, so that new energies can be studied without rerunning.
                np.savez_compressed(maps_dir / f"{name}__{pair.source_name}__{pair.target_name}.npz",
                                    **{c.origin: c.mapping for c in captured[0]})
                for candidate in captured[0]:
                    # Candidate maps are in the meshes' local numbering; these meshes drop no vertex.
                    errors = score(pair, target, candidate.mapping, cache)
                    writer.writerow(dict(set=name, source=pair.source_name, target=pair.target_name,
                                         origin=candidate.origin, chosen=int(candidate.origin in chosen),
                                         orientation=candidate.orientation, distortion=candidate.distortion,
                                         curvature=candidate.curvature,
                                         regional_orientation=candidate.regional_orientation,
                                         **{k: errors[k] for k in FIELDS[-4:]}))
                handle.flush()
                print(f"{name} {pair.source_name}->{pair.target_name} done", file=sys.stderr, flush=True)


def _choose(rows: list[dict], keep, power: float, slack: float | None = None,
            minimum: float = ORIENTATION_MIN) -> dict:
    """The candidate the library's rule keeps among ``rows`` that ``keep(row)`` admits.

    ``slack``: only maps of distortion at most ``slack`` x the least one (+ 0.01) count as
    orientation-preserving candidates (a variant; None: the library's rule).
    """
    pool = [r for r in rows if keep(r)]
    plausible = pool
    if slack is not None:
        least = min(r["distortion"] for r in pool)
        plausible = [r for r in pool if r["distortion"] <= slack * least + 0.01]
    pool = [r for r in plausible if r["orientation"] >= minimum] or pool
    return min(pool, key=lambda r: r["distortion"] * r["curvature"] ** power)


def replay(out: Path) -> str:
    """Mean error per set of each rule on the dumped candidates (Markdown)."""
    with out.open() as handle:
        rows = list(csv.DictReader(handle))
    for r in rows:
        for key in ("orientation", "distortion", "curvature", "regional_orientation", "mean_error",
                    "forgiven_error"):
            r[key] = float(r[key])
    pairs: dict = {}
    for r in rows:
        pairs.setdefault((r["set"], r["source"], r["target"]), []).append(r)

    def oriented(r):
        return not r["origin"].endswith("-distances")

    def distances(r):
        return not (r["origin"].startswith("extremities") and not r["origin"].endswith("-distances"))

    def gated(candidates, r):  # an oriented map only where its assignment's distance map keeps the orientation
        sibling = [q for q in candidates if q["origin"] == r["origin"] + "-distances"]
        return not sibling or sibling[0]["orientation"] >= 0.5

    rules = {
        "as run (both starts, the library's rule)": lambda c: [r for r in c if r["chosen"] == "1"][0],
    }
    for power in (3, 1, 0):
        energy = {3: "distortion x curvature^3", 1: "distortion x curvature", 0: "distortion alone"}[power]
        rules[f"distance starts (default), {energy}"] = lambda c, p=power: _choose(c, distances, p)
        rules[f"oriented starts, {energy}"] = lambda c, p=power: _choose(c, oriented, p)
        rules[f"both starts, {energy}"] = lambda c, p=power: _choose(c, lambda r: True, p)
        rules[f"both, oriented only where the distance map keeps orientation, {energy}"] = (
            lambda c, p=power: _choose(c, lambda r: gated(c, r), p))
    rules["distance starts, distortion x curvature^3, orientation only among maps <= 2x least distortion"] = (
        lambda c: _choose(c, distances, 3, slack=2.0))
    rules["oriented starts, distortion x curvature^3, orientation only among maps <= 2x least distortion"] = (
        lambda c: _choose(c, oriented, 3, slack=2.0))
    rules["oracle (truth picks), both starts"] = lambda c: min(c, key=lambda r: r["mean_error"])
    sets = sorted({k[0] for k in pairs})
    lines = ["| rule | " + " | ".join(f"{s} ({sum(k[0] == s for k in pairs)})" for s in sets) + " |",
             "|---|" + "---|" * len(sets)]
    for name, rule in rules.items():
        cells = []
        for s in sets:
            picked = [rule(c) for k, c in pairs.items() if k[0] == s]
            flips = sum(int(p["flipped"]) for p in picked)
            cells.append(f"{np.mean([p['mean_error'] for p in picked]):.4f} ({flips} flips)")
        lines.append(f"| {name} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def shells(out: Path) -> str:
    """The library rule's pick on each dumped pair, before and after :func:`meshcorr.stages.shells.shell_refine` (Markdown)."""
    import time

    from meshcorr.stages.shells import shell_refine

    with out.open() as handle:
        rows = list(csv.DictReader(handle))
    for r in rows:
        for key in ("orientation", "distortion", "curvature", "mean_error"):
            r[key] = float(r[key])
    pairs: dict = {}
    for r in rows:
        pairs.setdefault((r["set"], r["source"], r["target"]), []).append(r)
    known = {(p.set, p.source_name, p.target_name): p for ps in build_sets(quick=False).values() for p in ps}

    def distances(r):  # the default starts (meshcorr.pipeline.run.EXTREMITY_STARTS)
        return not (r["origin"].startswith("extremities") and not r["origin"].endswith("-distances"))

    results: dict = {}
    for key, candidates in pairs.items():
        pair = known[key]
        maps = np.load(out.with_suffix(".maps") / f"{key[0]}__{key[1]}__{key[2]}.npz")
        source, target = as_mesh(pair.source_path), as_mesh(pair.target_path)
        for label, pick in (("rule", _choose(candidates, distances, 3)),
                            ("oracle", min(candidates, key=lambda r: r["mean_error"]))):
            start = time.perf_counter()
            mapping = shell_refine(source, target, maps[pick["origin"]])
            seconds = time.perf_counter() - start  # the first pick's with both bases' eigensolves
            after = score(pair, target, mapping, GeodesicCache("heat"))
            results.setdefault((key[0], label), []).append((pick["mean_error"], after["mean_error"],
                                                            int(pick["flipped"]), after["flipped"], seconds))
        print(f"{key[0]} {key[1]}->{key[2]} shells done", file=sys.stderr, flush=True)
    lines = ["| set | start | pairs | before | after shells | flips before / after | median s (the rule's pick: with the bases' eigensolves) |",
             "|---|---|---|---|---|---|---|"]
    for (name, label), values in sorted(results.items()):
        v = np.array(values, dtype=float)
        lines.append(f"| {name} | {label} | {len(v)} | {v[:, 0].mean():.4f} | {v[:, 1].mean():.4f} | "
                     f"{int(v[:, 2].sum())} / {int(v[:, 3].sum())} | {np.median(v[:, 4]):.2f} |")
    return "\n".join(lines)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", type=Path, default=Path("benchmarks/cache/candidates.csv"))
    parser.add_argument("--per-set", type=int, default=20, help="pairs per set, spread evenly")
    parser.add_argument("--rules", action="store_true", help="replay the rules on the dump")
    parser.add_argument("--shells", action="store_true",
                        help="refine the default rule's pick and the best candidate by meshcorr.stages.shells")
    args = parser.parse_args(argv)
    if not DATA.is_dir():
        print(f"selection_study: {DATA} is absent; it needs ../shared/data. Skipping.", file=sys.stderr)
        return 0
    if args.shells:
        print(shells(args.out))
        return 0
    if not args.rules:
        args.out.parent.mkdir(parents=True, exist_ok=True)
        dump(args.per_set, args.out)
    print(replay(args.out))
    return 0


if __name__ == "__main__":
    sys.exit(main())
