"""The candidate maps of a part into the whole, each made dense and scored for the choice.

Each start of the partial mode (docs/method.md, "Partial shapes", steps
3-4) is a set of (part vertex, whole vertex) pairs (matched tips,
:mod:`meshcorr.choice.part_tips`; user landmarks) or a whole map (the
default mode's map of the part). :func:`part_candidate` makes it a dense map
(:func:`meshcorr.stages.part_landmarks.part_landmark_map`), refines it from
many spread landmarks (:func:`meshcorr.stages.part_landmarks.geodesic_refine`)
and scores it for :func:`meshcorr.choice.selection.choose_map`: the metric
distortion with the part's scale fitted
(:func:`meshcorr.stages.part_distortion.fitted_distortion`), the
orientation when both meshes have a trustworthy outside
(:func:`orientation_reliable`), and with landmarks :math:`(a_l, b_l)` their
mean error :math:`\\operatorname{mean}_l g_W(T(a_l), b_l) / D` (:math:`D`
the largest distance from the :math:`b_l`) and the share of them kept within
:data:`~meshcorr.choice.selection.LANDMARK_RADIUS` x :math:`D`.
"""

from __future__ import annotations

import numpy as np

from ..core.mesh import Mesh
from ..core.orientation import mesh_orientation
from ..stages.part_checks import RowFn
from ..stages.part_distortion import distortion_sources, fitted_distortion
from ..stages.part_landmarks import geodesic_refine, part_landmark_map
from .selection import LANDMARK_RADIUS, MapCandidate, score_orientation


def orientation_reliable(*meshes: Mesh) -> bool:
    """Whether the outside of every mesh can be trusted (:func:`meshcorr.core.orientation.mesh_orientation`)."""
    return all(mesh_orientation(mesh).reliable for mesh in meshes)


def part_candidate(origin: str, pairs: np.ndarray | None, start: np.ndarray | None, extra: dict, part: Mesh,
                   whole: Mesh, part_rows: RowFn, whole_rows: RowFn, interior: np.ndarray,
                   landmarks: np.ndarray | None, *, reliable: bool, random_state: int | None) -> MapCandidate:
    """One candidate map from landmark pairs or a start map, made dense, refined and scored (module docstring).

    Parameters
    ----------
    origin : str
        The start's name ("landmarks", "extremities-0", ...); "landmarks" keeps its pairs exactly.
    pairs : (L, 2) int or None
        (part vertex, whole vertex) pairs of the start, when ``start`` is None.
    start : (n_part,) int or None
        A start map, used instead of ``pairs``.
    extra : dict
        Scores of the start kept with the candidate (copied).
    part, whole : Mesh
    part_rows, whole_rows : callable
        Geodesic rows of each in its own units (:func:`meshcorr.stages.part_checks.geodesic_rows`).
    interior : (p,) int
        The part's vertices away from its cut (:func:`meshcorr.stages.part_cut.interior_vertices`).
    landmarks : (L, 2) int or None
        The user's landmarks, scored on every candidate.
    reliable : bool
        Whether the orientation is scored (:func:`orientation_reliable`).
    random_state : int or None

    Returns
    -------
    candidate : MapCandidate
        With ``extra["scale"]``, whole length per part length.
    """
    if start is None:
        start, _ = part_landmark_map(part_rows, whole_rows, pairs)
    mapping = geodesic_refine(part_rows, whole_rows, start, interior, random_state=random_state)
    if origin == "landmarks":
        mapping[pairs[:, 0]] = pairs[:, 1]
    candidate = MapCandidate(origin, mapping, extra=dict(extra))
    candidate.distortion, candidate.extra["scale"] = fitted_distortion(
        part_rows, whole_rows, mapping, distortion_sources(interior, random_state), interior)
    if reliable:
        score_orientation(candidate, part, whole, random_state=random_state)
    if landmarks is not None:
        rows = [whole_rows(int(b)) for b in landmarks[:, 1]]
        errors = np.array([row[mapping[a]] for row, a in zip(rows, landmarks[:, 0])])
        diameter = max(float(row.max()) for row in rows)
        candidate.landmark_error = float(errors.mean() / diameter)
        candidate.landmarks_kept = float(np.mean(errors <= LANDMARK_RADIUS * diameter))
    return candidate
