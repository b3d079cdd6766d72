"""Steps shared by the baselines: loading, pre-alignment, the final nearest match, the result."""

from __future__ import annotations

import numpy as np

from ..stages.anchors import proximity_matching
from ..core.laplacian import vertex_areas
from ..core.mesh import Mesh, MeshLike, as_mesh
from ..maps.result import Correspondence
from ..runtime.timing import StageTimer
from .align import align_pair

_NO_ANCHORS = np.zeros((0, 0))


def load_pair(source: MeshLike, target: MeshLike, *, largest_component: bool, timer: StageTimer,
              min_vertices: int = 4, reason: str = "") -> tuple[Mesh, Mesh]:
    """Validated source and target meshes (stage "load")."""
    with timer.stage("load"):
        src = as_mesh(source, name="source", largest_component=largest_component,
                      min_vertices=min_vertices, reason=reason)
        tgt = as_mesh(target, name="target", largest_component=largest_component,
                      min_vertices=min_vertices, reason=reason)
    return src, tgt


def spatial_points(src: Mesh, tgt: Mesh, *, prealign: bool, timer: StageTimer) -> tuple[np.ndarray, np.ndarray]:
    """Vertex positions, pre-aligned by :func:`~meshcorr.baselines.align.align_pair` if asked (stage "prealign").

    Returns
    -------
    P : (n1, 3) float
    Q : (n2, 3) float
    """
    if not prealign:
        return np.array(src.vertices), np.array(tgt.vertices)
    with timer.stage("prealign"):
        # Lumped vertex areas (of a point cloud: its Laplacian's, meshcorr.core.laplacian).
        return align_pair(src.vertices, tgt.vertices, vertex_areas(src), vertex_areas(tgt))


def nearest_map(moved: np.ndarray, Q: np.ndarray, *, bijective: bool) -> tuple[np.ndarray, np.ndarray]:
    """Nearest target point of each moved source point, or a linear assignment.

    Parameters
    ----------
    moved : (n1, d) float
    Q : (n2, d) float
    bijective : bool
        One-to-one by linear assignment (needs ``n1 == n2``).

    Returns
    -------
    mapping : (n1,) int
    distance : (n1,) float
    """
    return proximity_matching(moved, Q, _NO_ANCHORS, _NO_ANCHORS, bijective=bijective)


def finish(method: str, src: Mesh, tgt: Mesh, local_map: np.ndarray, local_cost: np.ndarray | None,
           timer: StageTimer, params: dict, **fields) -> Correspondence:
    """A :class:`Correspondence` in the input files' vertex numbering."""
    full_map = np.full(src.n_original, -1, dtype=np.int64)
    full_map[src.kept] = tgt.kept[local_map]
    full_cost = None
    if local_cost is not None:
        full_cost = np.full(src.n_original, np.nan)
        full_cost[src.kept] = local_cost
    return Correspondence(map=full_map, cost=full_cost, method=method, source_vertices=src.kept.copy(),
                          target_vertices=tgt.kept.copy(), timings=timer.timings, params=params,
                          source=src, target=tgt, **fields)
