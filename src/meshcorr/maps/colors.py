"""Per-vertex colourings: parts, coordinates and colour maps (numpy only).

A correspondence is judged by colouring the target by part and carrying each
colour to the source through the map (Jain & Zhang 2006, Figures 7-8); a good
map gives the source the same parts in the same colours. The colourings here
are smooth (so that small errors show as small colour shifts) and
part-revealing (so that swapped limbs or a mirrored map show as wrong
colours).

Colours are ``(n, 3) uint8`` RGB arrays. The colour maps are fixed tables
(samples of matplotlib's viridis, coolwarm and RdYlBu_r) so that the static
pictures and the HTML report agree and neither needs matplotlib for colour.
"""

from __future__ import annotations

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import dijkstra

from ..runtime.checks import check_choice, check_int
from ..core.pointcloud import edges as graph_edges

__all__ = ["COLORINGS", "COLORMAPS", "UNMAPPED_COLOR", "coordinate_colors", "mesh_coloring",
           "part_colors", "scalar_colors"]

#: Colour of source vertices that the map leaves unmapped (-1).
UNMAPPED_COLOR = np.array([170, 170, 170], dtype=np.uint8)

#: Colour-map tables: 11 evenly spaced RGB stops, interpolated linearly.
COLORMAPS = {
    # sequential, for scalar fields
    "viridis": [(68, 1, 84), (72, 36, 117), (65, 68, 135), (53, 95, 141), (42, 120, 142),
                (33, 145, 140), (34, 168, 132), (68, 191, 112), (122, 209, 81), (189, 223, 38),
                (253, 231, 37)],
    # diverging around 0, for eigenvectors
    "coolwarm": [(59, 76, 192), (89, 119, 227), (123, 159, 249), (158, 190, 255),
                 (192, 212, 245), (221, 220, 220), (242, 203, 183), (247, 172, 142),
                 (238, 132, 104), (214, 82, 68), (180, 4, 38)],
    # blue (small) to red (large), for errors
    "error": [(49, 54, 149), (69, 116, 179), (116, 173, 209), (170, 216, 233), (224, 243, 248),
              (255, 254, 190), (254, 224, 144), (253, 173, 96), (244, 109, 67), (214, 47, 39),
              (165, 0, 38)],
}

#: Distinct part colours (matplotlib's tab10 with its grey replaced, so that
#: grey means "unmapped" only).
PALETTE = np.array([(31, 119, 180), (255, 127, 14), (44, 160, 44), (214, 39, 40),
                    (148, 103, 189), (140, 86, 75), (227, 119, 194), (188, 189, 34),
                    (23, 190, 207), (255, 215, 0)], dtype=np.float64)

#: Names accepted by :func:`mesh_coloring`.
COLORINGS = ("parts", "xyz")


def scalar_colors(values, cmap: str = "viridis", *, vmin: float | None = None,
                  vmax: float | None = None) -> np.ndarray:
    """Colour a scalar field with a colour map.

    Parameters
    ----------
    values : (n,) float
        NaN values get :data:`UNMAPPED_COLOR`.
    cmap : {"viridis", "coolwarm", "error"}
    vmin, vmax : float, optional
        Values mapped to the ends of the colour map (default: the finite
        minimum and maximum); values outside are clipped.

    Returns
    -------
    colors : (n, 3) uint8
    """
    check_choice("cmap", cmap, tuple(COLORMAPS))
    values = np.asarray(values, dtype=np.float64)
    finite = np.isfinite(values)
    data = values[finite] if finite.any() else np.zeros(1)
    lo = float(data.min()) if vmin is None else float(vmin)
    hi = float(data.max()) if vmax is None else float(vmax)
    span = hi - lo if hi > lo else 1.0
    t = np.clip((np.where(finite, values, lo) - lo) / span, 0.0, 1.0)
    stops = np.asarray(COLORMAPS[cmap], dtype=np.float64)
    x = np.linspace(0.0, 1.0, len(stops))
    rgb = np.column_stack([np.interp(t, x, stops[:, c]) for c in range(3)])
    colors = np.round(rgb).astype(np.uint8)
    colors[~finite] = UNMAPPED_COLOR
    return colors


