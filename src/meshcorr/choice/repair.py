"""Repair of a partly mirrored map, started again from the part of it that keeps the orientation.

A map can be right on most of a shape and mirrored on a part of it: the
legs of a person or the hind legs of a dog swapped left for right under a
right upper body. Its whole-surface orientation score stays high (the part
is small), but the worst of its regions reverses the orientation
(:func:`meshcorr.core.map_orientation.regional_orientation`). ZoomOut does not undo
such a swap: at every scale the swapped part pulls the functional map its
own way.

This module starts again from the consistent part only. The sampled source
vertices whose mapped neighbourhood keeps the orientation, in regions that
keep it on the whole (:func:`meshcorr.core.map_orientation.consistent_vertices`),
give the orthogonal functional map :math:`C` of the first
:data:`REPAIR_K` Laplace-Beltrami functions,
:math:`\\Phi_1[S] C \\approx \\Phi_2[T(S)]` (the swapped part left out); a
map that coarse cannot tell the swapped legs apart from the rest of the
shape's structure, so it sends them the way the consistent part says. The
map of that :math:`C` is refined by ZoomOut as any other start
(:func:`meshcorr.stages.refine.zoomout`, from :data:`REPAIR_K` functions).

The repaired map does not replace the one it comes from: it is one more
candidate of the whole-map choice (:mod:`meshcorr.choice.selection`), which keeps
whichever the energies prefer. This is the "refinement started from the
consistent part" of the robust-maps issue; measured in
``benchmarks/RESULTS-robustness.md`` (TOSCA dog5 -> dog8, hind legs swapped
under a right front half: error 0.149 -> 0.024).
"""

from __future__ import annotations

import numpy as np

from ..runtime.threads import parallel_map
from ..core.mesh import Mesh
from ..core.map_orientation import consistent_vertices
from ..runtime.checks import check_vertex_map
from ..spectral.basis import basis_size, orthogonal_fit, pair_bases
from ..spectral.nearest import nearest_vertices
from ..stages.refine import REFINED_MAP, zoomout
from .selection import MapCandidate

#: Laplace-Beltrami functions of the functional map fitted on the consistent part.
REPAIR_K = 8
#: A map is repaired when its worst region keeps the orientation on less than this area fraction.
REPAIR_BELOW = 0.5


def repair_map(source: Mesh, target: Mesh, mapping: np.ndarray, *, k: int = 40, k_start: int = REPAIR_K,
               random_state: int | None = 0) -> np.ndarray | None:
    """A map started again from the part of ``mapping`` that keeps the orientation (module docstring).

    Parameters
    ----------
    source, target : Mesh
        With a reliable outside (:func:`meshcorr.core.orientation.mesh_orientation`).
    mapping : (n1,) int
        ``mapping[i]``: target vertex of source vertex i.
    k : int
        Final Laplace-Beltrami basis size of the ZoomOut refinement (the
        pipeline's ``refine_k``; clipped to the vertex counts).
    k_start : int
        Functions of the functional map fitted on the consistent part.
    random_state : int or None
        Seed of the bases, the orientation sample and ZoomOut's samples.

    Returns
    -------
    repaired : (n1,) int or None
        The new map; None when fewer than ``3 * k_start`` sampled vertices
        are consistent (nothing to start from).
    """
    mapping = check_vertex_map(mapping, source.n_vertices, target.n_vertices, messages=REFINED_MAP)
    k = basis_size(k, source, target)
    k_start = min(k_start, k)
    good = consistent_vertices(source, target, mapping, random_state=random_state)
    if len(good) < 3 * k_start:
        return None
    phi1, phi2 = pair_bases(source, target, k, random_state=random_state)
    C = orthogonal_fit(phi1[good, :k_start], phi2[mapping[good], :k_start])
    start = nearest_vertices(phi1[:, :k_start] @ C, phi2[:, :k_start], random_state=random_state)
    return zoomout(phi1, phi2, start, k_start=k_start, random_state=random_state)[0]


def repair_candidates(candidates: list[MapCandidate], source: Mesh, target: Mesh, *, k: int = 40,
                      random_state: int | None = 0) -> list[MapCandidate]:
    """The repairs of the partly mirrored candidates of the whole-map choice, as new candidates.

    Parameters
    ----------
    candidates : list of MapCandidate
        Scored (orientation and regional orientation measured).
    source, target : Mesh
    k : int
        As :func:`repair_map`.
    random_state : int or None

    Returns
    -------
    repaired : list of MapCandidate
        For each candidate that keeps the orientation on the whole (score
        >= 0.5) but reverses it in a region (:data:`REPAIR_BELOW`), the map of
        :func:`repair_map`, named ``"repaired-<origin>"``, not yet scored.
    """
    broken = [c for c in candidates if c.orientation >= 0.5 and c.regional_orientation < REPAIR_BELOW]
    maps = parallel_map(lambda c: repair_map(source, target, c.mapping, k=k, random_state=random_state), broken)
    return [MapCandidate(f"repaired-{c.origin}", mapping, extra=dict(c.extra))
            for c, mapping in zip(broken, maps) if mapping is not None]
