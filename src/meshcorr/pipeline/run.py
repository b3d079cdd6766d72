"""The spectral correspondence pipeline of Jain & Zhang (2006), top to bottom.

``match(source, target, settings)`` runs the steps of docs/method.md, each a
call to the stage that does it:

1. load: each input as a validated mesh or a checked prepared shape;
2. spectra (steps 1-3): geodesic distances, Gaussian affinities
   (sigma = the largest geodesic distance), the top-k eigenvectors scaled
   by sqrt(eigenvalue), the first dropped;
3. configurations (step 4): eigenvector reordering and sign correction;
4. alignment (step 5): thin-plate-spline ICP of each near-tied
   configuration, scored (the first round of the map choice,
   :mod:`meshcorr.choice.symmetry`);
5. matching (step 6): anchors and proximity-aided matching;
6. choice: the whole-map choice (:mod:`meshcorr.choice.whole_map`);
7. refinement: ZoomOut, the smooth shells, a bijective map (step 7);
8. result: the :class:`~meshcorr.maps.result.Correspondence`.

The baselines (:mod:`meshcorr.pipeline.methods`) and the partial mode
(:mod:`meshcorr.pipeline.partial`) are dispatched from :func:`match`.

Reference: V. Jain, H. Zhang, "Robust 3D shape correspondence in the
spectral domain", Shape Modeling International 2006.
"""

from __future__ import annotations

import os
import warnings
from contextlib import nullcontext
from typing import NamedTuple

import numpy as np

from ..core.orientation import mesh_orientation
from ..choice.confidence import no_rival, unsure_message
from ..choice.reverse_check import CYCLE_LIMIT, cycle_error
from ..choice.symmetry import ConfigurationCandidate, choose, score_configurations
from ..choice.whole_map import EXTREMITY_STARTS, WholeMapChoice, whole_map_choice
from ..core.coarse import CoarseCopy, coarse_copies, needs_copy
from ..core.holes import restrict
from ..io.meshes import declared_vertex_count
from ..core.mesh import Mesh, MeshLike
from ..errors import MeshWarning, ParameterError, PartialShapeWarning, UnsureChoiceWarning
from ..maps import result as result_module
from ..maps.result import Correspondence
from ..runtime.memory import check_coarse_fits
from ..runtime.progress import run_progress
from ..runtime.timing import StageProgress, StageTimer
from ..shapes.prepared import PreparedShape, as_meshes, pair_shapes, pair_spectrum
from ..spectral.modes import resolve_memory, select_mode
from ..stages.anchors import embedding_spread, match_with_anchors
from ..stages.bijection import check_fixed_pairs, nearest_bijection
from ..stages.landmarks import check_landmarks, landmark_descriptors
from ..spectral.basis import prefetch_bases
from ..stages.refine import refine_map
from ..stages.reorder import Configuration, rank_configurations
from ..stages.shells import shell_refine
from ..stages.lift import LIFT_ABOVE, LIFT_K_FACTOR, lift_to_fine
from .methods import applicable_options, run_method
from ..stages.part_checks import check_part_not_larger, check_roles, geodesic_rows, partiality_suspicion
from ..stages.part_region import invert_part_map, part_region
from .partial import match_part
from .settings import REFINE_K, Settings, as_settings, shape_settings

__all__ = ["match", "check_coarse_memory", "REFINE_K", "EXTREMITY_STARTS"]


