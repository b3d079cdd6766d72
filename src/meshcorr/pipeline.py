"""The spectral correspondence pipeline of Jain & Zhang (2006), top to bottom.

``match(source, target)`` runs ALGORITHM.md steps 1-7:

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

import numpy as np

from ._params import check_choice, check_float, check_int
from .anchors import anchor_descriptors, proximity_matching, select_anchors
from .geodesics import GEODESIC_METHODS
from .icp import tps_icp
from .mesh import Mesh, MeshLike, as_mesh
from .modes import MODES, N_LANDMARKS, SCALABLE_ABOVE, build_spectrum, resolve_memory, select_mode
from .reorder import REORDER_MODES, rank_configurations
from .result import Correspondence
from .timing import StageProgress, StageTimer

def match(source: MeshLike, target: MeshLike, *, k: int = 6, geodesic: str = "heat",
          scale_eigenvalues: bool = True, reorder: str = "exhaustive", icp_iterations: int = 10,
          n_control: int = 500, anneal: float = 0.5, n_anchors: int = 3, anchor_weight: float = 1.0,
          bijective: bool = False, largest_component: bool = False, random_state: int | None = 0,
          progress: StageProgress | None = None, mode: str = "auto", n_landmarks: int = N_LANDMARKS,
          max_memory: int | str | None = None, scalable_above: int = SCALABLE_ABOVE) -> Correspondence:
    """Dense vertex correspondence from ``source`` to ``target``.

    Parameters
    ----------
    source, target : path, trimesh.Trimesh, Mesh or (vertices, faces)
        Triangle meshes: closed or open 2-manifolds, one connected component
        each (see ``largest_component``). Any pose, position, rotation,
        uniform scale and vertex count.
    k : int
        Eigenpairs computed; the embedding has ``k - 1`` dimensions (paper: 6).
    geodesic : {"heat", "fmm", "exact", "dijkstra"}
        Geodesic solver (see :mod:`meshcorr.geodesics`).
    scale_eigenvalues : bool
        Scale eigenvectors by sqrt(eigenvalue) (the paper's default).
    reorder : {"exhaustive", "greedy", "signs", "signs-greedy", "none"}
        Eigenvector reordering and sign correction (see :mod:`meshcorr.reorder`).
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
        One-to-one map by linear assignment (equal vertex counts only).
    largest_component : bool
        Map only the largest connected component of each mesh instead of
        raising on several components.
    random_state : int or None
        Seed for everything random (eigensolver start, samples).
    progress : callable, optional
        ``progress(stage, done, total)``.
    mode : {"auto", "dense", "scalable"}
        "dense": all-pairs geodesics and the exact eigenpairs (``O(n^2)``
        memory, the reference); "scalable": landmark geodesics and the
        Nyström extension (``O(n m)``); "auto": dense up to
        ``scalable_above`` vertices if it fits in ``max_memory``, else
        scalable (see :mod:`meshcorr.modes`).
    n_landmarks : int
        m, landmark vertices of the scalable mode.
    max_memory : int or str, optional
        Bytes (or a size such as ``"4GiB"``) the dense mode may use; it
        refuses larger inputs. Default: 80 % of the memory available now.
    scalable_above : int
        Vertex count above which "auto" picks the scalable mode.

    Returns
    -------
    result : Correspondence
        ``result.map[i]`` is the target vertex of source vertex i.
    """
    k = check_int("k", k, minimum=2, maximum=10)
    check_choice("geodesic", geodesic, GEODESIC_METHODS)
    check_choice("reorder", reorder, REORDER_MODES)
    n_anchors = check_int("n_anchors", n_anchors, minimum=0)
    anchor_weight = check_float("anchor_weight", anchor_weight, minimum=0.0)
    check_choice("mode", mode, MODES)
    n_landmarks = check_int("n_landmarks", n_landmarks, minimum=k + 1)
    max_memory = resolve_memory(max_memory)
    timer = StageTimer(progress)

    with timer.stage("load"):
        why = f"The spectral embedding with k={k} needs at least {k + 2} vertices."
        src = as_mesh(source, name="source", largest_component=largest_component,
                      min_vertices=k + 2, reason=why)
        tgt = as_mesh(target, name="target", largest_component=largest_component,
                      min_vertices=k + 2, reason=why)

    # Steps 1-3: geodesic distances, Gaussian affinities, scaled spectral embedding.
    mode = select_mode(mode, src.n_vertices, tgt.n_vertices, max_memory=max_memory,
                       scalable_above=scalable_above, bijective=bijective)
    spectra = [build_spectrum(mesh, mode, k=k, geodesic=geodesic, scale=scale_eigenvalues,
                              n_landmarks=n_landmarks, random_state=random_state, timer=timer)
               for mesh in (src, tgt)]
    X, Y = spectra[0].embedding, spectra[1].embedding

    # Step 4: eigenvector reordering and sign correction.
    with timer.stage("reorder"):
        configurations = rank_configurations(X, Y, reorder, random_state=random_state)
        Y_configured = configurations[0].apply(Y)

    # Step 5: non-rigid alignment, thin-plate-spline ICP in the spectral domain.
    with timer.stage("icp"):
        icp = tps_icp(X, Y_configured, max_iter=icp_iterations, n_control=n_control,
                      anneal=anneal, random_state=random_state)

    # Steps 6-7: anchors, proximity-aided (optionally bijective) matching.
    # Geodesics are divided by each mesh's largest one so both are on one scale.
    with timer.stage("matching"):
        g1, g2 = spectra[0].geodesics_from, spectra[1].geodesics_from
        anchors = select_anchors(X, icp.warped, g1, g2, n_anchors)
        weights = np.full(n_anchors, anchor_weight)
        F1 = anchor_descriptors(anchors[:, 0], g1, weights)
        F2 = anchor_descriptors(anchors[:, 1], g2, weights)
        local_map, local_cost = proximity_matching(X, icp.warped, F1, F2, bijective=bijective)

    full_map = np.full(src.n_original, -1, dtype=np.int64)
    full_map[src.kept] = tgt.kept[local_map]
    full_cost = np.full(src.n_original, np.nan)
    full_cost[src.kept] = local_cost
    params = dict(k=k, geodesic=geodesic, scale_eigenvalues=scale_eigenvalues, reorder=reorder,
                  icp_iterations=icp_iterations, n_control=n_control, anneal=anneal,
                  n_anchors=n_anchors, anchor_weight=anchor_weight, bijective=bijective,
                  largest_component=largest_component, random_state=random_state, mode=mode,
                  n_landmarks=n_landmarks, max_memory=max_memory)
    return Correspondence(
        map=full_map, cost=full_cost, source_vertices=src.kept.copy(), target_vertices=tgt.kept.copy(),
        source_embedding=X, target_embedding=Y_configured, aligned_target_embedding=icp.warped,
        eigenvalues={"source": spectra[0].eigenvalues, "target": spectra[1].eigenvalues}, configuration=configurations[0],
        alternatives=configurations,
        anchors=np.stack([src.kept[anchors[:, 0]], tgt.kept[anchors[:, 1]]], axis=1),
        icp_history=icp.history, icp_converged=icp.converged, timings=timer.timings, params=params,
    )
