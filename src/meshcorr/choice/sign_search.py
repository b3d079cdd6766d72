"""A wider search for the global configuration: every sign of the first Laplace-Beltrami functions.

The candidate maps of the whole-map choice (:mod:`meshcorr.choice.whole_map`)
come from the spectral pipeline and from matched extremities; when the
right global configuration is among none of them (a person turned front to
back by every start), no energy can choose it. After Smooth Shells
(Eisenberger, Lähner, Cremers, CVPR 2020), this search proposes the
configurations of the first :data:`N_SIGNS` Laplace-Beltrami functions'
signs: for each sign vector :math:`s`, the map that sends each source
vertex to the nearest target vertex in the signed spectral coordinates
:math:`(s_1 \\phi^1_1, \\dots, s_K \\phi^1_K)` against
:math:`(\\phi^2_1, \\dots, \\phi^2_K)`, refined by a short ZoomOut and, when
it keeps the orientation, aligned by the smooth shells on the coarse
scales (:func:`meshcorr.stages.shells.shell_refine`). The
:data:`N_KEPT` maps of least alignment energy (what is left of the
alignment in the shells' product space) become starts of the whole-map
choice, where they are refined and judged like every other candidate.
All of it runs on coarse copies of :data:`SEARCH_VERTICES` vertices
(:mod:`meshcorr.core.coarse`), so its cost does not grow with the meshes.

Shapes whose Laplace-Beltrami functions do not correspond (a gorilla and
a person) give no useful configuration here; the extremity starts cover
them.
"""

from __future__ import annotations

import itertools

import numpy as np

from ..core.coarse import coarse_copy
from ..core.map_orientation import orientation_score
from ..core.mesh import Mesh
from ..spectral.basis import pair_bases
from ..spectral.nearest import nearest_vertices
from ..stages.refine import zoomout
from ..stages.shells import shell_refine

__all__ = ["N_KEPT", "N_SIGNS", "SEARCH_VERTICES", "sign_search_starts"]

#: Laplace-Beltrami functions (after the constant) whose signs are searched: 2^N_SIGNS configurations.
N_SIGNS = 6
#: Configurations of least alignment energy kept as starts of the whole-map choice.
N_KEPT = 2
#: Vertices of the coarse copies the search runs on.
SEARCH_VERTICES = 1000
#: Two kept maps are one when they agree on more than this share of the vertices.
SAME_MAP = 0.5
#: Basis size of the search's ZoomOut and shells.
SEARCH_K = 20
#: The coarse steps of the search's smooth shells (a short schedule: 64 configurations each get one).
SEARCH_SCALES = (6, 10, 14, 18)


def sign_search_starts(source: Mesh, target: Mesh, *, reliable: bool,
                       random_state: int | None = 0) -> list[tuple[str, np.ndarray, dict]]:
    """The starts of the whole-map choice from the sign search (module docstring).

    Parameters
    ----------
    source, target : Mesh
        Triangle meshes.
    reliable : bool
        Whether both outsides are defined (configurations that reverse the
        orientation are then dropped).
    random_state : int or None

    Returns
    -------
    starts : list of (origin, (n1,) int map, extra)
        ``"signs-r"``, the r-th of least alignment energy, with
        ``extra["search_alignment"]``; empty when a mesh cannot be copied.
    """
    copies = coarse_copy(source, SEARCH_VERTICES, above=1.2), coarse_copy(target, SEARCH_VERTICES, above=1.2)
    if None in copies:
        return []
    one, two = copies
    k = min(SEARCH_K, one.mesh.n_vertices - 1, two.mesh.n_vertices - 1)
    p1, p2 = pair_bases(one.mesh, two.mesh, k, random_state=random_state)
    n_signs = min(N_SIGNS, k - 2)
    scored = []
    for signs in itertools.product((1.0, -1.0), repeat=n_signs):
        signed = p1[:, :n_signs + 1] * np.array((1.0,) + signs)
        start = nearest_vertices(signed, p2[:, :n_signs + 1])
        mapping, _ = zoomout(p1, p2, start, k_start=n_signs + 1, step=1, n_sample=300, random_state=random_state)
        orientation = orientation_score(one.mesh, two.mesh, mapping, random_state=random_state) if reliable else None
        if orientation is not None and orientation < 0.5:
            continue
        energy: dict = {}
        mapping = shell_refine(one.mesh, two.mesh, mapping, k=k, scales=SEARCH_SCALES, energy=energy,
                               orientation=orientation, random_state=random_state)
        scored.append((energy["alignment"], len(scored), mapping))
    scored.sort(key=lambda item: item[:2])
    kept: list[tuple[float, np.ndarray]] = []
    for value, _, mapping in scored:  # distinct maps: several sign vectors often refine to one map
        if len(kept) < N_KEPT and all(np.mean(mapping == other) < SAME_MAP for _, other in kept):
            kept.append((value, mapping))
    return [(f"signs-{rank}", one.lift_map(mapping, two), {"search_alignment": value})
            for rank, (value, mapping) in enumerate(kept)]