def match(source: MeshLike | PreparedShape, target: MeshLike | PreparedShape, settings: Settings | None = None, *,
          progress: StageProgress | bool | None = None, **overrides) -> Correspondence:
    """Dense vertex correspondence from ``source`` to ``target``.

    Parameters
    ----------
    source, target : path, trimesh.Trimesh, Mesh, (vertices, faces) or PreparedShape
        Triangle meshes: closed or open 2-manifolds, one connected component
        each (see ``largest_component``), or point clouds. Any pose,
        position, rotation, uniform scale and vertex count. A shape from
        :func:`meshcorr.prepare` skips the per-shape work and gives the same
        map as its mesh; it must have been prepared with this call's
        per-shape settings (:func:`meshcorr.pipeline.settings.shape_settings`:
        ``k``, ``geodesic``, ``scale_eigenvalues``, ``n_samples``,
        ``refine``, ``refine_k``, ``largest_component``, ``random_state``,
        ``fill_holes`` as this call uses it: False with ``partial`` or
        ``bijective``) and the pair's mode.
    settings : Settings, optional
        Every option of the run (default: ``Settings()``); each one's
        meaning, default and maths are in :class:`meshcorr.Settings`.
    progress : callable or bool, optional
        ``progress(stage, done, total)``, or True for a progress bar
        (:class:`meshcorr.runtime.progress.TqdmProgress`, notebook-aware).
    **overrides
        Single fields of :class:`meshcorr.Settings` (``match(a, b, k=8)``),
        replacing those of ``settings``.

    Returns
    -------
    result : Correspondence
        ``result.map[i]`` is the target vertex of source vertex i.

    Raises
    ------
    ParameterError
        An unknown keyword (``n_landmarks`` names ``n_samples``), a value
        :class:`meshcorr.Settings` refuses, or one that does not fit the meshes.
    """
    settings = as_settings(settings, overrides)
    with run_progress(progress) as progress:  # one bar for the run (meshcorr.runtime.progress)
        if settings.method != "spectral":
            return _match_baseline(source, target, settings, progress)
        timer = StageTimer(progress)
        max_memory = resolve_memory(settings.max_memory)
        _check_declared_sizes(source, target, settings)
        shapes, pairs = _load(source, target, settings, timer)
        if settings.partial is not None:  # a part against the whole: meshcorr.pipeline.partial
            return _match_partial(shapes, pairs, settings, max_memory, timer)
        result = _match_whole(shapes, pairs, settings, max_memory, timer)
        result.stage_memory = timer.memory
        if settings.check_reverse:  # the pair matched the other way round (meshcorr.choice.reverse_check)
            with timer.stage("reverse"):
                result.confidence = _reverse_checked(result, source, target, settings)
            result.timings = timer.timings
    if result.confidence is not None and result.confidence["low"]:  # meshcorr.choice.confidence
        warnings.warn(unsure_message(result.confidence), UnsureChoiceWarning, stacklevel=2)
    return result


def _reverse_checked(result: Correspondence, source, target, settings: Settings) -> dict:
    """``result.confidence`` with the cycle error of the map and the map back, and ``low`` when it is large."""
    landmarks = None if settings.landmarks is None else np.asarray(settings.landmarks)[:, ::-1].tolist()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", MeshWarning)  # the reverse run's warnings are said by its own run
        reverse = match(target, source, settings.replace(check_reverse=False, landmarks=landmarks))
    error = cycle_error(result.source, result.map, reverse.map, geodesic=settings.geodesic,
                        random_state=settings.random_state)
    report = dict(result.confidence or no_rival().to_dict())
    report.update(cycle_error=round(error, 4), low=bool(report["low"] or error > CYCLE_LIMIT))
    return report


def _match_baseline(source, target, settings: Settings, progress) -> Correspondence:
    """A baseline of the paper (:mod:`meshcorr.pipeline.methods`) with the settings it takes."""
    common = dict(k=settings.k, geodesic=settings.geodesic, bijective=settings.bijective,
                  largest_component=settings.largest_component)
    source, target = as_meshes(source, target)
    return run_method(settings.method, source, target, prealign=settings.prealign,
                      random_state=settings.random_state, progress=progress,
                      **applicable_options(settings.method, common))


def _load(source, target, settings: Settings, timer: StageTimer) -> tuple[tuple, np.ndarray | None]:
    """Step "load": the shapes (meshes, or shapes prepared with these settings) and the landmarks, local numbering."""
    with timer.stage("load"):  # meshes, or shapes prepared with these settings (meshcorr.shapes.prepared)
        shapes = pair_shapes(source, target, shape_settings(settings))
        src, tgt = as_meshes(*shapes)
        pairs = check_landmarks(settings.landmarks, src, tgt)
    if settings.bijective and pairs is not None:  # named in the input's numbering
        check_fixed_pairs(np.stack([src.kept[pairs[:, 0]], tgt.kept[pairs[:, 1]]], axis=1))
    n_anchors, smaller = settings.n_anchors, min(src.n_vertices, tgt.n_vertices)
    if n_anchors > smaller:  # each anchor pairs two distinct vertices
        raise ParameterError(f"n_anchors={n_anchors} (--anchors) is more than the smaller shape's "
                             f"{smaller} vertices; the paper's few anchors (3-10) "
                             "are what the matching needs.")
    return shapes, pairs


class _Aligned(NamedTuple):
    """Steps 1-6 of a pair: spectra, configurations, the chosen and alternative aligned maps."""

    spectra: list
    configurations: list
    candidates: list
    chosen: ConfigurationCandidate
    other: ConfigurationCandidate | None
    reliable: bool
    refine_history: list
    bases_seconds: float | None


