"""The spectral correspondence pipeline of Jain & Zhang (2006), top to bottom.

``match(source, target)`` runs the steps 1-7 of docs/method.md:

1. all-pairs geodesic distances on each mesh;
2. Gaussian affinities, sigma = the largest geodesic distance;
3. spectral embedding: top-k eigenvectors scaled by sqrt(eigenvalue),
   the first dropped;
4. eigenvector reordering and sign correction (ranked configurations);
5. thin-plate-spline ICP in the spectral domain;
6. anchor selection and proximity-aided matching;
7. optionally a bijective map by linear assignment.

Reference: V. Jain, H. Zhang, "Robust 3D shape correspondence in the
spectral domain", Shape Modeling International 2006.
"""

from __future__ import annotations

import warnings
from typing import NamedTuple

import numpy as np

from ..runtime.checks import check_bool, check_choice, check_float, check_int, check_seed
from ..runtime.threads import parallel_map
from ..stages.anchors import EXACT_PAIRS, anchor_descriptors, embedding_neighbours, proximity_matching, select_anchors
from ..stages.bijection import check_fixed_pairs, nearest_bijection
from ..choice.curvature import curvature_disagreement
from ..errors import MeshWarning, ParameterError, PartialShapeWarning
from ..choice.extremities import match_extremities, spectrum_extremities
from ..stages.icp import tps_icp
from ..stages.landmarks import check_landmarks, landmark_descriptors, landmark_map
from ..core.mesh import Mesh, MeshLike
from .methods import METHOD_NAMES, applicable_options, changed_options, reject_inapplicable, run_method
from ..spectral.modes import MODES, N_SAMPLES, SCALABLE_ABOVE, resolve_memory, select_mode
from ..choice.orientation import mesh_orientation, orientation_score
from ..choice.oriented_start import fit_oriented_map
from .partial import (check_part_not_larger, check_partial_options, check_roles, geodesic_rows, invert_part_map,
                      match_part, part_region, partiality_suspicion)
from ..core.holes import fills, restrict, unfilled
from ..shapes.prepared import REFINE_K, PreparedShape, as_meshes, pair_shapes, pair_spectrum, shape_settings
from ..runtime.progress import as_progress
from ..stages.refine import prefetch_bases, refine_map
from ..stages.reorder import REORDER_MODES, Configuration, rank_configurations
from ..maps.result import Correspondence
from ..choice.repair import repair_candidates
from ..choice.selection import MapCandidate, candidate_summaries, choose_map, score_candidates, shell_candidates
from ..stages.shells import shell_refine
from ..choice.symmetry import (SYMMETRY_MODES, WIDE_CANDIDATES, Candidate, candidate_ranks, choose, metric_distortion,
                       right_map_missing)
from ..runtime.timing import StageProgress, StageTimer

#: How a tip assignment becomes a dense map: "distances" (meshcorr.stages.landmarks) or "oriented"
#: (meshcorr.choice.oriented_start, when the orientation is reliable); the first is named
#: "extremities-<rank>", others get their name appended. benchmarks/selection_study.py runs both:
#: "oriented" alone was better on TOSCA and SHREC'07 humans and much worse on gorilla -> human
#: (benchmarks/RESULTS-robustness-trials.md), so the default stays "distances".
EXTREMITY_STARTS: tuple[str, ...] = ("distances",)
from ..stages.tps import mean_pairwise_distance

#: Geodesic rows sampled on the source for the metric distortion of a candidate
#: (measured only when the orientation is unreliable).
N_DISTORTION_SOURCES = 16
ANCHOR_SCALES = ("embedding", "geodesic")
#: Default of a renamed keyword: passing it raises a ParameterError naming the new one.
_RENAMED = object()


