"""The whole-map choice's energy as the probability that a map is the right one (issue 34).

Two steps, one command each:

``collect``
    Runs ``meshcorr.match`` (default settings) on every pair of the sets of
    ``benchmarks/robustness.py`` and records each candidate map the whole-map
    choice ranks (:func:`meshcorr.choice.selection.choose_map` is hooked to see
    them), with its scores and its error against the truth, one CSV row per
    candidate. Rows are appended as pairs finish, so an interrupted run resumes.
``fit``
    Fits the weights of the energy on half ``a`` of each set (alternate pairs,
    the same halves as ``robustness.py --half``) and reports both halves apart:
    the mean error of the map each rule keeps, with flips counted, per set.

The model is a conditional logit over a pair's eligible candidates
(:func:`meshcorr.choice.selection.eligible`):

.. math::

    P(j \\mid \\text{pair}) = \\frac{e^{-E_j}}{\\sum_i e^{-E_i}},
    \\qquad E_j = w \\cdot \\left(\\log D_j, \\log C_j, \\log R^\\text{before}_j, \\log R^\\text{after}_j\\right),

with :math:`D` the metric distortion, :math:`C` the curvature disagreement and
:math:`R` the area fractions that the map reverses before and after the smooth
shells; the weights maximise the likelihood of the candidate of least error in
each pair of half ``a``. The library's rule is :math:`w = \\tau (1, 3, 1, 1)`;
``fit`` also gives the scale :math:`\\tau` of most likelihood for those
proportions (:data:`meshcorr.choice.selection.EVIDENCE_SCALE`).

Usage::

    nice -n 5 python benchmarks/choice_weights.py collect [--out benchmarks/cache/choice-weights.csv] [--per-set 16]
    python benchmarks/choice_weights.py fit [--out benchmarks/cache/choice-weights.csv]

Needs ``../shared/data``; exits with a message when it is absent.
"""

from __future__ import annotations

import argparse
import sys
import time
import warnings
from pathlib import Path

import numpy as np

import meshcorr
import meshcorr.choice.whole_map as whole_map
from meshcorr.choice.selection import REVERSED_FLOOR, eligible
from meshcorr.core.mesh import as_mesh
from meshcorr.evaluation.metrics import GeodesicCache
from robustness import DATA, _spread, appending, build_sets, previous_rows, score, truth_landmarks

FIELDS = ["set", "half", "source", "target", "origin", "chosen", "eligible", "orientation", "before",
          "distortion", "curvature", "alignment", "extrinsic", "deformation", "landmarks_kept", "mean_error",
          "flipped", "partial", "gaps"]
TERMS = ("distortion", "curvature", "before", "orientation")
LIBRARY = np.array([1.0, 3.0, 1.0, 1.0])


def collect_pair(pair, half: str) -> list[dict]:
    """One row per candidate the choice ranked."""
    seen: list = []
    original, original_choice = whole_map.choose_map, whole_map.whole_map_choice
    rows_of: dict = {}

    def capture(candidates, *, reliable):
        seen.append((list(candidates), eligible(candidates, reliable=reliable), reliable))
        return original(candidates, reliable=reliable)

    def capture_geodesics(src, tgt, spectra, *args, **kwargs):
        rows_of["target"], rows_of["n"] = spectra[1].geodesics_from, src.n_vertices
        return original_choice(src, tgt, spectra, *args, **kwargs)

    source = as_mesh(pair.source_path, name=pair.source_name)
    target = as_mesh(pair.target_path, name=pair.target_name)
    landmarks = truth_landmarks(pair, source) if pair.set.endswith("+5") else None
    import meshcorr.pipeline.run as run

    whole_map.choose_map, run.whole_map_choice = capture, capture_geodesics
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            result = meshcorr.match(source, target, landmarks=landmarks)
    finally:
        whole_map.choose_map, run.whole_map_choice = original, original_choice
    if not seen:
        return []
    candidates, pool, _ = seen[-1]
    chosen = {c["origin"] for c in result.map_candidates if c["chosen"]}
    pool_ids = {id(c) for c in pool}
    cache = GeodesicCache("heat")
    # Mean normalised geodesic distance on the target between each two candidates' images of the
    # distortion's seeded sources (meshcorr.choice.confidence's measure of "another configuration").
    from meshcorr.choice.selection import distortion_sources
    seeds = distortion_sources(rows_of["n"], 0)
    images = [[np.asarray(rows_of["target"](int(c.mapping[i]))) for i in seeds] for c in candidates]
    gaps = [[round(float(np.mean([row[d.mapping[i]] for row, i in zip(images[a], seeds)])), 4)
             for d in candidates] for a in range(len(candidates))]
    rows = []
    for index, c in enumerate(candidates):
        if c.mapping.shape[0] != source.n_vertices:  # coarse copies: not scored here
            return []
        rows.append(dict(set=pair.set, half=half, source=pair.source_name, target=pair.target_name,
                         origin=c.origin, chosen=int(c.origin in chosen), eligible=int(id(c) in pool_ids),
                         orientation=c.orientation, before=c.extra.get("zoomout_orientation", np.nan),
                         distortion=c.distortion, curvature=c.curvature,
                         alignment=c.extra.get("alignment", np.nan), extrinsic=c.extra.get("extrinsic", np.nan),
                         deformation=c.extra.get("deformation", np.nan), landmarks_kept=c.landmarks_kept,
                         gaps=" ".join(str(g) for g in gaps[index]),
                         **{k: v for k, v in score(pair, target, c.mapping, cache).items()
                            if k in ("mean_error", "flipped", "partial")}))
    return rows