def _match_whole(shapes, pairs: np.ndarray | None, settings: Settings, max_memory: int | None,
                 timer: StageTimer, fine: tuple | None = None) -> Correspondence:
    """Two whole shapes, the paper's steps in order, then the whole-map choice and the refinements."""
    src, tgt = as_meshes(*shapes)
    copies = _coarse_copies(src, tgt, settings, timer)
    if copies is not None:  # steps 1-6 and the choice on coarse copies, the winner refined on the meshes
        return _match_coarse_to_fine(src, tgt, copies, pairs, settings, max_memory, timer)
    mode = select_mode(settings.mode, src.n_vertices, tgt.n_vertices, max_memory=max_memory,
                       scalable_above=settings.scalable_above, bijective=settings.bijective)
    # The refinement's Laplace-Beltrami bases depend on the meshes only: a worker
    # thread computes them while steps 1-6 run (meshcorr.spectral.basis.prefetch_bases).
    with prefetch_bases(src, tgt, settings.refine_k, random_state=settings.random_state,
                        enabled=settings.refine) as bases:
        spectra = _spectra(shapes, settings, mode, timer)  # steps 1-3
        configurations = _configurations(spectra, settings, timer)  # step 4
        candidates, reliable = _alignment(src, tgt, spectra, configurations, settings, timer)  # step 5
        chosen, other = _matching(candidates, spectra, settings, reliable, timer)  # step 6
        if settings.refine:
            with timer.stage("refine"):
                bases.wait()
    history = _refinement(src, tgt, chosen, settings, timer)
    aligned = _Aligned(spectra, configurations, candidates, chosen, other, reliable, history, bases.seconds)
    shell_stage = settings.refine and settings.shells and not settings.bijective and not (src.is_cloud or
                                                                                          tgt.is_cloud)
    # The landmarks' geodesic distances, a further coordinate of the shells' product space.
    described = None if pairs is None or not shell_stage else tuple(
        landmark_descriptors(spectrum.geodesics_from, ends) for spectrum, ends in zip(spectra, pairs.T))
    choice = _choose_map(src, tgt, aligned, pairs, settings, shell_stage, described, timer, fine)
    local_map, other_map = _final_maps(src, tgt, choice, pairs, settings, shell_stage, described, timer)
    spectral_kept = choice.spectral_kept and not shell_stage
    result = _result(src, tgt, aligned, local_map, other_map, choice.summaries, spectral_kept, pairs,
                     settings, dict(mode=mode, max_memory=max_memory, shells=shell_stage), timer)
    if choice.confidence is not None:  # in the input numbering
        result.confidence = _renumbered(choice.confidence.to_dict(), src.kept, tgt.kept)
    return result


def _renumbered(report: dict, source_numbers: np.ndarray, target_numbers: np.ndarray) -> dict:
    """A ``result.confidence`` report with its suggested vertices renumbered (``numbers[v]`` for vertex v)."""
    rows = [dict(row, source=int(source_numbers[row["source"]]), chosen=int(target_numbers[row["chosen"]]),
                 rival=int(target_numbers[row["rival"]])) for row in report["suggested_landmarks"]]
    return dict(report, suggested_landmarks=rows)


def _check_declared_sizes(source, target, settings: Settings) -> None:
    """Two files (PLY or OFF) whose declared vertex counts would not fit ``max_memory``: refused before
    they are read (:func:`check_coarse_memory`); anything else is checked once loaded."""
    if not all(isinstance(shape, (str, os.PathLike)) for shape in (source, target)):
        return
    counts = declared_vertex_count(source), declared_vertex_count(target)
    if None not in counts:
        check_coarse_memory(*counts, settings)


def check_coarse_memory(n1: int, n2: int, settings: Settings) -> None:
    """Refuse (:class:`~meshcorr.errors.MemoryLimitError`) meshes of ``n1`` and ``n2`` vertices whose
    coarse-to-fine run would not fit ``settings.max_memory`` (:func:`meshcorr.runtime.memory.check_coarse_fits`).

    Only where the run takes that path (:func:`_coarse_copies`' conditions, point clouds aside);
    :func:`match` calls it with the counts two files declare, before reading them.
    """
    if (settings.method == "spectral" and settings.partial is None and settings.refine and not settings.bijective
            and settings.symmetry == "auto" and needs_copy(max(n1, n2), settings.coarse_vertices)):
        check_coarse_fits(n1, n2, resolve_memory(settings.max_memory))


