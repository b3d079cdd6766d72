"""The metric distortion of a part -> whole map, with the unknown scale between part and whole fitted.

With :math:`g_P` the geodesic distances on the part from a few seeded
interior vertices (:func:`distortion_sources`, :data:`N_DISTORTION_SOURCES`
of them) to the interior vertices, and :math:`g_W` those between their
images on the whole (docs/method.md, "Partial shapes", step 4),

.. math::

    s^* = \\arg\\min_s \\sum |g_P - s \\, g_W|, \\qquad
    \\text{distortion} = \\frac{\\operatorname{mean} |g_P - s^* g_W|}{\\operatorname{mean} g_P}

(:func:`fitted_distortion`): a score of the candidate maps and, as
:math:`1 / s^*`, the scale of the chosen one (whole length per part length).
"""

from __future__ import annotations

import numpy as np

from .part_checks import RowFn

#: Source vertices whose geodesic rows measure a candidate's distortion.
N_DISTORTION_SOURCES = 16


def distortion_sources(interior: np.ndarray, random_state: int | None) -> np.ndarray:
    """``(min(N, p),)`` int: the seeded interior vertices whose geodesic rows measure distortion and scale.

    ``N`` is :data:`N_DISTORTION_SOURCES`, ``p`` the number of ``interior`` vertices.
    """
    rng = np.random.default_rng(random_state)
    return rng.choice(interior, size=min(N_DISTORTION_SOURCES, len(interior)), replace=False)


def fitted_distortion(part_rows: RowFn, whole_rows: RowFn, mapping: np.ndarray, sources: np.ndarray,
                      interior: np.ndarray) -> tuple[float, float]:
    """Metric distortion of a part -> whole map with the scale fitted, and that scale.

    With :math:`g_P` and :math:`g_W` the geodesic distances from the ``sources``
    to the ``interior`` vertices and between their images,

    .. math::

        s^* = \\arg\\min_s \\sum |g_P - s \\, g_W|, \\qquad
        \\text{distortion} = \\frac{\\operatorname{mean} |g_P - s^* g_W|}{\\operatorname{mean} g_P}

    (a weighted median; Bronstein, Bronstein & Kimmel, PNAS 2006, for the
    distortion). Vertices near the cut are left out: their distances on the
    part can be longer than on the whole, the shortcut through the missing
    region being gone.

    Returns
    -------
    distortion : float
        About 0 for an isometric map, near 1 for a map that collapses.
    scale : float
        :math:`1 / s^*`: whole length per part length.
    """
    gp = np.concatenate([part_rows(int(i))[interior] for i in sources])
    gw = np.concatenate([whole_rows(int(mapping[i]))[mapping[interior]] for i in sources])
    ok = gw > 0
    if not ok.any():
        return 1.0, 1.0
    ratio = gp[ok] / gw[ok]
    order = np.argsort(ratio, kind="stable")
    weights = np.cumsum(gw[ok][order])
    s = float(ratio[order][np.searchsorted(weights, 0.5 * weights[-1])])
    return float(np.abs(gp - s * gw).mean() / max(gp.mean(), 1e-300)), 1.0 / max(s, 1e-300)
