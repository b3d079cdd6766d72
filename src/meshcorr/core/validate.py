"""Check that a triangle mesh can be used by meshcorr.

Every check raises :class:`~meshcorr.errors.MeshError` with a message that
names the problem, how many elements are affected (with the first few
offending indices) and the fix. All checks are vectorized numpy / scipy.

The checks run in this order: shapes (ragged lists, emptiness), real and
finite coordinates, face index range, the coordinates' scale, degenerate
faces, non-manifold faces / edges / vertices, unreferenced vertices and
connected components, minimum vertex count.
"""

from __future__ import annotations

import numbers

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

from meshcorr.errors import MeshError, ParameterError

__all__ = ["as_array", "check_finite", "check_scale", "check_vertex_count", "pinched_vertices", "plural", "select_component",
           "validate_mesh", "which"]

_SHOW = 5  # how many offending indices a message lists
_AREA_RTOL = 1e-12  # zero area: area <= _AREA_RTOL * bbox_diagonal**2
_MESHLAB = "MeshLab: Filters > Cleaning and Repairing > "


def which(word: str, words: str, indices) -> str:
    """``"vertex 3"`` or ``"vertices 3, 7, 9, ..."``: the first few of ``indices``."""
    indices = np.ravel(indices)
    shown = ", ".join(str(int(i)) for i in indices[:_SHOW])
    return f"{word if len(indices) == 1 else words} {shown}{', ...' if len(indices) > _SHOW else ''}"


def plural(count: int, word: str, words: str | None = None) -> str:
    """``"1 face"``, ``"2 faces"``; ``words`` is the plural when not ``word + "s"``."""
    return f"{count} {word if count == 1 else (words or word + 's')}"


def _first_bad_row(rows) -> str:
    """``" (row 1 has 2 entries)"``: the first row of a ragged list whose length is not 3."""
    index = 0
    try:
        for index, row in enumerate(rows):
            if len(row) != 3:
                return f" (row {index} has {len(row)} entries)"
    except TypeError:  # a row that is a number, not a sequence
        return f" (row {index} is not a sequence)"
    return ""


def as_array(values, what: str, shape: str, fix: str, name: str) -> np.ndarray:
    """``np.asarray(values)``; a ragged list (rows of different lengths) raises :class:`MeshError`.

    ``what`` and ``shape`` (e.g. ``"vertices"``, ``"(n, 3)"``) and ``fix`` (the advice) word the message.
    """
    try:
        return np.asarray(values)
    except ValueError as error:  # numpy >= 1.24: "inhomogeneous shape"
        raise MeshError(
            f"{name}: {what} must have shape {shape}; got rows of different lengths"
            f"{_first_bad_row(values)}. {fix}"
        ) from error


def _as_arrays(vertices, faces, name: str) -> tuple[np.ndarray, np.ndarray]:
    """Convert to float64 (n, 3) and int64 (m, 3) arrays, checking emptiness and shapes."""
    vertices = as_array(vertices, "vertices", "(n, 3)",
                         "Pass one row of x, y, z coordinates per vertex.", name)
    faces = as_array(faces, "faces", "(m, 3)",
                      "faces must be triangles; triangulate polygons first.", name)
    if vertices.size == 0 or faces.size == 0:
        what = "no vertices" if vertices.size == 0 else "no faces"
        raise MeshError(
            f"{name} is empty: it has {what} ({len(vertices)} vertices, "
            f"{len(faces)} faces). Check that the file contains a triangle "
            "mesh and not only a point cloud."
        )
    if vertices.ndim != 2 or vertices.shape[1] != 3:
        raise MeshError(
            f"{name}: vertices must have shape (n, 3); got {vertices.shape}. "
            "Pass one row of x, y, z coordinates per vertex."
        )
    if faces.ndim != 2 or faces.shape[1] != 3:
        raise MeshError(
            f"{name}: faces must have shape (m, 3); got {faces.shape}. "
            "faces must be triangles; triangulate polygons first."
        )
    if not np.issubdtype(vertices.dtype, np.number) or np.iscomplexobj(vertices):
        raise MeshError(
            f"{name}: vertex coordinates must be real numbers; got dtype {vertices.dtype}."
        )
    if not np.issubdtype(faces.dtype, np.integer):
        as_float = faces.astype(np.float64) if np.issubdtype(faces.dtype, np.number) else None
        if as_float is None or not np.all(np.isfinite(as_float) & (as_float == np.round(as_float))):
            raise MeshError(
                f"{name}: face indices must be integers; got dtype {faces.dtype} "
                "with non-integer values. Pass vertex indices (0-based) as ints."
            )
    return np.array(vertices, dtype=np.float64), np.array(faces, dtype=np.int64)