def _coarse_copies(src: Mesh, tgt: Mesh, settings: Settings, timer: StageTimer) -> tuple | None:
    """The two meshes' coarse copies (:mod:`meshcorr.core.coarse`), or None where the pair runs on the meshes.

    Not for point clouds, an unrefined map (the paper's map at every
    vertex), one-to-one maps and a ``symmetry`` other than "auto" (no
    choice to make), nor when both meshes are small already.
    """
    size = settings.coarse_vertices
    if (not settings.refine or settings.bijective or settings.symmetry != "auto" or src.is_cloud or tgt.is_cloud
            or not needs_copy(max(src.n_vertices, tgt.n_vertices), size)):
        return None
    # Refused before any heavy work when the path would not fit the memory allowed; above LIFT_ABOVE
    # vertices this check is the stage "large", which opens the large meshes' progress plan.
    with timer.stage("large") if max(src.n_vertices, tgt.n_vertices) > LIFT_ABOVE else nullcontext():
        check_coarse_memory(src.n_vertices, tgt.n_vertices, settings)
    children: dict = {}
    with timer.stage("coarse"):
        copies = tuple(coarse_copies([src, tgt], size, memory=children))  # large meshes side by side, in children
    if "coarse" in timer.memory:  # this process's peak and its children's (an upper bound)
        timer.memory["coarse"] += children.get("children_mib", 0.0)
    return None if None in copies else copies


def _match_coarse_to_fine(src: Mesh, tgt: Mesh, copies: tuple[CoarseCopy, CoarseCopy], pairs: np.ndarray | None,
                          settings: Settings, max_memory: int | None, timer: StageTimer) -> Correspondence:
    """The whole pipeline on the coarse copies (ZoomOut and shells included), its map carried to every vertex.

    Above :data:`meshcorr.stages.lift.LIFT_ABOVE` vertices the copies' map is lifted
    (:func:`meshcorr.stages.lift.lift_to_fine`) in time and memory linear in the vertex count:
    the copies' bases extended to the meshes, the last shell fitted on the copies, local nearest
    neighbours in the shells' product space. Below it the lifted map is refined on the meshes by
    ZoomOut and the smooth shells, with the meshes' own bases (computed in a worker thread
    meanwhile). Landmarks go to the coarse copies as their nearest coarse vertices and are held
    exactly on the meshes.
    """
    coarse_pairs = None if pairs is None else _coarse_landmarks(pairs, copies)
    coarse_settings = settings.replace(coarse_vertices=0)
    if max(src.n_vertices, tgt.n_vertices) > LIFT_ABOVE:
        coarse = _match_whole((copies[0].mesh, copies[1].mesh), coarse_pairs, coarse_settings, max_memory, timer,
                              fine=copies)
        with timer.stage("lift"):
            described = None
            if pairs is not None and settings.shells and len(coarse_pairs):
                described = tuple(landmark_descriptors(geodesic_rows(copy.mesh, settings.geodesic), ends)
                                  for copy, ends in zip(copies, coarse_pairs.T))
            # The copies' own numbering (as CoarseCopy.lift_map takes it); bases of twice the
            # refinement's size (measured on the lion pair at 80k: marker error 0.0205 -> 0.0141).
            mapping = lift_to_fine(copies, np.asarray(coarse.map), k=LIFT_K_FACTOR * settings.refine_k,
                                   landmarks=pairs, descriptors=described, random_state=settings.random_state,
                                   progress=timer.reporter("lift"))
        return _lifted_result(src, tgt, copies, coarse, mapping, coarse.refine_history, settings, timer, None)
    with prefetch_bases(src, tgt, settings.refine_k, random_state=settings.random_state) as bases:
        coarse = _match_whole((copies[0].mesh, copies[1].mesh), coarse_pairs, coarse_settings, max_memory, timer,
                              fine=copies)
        with timer.stage("refine"):
            bases.wait()
    with timer.stage("refine"):
        lifted = copies[0].lift_map(coarse.map, copies[1])
        mapping, history = refine_map(src, tgt, lifted, k=settings.refine_k, random_state=settings.random_state,
                                      landmarks=pairs)
    if settings.shells:
        with timer.stage("shells"):
            described = None if pairs is None else tuple(
                landmark_descriptors(geodesic_rows(mesh, settings.geodesic), ends) for mesh, ends in
                zip((src, tgt), pairs.T))
            mapping = shell_refine(src, tgt, mapping, k=settings.refine_k, landmarks=pairs, descriptors=described,
                                   random_state=settings.random_state)
    if pairs is not None:
        mapping[pairs[:, 0]] = pairs[:, 1]
    return _lifted_result(src, tgt, copies, coarse, mapping, history, settings, timer, bases.seconds)


