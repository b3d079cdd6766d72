"""The map the other way round as a check of the global choice.

The whole-map choice of a pair (:mod:`meshcorr.choice.whole_map`) and that
of the reversed pair are made apart, from other starts and energies. When
both are right, or both turned the same way, the map from the source to
the target and the map back send a source vertex about where it started;
when one of them turned the shape front to back, exchanged limbs or
mirrored it and the other did not, the round trip sends many vertices to
the other side of the source. The **cycle error**

.. math::

    c = \\frac{1}{|S|} \\sum_{i \\in S} \\frac{g_1(i, T_{21}(T_{12}(i)))}{\\sqrt{A_1}}

over :data:`N_CYCLE_SOURCES` seeded source vertices :math:`S` (geodesic
distance on the source over the square root of its area) is then large.
It does not say which of the two maps is wrong, only that they disagree:
above :data:`CYCLE_LIMIT` the choice is reported as unsure. Measured on the
SHREC'07 and TOSCA gorilla -> human pairs of ``benchmarks/robustness.py``
(``benchmarks/cycle_study.py``, ``benchmarks/RESULTS-robustness.md``), it
flags far more of the wrong maps than the energy margin
(:mod:`meshcorr.choice.confidence`), at the cost of a second match.
"""

from __future__ import annotations

import numpy as np

from ..core.mesh import Mesh
from ..stages.part_checks import geodesic_rows

__all__ = ["CYCLE_LIMIT", "N_CYCLE_SOURCES", "cycle_error"]

#: Source vertices the round trip is measured at.
N_CYCLE_SOURCES = 64
#: Cycle errors above this (geodesic distance over sqrt(area)) make the choice unsure: chosen on half "a" of
#: every set (the most wrong maps flagged with at most 10 % of the right ones; benchmarks/cycle_study.py).
CYCLE_LIMIT = 0.4


def cycle_error(source: Mesh, forward: np.ndarray, backward: np.ndarray, *, geodesic: str = "heat",
                random_state: int | None = 0) -> float:
    """Mean geodesic distance on the source between seeded vertices and their round trip (module docstring).

    Parameters
    ----------
    source : Mesh
        The source as matched; ``source.kept[v]`` is the input index of its vertex v.
    forward : (n1_input,) int
        Source -> target map in the inputs' numbering (-1: unmapped).
    backward : (n2_input,) int
        Target -> source map in the inputs' numbering (-1: unmapped).
    geodesic : str
        Geodesic solver of the distances.
    random_state : int or None
        Seed of the vertices measured.

    Returns
    -------
    error : float
        Over sqrt(source area); NaN when no sampled vertex makes the round trip.
    """
    forward, backward = np.asarray(forward, dtype=np.int64), np.asarray(backward, dtype=np.int64)
    to_local = np.full(max(int(source.kept.max()) + 1, len(forward)), -1, dtype=np.int64)
    to_local[source.kept] = np.arange(source.n_vertices)
    images = forward[source.kept]
    returned = np.full(source.n_vertices, -1, dtype=np.int64)
    mapped = images >= 0
    back = backward[images[mapped]]
    returned[np.flatnonzero(mapped)] = np.where(back >= 0, to_local[np.maximum(back, 0)], -1)
    candidates = np.flatnonzero(returned >= 0)
    if len(candidates) == 0:
        return float("nan")
    rng = np.random.default_rng(random_state)
    sample = rng.choice(candidates, size=min(N_CYCLE_SOURCES, len(candidates)), replace=False)
    rows = geodesic_rows(source, geodesic)
    distances = [float(rows(int(v))[returned[v]]) for v in sample]
    return float(np.mean(distances) / np.sqrt(source.area))