def check_finite(vertices: np.ndarray, name: str) -> None:
    """Refuse ``(n, 3)`` coordinates with NaN or inf in any row (:class:`MeshError` naming the first rows)."""
    bad = np.flatnonzero(~np.isfinite(vertices).all(axis=1))
    if len(bad):
        raise MeshError(
            f"{name}: NaN or inf coordinates in {plural(len(bad), 'vertex', 'vertices')} "
            f"({which('vertex', 'vertices', bad)}). "
            "Remove or repair these vertices before matching."
        )


#: The coordinates meshcorr's numerics handle: magnitudes up to :data:`MAX_COORDINATE` and a bounding box
#: at least :data:`MIN_EXTENT` across. Squared areas (lengths to the fourth power) overflow past about 1e77
#: and underflow below about 1e-77 (potpourri3d's heat method failed near 1e100, and near 1e-100 every
#: face looked degenerate); within these bounds the map of the examples is the same at every scale.
MAX_COORDINATE = 1e50
MIN_EXTENT = 1e-50


def check_scale(vertices: np.ndarray, name: str) -> None:
    """Refuse finite ``(n, 3)`` coordinates too large or too close together for the numerics
    (:data:`MAX_COORDINATE`, :data:`MIN_EXTENT`), naming the problem and the fix: rescale, as the map
    does not depend on uniform scale. A bounding box of no extent at all is left to the other checks."""
    if not len(vertices):
        return
    largest = float(np.abs(vertices).max())
    extent = float(np.ptp(vertices, axis=0).max())  # no squares: they under- or overflow here
    if largest > MAX_COORDINATE:
        problem = f"coordinates as large as {largest:.3g}"
    elif 0.0 < extent < MIN_EXTENT:
        problem = f"a bounding box only {extent:.3g} across"
    else:
        return
    raise MeshError(
        f"{name}: {problem}; meshcorr's numerics need coordinates within +-{MAX_COORDINATE:g} and a "
        f"bounding box at least {MIN_EXTENT:g} across (squared areas would over- or underflow). The map "
        "does not depend on uniform scale: centre the coordinates and divide them by the bounding box's "
        f"size{f' ({extent:.3g})' if extent > 0 else ''} before matching."
    )


def _check_index_range(faces: np.ndarray, n_vertices: int, name: str) -> None:
    bad = np.flatnonzero(((faces < 0) | (faces >= n_vertices)).any(axis=1))
    if len(bad):
        values = faces[bad][(faces[bad] < 0) | (faces[bad] >= n_vertices)]
        raise MeshError(
            f"{name}: {plural(len(bad), 'face')} with vertex indices outside "
            f"[0, {n_vertices - 1}] ({which('face', 'faces', bad)}; "
            f"{which('index', 'indices', values)}). "
            "Face indices must be 0-based and refer to the given vertices."
        )