def collect(out: Path, quick: bool, per_set: int, sets: list[str] | None = None) -> None:
    done = {(r["set"], r["source"], r["target"]) for r in previous_rows(out)}
    with appending(out, FIELDS) as (handle, writer):
        for name, pairs in build_sets(quick).items():
            if sets and name not in sets:
                continue
            spread = {id(p) for p in _spread(pairs, per_set)}
            for index, pair in enumerate(pairs):  # the half of the pair's place in the whole set
                if (name, pair.source_name, pair.target_name) in done or id(pair) not in spread:
                    continue
                start = time.perf_counter()
                rows = collect_pair(pair, "ab"[index % 2])
                for row in rows:
                    writer.writerow(row)
                handle.flush()
                print(f"{name} {pair.source_name}->{pair.target_name}: {len(rows)} candidates "
                      f"{time.perf_counter() - start:.1f} s", file=sys.stderr, flush=True)


#: The terms a model may use: the energy's four, and the smooth shells' own energies (their alignment
#: left, the extrinsic part of it, the deformation).
EXTRA_TERMS = ("alignment", "extrinsic", "deformation")


def features(row: dict, extra: tuple[str, ...] = ()) -> np.ndarray:
    """The logarithms of the energy's terms (reversed areas floored at REVERSED_FLOOR), then of ``extra``."""
    before = row["before"] if np.isfinite(row["before"]) else row["orientation"]
    values = [row["distortion"], row["curvature"], max(1 - before, REVERSED_FLOOR),
              max(1 - row["orientation"], REVERSED_FLOOR)]
    values += [row[name] if np.isfinite(row[name]) and row[name] > 0 else 1.0 for name in extra]
    return np.log(values)


def load(out: Path) -> dict:
    pairs: dict = {}
    for r in previous_rows(out):
        for k in ("orientation", "before", "distortion", "curvature", "alignment", "extrinsic", "deformation",
                  "landmarks_kept", "mean_error"):
            r[k] = float(r[k]) if r[k] not in ("", None) else np.nan
        for k in ("chosen", "eligible", "flipped", "partial"):
            r[k] = int(r[k])
        pairs.setdefault((r["set"], r["half"], r["source"], r["target"]), []).append(r)
    return pairs


def pick(rows: list[dict], weights: np.ndarray, extra: tuple[str, ...] = ()) -> dict:
    pool = [r for r in rows if r["eligible"]]
    return min(pool, key=lambda r: float(features(r, extra) @ weights))


def fit(pairs: dict, extra: tuple[str, ...] = ()) -> np.ndarray:
    """Weights of least negative log-likelihood of the best candidate of each pair of half a."""
    from scipy.optimize import minimize

    groups = []
    for (_, half, _, _), rows in pairs.items():
        pool = [r for r in rows if r["eligible"]]
        if half != "a" or len(pool) < 2:
            continue
        X = np.array([features(r, extra) for r in pool])
        best = int(np.argmin([r["mean_error"] for r in pool]))
        groups.append((X, best))

    def loss(w):
        total = 0.0
        for X, best in groups:
            e = -(X @ w)
            total -= e[best] - (np.log(np.sum(np.exp(e - e.max()))) + e.max())
        return total + 1e-3 * float(w @ w)

    start = np.concatenate([LIBRARY, np.zeros(len(extra))])
    return minimize(loss, start, method="Nelder-Mead", options={"maxiter": 8000, "xatol": 1e-4}).x


def fit_scale(pairs: dict, half: str = "a") -> float:
    """The scale tau of the library's weights of most likelihood of each pair's best candidate (``half``)."""
    from scipy.optimize import minimize_scalar

    groups = []
    for (_, pair_half, _, _), rows in pairs.items():
        pool = [r for r in rows if r["eligible"]]
        if pair_half == half and len(pool) >= 2:
            groups.append((np.array([features(r) for r in pool]) @ LIBRARY,
                           int(np.argmin([r["mean_error"] for r in pool]))))

    def loss(tau):
        total = 0.0
        for x, best in groups:
            e = -tau * x
            total -= e[best] - (np.log(np.sum(np.exp(e - e.max()))) + e.max())
        return total

    return float(minimize_scalar(loss, bounds=(0.01, 20.0), method="bounded").x)