def _coarse_landmarks(pairs: np.ndarray, copies: tuple[CoarseCopy, CoarseCopy]) -> np.ndarray | None:
    """Landmark pairs on the coarse copies: each end's nearest coarse vertex, the first pair of a coarse vertex kept."""
    coarse = np.stack([copies[0].child[pairs[:, 0]], copies[1].child[pairs[:, 1]]], axis=1)
    _, first = np.unique(coarse[:, 0], return_index=True)
    coarse = coarse[np.sort(first)]
    _, first = np.unique(coarse[:, 1], return_index=True)
    return coarse[np.sort(first)]


def _lifted_result(src: Mesh, tgt: Mesh, copies: tuple[CoarseCopy, CoarseCopy], coarse: Correspondence,
                   mapping: np.ndarray, history: list, settings: Settings, timer: StageTimer,
                   bases_seconds: float | None) -> Correspondence:
    """The Correspondence of a coarse-to-fine run: the refined map; per-vertex data of the copies at each
    vertex's nearest coarse vertex, the coarse anchors and alternative at their fine parents."""
    (one, two), lift = copies, (lambda values, copy: None if values is None else values[copy.child])
    alternative = None
    if coarse.alternative_map is not None:
        alternative = np.full(src.n_original, -1, dtype=np.int64)
        alternative[src.kept] = tgt.kept[one.lift_map(coarse.alternative_map, two)]
    full_map = np.full(src.n_original, -1, dtype=np.int64)
    full_map[src.kept] = tgt.kept[mapping]
    anchors = None if coarse.anchors is None else np.stack(
        [src.kept[one.parent[coarse.anchors[:, 0]]], tgt.kept[two.parent[coarse.anchors[:, 1]]]], axis=1)
    params = dict(coarse.params, coarse_vertices=settings.coarse_vertices,
                  coarse_sizes=[one.mesh.n_vertices, two.mesh.n_vertices],
                  landmarks=None if settings.landmarks is None else np.asarray(settings.landmarks).tolist())
    params.pop("meshcorr_version", None)
    background = dict(coarse.background_timings)
    if bases_seconds is not None:
        background["refine_bases"] = background.get("refine_bases", 0.0) + bases_seconds
    return restrict(Correspondence(  # without the holes' caps (meshcorr.core.holes)
        map=full_map, source=src, target=tgt, source_vertices=src.kept.copy(), target_vertices=tgt.kept.copy(),
        source_embedding=lift(coarse.source_embedding, one), target_embedding=lift(coarse.target_embedding, two),
        aligned_target_embedding=lift(coarse.aligned_target_embedding, two), eigenvalues=coarse.eigenvalues,
        configuration=coarse.configuration, alternatives=coarse.alternatives, anchors=anchors,
        icp_history=coarse.icp_history, icp_converged=coarse.icp_converged, timings=timer.timings,
        background_timings=background, params=params, candidates=coarse.candidates, alternative_map=alternative,
        orientation_reliable=coarse.orientation_reliable, refine_history=history,
        map_candidates=coarse.map_candidates, confidence=None if coarse.confidence is None else _renumbered(
            coarse.confidence, src.kept[one.parent], tgt.kept[two.parent])),
        src, tgt)


def _spectra(shapes, settings: Settings, mode: str, timer: StageTimer) -> list:
    """Steps 1-3: geodesic distances, Gaussian affinities, the scaled spectral embedding of each shape."""
    per_shape = shape_settings(settings)
    spectra = [pair_spectrum(shape, per_shape, mode, timer) for shape in shapes]
    src, tgt = as_meshes(*shapes)
    suspicion = partiality_suspicion(src, tgt, spectra[0].max_geodesic, spectra[1].max_geodesic)  # holes open or closed
    if suspicion:  # a part given as a whole shape (meshcorr.pipeline.partial)
        warnings.warn(suspicion, PartialShapeWarning, stacklevel=4)
    return spectra


def _configurations(spectra, settings: Settings, timer: StageTimer) -> list[Configuration]:
    """Step 4: eigenvector reordering and sign correction, every configuration ranked by cost."""
    with timer.stage("reorder"):
        return rank_configurations(spectra[0].embedding, spectra[1].embedding, settings.reorder,
                                   random_state=settings.random_state)


