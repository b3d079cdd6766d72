"""The whole-map choice judged on the maps as they are returned (issue 12), studied offline.

For 10 pairs of each set of ``benchmarks/robustness.py`` (spread evenly; ``--held-out``: 10 other
pairs of each set, spread evenly over the rest), runs ``meshcorr.match`` and records every candidate
map of the whole-map choice twice, with its scores and its errors against the truth:

- ``stage=raw``: as ZoomOut leaves it (the repaired candidates of :mod:`meshcorr.choice.repair` included);
- ``stage=shells``: after :func:`meshcorr.stages.shells.shell_refine` (the library's own maps for the
  candidates it refines; the others, which reverse the orientation, refined here the same way).

``--rules`` then replays choice rules on the CSV without running anything again:

- *before*: the rule of the library before the change: ZoomOut's maps without repairs, least
  distortion x curvature^3 among orientation scores >= 0.6, then the shells on the pick;
- *adopted*: the library's rule: repairs added, every map of orientation >= 0.5 judged after the
  shells, least distortion x curvature^3 x (1 - orientation before) x (1 - orientation after)
  for those;
- variants of it, and the oracle (the truth picks).

Usage::

    nice -n 5 python benchmarks/judged_choice.py --out benchmarks/cache/judged.csv [--held-out] [--both-starts]
    python benchmarks/judged_choice.py --out benchmarks/cache/judged.csv --rules

``--both-starts`` also turns tip assignments into maps by ``meshcorr.choice.oriented_start``
(``meshcorr.pipeline.run.EXTREMITY_STARTS``). This hooks ``meshcorr.pipeline.run.score_candidates`` to see
the candidate maps (a study tool, not an API). Needs ``../shared/data``; exits with a message when it
is absent.
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
from meshcorr.choice.selection import ORIENTATION_MIN, REVERSED_FLOOR, MapCandidate
from meshcorr.stages.shells import shell_refine
from robustness import DATA, _spread, build_sets, previous_rows, score

FIELDS = ["set", "source", "target", "origin", "stage", "chosen", "orientation", "distortion", "curvature",
          "regional_orientation", "mean_error", "forgiven_error", "flipped", "partial"]
SCORES = ("orientation", "distortion", "curvature", "regional_orientation")


def study_pairs(held_out: bool) -> list:
    """10 pairs of each set (``held_out``: 10 of the pairs that are not among those)."""
    chosen = []
    for name, pairs in build_sets(quick=False).items():
        if name.endswith("+5"):
            continue
        first = _spread(pairs, 10)
        if held_out:
            names = {(p.source_name, p.target_name) for p in first}
            first = _spread([p for p in pairs if (p.source_name, p.target_name) not in names], 10)
        chosen += first
    return chosen


def run(pair) -> list[dict]:
    """One row per candidate and stage, and a ``final`` row for the library's answer."""
    calls: list = []
    context: dict = {}
    original = pipeline.score_candidates

    def capture(candidates, *args, **kwargs):
        original(candidates, *args, **kwargs)
        context.update(args=args, kwargs=kwargs)
        calls.append([MapCandidate(c.origin, c.mapping.copy(), **{k: getattr(c, k) for k in SCORES},
                                   extra=dict(c.extra)) for c in candidates])

    source = as_mesh(pair.source_path, name=pair.source_name)
    target = as_mesh(pair.target_path, name=pair.target_name)
    pipeline.score_candidates = capture
    try:
        result = meshcorr.match(source, target)
    finally:
        pipeline.score_candidates = original
    raw = calls[0] + (calls[1] if len(calls) > 1 else [])
    shelled = {c.origin: c for c in (calls[2] if len(calls) > 2 else [])}
    rest = [MapCandidate(c.origin, shell_refine(source, target, c.mapping, orientation=c.orientation),
                         extra=dict(c.extra, shells=1.0)) for c in raw if c.origin not in shelled]
    if rest:  # the mirrored maps the library leaves as they are: refined here the same way
        original(rest, *context["args"], **context["kwargs"])
        shelled.update({c.origin: c for c in rest})
    chosen = {c["origin"] for c in result.map_candidates if c["chosen"]}
    cache = GeodesicCache("heat")
    key = dict(set=pair.set, source=pair.source_name, target=pair.target_name)
    rows = [dict(key, origin="final", stage="final", chosen=1, **score(pair, target, result.local_map(), cache))]
    for stage, candidates in (("raw", raw), ("shells", list(shelled.values()))):
        for c in candidates:
            rows.append(dict(key, origin=c.origin, stage=stage, chosen=int(c.origin in chosen),
                             **{k: getattr(c, k) for k in SCORES}, **score(pair, target, c.mapping, cache)))
    return rows


