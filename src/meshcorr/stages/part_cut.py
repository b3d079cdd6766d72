"""The cut of a part: the band along its boundary where it stops agreeing with the whole.

A part :math:`P` of a whole shape :math:`W` (``match(..., partial="source")``,
docs/method.md, "Partial shapes") keeps the whole's geodesic distances away
from its cut only: near the boundary a shortest path of the whole may run
through the missing region, so the part's distance is longer, and the cut
makes new maxima of the average geodesic distance (false tips). With
:math:`d(i)` the distance of vertex :math:`i` to the boundary along the
surface (:func:`meshcorr.core.boundary.boundary_distance`) and
:math:`b` = :data:`BOUNDARY_BAND`,

.. math::

    I = \\{ i : d(i) > b \\sqrt{\\operatorname{area}(P)} \\}, \\qquad
    w_i = \\operatorname{clip}\\left( \\frac{d(i)}{b \\sqrt{\\operatorname{area}(P)}},
    w_{\\min}, 1 \\right),

the interior :math:`I` (:func:`interior_vertices`: where tips, landmarks and
distortion are taken) and the weights :math:`w` of the part's vertices in
the refinements' fits (:func:`cut_weights`, :math:`w_{\\min}` =
:data:`MIN_CUT_WEIGHT`).
"""

from __future__ import annotations

import numpy as np

from ..core.boundary import boundary_distance
from ..core.mesh import Mesh

#: Vertices of the part closer than this x sqrt(area of the part) to its boundary are "near the cut".
BOUNDARY_BAND = 0.08
#: Weight of a vertex on the cut in the refinements' fits (:func:`cut_weights`).
MIN_CUT_WEIGHT = 0.1


def interior_vertices(part: Mesh, *, band: float = BOUNDARY_BAND) -> np.ndarray:
    """``(p,)`` int: the vertices farther than ``band`` x sqrt(area) from the boundary.

    All vertices when fewer than a tenth of them are that far (a thin strip).
    """
    far = np.flatnonzero(boundary_distance(part) > band * np.sqrt(part.area))
    return far if len(far) >= max(10, part.n_vertices // 10) else np.arange(part.n_vertices)


def cut_weights(part: Mesh) -> np.ndarray:
    """``(n_part,)`` float: each vertex's weight in a fit, from :data:`MIN_CUT_WEIGHT` on the cut to 1 away from it.

    The distance to the boundary over :data:`BOUNDARY_BAND` x sqrt(area), clipped to [:data:`MIN_CUT_WEIGHT`, 1].
    """
    return np.clip(boundary_distance(part) / (BOUNDARY_BAND * np.sqrt(part.area)), MIN_CUT_WEIGHT, 1.0)