def _alignment(src: Mesh, tgt: Mesh, spectra, configurations: list[Configuration], settings: Settings,
               timer: StageTimer) -> tuple[list[ConfigurationCandidate], bool]:
    """Step 5 for each near-tied configuration, scored (:func:`meshcorr.choice.symmetry.score_configurations`)."""
    with timer.stage("symmetry"):
        reliable = mesh_orientation(src).reliable and mesh_orientation(tgt).reliable
    candidates = score_configurations(src, tgt, spectra, configurations, icp_iterations=settings.icp_iterations,
                                      n_control=settings.n_control, anneal=settings.anneal, reliable=reliable,
                                      random_state=settings.random_state, timer=timer)
    if not reliable and settings.symmetry == "auto" and len(candidates) > 1:
        unsure = src if mesh_orientation(src).reason else tgt
        why = f"{unsure.name}: {mesh_orientation(unsure).reason}"
        warnings.warn(f"The left/right orientation cannot be checked: {why}. The map may be the mirror "
                      "image of the right one; compare it with result.alternative_map.", MeshWarning,
                      stacklevel=4)
    return candidates, reliable


def _matching(candidates: list[ConfigurationCandidate], spectra, settings: Settings, reliable: bool,
              timer: StageTimer) -> tuple[ConfigurationCandidate, ConfigurationCandidate | None]:
    """Step 6: the configuration the ``symmetry`` rule chooses and its alternative, matched with anchors."""
    chosen, other = choose(candidates, settings.symmetry, orientation_reliable=reliable)
    with timer.stage("matching"):
        use_spread = settings.anchor_scale == "embedding" and settings.n_anchors > 0
        spread = embedding_spread(spectra[0]) if use_spread else 1.0
        for candidate in (chosen, other):
            if candidate is not None:
                mapping, cost, anchors = match_with_anchors(
                    spectra[0].embedding, candidate.extra["icp"].warped, spectra[0].geodesics_from,
                    spectra[1].geodesics_from, spread, n_anchors=settings.n_anchors,
                    anchor_weight=settings.anchor_weight, anchor_scale=settings.anchor_scale,
                    bijective=settings.bijective)
                candidate.mapping = mapping
                candidate.extra.update(anchors=anchors, cost=cost)
    return chosen, other


def _refinement(src: Mesh, tgt: Mesh, chosen: ConfigurationCandidate, settings: Settings,
                timer: StageTimer) -> list:
    """ZoomOut refinement of the chosen map only (the alternative stays as the matching gave it)."""
    if not settings.refine:
        return []
    with timer.stage("refine"):
        chosen.mapping, history = refine_map(src, tgt, chosen.mapping, k=settings.refine_k,
                                             bijective=settings.bijective, random_state=settings.random_state)
    return history


def _final_maps(src: Mesh, tgt: Mesh, choice: WholeMapChoice, pairs: np.ndarray | None, settings: Settings,
                shell_stage: bool, described, timer: StageTimer) -> tuple[np.ndarray, np.ndarray | None]:
    """The chosen map through the smooth shells (unless the choice judged it after them) and step 7."""
    local_map, other_map = choice.mapping, choice.other
    if shell_stage:
        with timer.stage("shells"):  # meshcorr.stages.shells: extrinsic alignment of the chosen map
            if not choice.shelled:
                local_map = shell_refine(src, tgt, local_map, k=settings.refine_k, landmarks=pairs,
                                         descriptors=described, orientation=choice.orientation,
                                         random_state=settings.random_state)
    if settings.bijective:  # an unrefined start of the whole-map choice, or pinned landmarks, are not one-to-one
        local_map = nearest_bijection(local_map, tgt.vertices, fixed=pairs)
        other_map = None if other_map is None else nearest_bijection(other_map, tgt.vertices)
    return local_map, other_map


def _choose_map(src: Mesh, tgt: Mesh, aligned: _Aligned, pairs: np.ndarray | None, settings: Settings,
                shell_stage: bool, described, timer: StageTimer, fine: tuple | None) -> WholeMapChoice:
    """The whole-map choice (stages "whole-map" and "shells"), or the spectral map when it does not run."""
    chosen, other = aligned.chosen, aligned.other
    choice = WholeMapChoice(chosen.mapping, None if other is None else other.mapping, [])
    if settings.symmetry == "auto" and (settings.extremities or pairs is not None):
        starts = EXTREMITY_STARTS + (("oriented",) if settings.oriented_starts else ())
        choice = whole_map_choice(
            src, tgt, aligned.spectra, chosen.mapping, choice.other, pairs, extremities=settings.extremities,
            refine=settings.refine, refine_k=settings.refine_k, bijective=settings.bijective,
            reliable=aligned.reliable, shells=shell_stage, timer=timer, described=described, tip_starts=starts,
            random_state=settings.random_state, fine=fine, sign_search=settings.sign_search)
    return choice