def _energy(row: dict, reversed_area: str) -> float:
    """distortion x curvature^3, times the reversed areas named by ``reversed_area``.

    ``"both"`` (the library's): before and after the shells, for a map the shells refined;
    ``"after"``: after them only; ``"none"``.
    """
    value = row["distortion"] * row["curvature"] ** 3
    if reversed_area == "none" or "before" not in row:
        return value
    factors = (row["before"], row["orientation"]) if reversed_area == "both" else (row["orientation"],)
    return value * float(np.prod([max(1.0 - o, REVERSED_FLOOR) for o in factors]))


def _choose(rows: list[dict], reversed_area: str) -> dict:
    pool = [r for r in rows if r["orientation"] >= ORIENTATION_MIN] or rows
    return min(pool, key=lambda r: _energy(r, reversed_area))


def replay(out: Path) -> str:
    """Mean error (flips counted) per set of each rule on the CSV (Markdown)."""
    rows = previous_rows(out)
    for r in rows:
        for k in (*SCORES, "mean_error"):
            r[k] = float(r[k]) if r[k] not in ("", None) else np.nan
        r["flipped"], r["partial"] = int(r["flipped"]), int(r["partial"])
    pairs: dict = {}
    for r in rows:
        pairs.setdefault((r["set"], r["source"], r["target"]), {}).setdefault(r["stage"], []).append(r)

    def shelled(p, r):
        return [s for s in p["shells"] if s["origin"] == r["origin"]][0]

    def judged(p, repairs=True, all_shelled=False):
        return [dict(shelled(p, r), before=r["orientation"]) if (r["orientation"] >= 0.5 or all_shelled) else r
                for r in p["raw"] if repairs or not r["origin"].startswith("repaired")]

    def plain(p):
        return [r for r in p["raw"] if not r["origin"].startswith("repaired")]

    rules = {
        "library as run": lambda p: p["final"][0],
        "before: ZoomOut's maps, distortion x curvature^3, then the shells":
            lambda p: shelled(p, _choose(plain(p), "none")),
        "adopted: repairs, judged after the shells, x reversed areas before and after":
            lambda p: _choose(judged(p), "both"),
        "adopted without the repairs": lambda p: _choose(judged(p, repairs=False), "both"),
        "adopted, x reversed area after the shells only": lambda p: _choose(judged(p), "after"),
        "adopted without the reversed areas": lambda p: _choose(judged(p), "none"),
        "adopted, every map shelled (mirrored ones too)": lambda p: _choose(judged(p, all_shelled=True), "both"),
        "oracle (the truth picks), ZoomOut's maps": lambda p: min(p["raw"], key=lambda r: r["mean_error"]),
        "oracle, after the shells": lambda p: min(p["shells"], key=lambda r: r["mean_error"]),
    }
    sets = sorted({k[0] for k in pairs})
    lines = ["| rule | " + " | ".join(f"{s} ({sum(k[0] == s for k in pairs)})" for s in sets) + " | all |",
             "|---|" + "---|" * (len(sets) + 1)]
    for name, rule in rules.items():
        cells, everything = [], []
        for s in sets:
            picked = [rule(p) for k, p in pairs.items() if k[0] == s]
            everything += picked
            cells.append(f"{np.mean([r['mean_error'] for r in picked]):.4f} "
                         f"({sum(r['flipped'] for r in picked)} flips, {sum(r['partial'] for r in picked)} partial)")
        lines.append(f"| {name} | " + " | ".join(cells) + f" | {np.mean([r['mean_error'] for r in everything]):.4f} |")
    return "\n".join(lines)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", type=Path, default=Path("benchmarks/cache/judged.csv"))
    parser.add_argument("--held-out", action="store_true", help="10 other pairs of each set")
    parser.add_argument("--both-starts", action="store_true", help="oriented starts from the tips as well")
    parser.add_argument("--rules", action="store_true", help="replay the rules on the CSV")
    args = parser.parse_args(argv)
    if not DATA.is_dir():
        print(f"judged_choice: {DATA} is absent; it needs ../shared/data. Skipping.", file=sys.stderr)
        return 0
    if not args.rules:
        if args.both_starts:
            pipeline.EXTREMITY_STARTS = ("oriented", "distances")
        done = {(r["set"], r["source"], r["target"]) for r in previous_rows(args.out)}
        args.out.parent.mkdir(parents=True, exist_ok=True)
        new_file = not args.out.is_file()
        with args.out.open("a", newline="") as handle:
            writer = csv.DictWriter(handle, fieldnames=FIELDS, extrasaction="ignore")
            if new_file:
                writer.writeheader()
            for pair in study_pairs(args.held_out):
                if (pair.set, pair.source_name, pair.target_name) in done:
                    continue
                writer.writerows(run(pair))
                handle.flush()
                print(f"{pair.set} {pair.source_name}->{pair.target_name} done", file=sys.stderr, flush=True)
    print(replay(args.out))
    return 0


if __name__ == "__main__":
    sys.exit(main())