def match(source: MeshLike | PreparedShape, target: MeshLike | PreparedShape, *, k: int = 6,
          geodesic: str = "heat",
          scale_eigenvalues: bool = True, reorder: str = "exhaustive", icp_iterations: int = 10,
          n_control: int = 500, anneal: float = 0.5, n_anchors: int = 3, anchor_weight: float = 1.0,
          bijective: bool = False, largest_component: bool = False, random_state: int | None = 0,
          progress: StageProgress | None = None, mode: str = "auto", n_samples: int = N_SAMPLES,
          max_memory: int | str | None = None, scalable_above: int = SCALABLE_ABOVE,
          method: str = "spectral", prealign: bool = True,
          symmetry: str = "auto", refine: bool = True, refine_k: int = REFINE_K, shells: bool = True,
          anchor_scale: str = "embedding", landmarks=None, extremities: bool = True,
          oriented_starts: bool = False, partial: str | None = None, fill_holes: bool = True,
          n_landmarks=_RENAMED) -> Correspondence:
    """Dense vertex correspondence from ``source`` to ``target``.

    Parameters
    ----------
    source, target : path, trimesh.Trimesh, Mesh, (vertices, faces) or PreparedShape
        Triangle meshes: closed or open 2-manifolds, one connected component
        each (see ``largest_component``). Any pose, position, rotation,
        uniform scale and vertex count. A shape from :func:`meshcorr.prepare`
        skips the per-shape work and gives the same map as its mesh; it must
        have been prepared with this call's ``k``, ``geodesic``,
        ``scale_eigenvalues``, ``n_samples``, ``refine``, ``refine_k``,
        ``largest_component``, ``random_state``, ``fill_holes`` (as this
        call uses it: False with ``partial`` or ``bijective``) and the pair's mode.
    k : int
        Eigenpairs computed; the embedding has ``k - 1`` dimensions (paper: 6).
    geodesic : {"heat", "fmm", "exact", "dijkstra"}
        Geodesic solver (see :mod:`meshcorr.core.geodesics`).
    scale_eigenvalues : bool
        Scale eigenvectors by sqrt(eigenvalue) (the paper's default).
    reorder : {"exhaustive", "greedy", "signs", "signs-greedy", "none"}
        Eigenvector reordering and sign correction (see :mod:`meshcorr.stages.reorder`).
    icp_iterations : int
        Most thin-plate-spline ICP iterations; 0 skips the alignment.
    n_control : int
        Spline control points.
    anneal : float
        Factor lowering the spline regulariser each iteration.
    n_anchors : int
        h, anchor pairs for proximity-aided matching (0 disables it).
    anchor_weight : float
        alpha, weight of each anchor's geodesic term.
    bijective : bool
        One-to-one map by linear assignment (equal vertex counts only; each
        landmark vertex given once): every target vertex exactly once
        (:mod:`meshcorr.stages.bijection`).
    largest_component : bool
        Map only the largest connected component of each mesh instead of
        raising on several components.
    random_state : int or None
        Seed for everything random (eigensolver start, samples).
    progress : callable or bool, optional
        ``progress(stage, done, total)``, or True for a progress bar
        (:class:`meshcorr.runtime.progress.TqdmProgress`, notebook-aware).
    mode : {"auto", "dense", "scalable"}
        "dense": all-pairs geodesics and the exact eigenpairs (``O(n^2)``
        memory, the reference); "scalable": landmark geodesics and the
        Nyström extension (``O(n m)``); "auto": dense up to
        ``scalable_above`` vertices if it fits in ``max_memory``, else
        scalable (see :mod:`meshcorr.spectral.modes`).
    n_samples : int
        m, Nyström samples (landmark vertices) of the scalable mode
        (formerly ``n_landmarks``, which now raises :class:`ParameterError`).
    max_memory : int or str, optional
        Bytes (or a size such as ``"4GiB"``) the dense mode may use; it
        refuses larger inputs. Default: 80 % of the memory available now.
    scalable_above : int
        Vertex count above which "auto" picks the scalable mode.
    method : {"spectral", "shapiro-brady", "shapiro-brady-scaled", "tps-rpm", "icp", "shape-context"}
        "spectral" is this pipeline; the others are the paper's baselines
        (:mod:`meshcorr.baselines`), which take ``k``, ``geodesic``,
        ``bijective`` and ``largest_component`` where they apply; an option
        changed from its default that the method does not use raises
        :class:`ParameterError` naming it (:func:`meshcorr.pipeline.methods.reject_inapplicable`).
    prealign : bool
        Pre-align the inputs to their principal axes (spatial baselines only).
    symmetry : {"auto", "cost", "mirror"}
        How to choose among near-tied eigenvector configurations (the
        left/right mirror, :mod:`meshcorr.choice.symmetry`): "auto" keeps the
        orientation-preserving map whose curvature agrees best, then the
        whole-map choice (``extremities``, ``landmarks``); "cost" the cheapest
        configuration (the paper); "mirror" the configuration of the other
        orientation than "auto"'s (it may be the cheapest, and then the same
        map as "cost"). "cost" and "mirror" skip the whole-map choice and do
        not go with ``landmarks`` (:class:`ParameterError`).
    refine : bool
        Refine the map by ZoomOut spectral upsampling (:mod:`meshcorr.stages.refine`).
    refine_k : int
        Laplace-Beltrami basis size of the refinement.
    shells : bool
        After the refinement, align the shapes' smooth shells (their
        coordinates low-passed to a growing number of Laplace-Beltrami
        functions) by a rigid motion and a smooth deformation, and map in the
        product of that space and the spectral one (:mod:`meshcorr.stages.shells`,
        after Smooth Shells), on a schedule of small steps
        (:data:`meshcorr.stages.shells.SCALES`). With ``landmarks`` their geodesic
        distances join that space. Meshes only, with ``refine`` and without
        ``bijective`` (point clouds and one-to-one maps keep the ZoomOut
        map); a declared part is aligned with the whole's shells from 16
        functions on (:mod:`meshcorr.pipeline.partial`, step 6).
    anchor_scale : {"embedding", "geodesic"}
        "embedding": the anchor term is expressed in the embedding's length
        scale (its geodesics times mean embedding distance / (h x mean
        normalised geodesic distance)), so it is commensurate with the
        embedding term; "geodesic": geodesics divided by the largest one,
        as the paper does (docs/method.md, step 6).
    landmarks : sequence of (source_index, target_index), optional
        Vertices the user knows to correspond (0-based, input numbering).
        They start a candidate map of their own, decide among the candidate
        maps (the one that agrees with them wins: this settles the left/right
        choice), join the descriptors of the smooth-shell alignment (their
        geodesic distances) and are mapped exactly (:mod:`meshcorr.choice.selection`).
    extremities : bool
        Also try maps started from matched shape extremities
        (:mod:`meshcorr.choice.extremities`) and keep the map the whole-map energies
        prefer (:mod:`meshcorr.choice.selection`); needed when the shapes'
        proportions differ. Used with ``symmetry="auto"``.
    oriented_starts : bool
        Also turn each tip assignment into a map by an orientation-preserving
        functional-map fit (:mod:`meshcorr.choice.oriented_start`), not only by
        distances to the tips. Distances to tips that lie near one plane (a
        person standing: head, hands and feet) cannot tell front from back;
        the fit can. Measured better on people of one species (SHREC'07
        humans) and worse across species (gorilla -> human: the fit turns a
        mirrored assignment into a map turned front to back that the energies
        do not always reject), so it is off by default
        (``benchmarks/RESULTS-robustness.md``). Needs a reliable orientation.
    partial : {None, "source", "target"}
        None: both shapes are whole (they may have small holes).
        ``"source"``: the source is a part of the target (one side of a scan,
        a shape cut by a plane or with large holes); ``"target"``: the target
        is a part of the source. The map then covers the part only (with
        ``"target"``, source vertices outside the matched region get -1), and
        ``result.matched_region`` / ``result.matched_area_fraction`` say which
        region of the whole shape was matched (:mod:`meshcorr.pipeline.partial`; the
        options of steps 1-7 shape one of its starting maps). A declared part
        must have a boundary and must not be larger than the whole;
        ``bijective=True``, a ``symmetry`` other than "auto" and a method
        other than "spectral" do not go with it (each raises
        :class:`~meshcorr.errors.PartialityError`). When it is None and one
        shape has a long open boundary the other lacks,
        :class:`~meshcorr.errors.PartialShapeWarning` names the mode to use.
    fill_holes : bool
        Close the meshes' holes before matching: each simple boundary loop
        gets a fan of triangles around a new centre vertex, and the map is
        reported on the input's vertices only (a vertex sent onto a cap goes
        to the nearest vertex of its hole's rim; :mod:`meshcorr.core.holes`).
        Holes change geodesics, the Laplace-Beltrami functions and the
        extremities; closed, a shape with holes maps about as well as
        without them. Not done with ``partial`` (a part's boundary is its
        cut) nor with ``bijective`` (the vertex counts must stay).

    Returns
    -------
    result : Correspondence
        ``result.map[i]`` is the target vertex of source vertex i.
    """
    check_partial_options(partial, method, changed_options(match, locals()))  # PartialityError
    reject_inapplicable(method, changed_options(match, locals()))  # ParameterError naming unused options
    progress = as_progress(progress)
    random_state = check_seed(random_state)
    for name, value in (("bijective", bijective), ("shells", shells), ("extremities", extremities),
                        ("oriented_starts", oriented_starts), ("prealign", prealign)):
        check_bool(name, value)
    if check_choice("method", method, METHOD_NAMES) != "spectral":
        common = dict(k=k, geodesic=geodesic, bijective=bijective, largest_component=largest_component)
        source, target = as_meshes(source, target)
        return run_method(method, source, target, prealign=prealign, random_state=random_state,
                          progress=progress, **applicable_options(method, common))

    if n_landmarks is not _RENAMED:
        raise ParameterError(f"n_landmarks was renamed n_samples (the Nyström sample count of the scalable "
                             f"mode): pass n_samples={n_landmarks!r} instead.")
    settings = shape_settings(k=k, geodesic=geodesic, scale_eigenvalues=scale_eigenvalues, n_samples=n_samples,
                              refine=refine, refine_k=refine_k, largest_component=largest_component,
                              random_state=random_state, fill_holes=fill_holes)
    settings["fill_holes"] = fills(fill_holes, partial=partial, bijective=bijective)
    k, n_samples, refine_k = settings["k"], settings["n_samples"], settings["refine_k"]
    check_choice("reorder", reorder, REORDER_MODES)
    n_anchors = check_int("n_anchors", n_anchors, minimum=0)
    anchor_weight = check_float("anchor_weight", anchor_weight, minimum=0.0)
    check_choice("mode", mode, MODES)
    max_memory = resolve_memory(max_memory)
    check_choice("symmetry", symmetry, SYMMETRY_MODES)
    check_choice("anchor_scale", anchor_scale, ANCHOR_SCALES)
    timer = StageTimer(progress)

    with timer.stage("load"):  # meshes, or shapes prepared with these settings (meshcorr.shapes.prepared)
        shapes = pair_shapes(source, target, settings)
        src, tgt = as_meshes(*shapes)
        pairs = check_landmarks(landmarks, src, tgt)
    if bijective and pairs is not None:  # named in the input's numbering
        check_fixed_pairs(np.stack([src.kept[pairs[:, 0]], tgt.kept[pairs[:, 1]]], axis=1))
    if n_anchors > min(src.n_vertices, tgt.n_vertices):  # each anchor pairs two distinct vertices
        raise ParameterError(f"n_anchors={n_anchors} (--anchors) is more than the smaller shape's "
                             f"{min(src.n_vertices, tgt.n_vertices)} vertices; the paper's few anchors (3-10) "
                             "are what the matching needs.")
    if pairs is not None and symmetry != "auto":
        raise ParameterError(f"Landmarks settle the left/right choice in the whole-map choice (symmetry='auto'); "
                             f"symmetry={symmetry!r} (--symmetry {symmetry}) would set them aside. Keep "
                             "symmetry='auto' (the default) with landmarks.")
    if partial is not None:  # a part against the whole: meshcorr.pipeline.partial; the default mode gives one start
        spectral_options = dict(k=k, geodesic=geodesic, scale_eigenvalues=scale_eigenvalues, reorder=reorder,
                                icp_iterations=icp_iterations, n_control=n_control, anneal=anneal,
                                n_anchors=n_anchors, anchor_weight=anchor_weight, anchor_scale=anchor_scale,
                                largest_component=largest_component, mode=mode, n_samples=n_samples,
                                max_memory=max_memory, scalable_above=scalable_above, refine=refine,
                                refine_k=refine_k, shells=shells, random_state=random_state, fill_holes=False)
        return _match_partial(shapes, pairs, partial, spectral_options, extremities=extremities, timer=timer)

    mode = select_mode(mode, src.n_vertices, tgt.n_vertices, max_memory=max_memory,
                       scalable_above=scalable_above, bijective=bijective)
    # The refinement's Laplace-Beltrami bases depend on the meshes only: a worker
    # thread computes them while steps 1-7 run (meshcorr.stages.refine.prefetch_bases).
    with prefetch_bases(src, tgt, refine_k, random_state=random_state, enabled=refine) as bases:
        # Steps 1-3: geodesic distances, Gaussian affinities, scaled spectral embedding.
        spectra = [pair_spectrum(shape, settings, mode, timer) for shape in shapes]
        X, Y = spectra[0].embedding, spectra[1].embedding
        suspicion = partiality_suspicion(unfilled(src), unfilled(tgt), spectra[0].max_geodesic,
                                         spectra[1].max_geodesic)
        if suspicion:  # a part given as a whole shape (meshcorr.pipeline.partial)
            warnings.warn(suspicion, PartialShapeWarning, stacklevel=2)

        # Step 4: eigenvector reordering and sign correction.
        with timer.stage("reorder"):
            configurations = rank_configurations(X, Y, reorder, random_state=random_state)

        # Steps 5-7 for each near-tied configuration; the left/right mirror is
        # resolved by the orientation of each candidate's map (meshcorr.choice.symmetry).
        options = dict(icp_iterations=icp_iterations, n_control=n_control, anneal=anneal,
                       n_anchors=n_anchors, anchor_weight=anchor_weight, anchor_scale=anchor_scale,
                       bijective=bijective, random_state=random_state)
        with timer.stage("symmetry"):
            reliable = mesh_orientation(src).reliable and mesh_orientation(tgt).reliable
        candidates = _score_candidates(src, tgt, spectra, configurations, timer, options, reliable=reliable)
        chosen, other = choose(candidates, symmetry, orientation_reliable=reliable)
        if not reliable and symmetry == "auto" and len(candidates) > 1:
            unsure = src if mesh_orientation(src).reason else tgt
            why = f"{unsure.name}: {mesh_orientation(unsure).reason}"
            warnings.warn(f"The left/right orientation cannot be checked: {why}. The map may be the mirror "
                          "image of the right one; compare it with result.alternative_map.", MeshWarning,
                          stacklevel=2)
        with timer.stage("matching"):
            spread = embedding_spread(spectra[0]) if anchor_scale == "embedding" and n_anchors > 0 else 1.0
            for candidate in (chosen, other):
                if candidate is not None:
                    _finish(candidate, X, spectra, spread, **options)
        if refine:
            with timer.stage("refine"):
                bases.wait()
    refine_history: list = []
    if refine:  # the chosen map only: the alternative is kept as proximity matching gave it
        with timer.stage("refine"):
            chosen.mapping, refine_history = refine_map(src, tgt, chosen.mapping, k=refine_k,
                                                        bijective=bijective, random_state=random_state)
    # Whole-map choice: the spectral map against maps from matched extremities
    # and from the user's landmarks, each refined alike (meshcorr.choice.selection).
    shell_stage = refine and shells and not bijective and not (src.is_cloud or tgt.is_cloud)
    # The landmarks' geodesic distances, a further coordinate of the shells' product space.
    described = None if pairs is None or not shell_stage else tuple(
        landmark_descriptors(spectrum.geodesics_from, ends) for spectrum, ends in zip(spectra, pairs.T))
    choice = _Choice(chosen.mapping, None if other is None else other.mapping, [])
    if symmetry == "auto" and (extremities or pairs is not None):  # stages "whole-map" and "shells"
        choice = _whole_map_choice(
            src, tgt, spectra, chosen.mapping, choice.other, pairs, extremities=extremities, refine=refine,
            refine_k=refine_k, bijective=bijective, reliable=reliable, shells=shell_stage, timer=timer,
            described=described, tip_starts=EXTREMITY_STARTS + (("oriented",) if oriented_starts else ()),
            random_state=random_state)
    local_map, other_map, map_candidates = choice.mapping, choice.other, choice.summaries
    spectral_kept = choice.spectral_kept
    if shell_stage:
        with timer.stage("shells"):  # meshcorr.stages.shells: extrinsic alignment of the chosen map
            if not choice.shelled:
                local_map = shell_refine(src, tgt, local_map, k=refine_k, landmarks=pairs, descriptors=described,
                                         orientation=choice.orientation, random_state=random_state)
        spectral_kept = False
    if bijective:  # an unrefined start of the whole-map choice, or pinned landmarks, are not one-to-one
        local_map = nearest_bijection(local_map, tgt.vertices, fixed=pairs)
        other_map = None if other_map is None else nearest_bijection(other_map, tgt.vertices)
    icp, anchors = chosen.extra["icp"], chosen.extra["anchors"]

    full_map = np.full(src.n_original, -1, dtype=np.int64)
    full_map[src.kept] = tgt.kept[local_map]
    full_cost = None  # the matching cost means something only for the unrefined spectral map
    if not refine and spectral_kept:
        full_cost = np.full(src.n_original, np.nan)
        full_cost[src.kept] = chosen.extra["cost"]
    alternative_map = None
    if other_map is not None:
        alternative_map = np.full(src.n_original, -1, dtype=np.int64)
        alternative_map[src.kept] = tgt.kept[other_map]
    summaries = [dict(c.to_dict(), chosen=c is chosen, alternative=c is other) for c in candidates]
    Y_configured = chosen.configuration.apply(Y)
    params = dict(k=k, geodesic=geodesic, scale_eigenvalues=scale_eigenvalues, reorder=reorder,
                  icp_iterations=icp_iterations, n_control=n_control, anneal=anneal,
                  n_anchors=n_anchors, anchor_weight=anchor_weight, bijective=bijective,
                  largest_component=largest_component, random_state=random_state, mode=mode,
                  n_samples=n_samples, max_memory=max_memory, symmetry=symmetry, refine=refine,
                  refine_k=refine_k, shells=shell_stage, anchor_scale=anchor_scale, extremities=extremities,
                  oriented_starts=oriented_starts, fill_holes=settings["fill_holes"],  # as they ran
                  landmarks=None if pairs is None else np.stack([src.kept[pairs[:, 0]], tgt.kept[pairs[:, 1]]],
                                                                axis=1).tolist())
    return restrict(Correspondence(  # without the holes' caps (meshcorr.core.holes)
        map=full_map, cost=full_cost, source=src, target=tgt,
        source_vertices=src.kept.copy(), target_vertices=tgt.kept.copy(),
        source_embedding=X, target_embedding=Y_configured, aligned_target_embedding=icp.warped,
        eigenvalues={"source": spectra[0].eigenvalues, "target": spectra[1].eigenvalues}, configuration=chosen.configuration,
        alternatives=_chosen_first(configurations, chosen, other),
        anchors=np.stack([src.kept[anchors[:, 0]], tgt.kept[anchors[:, 1]]], axis=1),
        icp_history=icp.history, icp_converged=icp.converged, timings=timer.timings,
        background_timings={} if bases.seconds is None else {"refine_bases": bases.seconds}, params=params,
        candidates=summaries, alternative_map=alternative_map, orientation_reliable=reliable,
        refine_history=refine_history, map_candidates=map_candidates,
    ), src, tgt)


