"""Does the LandmarkWarning fire on wrong landmarks, name the wrong pairs, and stay silent on right ones?

For a few pairs of TOSCA 5k and TOSCA gorilla -> human (``robustness.py``'s
sets), ``meshcorr.match`` runs with landmark sets made from the truth:

- ``right-5``, ``right-7``: 5 and 7 truth pairs (``robustness.truth_landmarks``);
- ``wrong-2of7``: 7 truth pairs, 2 of them given a random target vertex far
  (over 0.2 of the largest geodesic distance) from the truth;
- ``random-4``: 4 random source vertices sent to random target vertices;
- ``swapped-7``: 7 pairs from the mirrored truth (``*.sym.vts``: left and right swapped).

It reports, per set and per half of the pairs (``dev``: the pairs the
constants of ``meshcorr.choice.landmark_doubts`` were chosen on; ``test``:
the others), how often the warning fires, how many of the wrong pairs it
names and how many right pairs it names; and, per run, the raw
disagreements (``meshcorr.stages.landmarks.landmark_disagreement``). Skips
when ``../shared/data`` is missing. Usage::

    OPENBLAS_NUM_THREADS=1 python benchmarks/landmark_check.py [--pairs 4]
"""

from __future__ import annotations

import argparse
import sys
import time
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

import meshcorr  # noqa: E402
from meshcorr.core.mesh import as_mesh  # noqa: E402
from meshcorr.stages.part_checks import geodesic_rows  # noqa: E402
from meshcorr.stages.landmarks import landmark_disagreement  # noqa: E402

SCENARIOS = ("right-5", "right-7", "wrong-2of7", "random-4", "swapped-7")


def landmark_sets(pair, source, target, rng) -> dict[str, tuple[np.ndarray, set]]:
    """Scenario -> (pairs, rows that are wrong)."""
    from robustness import truth_landmarks
    seven = truth_landmarks(pair, source, 7)
    wrong = seven.copy()
    rows = rng.choice(7, 2, replace=False)
    rows_of = geodesic_rows(target)
    diameter = max(float(rows_of(int(b)).max()) for b in seven[:, 1])
    for row in rows:
        distances = rows_of(int(seven[row, 1]))
        wrong[row, 1] = rng.choice(np.flatnonzero(distances > 0.2 * diameter))
    index = {int(v): k for k, v in enumerate(pair.source_points)}
    swapped = np.array([[a, pair.target_sym_points[index[int(a)]]] for a in seven[:, 0]])
    moved = {k for k in range(7) if swapped[k, 1] != seven[k, 1]}
    random = np.stack([rng.choice(source.n_vertices, 4, replace=False),
                       rng.choice(target.n_vertices, 4, replace=False)], axis=1)
    return {"right-5": (truth_landmarks(pair, source, 5), set()), "right-7": (seven, set()),
            "wrong-2of7": (wrong, {int(r) for r in rows}), "random-4": (random, set(range(4))),
            "swapped-7": (swapped, moved)}


RECORD: dict = {}


def _recording(doubts):
    """``landmark_doubts`` that also keeps which landmarks the best free map keeps (for choosing the rules)."""
    from meshcorr.choice.landmark_doubts import best_free_map
    from meshcorr.choice.selection import LANDMARK_RADIUS

    def recorded(candidates, chosen, pairs, g1, g2, *, reliable):
        best = best_free_map(candidates, reliable=reliable)
        RECORD.update(kept=(best.landmark_errors <= LANDMARK_RADIUS).astype(int).tolist(),
                      orientation=(round(float(chosen.orientation), 2), round(float(best.orientation), 2)))
        return doubts(candidates, chosen, pairs, g1, g2, reliable=reliable)
    return recorded


def run(pair, landmarks: np.ndarray, source, target) -> tuple[str | None, float]:
    """The LandmarkWarning's message (None without one) and the seconds taken."""
    start = time.perf_counter()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        meshcorr.match(source, target, landmarks=landmarks.tolist())
    found = [str(w.message) for w in caught if issubclass(w.category, meshcorr.LandmarkWarning)]
    return (found[0] if found else None), time.perf_counter() - start


def named_rows(message: str | None, landmarks: np.ndarray) -> set:
    """Rows of ``landmarks`` whose 'source -> target' the message names."""
    if message is None:
        return set()
    return {k for k, (a, b) in enumerate(landmarks) if f" {a} -> {b} (" in message or f": {a} -> {b} (" in message}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--pairs", type=int, default=4, help="pairs of each set (half dev, half test)")
    args = parser.parse_args(argv)
    from meshcorr.choice import whole_map
    whole_map.landmark_doubts = _recording(whole_map.landmark_doubts)
    from robustness import DATA, tosca_pairs
    if not (DATA / "tosca5k").is_dir() or not (DATA / "tosca-noniso").is_dir():
        print(f"landmark_check: skipped, no data under {DATA}")
        return 0
    rows = []
    rng = np.random.default_rng(0)
    for set_name in ("tosca5k", "tosca-noniso"):
        for number, pair in enumerate(tosca_pairs(DATA / set_name, set_name, args.pairs)):
            half = "dev" if number % 2 == 0 else "test"
            source, target = as_mesh(pair.source_path), as_mesh(pair.target_path)
            for scenario, (landmarks, wrong) in landmark_sets(pair, source, target, rng).items():
                message, seconds = run(pair, landmarks, source, target)
                named = named_rows(message, landmarks)
                disagreement = landmark_disagreement(*_rows(source, target), landmarks)
                rows.append(dict(set=set_name, half=half, pair=f"{pair.source_name}->{pair.target_name}",
                                 scenario=scenario, warned=message is not None, wrong=sorted(wrong),
                                 named=sorted(named), seconds=seconds))
                print(f"{set_name:13s} {half:4s} {pair.source_name:>13s}->{pair.target_name:<13s} {scenario:10s} "
                      f"warned={int(message is not None)} wrong={sorted(wrong)} named={sorted(named)} "
                      f"disagreement={np.round(disagreement, 3).tolist()} free-kept={RECORD.get('kept')} "
                      f"orientation(chosen,free)={RECORD.get('orientation')} {seconds:.0f}s", flush=True)
    print()
    print("| set | half | scenario | runs | warned | wrong pairs named | right pairs named |")
    print("|---|---|---|---|---|---|---|")
    for set_name in ("tosca5k", "tosca-noniso"):
        for half in ("dev", "test"):
            for scenario in SCENARIOS:
                some = [r for r in rows if (r["set"], r["half"], r["scenario"]) == (set_name, half, scenario)]
                if not some:
                    continue
                wrong = sum(len(r["wrong"]) for r in some)
                hit = sum(len(set(r["named"]) & set(r["wrong"])) for r in some)
                false = sum(len(set(r["named"]) - set(r["wrong"])) for r in some)
                print(f"| {set_name} | {half} | {scenario} | {len(some)} | {sum(r['warned'] for r in some)} | "
                      f"{hit}/{wrong} | {false} |")
    return 0


def _rows(source, target):
    """Geodesic rows of both shapes (the disagreement does not depend on their scale)."""
    return geodesic_rows(source), geodesic_rows(target)


if __name__ == "__main__":
    sys.exit(main())
