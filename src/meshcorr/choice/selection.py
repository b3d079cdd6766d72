"""The whole-map choice: several complete candidate maps, judged by the whole map.

The spectral pipeline's near-tied configurations (:mod:`meshcorr.choice.symmetry`)
are chosen between by scores of maps that are only as fine as a
five-dimensional embedding, and every one of them can be wrong when the
shapes' proportions differ (arms sent to legs). After refinement, this
stage puts the spectral map next to maps started from matched extremities
(:mod:`meshcorr.choice.extremities`) and, when given, from the user's landmarks
(:mod:`meshcorr.stages.landmarks`), each refined the same way, and keeps the
one that the following energies prefer:

- **orientation** (:func:`meshcorr.core.map_orientation.orientation_score`): the
  area fraction on which the map keeps the orientation. A left/right mirror
  reverses it everywhere; maps below :data:`ORIENTATION_MIN` are set aside
  whenever one above exists and the orientation can be trusted.
- **metric distortion** (:func:`meshcorr.choice.symmetry.metric_distortion`, the
  Gromov-Hausdorff-type energy of Bronstein, Bronstein & Kimmel, PNAS 2006):
  how much geodesic distances change under the map, from
  :data:`N_DISTORTION_SOURCES` seeded source vertices to all others. A map
  whose legs are swapped under a right upper body (a *partial* mirror) keeps
  distances within each leg but not from a foot to a hand: it is more
  distorted than the right map, which the whole-surface orientation cannot
  see.
- **curvature disagreement** (:func:`meshcorr.choice.curvature.curvature_disagreement`):
  how much the ball-averaged signed mean curvature changes across the map.
  A person turned half a turn about the long axis (front to back and left
  to right) keeps the orientation and, a person being thin, nearly every
  distance, but sends a nose to the back of the head; its curvature
  disagrees.
- **reversed areas**: for a map refined by the smooth shells
  (:func:`shell_candidates`: the pipeline judges the maps as it returns
  them), the area fractions on which it reverses the orientation before
  and after the shells, :math:`1 - o_\\text{ZoomOut}` and
  :math:`1 - o_\\text{shells}` (each floored at :data:`REVERSED_FLOOR`).
  After the shells a right map keeps the orientation almost everywhere, a
  map with a part mirrored does not; but the shells also tidy a map turned
  front to back, whose ZoomOut map showed it (TOSCA michael16 -> michael8:
  0.83 and 0.93 for the right map, 0.61 and 0.95 for the turned one).
  ZoomOut's maps alone are too noisy for this term, and it is left out for
  them.
- **regional orientation** (:func:`meshcorr.core.map_orientation.regional_orientation`):
  the orientation score of the worst of 12 regions; reported, so that a
  partly mirrored result can be seen in ``--json``; a map whose worst region
  is below :data:`meshcorr.choice.repair.REPAIR_BELOW` gets a repaired candidate
  (:func:`meshcorr.choice.repair.repair_candidates`).
- **landmarks kept**: with user landmarks, the fraction of them that the map
  sends within :data:`LANDMARK_RADIUS` (of the target's largest geodesic
  distance) of where the user says they go; only the maps that keep the
  most are considered by the rules above. A count, not a mean distance: one
  landmark in a region every map gets wrong must not outweigh the others
  (measured: a gorilla -> man pair whose mirrored map had the smaller mean).
  ``landmark_error``, the mean of those distances, is reported. Landmark
  vertices are then mapped exactly to their partners.

The map kept is the most probable one: the one of least :func:`energy`,
minus the log-probability that a candidate is the right map when each
score is independent evidence whose strength grows with its logarithm,
:math:`E = \\tau (\\log D + 3 \\log C + \\log R_\\text{before} + \\log R_\\text{after})`
(the weight 3 was the best of 0-6 on the development pairs,
``benchmarks/RESULTS-robustness-trials.md``, and the orientation threshold
the best of 0.5-0.65; :math:`\\tau` calibrates the probabilities,
:func:`choice_probabilities`). Without a reliable orientation the signed
curvature is undefined and the distortion alone decides.

Measured on TOSCA, TOSCA gorilla -> human and SHREC'07 pairs in
``benchmarks/RESULTS-robustness.md``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..runtime.threads import parallel_map
from .curvature import curvature_disagreement
from ..core.map_orientation import orientation_scores
from ..stages.shells import shell_refine
from .symmetry import metric_distortion, rounded

#: Maps of orientation score below this are set aside when one above exists.
ORIENTATION_MIN = 0.6
#: Seeded source vertices of the metric distortion.
N_DISTORTION_SOURCES = 24
#: Exponent of the curvature disagreement in the energy a map is chosen by.
CURVATURE_POWER = 3
#: Least area fraction of reversed orientation counted in the energy of a map refined by the shells.
REVERSED_FLOOR = 1e-3
#: The energy's scale tau: minus the log-probability of a map is tau x its log-scores (fitted on half a of
#: benchmarks/choice_weights.py's pairs by the likelihood of each pair's best candidate; it changes no choice).
EVIDENCE_SCALE = 2.0
#: Scores below this count as this in the energy's logarithms (an exact map has no distortion).
SCORE_FLOOR = 1e-12
#: A landmark is kept by a map that sends it within this (normalised geodesic distance) of its partner.
LANDMARK_RADIUS = 0.05
#: Candidates whose images of the distortion's source vertices lie on average closer than this (normalised
#: geodesic distance on the target) are one map: only the one of least energy is repaired and shelled.
SAME_MAP_DISTANCE = 0.015


@dataclass
class MapCandidate:
    """Second round of the map choice: one complete candidate map and its scores.

    The first round (:class:`meshcorr.choice.symmetry.ConfigurationCandidate`)
    chose among near-tied eigenvector configurations; this one chooses among
    whole maps (the spectral map, maps started from extremities or landmarks,
    their repairs and smooth shells) by the energies of the module docstring.

    Attributes
    ----------
    origin : str
        Where it comes from: ``"spectral"`` (the pipeline's map),
        ``"spectral-alternative"`` (its alternative, unrefined),
        ``"extremities-r"`` (the r-th best extremity assignment) or
        ``"landmarks"``.
    mapping : (n1,) int
        Source vertex -> target vertex, local numbering.
    orientation, distortion, curvature, regional_orientation, landmark_error, landmarks_kept : float
        The energies of the module docstring (NaN where not measured).
    extra : dict
        ``extremity_energy`` for extremity maps.
    landmark_errors : (L,) float or None
        With user landmarks: the normalised geodesic distance from where the
        map sends each landmark to its partner (:mod:`meshcorr.choice.landmark_doubts`).
    same_as : str or None
        For a near-copy left out by :func:`distinct_candidates`: the origin of
        the candidate kept in its place.
    """

    origin: str
    mapping: np.ndarray
    orientation: float = np.nan
    distortion: float = np.nan
    curvature: float = np.nan
    regional_orientation: float = np.nan
    landmark_error: float = np.nan
    landmarks_kept: float = np.nan
    extra: dict = field(default_factory=dict)
    landmark_errors: np.ndarray | None = None  # (L,) how far each landmark is sent from its partner
    same_as: str | None = None  # set by distinct_candidates: the origin of the kept copy of this map

    def to_dict(self) -> dict:
        copy = {} if self.same_as is None else {"same_as": self.same_as}
        return {"origin": self.origin, **copy, "orientation": rounded(self.orientation, 4),
                "distortion": rounded(self.distortion, 5), "curvature": rounded(self.curvature, 4),
                "regional_orientation": rounded(self.regional_orientation, 4),
                "landmark_error": rounded(self.landmark_error, 5),
                "landmarks_kept": rounded(self.landmarks_kept, 4),
                **{key: rounded(value, 5) for key, value in self.extra.items()}}


def score_candidates(candidates: list[MapCandidate], source, target, source_geodesics, target_geodesics, *,
                     reliable: bool, landmarks: np.ndarray | None = None,
                     random_state: int | None = 0, fine=None) -> None:
    """Fill in each candidate's energies (module docstring), in place.

    Parameters
    ----------
    candidates : list of MapCandidate
    source, target : Mesh
    source_geodesics, target_geodesics : callable
        ``f(i)``: normalised geodesic distances from vertex i, ``(n,)``.
    reliable : bool
        Whether both meshes' outsides are defined (orientation scores are
        then measured).
    landmarks : (L, 2) int, optional
        User landmark pairs, local numbering.
    random_state : int or None
        Seed of the distortion's source vertices and the orientation sample.
    fine : (CoarseCopy, CoarseCopy), optional
        When ``source`` and ``target`` are coarse copies
        (:mod:`meshcorr.core.coarse`): the curvature disagreement is measured
        on the full meshes, each map lifted to them (a copy of a few thousand
        vertices blurs the nose, the toes and the knee caps that tell front
        from back); the other energies on the copies.
    """
    sources = distortion_sources(source.n_vertices, random_state)
    rows: dict = {}
    for candidate in candidates:
        mapping = candidate.mapping
        candidate.distortion = metric_distortion(source_geodesics, target_geodesics, mapping, sources, rows)
        if reliable:
            score_orientation(candidate, source, target, random_state=random_state, fine=fine)
        if landmarks is not None:
            errors = np.array([target_geodesics(int(b))[mapping[a]] for a, b in landmarks])
            candidate.landmark_errors = errors
            candidate.landmark_error = float(errors.mean())
            candidate.landmarks_kept = float(np.mean(errors <= LANDMARK_RADIUS))


def distortion_sources(n_vertices: int, random_state: int | None = 0) -> np.ndarray:
    """The seeded source vertices of the metric distortion in :func:`score_candidates`.

    Parameters
    ----------
    n_vertices : int
        Vertices of the source.
    random_state : int or None

    Returns
    -------
    sources : (min(N_DISTORTION_SOURCES, n_vertices),) int
        They depend on the vertex count and the seed only, so
        :func:`meshcorr.shapes.prepared.prepare` computes their geodesic rows once per shape.
    """
    rng = np.random.default_rng(random_state)
    return rng.choice(n_vertices, size=min(N_DISTORTION_SOURCES, n_vertices), replace=False)


def score_orientation(candidate: MapCandidate, source, target, *, random_state: int | None = 0,
                      fine=None) -> None:
    """Fill in a candidate's orientation, curvature disagreement and worst regional orientation, in place.

    Parameters
    ----------
    candidate : MapCandidate
    source, target : Mesh
        Both with a reliable outside (:func:`meshcorr.core.orientation.mesh_orientation`).
    random_state : int or None
        Seed of the samples.
    """
    mapping = candidate.mapping
    orientation, regional = orientation_scores(source, target, mapping, random_state=random_state)
    candidate.orientation = orientation
    if fine is None:
        candidate.curvature = curvature_disagreement(source, target, mapping, random_state=random_state)
    else:  # on the full meshes (score_candidates)
        candidate.curvature = curvature_disagreement(fine[0].fine, fine[1].fine, fine[0].lift_map(mapping, fine[1]),
                                                     random_state=random_state)
    candidate.regional_orientation = float(regional.min())


def choose_map(candidates: list[MapCandidate], *, reliable: bool
               ) -> tuple[MapCandidate, MapCandidate | None]:
    """The map the energies prefer, and the best map of the opposite orientation.

    Parameters
    ----------
    candidates : list of MapCandidate
        Scored by :func:`score_candidates`; the spectral map first.
    reliable : bool
        Whether orientation scores were measured.

    Returns
    -------
    chosen : MapCandidate
    alternative : MapCandidate or None
        The candidate of least :func:`energy` whose orientation score is on
        the other side of 0.5 (with an unreliable orientation: the least
        distorted other candidate); None if there is none.
    """
    chosen = min(eligible(candidates, reliable=reliable), key=lambda c: energy(c, reliable))
    rest = [c for c in candidates if c is not chosen]
    if reliable:
        rest = [c for c in rest if (c.orientation >= 0.5) != (chosen.orientation >= 0.5)]
    alternative = min(rest, key=lambda c: energy(c, reliable)) if rest else None
    return chosen, alternative


def eligible(candidates: list[MapCandidate], *, reliable: bool) -> list[MapCandidate]:
    """The candidates :func:`choose_map` ranks by :func:`energy`.

    Those that keep the most landmarks (all of them without landmarks) and,
    with a reliable orientation, whose orientation score is at least
    :data:`ORIENTATION_MIN` (all of those kept so far if none is).
    """
    pool = list(candidates)
    if all(np.isfinite(c.landmarks_kept) for c in pool):
        best = max(c.landmarks_kept for c in pool)
        pool = [c for c in pool if c.landmarks_kept == best]
    if reliable:
        pool = [c for c in pool if c.orientation >= ORIENTATION_MIN] or pool
    return pool


def candidate_summaries(candidates: list[MapCandidate], chosen: MapCandidate,
                        alternative: MapCandidate | None, *, reliable: bool) -> list[dict]:
    """Every candidate's scores for ``--json`` and ``result.map_candidates``.

    :meth:`MapCandidate.to_dict`, its :func:`energy` (``"energy"``: the rule's
    value, among the candidates that keep the most landmarks and, with a
    reliable orientation, whose orientation is at least :data:`ORIENTATION_MIN`),
    and whether it is the chosen map or the alternative.
    """
    return [dict(c.to_dict(), energy=round(energy(c, reliable), 3), chosen=c is chosen,
                 alternative=c is alternative) for c in candidates]


def energy(candidate: MapCandidate, reliable: bool) -> float:
    """Minus the log-probability (up to a constant) that ``candidate`` is the right map, from its scores.

    .. math::

        E = \\tau \\left(\\log D + 3 \\log C + \\log R_\\text{before} + \\log R_\\text{after}\\right),
        \\qquad P(\\text{candidate } j \\text{ is right}) = e^{-E_j} / \\textstyle\\sum_i e^{-E_i},

    with :math:`D` the metric distortion, :math:`C` the curvature
    disagreement and, for a map refined by the smooth shells,
    :math:`R = \\max(1 - o, 10^{-3})` the area fractions on which it
    reverses the orientation before (``extra["zoomout_orientation"]``) and
    after them (:data:`REVERSED_FLOOR`). Each score is treated as
    independent evidence of a wrong map whose strength grows with its
    logarithm: a map twice as distorted as another must have a curvature
    disagreement :math:`2^{1/3}` times smaller to be as likely. The
    exponents were chosen on development pairs (module docstring) and
    :math:`\\tau` = :data:`EVIDENCE_SCALE` on half ``a`` of the sets of
    ``benchmarks/choice_weights.py`` so that the probabilities
    (:func:`choice_probabilities`) are calibrated; :math:`\\tau` changes no
    choice. Without a reliable orientation, :math:`E = \\tau \\log D`.
    Scores are floored at :data:`SCORE_FLOOR` (an exact map scores 0).
    """
    terms = [(1.0, candidate.distortion)]
    if reliable:
        terms.append((CURVATURE_POWER, candidate.curvature))
        if candidate.extra.get("shells"):
            for orientation in (candidate.extra["zoomout_orientation"], candidate.orientation):
                terms.append((1.0, max(1.0 - orientation, REVERSED_FLOOR)))
    return EVIDENCE_SCALE * sum(weight * float(np.log(max(value, SCORE_FLOOR))) if weight else 0.0
                                for weight, value in terms)


def choice_probabilities(candidates: list[MapCandidate], reliable: bool) -> np.ndarray:
    """``(len(candidates),)`` the probability of each candidate being the right map: the softmax of -:func:`energy`."""
    energies = -np.array([energy(c, reliable) for c in candidates])
    weights = np.exp(energies - energies.max())
    return weights / weights.sum()


def distinct_candidates(candidates: list[MapCandidate], target_geodesics, sources: np.ndarray, *,
                        reliable: bool) -> tuple[list[MapCandidate], list[MapCandidate]]:
    """The candidates without near-copies: of each group of one map, the one of least :func:`energy`.

    Starts from different tips often end, after ZoomOut, at the same map
    (a TOSCA pair: six of eight candidates within 0.004 of one another).
    Repairing and shelling each copy costs the same as a different map and
    changes nothing the choice can see, so before those steps the
    candidates are taken in order of energy (the user's landmarks' own map
    first: the shells hold it to them) and one is dropped when it
    sends the ``sources`` on average within :data:`SAME_MAP_DISTANCE` of
    where a kept candidate sends them.

    Parameters
    ----------
    candidates : list of MapCandidate
        Scored (:func:`score_candidates`).
    target_geodesics : callable
        ``f(i)``: normalised geodesic distances from target vertex i, ``(n2,)``.
    sources : (m,) int
        Source vertices at which the maps are compared (:func:`distortion_sources`).
    reliable : bool
        As :func:`energy`.

    Returns
    -------
    kept : list of MapCandidate
        In the order of ``candidates``.
    copies : list of MapCandidate
        The others, each with :attr:`MapCandidate.same_as` set.
    """
    sources = np.asarray(sources, dtype=np.int64)
    kept: list[tuple[MapCandidate, list[np.ndarray]]] = []
    for candidate in sorted(candidates, key=lambda c: (c.origin != "landmarks", energy(c, reliable))):
        images = candidate.mapping[sources]
        for other, rows in kept:
            if np.mean([row[i] for row, i in zip(rows, images)]) < SAME_MAP_DISTANCE:
                candidate.same_as = other.origin
                break
        else:
            kept.append((candidate, [np.asarray(target_geodesics(int(t))) for t in images]))
    survivors = {id(c) for c, _ in kept}
    return [c for c in candidates if id(c) in survivors], [c for c in candidates if id(c) not in survivors]


def shell_candidates(candidates: list[MapCandidate], source, target, *, k: int,
                     landmarks: np.ndarray | None = None,
                     descriptors: tuple[np.ndarray, np.ndarray] | None = None,
                     random_state: int | None = 0) -> list[MapCandidate]:
    """Refine the candidates that keep the orientation by :func:`meshcorr.stages.shells.shell_refine`, in place.

    Parameters
    ----------
    candidates : list of MapCandidate
        Scored by :func:`score_candidates`.
    source, target : Mesh
        Triangle meshes with a reliable outside.
    k : int
        Laplace-Beltrami basis size of the shells (the pipeline's ``refine_k``).
    landmarks : (L, 2) int, optional
        User landmark pairs: held by the ``"landmarks"`` candidate only (the
        others must show by themselves whether they agree with them).
    descriptors : ((n1, d), (n2, d)) float, optional
        The landmarks' geodesic distances (:func:`meshcorr.stages.shells.shell_refine`),
        used by the ``"landmarks"`` candidate only, like the pins.
    random_state : int or None

    Returns
    -------
    refined : list of MapCandidate
        The candidates of orientation score >= 0.5, their maps replaced by
        the shells', ``extra["shells"] = 1`` and their score so far kept as
        ``extra["zoomout_orientation"]``: to be scored again. The
        others (mirror images, set aside by :func:`choose_map` whenever one
        of these exists) are left as they are.
    """
    chosen = [c for c in candidates if c.orientation >= 0.5]

    def shelled(candidate: MapCandidate) -> tuple[np.ndarray, dict]:
        held, energy = candidate.origin == "landmarks", {}
        mapping = shell_refine(source, target, candidate.mapping, k=k, landmarks=landmarks if held else None,
                               descriptors=descriptors if held else None,
                               orientation=candidate.orientation, random_state=random_state, energy=energy)
        return mapping, energy

    for candidate, (mapping, energy) in zip(chosen, parallel_map(shelled, chosen)):  # one thread per core
        candidate.mapping = mapping
        candidate.extra.update(shells=1.0, zoomout_orientation=candidate.orientation, **energy)
    return chosen