def embedding_spread(spectrum) -> float:
    """:func:`meshcorr.stages.tps.mean_pairwise_distance` of a spectrum's embedding, computed once per spectrum.

    The anchors' length scale of :func:`_finish` depends on the source shape
    only (a seeded sample of its embedding), so a prepared shape matched many
    times measures it once (kept in ``spectrum.memo``; the same value).
    """
    if "spread" not in spectrum.memo:
        spectrum.memo["spread"] = mean_pairwise_distance(spectrum.embedding)
    return spectrum.memo["spread"]


def _match_partial(shapes, pairs: np.ndarray | None, partial: str, spectral_options: dict, *, extremities: bool,
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
    turned round (:func:`meshcorr.pipeline.partial.invert_part_map`): source vertices
    outside the matched region get -1.
    """
    geodesic, refine, refine_k = (spectral_options[key] for key in ("geodesic", "refine", "refine_k"))
    random_state = spectral_options["random_state"]
    src, tgt = as_meshes(*shapes)
    ordered = shapes if partial == "source" else shapes[::-1]
    part, whole = as_meshes(*ordered)
    part_rows, whole_rows = geodesic_rows(part, geodesic), geodesic_rows(whole, geodesic)
    check_roles(part, whole, part_rows, whole_rows, role=partial)
    if pairs is not None and partial == "target":
        pairs = pairs[:, ::-1].copy()
    with timer.stage("whole-to-whole"), warnings.catch_warnings():
        # The part matched as a whole shape is one start among the others (its warnings, e.g. of
        # partiality, do not apply here). Meshes, not prepared shapes: those keep the part's boundary.
        warnings.simplefilter("ignore", MeshWarning)
        plain = match(part, whole, extremities=extremities, **dict(spectral_options, fill_holes=True))
    initial = [("whole-to-whole", plain.local_map())]
    if plain.alternative_map is not None:  # input numbering -> the meshes' local numbering
        to_local = np.full(whole.n_original, -1, dtype=np.int64)
        to_local[whole.kept] = np.arange(whole.n_vertices)
        initial.append(("whole-to-whole-alternative", to_local[plain.alternative_map[part.kept]]))
    found = match_part(part, whole, part_rows, whole_rows, landmarks=pairs, extremities=extremities,
                       initial_maps=initial, refine=refine, refine_k=refine_k, shells=spectral_options["shells"],
                       random_state=random_state, timer=timer)
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
    params = dict(spectral_options, extremities=extremities, symmetry="auto", partial=partial,
                  landmarks=None if pairs is None else (pairs if partial == "source" else pairs[:, ::-1]).tolist())
    return Correspondence(
        map=full_maps[0], source=src, target=tgt, source_vertices=src.kept.copy(), target_vertices=tgt.kept.copy(),
        timings=timer.timings, params=params, alternative_map=full_maps[1], orientation_reliable=found.reliable,
        refine_history=found.history, map_candidates=found.candidates, partial=partial, matched_region=region,
        matched_area_fraction=found.area_fraction)


class _Choice(NamedTuple):
    """What :func:`_whole_map_choice` returns."""

    mapping: np.ndarray  # the chosen local map
    other: np.ndarray | None  # the least distorted map of the other orientation, else the spectral alternative
    summaries: list  # every candidate's scores (MapCandidate.to_dict, chosen, alternative)
    spectral_kept: bool = True  # the chosen map is the spectral map unchanged (no other candidate, no pin)
    shelled: bool = False  # the candidates were judged after meshcorr.stages.shells: the chosen map is final
    orientation: float | None = None  # the chosen map's orientation score, when it is that exact map's


def _whole_map_choice(src: Mesh, tgt: Mesh, spectra, spectral_map: np.ndarray, spectral_other,
                      pairs: np.ndarray | None, *, extremities: bool, refine: bool, refine_k: int,
                      bijective: bool, reliable: bool, shells: bool, timer: StageTimer,
                      described: tuple[np.ndarray, np.ndarray] | None = None,
                      tip_starts: tuple[str, ...] = EXTREMITY_STARTS, random_state) -> _Choice:
    """Candidate maps from extremities and landmarks, scored with the spectral map; the winner.

    With ``shells`` on and a reliable orientation, the choice is made between
    the maps as the pipeline returns them: each partly mirrored candidate
    adds its repair (:func:`meshcorr.choice.repair.repair_candidates`), and every
    candidate that keeps the orientation is refined by the smooth shells
    (:func:`meshcorr.choice.selection.shell_candidates`) and scored again. A right
    map whose ZoomOut vertices are scattered locally scores as low as a
    mirrored one before the shells (TOSCA michael11 -> michael16: 0.59
    against 0.2-0.58) and above 0.9 after them.
    """
    with timer.stage("whole-map"):
        g1, g2 = spectra[0].geodesics_from, spectra[1].geodesics_from
        hows = tuple(dict.fromkeys(tip_starts)) if reliable else ("distances",)  # the first is unnamed
        starts: list[tuple[str, np.ndarray, dict]] = []
        if pairs is not None:
            starts.append(("landmarks", landmark_map(g1, g2, pairs), {}))
        if extremities:
            tips = [spectrum_extremities(mesh, spectrum, random_state=random_state)
                    for mesh, spectrum in zip((src, tgt), spectra)]
            for rank, (energy, assignment) in enumerate(match_extremities(*tips)):
                for how in hows:
                    start = (fit_oriented_map(src, tgt, g1, g2, assignment, basis_k=refine_k,
                                              random_state=random_state) if how == "oriented"
                             else landmark_map(g1, g2, assignment))
                    suffix = "" if how == hows[0] else f"-{how}"
                    starts.append((f"extremities-{rank}{suffix}", start, {"extremity_energy": energy}))
        candidates = [MapCandidate("spectral", spectral_map)]
        if spectral_other is not None:  # unrefined: it is kept as the alternative, rarely chosen
            candidates.append(MapCandidate("spectral-alternative", spectral_other))
        def refined(start: tuple[str, np.ndarray, dict]) -> np.ndarray:
            # Only the landmarks' own map is held to them while refined: the others must show
            # by themselves whether they agree with the landmarks (meshcorr.choice.selection).
            origin, mapping, _ = start
            pins = pairs if origin == "landmarks" else None
            return refine_map(src, tgt, mapping, k=refine_k, bijective=bijective, random_state=random_state,
                              landmarks=pins)[0] if refine else mapping

        # Independent refinements, mostly BLAS and LAPACK: one thread per core (same maps as a loop).
        for (origin, _, extra), mapping in zip(starts, parallel_map(refined, starts)):
            candidates.append(MapCandidate(origin, mapping, extra=extra))
        score_candidates(candidates, src, tgt, g1, g2, reliable=reliable, landmarks=pairs, random_state=random_state)
    if shells and reliable:  # judge the maps as they will be returned (module docstrings of these steps)
        with timer.stage("shells"):
            scored = dict(reliable=reliable, landmarks=pairs, random_state=random_state)
            repaired = repair_candidates(candidates, src, tgt, k=refine_k, random_state=random_state)
            score_candidates(repaired, src, tgt, g1, g2, **scored)
            candidates += repaired
            final = shell_candidates(candidates, src, tgt, k=refine_k, landmarks=pairs, descriptors=described,
                                     random_state=random_state)
            score_candidates(final, src, tgt, g1, g2, **scored)
    chosen, alternative = choose_map(candidates, reliable=reliable)
    mapping = chosen.mapping.copy()
    if pairs is not None:
        mapping[pairs[:, 0]] = pairs[:, 1]
    other = alternative.mapping if alternative is not None else spectral_other
    summaries = candidate_summaries(candidates, chosen, alternative, reliable=reliable)
    shelled = bool(chosen.extra.get("shells"))
    return _Choice(mapping, other, summaries, chosen.origin == "spectral" and pairs is None and not shelled,
                   shelled, chosen.orientation if pairs is None and np.isfinite(chosen.orientation) else None)


def _chosen_first(configurations: list[Configuration], chosen: Candidate,
                  other: Candidate | None) -> list[Configuration]:
    """The ranked configurations with the chosen one first and the alternative second."""
    head = [chosen.configuration] + ([other.configuration] if other is not None else [])
    return head + [c for c in configurations if all(c is not h for h in head)]


def _score_candidates(src: Mesh, tgt: Mesh, spectra, configurations: list[Configuration],
                      timer: StageTimer, options: dict, *, reliable: bool) -> list[Candidate]:
    """Align each near-tied configuration and score its map (orientation, curvature).

    The scores use each candidate's TPS-ICP nearest-neighbour map: the
    anchors and the refinement only run for the chosen map and its
    alternative (:func:`_finish`). When the near-tied set seems to lack the
    right map (:func:`meshcorr.choice.symmetry.right_map_missing`), the cheapest
    ``WIDE_CANDIDATES`` configurations are scored. The metric distortion (single-source
    geodesic solves, the costliest score at 100k vertices) is measured only
    when the orientation is unreliable, the one case where it decides.
    """
    X, Y = spectra[0].embedding, spectra[1].embedding
    g1, g2 = spectra[0].geodesics_from, spectra[1].geodesics_from
    seed = options["random_state"]
    rng = np.random.default_rng(seed)
    sources = rng.choice(len(X), size=min(N_DISTORTION_SOURCES, len(X)), replace=False)
    source_rows: dict = {}

    def score(ranks: list[int]) -> list[Candidate]:
        # The candidates' alignments are independent: one thread per core (meshcorr.runtime.threads).
        with timer.stage("icp"):
            icps = parallel_map(lambda rank: _align(X, configurations[rank].apply(Y), **options), ranks)
        with timer.stage("symmetry"):
            return [Candidate(
                rank=rank, configuration=configurations[rank],
                orientation=orientation_score(src, tgt, icp.matches, random_state=seed),
                curvature=curvature_disagreement(src, tgt, icp.matches, random_state=seed),
                distortion=(np.nan if reliable else
                            metric_distortion(g1, g2, icp.matches, sources, source_rows)),
                mapping=icp.matches, extra={"icp": icp, "anchors": np.zeros((0, 2), dtype=np.int64),
                                            "cost": None}) for rank, icp in zip(ranks, icps)]

    ranks = candidate_ranks(configurations)
    candidates = score(ranks)
    if reliable and right_map_missing(candidates):
        candidates += score([rank for rank in range(min(WIDE_CANDIDATES, len(configurations)))
                             if rank not in ranks])
    return candidates


def _align(X: np.ndarray, Y_configured: np.ndarray, *, icp_iterations: int, n_control: int,
           anneal: float, random_state, **_):
    """Step 5: thin-plate-spline ICP of one configured target embedding."""
    return tps_icp(X, Y_configured, max_iter=icp_iterations, n_control=n_control, anneal=anneal,
                   random_state=random_state)


def _finish(candidate: Candidate, X: np.ndarray, spectra, spread: float, *, n_anchors: int,
            anchor_weight: float, anchor_scale: str, bijective: bool, **_) -> None:
    """Steps 6-7 for one aligned candidate: anchors, proximity-aided matching.

    With ``anchor_scale="embedding"`` the normalised geodesic term is put in
    the embedding's length scale: multiplied by the mean distance between
    embedded points over ``h`` times the mean normalised geodesic distance
    to the anchors (docs/method.md, "Choices where the paper is silent": geodesics in [0, 1] summed over
    three anchors dwarf embedding distances of ~0.1-0.3). ``spread`` is that mean
    distance, :func:`meshcorr.stages.tps.mean_pairwise_distance` of ``X``.
    """
    warped = candidate.extra["icp"].warped
    g1, g2 = spectra[0].geodesics_from, spectra[1].geodesics_from
    # Beyond EXACT_PAIRS both steps search each source point's nearest embedded target points.
    neighbours = embedding_neighbours(X, warped) if len(X) * len(warped) > EXACT_PAIRS else None
    anchors = select_anchors(X, warped, g1, g2, n_anchors, neighbours=neighbours)
    F1 = anchor_descriptors(anchors[:, 0], g1, np.ones(n_anchors))
    F2 = anchor_descriptors(anchors[:, 1], g2, np.ones(n_anchors))
    scale = anchor_weight
    if anchor_scale == "embedding" and n_anchors > 0:
        mean_geodesic = 0.5 * (F1.mean() + F2.mean())
        scale *= spread / (n_anchors * max(mean_geodesic, 1e-12))
    mapping, cost = proximity_matching(X, warped, F1 * scale, F2 * scale, bijective=bijective,
                                       neighbours=neighbours)
    candidate.mapping = mapping
    candidate.extra.update(anchors=anchors, cost=cost)