def _result(src: Mesh, tgt: Mesh, aligned: _Aligned, local_map: np.ndarray, other_map: np.ndarray | None,
            map_candidates: list, spectral_kept: bool, pairs: np.ndarray | None, settings: Settings,
            resolved: dict, timer: StageTimer) -> Correspondence:
    """The Correspondence of a whole-to-whole run, in the input numbering, without the holes' caps."""
    chosen, other, spectra = aligned.chosen, aligned.other, aligned.spectra
    icp, anchors = chosen.extra["icp"], chosen.extra["anchors"]
    full_map = np.full(src.n_original, -1, dtype=np.int64)
    full_map[src.kept] = tgt.kept[local_map]
    full_cost = None  # the matching cost means something only for the unrefined spectral map
    if not settings.refine and spectral_kept:
        full_cost = np.full(src.n_original, np.nan)
        full_cost[src.kept] = chosen.extra["cost"]
    alternative_map = None
    if other_map is not None:
        alternative_map = np.full(src.n_original, -1, dtype=np.int64)
        alternative_map[src.kept] = tgt.kept[other_map]
    summaries = [dict(c.to_dict(), chosen=c is chosen, alternative=c is other) for c in aligned.candidates]
    landmarks = None if pairs is None else np.stack([src.kept[pairs[:, 0]], tgt.kept[pairs[:, 1]]], axis=1).tolist()
    return restrict(Correspondence(  # without the holes' caps (meshcorr.core.holes)
        map=full_map, cost=full_cost, source=src, target=tgt,
        source_vertices=src.kept.copy(), target_vertices=tgt.kept.copy(),
        source_embedding=spectra[0].embedding, target_embedding=chosen.configuration.apply(spectra[1].embedding),
        aligned_target_embedding=icp.warped,
        eigenvalues={"source": spectra[0].eigenvalues, "target": spectra[1].eigenvalues},
        configuration=chosen.configuration, alternatives=_chosen_first(aligned.configurations, chosen, other),
        anchors=np.stack([src.kept[anchors[:, 0]], tgt.kept[anchors[:, 1]]], axis=1),
        icp_history=icp.history, icp_converged=icp.converged, timings=timer.timings,
        background_timings={} if aligned.bases_seconds is None else {"refine_bases": aligned.bases_seconds},
        params=_whole_params(settings, resolved, landmarks), candidates=summaries,
        alternative_map=alternative_map, orientation_reliable=aligned.reliable,
        refine_history=aligned.refine_history, map_candidates=map_candidates,
    ), src, tgt)


def _whole_params(settings: Settings, resolved: dict, landmarks: list | None) -> dict:
    """``result.params`` of a whole-to-whole run: the settings as they ran (mode, memory, shells resolved)."""
    s = settings
    return dict(k=s.k, geodesic=s.geodesic, scale_eigenvalues=s.scale_eigenvalues, reorder=s.reorder,
                icp_iterations=s.icp_iterations, n_control=s.n_control, anneal=s.anneal,
                n_anchors=s.n_anchors, anchor_weight=s.anchor_weight, bijective=s.bijective,
                largest_component=s.largest_component, random_state=s.random_state, mode=resolved["mode"],
                n_samples=s.n_samples, max_memory=resolved["max_memory"], symmetry=s.symmetry, refine=s.refine,
                refine_k=s.refine_k, shells=resolved["shells"], anchor_scale=s.anchor_scale,
                extremities=s.extremities, oriented_starts=s.oriented_starts, sign_search=s.sign_search,
                fill_holes=shape_settings(s)["fill_holes"], landmarks=landmarks)  # as they ran


def _partial_options(settings: Settings, max_memory: int | None) -> dict:
    """The settings of the partial mode's whole-to-whole start, in the order ``result.params`` lists them."""
    s = settings
    return dict(k=s.k, geodesic=s.geodesic, scale_eigenvalues=s.scale_eigenvalues, reorder=s.reorder,
                icp_iterations=s.icp_iterations, n_control=s.n_control, anneal=s.anneal,
                n_anchors=s.n_anchors, anchor_weight=s.anchor_weight, anchor_scale=s.anchor_scale,
                largest_component=s.largest_component, mode=s.mode, n_samples=s.n_samples,
                max_memory=max_memory, scalable_above=s.scalable_above, refine=s.refine,
                refine_k=s.refine_k, shells=s.shells, random_state=s.random_state, fill_holes=False,
                sign_search=True)  # always for a part (_match_partial's docstring)


