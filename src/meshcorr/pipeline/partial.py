"""Matching a part of a shape to the whole shape (``match(..., partial="source")``).

A scan seen from one side, a body cut by the field of view or a surface with
large holes is a *part* :math:`P` of a whole shape :math:`W`. The global steps
of the whole-to-whole pipeline do not hold on a part: the Jain-Zhang
affinities are scaled by the largest geodesic distance and their
eigenvectors are global, so the part's embedding is not the restriction of
the whole's (a TOSCA cat cut to 70 % maps onto the whole cat with a mean
error of 0.1-0.6 instead of 0.03); and the part's Laplace-Beltrami spectrum
is "stretched": its first :math:`k` eigenfunctions correspond to about the
first :math:`k / r` of the whole's, :math:`r = \\operatorname{area}(P) /
\\operatorname{area}(W)` in common units (Rodolà, Cosmo, Bronstein, Torsello
& Cremers, "Partial functional correspondence", Computer Graphics Forum 36(1),
2017: the functional map of a part is slanted-diagonal with that slope).
What does hold is that geodesic distances between points of the part away
from its cut are (nearly) those of the whole. The partial mode is built on
that (docs/method.md, "Partial shapes"):

1. **Extremities** (:mod:`meshcorr.choice.part_tips`): the tips of the whole, and
   those of the part that lie farther than
   :data:`~meshcorr.stages.part_cut.BOUNDARY_BAND` x sqrt(area(P)) from its
   boundary (a cut makes new maxima of the average geodesic distance along
   it; :mod:`meshcorr.stages.part_cut`).
2. **Tip assignments** (:func:`meshcorr.choice.part_tips.match_part_tips`): a
   consensus search over triangles of tips (after RANSAC): each triangle of the part's tips
   against each triangle of the whole's whose sides agree up to a common
   scale, the other tips joining where their distances agree too (tips of
   either side may have no counterpart); the assignments with the most tips
   win, ties broken by the distortion of their geodesic distances, each
   side divided by its own sum (the scale between part and whole is
   unknown).
3. **Dense maps** (:mod:`meshcorr.stages.part_landmarks`): each assignment
   becomes a map by nearest geodesic-distance descriptors, then
   :func:`~meshcorr.stages.part_landmarks.geodesic_refine` re-takes
   :data:`~meshcorr.stages.part_landmarks.N_REFINE_LANDMARKS`
   farthest-point landmarks away from the boundary with their current images
   and maps again: a few well-spread landmarks fix the map far better than
   the few tips do.
4. **The choice** (:mod:`meshcorr.choice.part_candidates`,
   :mod:`meshcorr.choice.selection`): orientation (a part of a closed shape
   has a well-defined outside once its boundary loops are capped,
   :mod:`meshcorr.core.orientation`), curvature disagreement and the metric
   distortion of :func:`meshcorr.stages.part_distortion.fitted_distortion`,
   which fits the unknown scale and leaves out the vertices near the cut.
5. **Partial ZoomOut** (:func:`meshcorr.stages.partial_zoomout.partial_zoomout`):
   the chosen map is refined in Laplace-Beltrami bases of :math:`k` functions on the part and
   :math:`\\lceil k / r \\rceil` on the whole, :math:`r` the area fraction of
   the matched region, with a rectangular functional map whose rows are
   orthonormal up to a common scale (the slanted-diagonal structure above
   gives :math:`C C^\\top \\approx I / r`), and with the whole's vertices
   restricted to the matched region (the part's "indicator function" of
   Rodolà et al., here estimated from the map instead of optimised). Vertices
   near the cut are weighted down in every fit
   (:func:`meshcorr.stages.part_cut.cut_weights`).
6. **Smooth shells** (:func:`meshcorr.stages.shells.shell_refine` with
   ``part_fraction``): the part's shells aligned with the whole's, from 16
   functions on the part (and :math:`\\lceil k / r \\rceil` on the whole) to
   the coordinates themselves, the whole's vertices restricted to the
   region matched by the zoomed-out map and the cut weighted down as above
   (meshes only).
7. **The matched region** (:func:`meshcorr.stages.part_region.matched_region`):
   the whole's vertices reached by the map, joined by a morphological closing along the surface,
   reported as a vertex mask and its area fraction.

Litany, Rodolà, Bronstein & Bronstein ("Fully spectral partial shape
matching", Computer Graphics Forum 36(2), 2017) solve for the part's basis
jointly with the map; that optimisation is not used here.

This module is the orchestration (:func:`match_part`); each step lives in
the module named above.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from math import ceil
from typing import Sequence

import numpy as np

from ..choice.part_candidates import orientation_reliable, part_candidate
from ..choice.part_tips import match_part_tips, part_extremities, whole_extremities
from ..choice.selection import candidate_summaries, choose_map
from ..core.mesh import Mesh
from ..errors import PartialityError
from ..runtime.threads import parallel_map
from ..runtime.timing import StageTimer
from ..spectral.basis import laplace_basis
from ..stages.part_checks import RowFn
from ..stages.part_cut import cut_weights, interior_vertices
from ..stages.part_distortion import distortion_sources, fitted_distortion
from ..stages.part_region import area_fraction, matched_share, part_region
from ..stages.partial_zoomout import partial_zoomout
from ..stages.shells import shell_refine


@dataclass
class PartialMap:
    """The outcome of :func:`match_part`.

    Attributes
    ----------
    mapping : (n_part,) int
        Whole vertex of each part vertex (local numbering).
    alternative : (n_part,) int or None
        The best candidate of the other orientation (usually the mirror image).
    region : (n_whole,) bool
        The whole's vertices with a counterpart on the part.
    area_fraction : float
        Area of ``region`` over the whole's area.
    scale : float
        Whole length per part length, fitted to the geodesic distances of the map.
    candidates : list of dict
        Each candidate map's origin and scores (:class:`meshcorr.choice.selection.MapCandidate`).
    reliable : bool
        Whether the orientation of both meshes could be trusted.
    history : list of dict
        Per partial ZoomOut iteration: basis sizes and the fraction of samples whose image changed.
    """

    mapping: np.ndarray
    alternative: np.ndarray | None
    region: np.ndarray
    area_fraction: float
    scale: float
    candidates: list = field(default_factory=list)
    reliable: bool = True
    history: list = field(default_factory=list)


def match_part(part: Mesh, whole: Mesh, part_rows: RowFn, whole_rows: RowFn, *, landmarks: np.ndarray | None = None,
               extremities: bool = True, initial_maps: Sequence[tuple[str, np.ndarray]] = (), refine: bool = True,
               refine_k: int = 40, shells: bool = True, random_state: int | None = 0,
               timer: StageTimer | None = None) -> PartialMap:
    """Map a part of a shape into the whole shape (module docstring, steps 1-7).

    Parameters
    ----------
    part, whole : Mesh
    part_rows, whole_rows : callable
        Geodesic rows of each in its own units (:func:`meshcorr.stages.part_checks.geodesic_rows`).
    landmarks : (L, 2) int, optional
        Known (part vertex, whole vertex) pairs: a candidate map of their own,
        decisive in the choice (:mod:`meshcorr.choice.selection`).
    extremities : bool
        Start candidate maps from matched tips.
    initial_maps : sequence of (str, (n_part,) int)
        Further starts, named (e.g. the map of the part matched as a whole
        shape, which holds when the cut leaves the shape's global structure).
    refine : bool
        Finish with :func:`meshcorr.stages.partial_zoomout.partial_zoomout`.
    refine_k : int
        Its basis size on the part.
    shells : bool
        Then align the part's smooth shells with the whole's
        (:func:`meshcorr.stages.shells.shell_refine` with ``part_fraction``; meshes
        only, stage "shells").
    random_state : int or None
    timer : StageTimer, optional
        Receives the stages "extremities", "candidates", "refine", "shells" and "region".

    Returns
    -------
    result : PartialMap

    Raises
    ------
    PartialityError
        No candidate map: fewer than three tips of the part could be assigned and no landmarks.
    """
    timer = timer or StageTimer()
    with timer.stage("extremities"):
        interior = interior_vertices(part)
        starts = _starts(part, whole, part_rows, whole_rows, interior, landmarks, extremities, initial_maps,
                         random_state)
    if not starts:
        raise PartialityError(
            f"No start for a partial map of {part.name!r}: fewer than three of its tips lie away from its "
            "boundary. Give a few corresponding vertices (landmarks=[(i, j), ...], CLI --landmarks).")
    with timer.stage("candidates"):
        reliable = orientation_reliable(part, whole)
        candidates = [part_candidate(origin, pairs, start, extra, part, whole, part_rows, whole_rows, interior,
                                     landmarks, reliable=reliable, random_state=random_state)
                      for origin, pairs, start, extra in starts]
        chosen, alternative = choose_map(candidates, reliable=reliable)
        mapping, scale = chosen.mapping, chosen.extra.pop("scale")
        for candidate in candidates:
            candidate.extra.pop("scale", None)
    history: list[dict] = []
    if refine:
        mapping, history = _refine(part, whole, mapping, scale, landmarks, refine_k=refine_k, shells=shells,
                                   random_state=random_state, timer=timer)
    with timer.stage("region"):
        _, scale = fitted_distortion(part_rows, whole_rows, mapping, distortion_sources(interior, random_state),
                                     interior)
        region = part_region(part, whole, mapping, scale)
    summaries = candidate_summaries(candidates, chosen, alternative, reliable=reliable)
    return PartialMap(mapping=mapping, alternative=None if alternative is None else alternative.mapping,
                      region=region, area_fraction=area_fraction(whole, region), scale=scale,
                      candidates=summaries, reliable=reliable, history=history)

def _starts(part: Mesh, whole: Mesh, part_rows: RowFn, whole_rows: RowFn, interior: np.ndarray,
            landmarks: np.ndarray | None, extremities: bool, initial_maps: Sequence[tuple[str, np.ndarray]],
            random_state: int | None) -> list[tuple[str, np.ndarray | None, np.ndarray | None, dict]]:
    """The starts of the candidate maps (steps 1-2): (origin, pairs or None, start map or None, scores).

    The landmarks first, then the given maps, then the tip assignments of
    :func:`meshcorr.choice.part_tips.match_part_tips`, best first.
    """
    starts: list[tuple[str, np.ndarray | None, np.ndarray | None, dict]] = []
    if landmarks is not None:
        starts.append(("landmarks", landmarks, None, {}))
    starts += [(origin, None, np.asarray(mapping, dtype=np.int64), {}) for origin, mapping in initial_maps]
    if extremities:
        tips = part_extremities(part, part_rows, interior, random_state=random_state)
        whole_tips = whole_extremities(whole, whole_rows, random_state=random_state)
        for rank, (energy, pairs) in enumerate(match_part_tips(tips, whole_tips)):
            starts.append((f"extremities-{rank}", pairs, None, {"extremity_energy": energy, "n_tips": len(pairs)}))
    return starts


def _refine(part: Mesh, whole: Mesh, mapping: np.ndarray, scale: float, landmarks: np.ndarray | None, *,
            refine_k: int, shells: bool, random_state: int | None, timer: StageTimer
            ) -> tuple[np.ndarray, list[dict]]:
    """Steps 5-6: the partial ZoomOut in the region the map reaches, then the part's smooth shells.

    Both keep the whole's vertices to the region of the map they start from
    (:func:`meshcorr.stages.part_region.matched_share`) and weight the part's
    vertices down near the cut (:func:`meshcorr.stages.part_cut.cut_weights`).
    """
    with timer.stage("refine"):
        region, ratio = matched_share(part, whole, mapping, scale)
        k = min(refine_k, part.n_vertices - 1)
        k_whole = min(int(ceil(k / ratio)), whole.n_vertices - 1)
        part_basis, whole_basis = parallel_map(
            lambda item: laplace_basis(item[0], item[1], random_state=random_state)[1],
            ((part, k), (whole, k_whole)))
        weights = cut_weights(part)
        mapping, history = partial_zoomout(part_basis, whole_basis, mapping, ratio=ratio, allowed=region,
                                           weights=weights, random_state=random_state)
        if landmarks is not None:
            mapping[landmarks[:, 0]] = landmarks[:, 1]
    if shells and not (part.is_cloud or whole.is_cloud):
        with timer.stage("shells"):  # in the region of the zoomed-out map, with the same weights
            region, ratio = matched_share(part, whole, mapping, scale)
            mapping = shell_refine(part, whole, mapping, k=k, landmarks=landmarks, part_fraction=ratio,
                                   region=region, weights=weights, random_state=random_state)
    return mapping, history
