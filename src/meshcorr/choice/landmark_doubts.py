"""Whether the user's landmarks look right: against each other and against the maps found without them.

Landmarks weigh in every step they reach (the landmarks' own candidate map,
its refinement, the smooth shells' pins, the whole-map choice), so a wrong
pair bends the map around it and a set of random or left/right-swapped pairs
gives a wrong map everywhere. Two checks, both relative to the landmarks
themselves (a gorilla and a person disagree more than two poses of one
person, and neither check may warn on a right set):

- **against each other** (:func:`meshcorr.stages.landmarks.landmark_disagreement`):
  with 4 or more pairs, a pair whose geodesic distances to the other
  landmarks disagree across the shapes :data:`OUTLIER_RATIO` times more than
  the pairs' median, and by at least :data:`OUTLIER_FLOOR` of the mean
  landmark distance, is named if the best map found without the landmarks
  (below) does not keep it either. A gorilla's hand given as a person's
  disagrees 5-8 times the median by itself (longer arms), a wrong pair on
  TOSCA 3-20 times: the ratio is set high, and the map's word is needed.
- **against the maps** (:mod:`meshcorr.choice.selection`): the candidate
  maps not started from the landmarks nor held to them ("free" maps: the
  spectral map, maps from extremities, their repairs) show by themselves
  where each landmark goes. When the free maps that keep the orientation
  (all of them when it cannot be trusted) keep at most half of the landmarks
  (:data:`~meshcorr.choice.selection.LANDMARK_RADIUS`), the set disagrees
  with every map found without it; when the map chosen reverses the
  orientation while such a free map exists, the landmarks chose a mirror
  image. Either way, the landmarks that the best free map does not keep
  are named.

The thresholds were chosen on half of the TOSCA and TOSCA gorilla -> human
pairs of ``benchmarks/landmark_check.py`` and checked on the other half
(``benchmarks/RESULTS-robustness-trials.md``).
"""

from __future__ import annotations

import numpy as np

from ..stages.landmarks import RowFn, landmark_disagreement
from .selection import LANDMARK_RADIUS, ORIENTATION_MIN, MapCandidate

__all__ = ["OUTLIER_FLOOR", "OUTLIER_RATIO", "best_free_map", "free_maps", "landmark_doubts"]

#: A pair disagrees with the others when its disagreement is this many times the pairs' median ...
OUTLIER_RATIO = 8.0
#: ... and at least this (a fraction of the mean distance between the source landmarks).
OUTLIER_FLOOR = 0.1
#: The fewest pairs among which one can be told apart as disagreeing with the others.
MIN_PAIRS = 4


def landmark_doubts(candidates: list[MapCandidate], chosen: MapCandidate, pairs: np.ndarray,
                    source_geodesics: RowFn, target_geodesics: RowFn, *, reliable: bool) -> dict[int, str]:
    """The landmark pairs that look wrong, and why (module docstring).

    Parameters
    ----------
    candidates : list of MapCandidate
        Scored with the landmarks (:func:`meshcorr.choice.selection.score_candidates`).
    chosen : MapCandidate
        The map the whole-map choice kept.
    pairs : (L, 2) int
        The user's landmark pairs, local numbering.
    source_geodesics, target_geodesics : callable
        ``f(i)``: normalised geodesic distances from vertex i, ``(n,)``.
    reliable : bool
        Whether the orientation scores can be trusted.

    Returns
    -------
    doubts : dict
        Row of ``pairs`` -> what is wrong with it; empty when nothing is.
    """
    doubts: dict[int, str] = {}
    best = best_free_map(candidates, reliable=reliable)
    if len(pairs) >= MIN_PAIRS and best is not None:
        disagreement = landmark_disagreement(source_geodesics, target_geodesics, pairs)
        typical = float(np.median(disagreement))
        outlying = ((disagreement > max(OUTLIER_RATIO * typical, OUTLIER_FLOOR))
                    & (best.landmark_errors > LANDMARK_RADIUS))
        for row in np.flatnonzero(outlying):
            doubts[int(row)] = (f"its geodesic distances to the other landmarks differ by {disagreement[row]:.0%} "
                                f"between the shapes (the pairs' median: {typical:.0%})")
    for row, why in _against_maps(best, chosen, reliable).items():
        doubts[row] = f"{doubts[row]}; {why}" if row in doubts else why
    return dict(sorted(doubts.items()))


def best_free_map(candidates: list[MapCandidate], *, reliable: bool) -> MapCandidate | None:
    """The free map (:func:`free_maps`) that keeps the most landmarks, the nearest on average among those."""
    free = free_maps(candidates, reliable=reliable)
    if not free:
        return None
    return max(free, key=lambda c: (int(np.sum(c.landmark_errors <= LANDMARK_RADIUS)), -c.landmark_error))


def free_maps(candidates: list[MapCandidate], *, reliable: bool) -> list[MapCandidate]:
    """The candidates found without the landmarks that keep the orientation (all of them, when none does
    or the orientation cannot be trusted)."""
    free = [c for c in candidates if "landmarks" not in c.origin and c.landmark_errors is not None]
    if reliable:
        free = [c for c in free if c.orientation >= ORIENTATION_MIN] or free
    return free


def _against_maps(best: MapCandidate | None, chosen: MapCandidate, reliable: bool) -> dict[int, str]:
    """Landmarks that the best free map does not keep, when the free maps keep at most half of them or
    the landmarks chose a mirror image."""
    if best is None:
        return {}
    missed = np.flatnonzero(best.landmark_errors > LANDMARK_RADIUS)
    count, kept = len(best.landmark_errors), len(best.landmark_errors) - len(missed)
    mirrored = reliable and chosen.orientation < 0.5 <= best.orientation
    if len(missed) == 0 or (2 * kept > count and not mirrored):
        return {}
    why = (f"the map chosen with the landmarks is a mirror image (orientation kept on {chosen.orientation:.0%} "
           "of the area): left and right swapped?" if mirrored else
           f"every map found without the landmarks keeps at most {kept} of the {count}")
    return {int(row): f"{why}; the best such map sends it {best.landmark_errors[row]:.2f} (of the target's "
                      "largest geodesic distance) from its partner" for row in missed}