def _match_partial(shapes, pairs: np.ndarray | None, settings: Settings, max_memory: int | None,
                   timer: StageTimer) -> Correspondence:
    """A part against the whole shape (:func:`meshcorr.pipeline.partial.match_part`), as a Correspondence.

    The whole-to-whole pipeline maps the part into the whole once, as it
    would without ``partial`` (its holes and cut closed by
    :mod:`meshcorr.core.holes`, the whole-map choice with ``extremities``, the
    smooth shells): that map and its alternative are two of the starts
    :func:`~meshcorr.pipeline.partial.match_part` chooses from (on 36 plane cuts of
    ``benchmarks/scans.py`` this start lowered the partial mode's error
    from 0.090 to 0.055; steps 1-7 alone, the start before, are right only
    when the cut leaves the shape's global structure). With
    ``partial="target"`` the target is mapped into the source and the map is
    turned round (:func:`meshcorr.stages.part_region.invert_part_map`): source vertices
    outside the matched region get -1.

    The whole-to-whole start always adds the sign search's starts
    (:mod:`meshcorr.choice.sign_search`, ``sign_search=True``): a part's tips
    are a subset of the whole's, and the starts from matched tips often all
    miss its global configuration. On 12 plane cuts to 75 % of three TOSCA
    dog pairs this took the mean error from 0.157 to 0.075 (0.200 -> 0.035
    on the half not looked at first), and it left the 24 cuts of
    ``benchmarks/partial_check.py`` as they were (0.058 -> 0.059), at about
    1.5 s more a part (``benchmarks/RESULTS-partial.md``).
    """
    partial, extremities, options = settings.partial, settings.extremities, _partial_options(settings, max_memory)
    src, tgt = as_meshes(*shapes)
    ordered = shapes if partial == "source" else shapes[::-1]
    part, whole = as_meshes(*ordered)
    part_rows, whole_rows = geodesic_rows(part, settings.geodesic), geodesic_rows(whole, settings.geodesic)
    check_roles(part, whole, part_rows, whole_rows, role=partial)
    if pairs is not None and partial == "target":
        pairs = pairs[:, ::-1].copy()
    with timer.stage("whole-to-whole"), warnings.catch_warnings():
        # The part matched as a whole shape is one start among the others (its warnings, e.g. of
        # partiality, do not apply here). Meshes, not prepared shapes: those keep the part's boundary.
        warnings.simplefilter("ignore", MeshWarning)
        plain = match(part, whole, Settings(**dict(options, fill_holes=True), extremities=extremities))
    initial = [("whole-to-whole", plain.local_map())]
    if plain.alternative_map is not None:  # input numbering -> the meshes' local numbering
        to_local = np.full(whole.n_original, -1, dtype=np.int64)
        to_local[whole.kept] = np.arange(whole.n_vertices)
        initial.append(("whole-to-whole-alternative", to_local[plain.alternative_map[part.kept]]))
    found = match_part(part, whole, part_rows, whole_rows, landmarks=pairs, extremities=extremities,
                       initial_maps=initial, refine=settings.refine, refine_k=settings.refine_k,
                       shells=settings.shells, random_state=settings.random_state, timer=timer)
    check_part_not_larger(part, whole, found.scale, role=partial)
    local_map, other_map = found.mapping, found.alternative
    if partial == "target":
        with timer.stage("region"):
            local_map = invert_part_map(whole, found.mapping, found.region)
            other_map = None if other_map is None else invert_part_map(
                whole, other_map, part_region(part, whole, other_map, found.scale))
    full_maps = []
    for mapping in (local_map, other_map):
        full = None
        if mapping is not None:
            full = np.full(src.n_original, -1, dtype=np.int64)
            mapped = mapping >= 0
            full[src.kept[mapped]] = tgt.kept[mapping[mapped]]
        full_maps.append(full)
    region = np.zeros(whole.n_original, dtype=bool)
    region[whole.kept[found.region]] = True
    params = dict(options, extremities=extremities, symmetry="auto", partial=partial,
                  landmarks=None if pairs is None else (pairs if partial == "source" else pairs[:, ::-1]).tolist())
    return Correspondence(
        map=full_maps[0], source=src, target=tgt, source_vertices=src.kept.copy(), target_vertices=tgt.kept.copy(),
        timings=timer.timings, params=params, alternative_map=full_maps[1], orientation_reliable=found.reliable,
        refine_history=found.history, map_candidates=found.candidates, partial=partial, matched_region=region,
        matched_area_fraction=found.area_fraction)


def _chosen_first(configurations: list[Configuration], chosen: ConfigurationCandidate,
                  other: ConfigurationCandidate | None) -> list[Configuration]:
    """The ranked configurations with the chosen one first and the alternative second."""
    head = [chosen.configuration] + ([other.configuration] if other is not None else [])
    return head + [c for c in configurations if all(c is not h for h in head)]


# "Match again" of Correspondence.pick() runs match through this hook (maps may not import pipeline).
result_module.RERUN = match