def coordinate_colors(vertices) -> np.ndarray:
    """Colour each vertex by its position: x, y, z scaled to red, green, blue.

    Parameters
    ----------
    vertices : (n, 3) float

    Returns
    -------
    colors : (n, 3) uint8
        ``0.15 + 0.85 (v - min) / (max - min)`` per axis, so no vertex is black.
    """
    vertices = np.asarray(vertices, dtype=np.float64)
    lo, hi = vertices.min(axis=0), vertices.max(axis=0)
    t = (vertices - lo) / np.where(hi > lo, hi - lo, 1.0)
    return np.round(255 * (0.15 + 0.85 * t)).astype(np.uint8)


def _edge_graph(vertices: np.ndarray, faces: np.ndarray):
    """Sparse symmetric graph of mesh edges weighted by their length (a cloud's: its one-ring neighbours)."""
    edges = graph_edges(vertices, faces.reshape(-1, 3))
    edges = edges[edges[:, 0] != edges[:, 1]]
    length = np.linalg.norm(vertices[edges[:, 0]] - vertices[edges[:, 1]], axis=1)
    length = np.maximum(length, 1e-12)  # a zero weight would mean "no edge" to csgraph
    n = len(vertices)
    return coo_matrix((length, (edges[:, 0], edges[:, 1])), shape=(n, n)).tocsr()


def part_colors(vertices, faces, *, n_parts: int = 8, softness: float = 0.06) -> np.ndarray:
    """A smooth colouring that gives each extremity of a shape its own colour.

    ``n_parts`` seeds are placed by farthest-point sampling on edge-graph
    geodesics, starting at the vertex farthest from vertex 0, so they land
    on the tips of limbs, head and tail first. Each vertex blends the seed
    colours with soft-min weights

    .. math::

        w_{ij} \\propto \\exp\\left(-\\frac{d_{ij} - \\min_l d_{il}}{\\tau}\\right),
        \\qquad \\tau = \\text{softness} \\cdot \\max_{i} \\min_j d_{ij} \\cdot 4,

    so parts are flat colours with smooth seams. Edge-graph (Dijkstra)
    distances overestimate geodesics by ~10 %, which does not matter for a
    colouring and works on any mesh (several components: each gets seeds as
    long as there are enough; vertices no seed reaches are grey).

    Parameters
    ----------
    vertices : (n, 3) float
    faces : (m, 3) int
        Triangles; ``m = 0`` for a point cloud (its graph joins each point to
        its nearest neighbours, :func:`meshcorr.core.pointcloud.edges`).
    n_parts : int
        Seeds (at most 10 distinct colours; more repeat the palette).
    softness : float
        Width of the seams relative to the seed spacing.

    Returns
    -------
    colors : (n, 3) uint8
    """
    n_parts = check_int("n_parts", n_parts, minimum=1)
    vertices = np.asarray(vertices, dtype=np.float64)
    faces = np.asarray(faces, dtype=np.int64)
    graph = _edge_graph(vertices, faces)
    n = len(vertices)
    n_parts = min(n_parts, n)
    distances = np.empty((n_parts, n))
    from_first = dijkstra(graph, indices=[0], directed=False)[0]
    seed = int(np.argmax(np.where(np.isfinite(from_first), from_first, -1.0)))
    nearest = np.full(n, np.inf)
    for p in range(n_parts):
        distances[p] = dijkstra(graph, indices=[seed], directed=False)[0]
        nearest = np.minimum(nearest, distances[p])
        # The next seed is the farthest vertex; an unreached component counts as farthest.
        seed = int(np.argmax(np.where(np.isfinite(nearest), nearest, np.finfo(float).max)))
    reached = np.isfinite(nearest)
    spacing = float(nearest[reached].max()) if reached.any() else 1.0
    tau = max(4.0 * softness * spacing, 1e-12)
    excess = np.where(np.isfinite(distances), distances - np.where(reached, nearest, 0.0), np.inf)
    weights = np.exp(-excess / tau)
    weights /= np.maximum(weights.sum(axis=0), 1e-300)
    palette = PALETTE[np.arange(n_parts) % len(PALETTE)]
    colors = np.round(weights.T @ palette).astype(np.uint8)
    colors[~reached] = UNMAPPED_COLOR
    return colors


def mesh_coloring(name: str, vertices, faces) -> np.ndarray:
    """A named colouring of a mesh: ``"parts"`` (:func:`part_colors`) or ``"xyz"``.

    Parameters
    ----------
    name : {"parts", "xyz"}
    vertices : (n, 3) float
    faces : (m, 3) int

    Returns
    -------
    colors : (n, 3) uint8
    """
    check_choice("coloring", name, COLORINGS)
    if name == "parts":
        return part_colors(vertices, faces)
    return coordinate_colors(vertices)
