"""How sure the whole-map choice is: the probability of its global configuration and the margin to the best rival.

The whole-map choice (:mod:`meshcorr.choice.selection`) keeps the candidate
map of least energy, minus the log-probability that a candidate is the
right map (:func:`meshcorr.choice.selection.energy`). Its candidates include
near-copies of one another (a map, its repair, its smooth-shell
refinement) and maps of a different *global configuration*: the mirror
image, the shape turned front to back, limbs exchanged. A candidate is a
**rival** when it sends the seeded source vertices of the metric
distortion on average farther than :data:`RIVAL_DISTANCE` (normalised
geodesic distance on the target) from where the chosen map sends them.
Two numbers say how sure the choice is:

- the **probability** that the chosen configuration is the right one: the
  summed probability (:func:`meshcorr.choice.selection.choice_probabilities`)
  of the candidates that are not rivals, the chosen one included;
- the **margin** to the best rival,

  .. math::

      \\text{margin} = E(\\text{rival}) - E(\\text{chosen}) = \\log \\frac{P(\\text{chosen})}{P(\\text{rival})},

  undefined (``inf``, probability 1) when no candidate is a rival.

Only maps the choice's rules let compete are rivals
(:func:`meshcorr.choice.selection.eligible`: those that keep as many of the
user's landmarks and, where the outside is defined, the orientation), so
the margin is never negative: a mirror image that the orientation sets
aside, or a map the landmarks contradict, does not make a choice unsure.

Below :data:`LOW_MARGIN` the choice is reported as unsure, with the few
source vertices where the chosen map and the rival disagree most, spread
over the shape (each at least :data:`SUGGESTION_SPACING` from the others):
a landmark on each settles the choice (``landmarks=``, ``--landmarks``).
:data:`LOW_MARGIN` was chosen on a fixed half of each set of
``benchmarks/robustness.py``: the threshold that flags the most wrong maps
while flagging at most 10 % of the right ones. The margin separates them
poorly (``benchmarks/RESULTS-robustness.md``): many wrong maps are chosen
with a wide margin (the right map was no candidate) and many right ones
with a narrow one, so the warning catches few wrong maps; the margin, the
probability and the suggested landmarks are reported for every map.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

__all__ = ["LOW_MARGIN", "RIVAL_DISTANCE", "Confidence", "choice_confidence", "no_rival", "unsure_message"]

#: A candidate whose images lie on average farther than this from the chosen map's is a rival.
RIVAL_DISTANCE = 0.1
#: Margins (log-probability ratios) below this are reported as an unsure choice: chosen on half "a" of each
#: set of benchmarks/robustness.py (the most wrong maps flagged with at most 10 % of the right ones;
#: benchmarks/confidence_threshold.py, benchmarks/RESULTS-robustness.md): 0.05 decades of the energy's
#: former product form, 0.05 x ln(10) x EVIDENCE_SCALE in this unit (the same maps flagged).
LOW_MARGIN = 0.23
#: Landmarks suggested for an unsure choice.
N_SUGGESTIONS = 3
#: Least normalised geodesic distance between two suggested source vertices.
SUGGESTION_SPACING = 0.25


@dataclass(frozen=True)
class Confidence:
    """How sure the whole-map choice is (module docstring).

    Attributes
    ----------
    margin : float
        :math:`\\log P(\\text{chosen}) / P(\\text{rival})`, the energy between the best
        rival and the chosen map (``inf`` without a rival).
    rival : str or None
        The rival candidate's origin.
    suggestions : (s, 3) int
        Rows ``(source vertex, its image under the chosen map, its image
        under the rival)`` where the two disagree most (local numbering of
        the matched meshes); empty without a rival.
    probability : float
        The probability that the chosen global configuration is the right
        one (module docstring); 1 without a rival.
    """

    margin: float
    rival: str | None
    suggestions: np.ndarray
    probability: float = 1.0

    @property
    def low(self) -> bool:
        """Whether the choice is unsure (margin below :data:`LOW_MARGIN`)."""
        return bool(self.margin < LOW_MARGIN)

    def to_dict(self) -> dict:
        return {"margin": None if not np.isfinite(self.margin) else round(float(self.margin), 4),
                "probability": round(float(self.probability), 4), "low": self.low, "rival": self.rival,
                "suggested_landmarks": [{"source": int(s), "chosen": int(a), "rival": int(b)}
                                        for s, a, b in self.suggestions]}


def choice_confidence(candidates: list, chosen, energies: dict, source_geodesics: Callable[[int], np.ndarray],
                      target_geodesics: Callable[[int], np.ndarray], sources: np.ndarray) -> Confidence:
    """The margin of ``chosen`` over its best rival and the landmarks that would settle it.

    Parameters
    ----------
    candidates : list of MapCandidate
        The scored candidates the energy chooses among
        (:func:`meshcorr.choice.selection.eligible`), ``chosen`` among them.
    chosen : MapCandidate
    energies : dict
        ``id(candidate) -> energy`` (:func:`meshcorr.choice.selection.energy`, minus a
        log-probability).
    source_geodesics, target_geodesics : callable
        ``f(i)``: normalised geodesic distances from vertex i, ``(n,)``.
    sources : (m,) int
        Seeded source vertices at which maps are compared.

    Returns
    -------
    confidence : Confidence
    """
    sources = np.asarray(sources, dtype=np.int64)
    images = chosen.mapping[sources]
    rows = [np.asarray(target_geodesics(int(t))) for t in images]
    best, best_gaps, rivals = None, None, set()
    for candidate in candidates:
        if candidate is chosen:
            continue
        gaps = np.array([row[candidate.mapping[s]] for row, s in zip(rows, sources)])
        if gaps.mean() > RIVAL_DISTANCE:
            rivals.add(id(candidate))
            if best is None or energies[id(candidate)] < energies[id(best)]:
                best, best_gaps = candidate, gaps
    if best is None:
        return no_rival()
    values = np.array([-energies[id(c)] for c in candidates])
    weights = np.exp(values - values.max())
    kept = np.array([id(c) not in rivals for c in candidates])
    probability = float(weights[kept].sum() / weights.sum())
    margin = float(energies[id(best)] - energies[id(chosen)])
    picked: list[int] = []
    for index in np.argsort(-best_gaps, kind="stable"):
        if len(picked) == N_SUGGESTIONS or best_gaps[index] <= RIVAL_DISTANCE:
            break
        row = np.asarray(source_geodesics(int(sources[index])))
        if all(row[sources[other]] >= SUGGESTION_SPACING for other in picked):
            picked.append(int(index))
    chosen_sources = sources[picked]
    suggestions = np.stack([chosen_sources, chosen.mapping[chosen_sources], best.mapping[chosen_sources]], axis=1)
    return Confidence(margin, best.origin, suggestions.astype(np.int64), probability)


def no_rival() -> Confidence:
    """The confidence of a choice no other configuration competed with: infinite margin, probability 1."""
    return Confidence(float("inf"), None, np.empty((0, 3), dtype=np.int64))


def unsure_message(report: dict) -> str:
    """The warning of an unsure choice, from ``result.confidence`` (:meth:`Confidence.to_dict`, input numbering,
    with ``cycle_error`` when the pair was also matched the other way round)."""
    rows = report["suggested_landmarks"]
    pick = "meshcorr pick SOURCE TARGET --map MAP -o LANDMARKS.txt (in Python: result.pick())"
    cycle = report.get("cycle_error")
    if cycle is not None and (not (report["margin"] is not None and report["margin"] < LOW_MARGIN) or not rows):
        where = ("" if not rows else " They disagree with the best other map most at source vertices "
                 + ", ".join(str(row["source"]) for row in rows) + ".")
        return (f"The global choice of the map is unsure: the map back from the target disagrees with it (a round "
                f"trip moves source vertices by {cycle:.2f} of sqrt(area) on average): one of the two is turned "
                f"front to back, mirrored or has limbs exchanged.{where} Look at the map and click a few "
                f"landmarks on it: {pick}; then landmarks=[(source, target), ...] or --landmarks FILE, one "
                "'source target' pair a line.")
    sources = ", ".join(str(row["source"]) for row in rows)
    chosen = ", ".join(str(row["chosen"]) for row in rows)
    rival = ", ".join(str(row["rival"]) for row in rows)
    probability = report.get("probability")
    odds = "" if probability is None else f"; the chosen configuration's probability is {probability:.2f}"
    return (f"The global choice of the map is unsure: a map of another configuration ({report['rival']!r}: "
            f"a mirror image, a front/back turn or limbs exchanged) is almost as likely (log-probability "
            f"ratio {report['margin']:.2f}, below {LOW_MARGIN} is unsure{odds}). They disagree most at source vertices "
            f"{sources}, which the chosen map sends to target vertices {chosen} and the other to {rival}. "
            f"Look at the map and click landmarks on those vertices: {pick}; then "
            "landmarks=[(source, target), ...] or --landmarks FILE, one 'source target' pair a line.")