def _check_degenerate(vertices: np.ndarray, faces: np.ndarray, name: str) -> None:
    repeated = (
        (faces[:, 0] == faces[:, 1]) | (faces[:, 1] == faces[:, 2]) | (faces[:, 2] == faces[:, 0])
    )
    corners = vertices[faces]
    double_area = np.linalg.norm(
        np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]), axis=1
    )
    referenced = np.zeros(len(vertices), dtype=bool)
    referenced[faces.ravel()] = True
    used = vertices[referenced]
    diagonal = float(np.linalg.norm(used.max(axis=0) - used.min(axis=0)))
    zero_area = 0.5 * double_area <= _AREA_RTOL * diagonal**2
    bad = np.flatnonzero(repeated | zero_area)
    if len(bad):
        raise MeshError(
            f"{name}: {plural(len(bad), 'degenerate face')} "
            f"({int(repeated.sum())} with a repeated vertex index, "
            f"{int((zero_area & ~repeated).sum())} with zero area; "
            f"{which('face', 'faces', bad)}). "
            "Remove degenerate faces / clean the mesh first "
            f"(e.g. {_MESHLAB}Remove Zero Area Faces)."
        )


def _edges(faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Undirected edges of every face corner.

    Returns
    -------
    edges : (3m, 2) int64
        Sorted vertex pairs; row ``3 * f + j`` joins corners ``j`` and
        ``(j + 1) % 3`` of face ``f``.
    corners : (3m, 2) int64
        The corner ids (``3 * f + j``) of the two endpoints of each row of ``edges``.
    """
    m = len(faces)
    corner = np.arange(3 * m, dtype=np.int64).reshape(m, 3)
    a, b = faces.ravel(), faces[:, [1, 2, 0]].ravel()
    ca, cb = corner.ravel(), corner[:, [1, 2, 0]].ravel()
    swap = a > b
    edges = np.column_stack([np.where(swap, b, a), np.where(swap, a, b)])
    corners = np.column_stack([np.where(swap, cb, ca), np.where(swap, ca, cb)])
    return edges, corners


def _repeated_rows(rows: np.ndarray, n_values: int) -> np.ndarray:
    """Mask of the rows of ``rows`` (``(m, 3)`` ints in ``[0, n_values)``) equal to an earlier row.

    The rows are encoded as one int64 each while ``n_values ** 3`` fits (up to
    ~2 million vertices), which sorts ~5x faster than ``np.unique(axis=0)``.
    """
    if n_values ** 3 < 2 ** 62:
        n = np.int64(n_values)
        keys = (rows[:, 0] * n + rows[:, 1]) * n + rows[:, 2]
        _, first, inverse = np.unique(keys, return_index=True, return_inverse=True)
    else:
        _, first, inverse = np.unique(rows, axis=0, return_index=True, return_inverse=True)
    return first[inverse.ravel()] != np.arange(len(rows))


def _pinched(faces: np.ndarray, n_vertices: int, corners: np.ndarray, start: np.ndarray,
             counts: np.ndarray) -> np.ndarray:
    """Vertices whose faces form several fans, from the sorted edges of :func:`_check_manifold`."""
    # Corners of one vertex in two faces that share an edge containing it are
    # in the same fan; a vertex whose corners form several fans is non-manifold.
    shared = start[counts == 2]
    links = np.concatenate([corners[shared], corners[shared + 1]], axis=1)  # (k, 4)
    rows = np.concatenate([links[:, 0], links[:, 1]])
    cols = np.concatenate([links[:, 2], links[:, 3]])
    n_corners = 3 * len(faces)
    graph = sp.coo_matrix((np.ones(len(rows)), (rows, cols)), shape=(n_corners, n_corners))
    n_fans, labels = connected_components(graph, directed=False)
    fan_vertex = np.empty(n_fans, dtype=np.int64)
    fan_vertex[labels] = faces.ravel()
    return np.flatnonzero(np.bincount(fan_vertex, minlength=n_vertices) > 1)


def pinched_vertices(faces: np.ndarray, n_vertices: int) -> np.ndarray:
    """Vertices where separate sheets of faces touch at a single point.

    Parameters
    ----------
    faces : (m, 3) int
        Faces of a mesh whose edges each have one or two faces.
    n_vertices : int

    Returns
    -------
    pinched : (p,) int
        The vertices whose incident faces form more than one fan.
    """
    edges, corners = _edges(np.asarray(faces, dtype=np.int64))
    keys = edges[:, 0] * np.int64(n_vertices) + edges[:, 1]
    order = np.argsort(keys, kind="stable")
    keys = keys[order]
    start = np.flatnonzero(np.r_[True, keys[1:] != keys[:-1]])
    counts = np.diff(np.r_[start, len(keys)])
    return _pinched(faces, n_vertices, corners[order], start, counts)


def _check_manifold(faces: np.ndarray, n_vertices: int, name: str) -> None:
    fix_edges = f"Repair the mesh first (e.g. {_MESHLAB}Repair non Manifold Edges)."
    repeats = np.flatnonzero(_repeated_rows(np.sort(faces, axis=1), n_vertices))
    if len(repeats):
        raise MeshError(
            f"{name} is non-manifold: {plural(len(repeats), 'duplicate face')} "
            f"({which('face', 'faces', repeats)} repeat{'s' if len(repeats) == 1 else ''} "
            "the vertices of an earlier face). "
            f"Remove duplicate faces first (e.g. {_MESHLAB}Remove Duplicate Faces)."
        )
    edges, corners = _edges(faces)
    # One int64 key per edge: a stable argsort orders the edges as
    # lexsort((edges[:, 1], edges[:, 0])) does, ~5x faster at 100k vertices.
    keys = edges[:, 0] * np.int64(n_vertices) + edges[:, 1]
    order = np.argsort(keys, kind="stable")
    edges, corners, keys = edges[order], corners[order], keys[order]
    start = np.flatnonzero(np.r_[True, keys[1:] != keys[:-1]])
    counts = np.diff(np.r_[start, len(edges)])
    if (counts > 2).any():
        bad = edges[start[counts > 2]]
        shown = ", ".join(f"({i}, {j})" for i, j in bad[:_SHOW])
        shown += ", ..." if len(bad) > _SHOW else ""
        raise MeshError(
            f"{name} is non-manifold: {plural(len(bad), 'edge')} shared by more than "
            f"2 faces ({'edge' if len(bad) == 1 else 'edges'} {shown}). {fix_edges}"
        )
    bad = _pinched(faces, n_vertices, corners, start, counts)
    if len(bad):
        raise MeshError(
            f"{name} is non-manifold: {plural(len(bad), 'vertex', 'vertices')} "
            "where separate sheets of faces touch at a single point "
            f"({which('vertex', 'vertices', bad)}). "
            f"Repair the mesh first (e.g. {_MESHLAB}Repair non Manifold Vertices)."
        )


def select_component(
    vertices: np.ndarray, faces: np.ndarray, largest_component: bool, name: str
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(n', 3)`` vertices, ``(m', 3)`` faces and ``(n',)`` kept indices of the mesh's one connected surface.

    Without ``largest_component`` a mesh with unreferenced vertices or several
    components raises :class:`MeshError`; with it, the component with the most
    vertices is kept (ties: the one holding the lowest vertex index) and the
    faces are reindexed into it (``vertices[kept]``).
    """
    n = len(vertices)
    referenced = np.bincount(faces.ravel(), minlength=n) > 0
    edges, _ = _edges(faces)
    graph = sp.coo_matrix((np.ones(len(edges)), (edges[:, 0], edges[:, 1])), shape=(n, n))
    _, labels = connected_components(graph, directed=False)
    used_labels, sizes = np.unique(labels[referenced], return_counts=True)
    unreferenced = np.flatnonzero(~referenced)
    if not largest_component and len(unreferenced):
        raise MeshError(
            f"{name}: {plural(len(unreferenced), 'vertex', 'vertices')} "
            f"used by no face ({which('vertex', 'vertices', unreferenced)}). "
            "Remove unreferenced vertices "
            f"(e.g. {_MESHLAB}Remove Unreferenced Vertices), or pass --largest-component "
            "(CLI) / largest_component=True (API) to drop them."
        )
    if not largest_component and len(sizes) > 1:
        listed = ", ".join(str(s) for s in np.sort(sizes)[::-1][:_SHOW])
        raise MeshError(
            f"{name} has {len(sizes)} connected components (vertex counts, largest first: "
            f"{listed}{', ...' if len(sizes) > _SHOW else ''}); a correspondence needs a "
            "single connected surface. Pass --largest-component (CLI) / "
            "largest_component=True (API) to keep only the largest one."
        )
    if len(sizes) == 1 and not len(unreferenced):
        return vertices, faces, np.arange(n, dtype=np.int64)
    # Ties go to the component holding the lowest vertex index (np.argmax is first).
    best = used_labels[np.argmax(sizes)]
    kept = np.flatnonzero((labels == best) & referenced).astype(np.int64)
    new_index = np.full(n, -1, dtype=np.int64)
    new_index[kept] = np.arange(len(kept))
    new_faces = new_index[faces[labels[faces[:, 0]] == best]]
    return vertices[kept], new_faces, kept


def validate_mesh(
    vertices,
    faces,
    *,
    min_vertices: int = 3,
    largest_component: bool = False,
    name: str = "mesh",
    reason: str | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Check a triangle mesh and return clean arrays, optionally its largest component.

    Parameters
    ----------
    vertices : (n, 3) float
        Vertex coordinates.
    faces : (m, 3) int
        Triangles as 0-based vertex indices.
    min_vertices : int, default 3
        Fewest vertices the (selected) mesh may have.
    largest_component : bool, default False
        If True, keep only the connected component with the most vertices
        (ties: the one holding the lowest vertex index) and drop the others and
        any unreferenced vertices instead of raising.
    name : str, default "mesh"
        How messages refer to the mesh (e.g. a file name).
    reason : str, optional
        Why ``min_vertices`` are needed, quoted in the message, e.g.
        ``"the spectral embedding with k=30 needs at least 31 vertices"``.

    Returns
    -------
    vertices : (n', 3) float64
        A copy of the kept vertices, in their original order.
    faces : (m', 3) int64
        The kept faces, reindexed into the kept vertices.
    kept : (n',) int64
        Original index of each kept vertex (``arange(n)`` when nothing is
        dropped), so ``vertices == original_vertices[kept]``.

    Raises
    ------
    MeshError
        If the mesh is empty, not (n, 3) / (m, 3) (ragged lists included), has
        coordinates that are not real numbers or are NaN or inf, out-of-range
        indices, degenerate or duplicate faces, non-manifold edges or vertices,
        unreferenced vertices or several components (unless
        ``largest_component``), or fewer than ``min_vertices`` vertices.
    ParameterError
        If ``min_vertices`` is not an int >= 1.
    """
    if (
        not isinstance(min_vertices, numbers.Integral)
        or isinstance(min_vertices, bool)
        or min_vertices < 1
    ):
        raise ParameterError(
            "The 'min_vertices' parameter of validate_mesh must be an int >= 1. "
            f"Got {min_vertices!r} instead."
        )
    vertices, faces = _as_arrays(vertices, faces, name)
    check_finite(vertices, name)
    _check_index_range(faces, len(vertices), name)
    check_scale(vertices[np.unique(faces)], name)  # before the areas of the degenerate faces' check
    _check_degenerate(vertices, faces, name)
    _check_manifold(faces, len(vertices), name)
    vertices, faces, kept = select_component(vertices, faces, largest_component, name)
    check_vertex_count(len(vertices), min_vertices, name, reason)
    return vertices, faces, kept


def check_vertex_count(n_vertices: int, min_vertices: int, name: str, reason: str = "") -> None:
    """Refuse a mesh of fewer than ``min_vertices`` vertices (:class:`MeshError`, ``reason`` says why)."""
    if n_vertices < min_vertices:
        why = f": {reason.rstrip('.')}" if reason else ""
        raise MeshError(
            f"{name} has {n_vertices} vertices but at least {min_vertices} are "
            f"needed{why}. Use a finer mesh or lower the parameter that needs them."
        )