def pick_configuration(rows: list[dict], tau: float, within: float = 0.1) -> dict:
    """The candidate whose global configuration is most probable: the summed softmax(-tau x library
    log-energy) of the eligible candidates within ``within`` of it (the ``gaps`` column), ties to the least
    energy."""
    index = {id(r): i for i, r in enumerate(rows)}
    pool = [r for r in rows if r["eligible"]]
    energies = np.array([float(features(r) @ LIBRARY) for r in pool])
    weights = np.exp(-tau * (energies - energies.min()))
    gaps = [[float(g) for g in r["gaps"].split()] for r in pool]
    mass = [sum(w for other, w in zip(pool, weights) if gaps[a][index[id(other)]] <= within)
            for a in range(len(pool))]
    best = max(range(len(pool)), key=lambda a: (round(mass[a], 9), -energies[a]))
    return pool[best]


def configuration_report(pairs: dict) -> str:
    """Mean error per set and half of the most probable configuration's candidate, for a few tau."""
    pairs = {k: v for k, v in pairs.items() if all(r.get("gaps") for r in v)}
    sets = sorted({k[0] for k in pairs})
    lines = []
    for half in "ab":
        lines += [f"\nHalf {half} (the configuration rule):\n", "| rule | " + " | ".join(sets) + " |",
                  "|---|" + "---|" * len(sets)]
        rules = {"library": lambda rows: pick(rows, LIBRARY), "oracle": lambda rows: min(rows, key=lambda r: r["mean_error"])}
        for tau in (0.25, 0.5, 1.0, 2.0, 4.0):
            rules[f"most probable configuration, tau {tau}"] = lambda rows, tau=tau: pick_configuration(rows, tau)
        for name, rule in rules.items():
            cells = []
            for s in sets:
                picked = [rule(rows) for k, rows in pairs.items() if k[0] == s and k[1] == half]
                cells.append(f"{np.mean([r['mean_error'] for r in picked]):.4f} ({len(picked)}, "
                             f"{sum(r['flipped'] for r in picked)} flips)")
            lines.append(f"| {name} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def report(pairs: dict, rules: dict) -> str:
    sets = sorted({k[0] for k in pairs})
    lines = []
    for half in "ab":
        lines += [f"\nHalf {half}:\n", "| rule | " + " | ".join(sets) + " |", "|---|" + "---|" * len(sets)]
        for name, (weights, extra) in rules.items():
            cells = []
            for s in sets:
                picked = [pick(rows, weights, extra) if weights is not None else min(rows, key=lambda r: r["mean_error"])
                          for k, rows in pairs.items() if k[0] == s and k[1] == half]
                cells.append(f"{np.mean([r['mean_error'] for r in picked]):.4f} ({len(picked)}, "
                             f"{sum(r['flipped'] for r in picked)} flips)")
            lines.append(f"| {name} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("step", choices=("collect", "fit"))
    parser.add_argument("--out", type=Path, default=Path("benchmarks/cache/choice-weights.csv"))
    parser.add_argument("--quick", action="store_true", help="at most 8 pairs per set")
    parser.add_argument("--sets", nargs="+", default=None, help="collect: only these sets")
    parser.add_argument("--per-set", type=int, default=0,
                        help="collect: this many pairs of each set, spread evenly (0: all)")
    args = parser.parse_args(argv)
    if not DATA.is_dir():
        print(f"choice_weights: {DATA} is absent; this benchmark needs ../shared/data. Skipping.", file=sys.stderr)
        return 0
    if args.step == "collect":
        collect(args.out, args.quick, args.per_set, args.sets)
        return 0
    pairs = load(args.out)
    weights = fit(pairs)
    wider = fit(pairs, EXTRA_TERMS)
    print(f"the library's weights (1, 3, 1, 1) x tau: tau = {fit_scale(pairs):.2f} on half a, "
          f"{fit_scale(pairs, 'b'):.2f} on half b")
    print(f"fitted weights (log D, log C, log R before, log R after): {np.round(weights, 3).tolist()}")
    print(f"with the shells' energies ({', '.join(EXTRA_TERMS)}): {np.round(wider, 3).tolist()}")
    print(report(pairs, {"library (1, 3, 1, 1)": (LIBRARY, ()), "fitted on half a": (weights, ()),
                         "fitted, with the shells' energies": (wider, EXTRA_TERMS),
                         "distortion only": (np.array([1.0, 0, 0, 0]), ()), "oracle": (None, ())}))
    if any(r.get("gaps") for rows in pairs.values() for r in rows):
        print(configuration_report(pairs))
    return 0


if __name__ == "__main__":
    sys.exit(main())
