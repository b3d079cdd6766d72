"""Partial shapes and holes made from a whole mesh, for experiments and tests.

Real scans are parts of shapes: one side of an object, a body cut by the
scanner's field of view, a surface with holes where the sensor saw nothing.
These functions make such inputs from a complete mesh in a reproducible way
and return, with the new mesh, the original index of each vertex it keeps,
so that a ground-truth map of the whole shape restricts to the part as
``truth[kept]``.

- :func:`cut_by_plane` keeps the side of a plane that holds a given fraction
  of the area (the plane's normal is random or given).
- :func:`remove_balls` removes geodesic balls around random centres until
  the kept area is a given fraction.
- :func:`punch_holes` removes a number of small geodesic discs.

Faces are kept or removed by the mean of their vertices' values (height
along the plane's normal, distance to the nearest centre), the vertices
of no kept face are dropped, faces are taken away at vertices where two sheets
would touch at a single point (a cut through a thin part can leave such a
pinch, which :func:`meshcorr.validate.validate_mesh` refuses), and the largest
connected piece is kept (a cut can leave islands), so the result is a valid
input to :func:`meshcorr.match`. Geodesic distances come from the heat method
(:mod:`meshcorr.geodesics`, potpourri3d).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

from ._params import check_int
from .errors import ParameterError
from .geodesics import geodesic_solver
from .mesh import Mesh, MeshLike, as_mesh


def _face_areas(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    v = vertices[faces]
    return 0.5 * np.linalg.norm(np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0]), axis=1)


def _faces_below(mesh: Mesh, values: np.ndarray, keep: float) -> np.ndarray:
    """``(m,)`` bool: the faces of least mean vertex value that hold ``keep`` of the area."""
    face_values = values[mesh.faces].mean(axis=1)
    order = np.argsort(face_values, kind="stable")
    cumulative = np.cumsum(_face_areas(mesh.vertices, mesh.faces)[order])
    kept = np.zeros(len(face_values), dtype=bool)
    kept[order[:np.searchsorted(cumulative, keep * cumulative[-1]) + 1]] = True
    return kept


def _keep_fraction(value, func: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not 0.0 < value < 1.0:
        raise ParameterError(f"{func}: keep must be a fraction of the area strictly between 0 and 1, got {value!r}.")
    return float(value)


def submesh(mesh: Mesh, keep_faces: np.ndarray, *, name: str | None = None) -> tuple[Mesh, np.ndarray]:
    """The largest connected piece of the kept faces.

    Parameters
    ----------
    mesh : Mesh
    keep_faces : (m,) bool
        Faces that may stay.
    name : str, optional
        Name of the new mesh; default ``"<mesh> (part)"``.

    Returns
    -------
    part : Mesh
    kept : (p,) int
        Index in ``mesh`` of each vertex of ``part``.
    """
    faces = _without_pinches(mesh.faces[np.asarray(keep_faces, dtype=bool)], mesh.n_vertices)
    if len(faces) == 0:
        raise ParameterError(f"Nothing of {mesh.name} is left to keep: keep a larger part.")
    # Face adjacency through shared vertices: face f - vertex v incidence, squared.
    incidence = sp.csr_matrix((np.ones(faces.size), (np.repeat(np.arange(len(faces)), 3), faces.ravel())),
                              shape=(len(faces), mesh.n_vertices))
    _, labels = connected_components(incidence @ incidence.T, directed=False)
    areas = np.bincount(labels, _face_areas(mesh.vertices, faces))
    faces = faces[labels == np.argmax(areas)]
    kept = np.unique(faces)
    reindex = np.full(mesh.n_vertices, -1, dtype=np.int64)
    reindex[kept] = np.arange(len(kept))
    part = as_mesh((mesh.vertices[kept], reindex[faces]), name=name or f"{mesh.name} (part)")
    return part, kept


def _without_pinches(faces: np.ndarray, n_vertices: int) -> np.ndarray:
    """``faces`` without the smaller fans at each vertex where several fans meet (a pinch).

    The corners of a vertex in two faces that share an edge through it are in
    one fan (as :func:`meshcorr.validate.validate_mesh` tests); at a vertex of
    several fans only the fan of most corners keeps its faces. Removing faces
    can pinch another vertex, so this repeats until no pinch is left.
    """
    from .validate import _edges

    while True:  # each pass removes faces, so it ends
        if len(faces) == 0:
            return faces
        edges, corners = _edges(faces)
        keys = edges[:, 0] * np.int64(n_vertices) + edges[:, 1]
        order = np.argsort(keys, kind="stable")
        keys, corners = keys[order], corners[order]
        pair = np.flatnonzero(keys[1:] == keys[:-1])  # an edge in two faces: its corners link up
        links = np.concatenate([corners[pair], corners[pair + 1]], axis=1)  # (k, 4)
        n_corners = 3 * len(faces)
        graph = sp.coo_matrix((np.ones(2 * len(links)), (np.r_[links[:, 0], links[:, 1]],
                                                          np.r_[links[:, 2], links[:, 3]])),
                              shape=(n_corners, n_corners))
        n_fans, fan = connected_components(graph, directed=False)
        fan_size = np.bincount(fan, minlength=n_fans)
        fan_vertex = np.empty(n_fans, dtype=np.int64)
        fan_vertex[fan] = faces.ravel()
        # The largest fan of each vertex (ties: the first).
        best = np.full(n_vertices, -1, dtype=np.int64)
        by_size = np.lexsort((-np.arange(n_fans), fan_size))  # ascending size: larger ones overwrite
        best[fan_vertex[by_size]] = by_size
        losing = best[faces.ravel()] != fan
        if not losing.any():
            return faces
        faces = faces[~losing.reshape(-1, 3).any(axis=1)]


def cut_by_plane(mesh: MeshLike, *, keep: float = 0.7, normal=None,
                 random_state: int | None = 0) -> tuple[Mesh, np.ndarray]:
    """The part of ``mesh`` on one side of a plane, holding ``keep`` of the area.

    The plane is :math:`\\{x : x \\cdot n = t\\}`; the vertices with
    :math:`x \\cdot n \\le t` stay, with :math:`t` the area-weighted
    ``keep`` quantile of :math:`x \\cdot n` over the vertices.

    Parameters
    ----------
    mesh : path, Mesh, trimesh.Trimesh or (vertices, faces)
    keep : float
        Fraction of the area to keep, in (0, 1). The largest piece is kept,
        so the result can hold slightly less.
    normal : (3,) float, optional
        Plane normal; default a random unit vector from ``random_state``.
    random_state : int or None

    Returns
    -------
    part : Mesh
    kept : (p,) int
        Index in ``mesh`` of each vertex of ``part``.
    """
    mesh = as_mesh(mesh)
    keep = _keep_fraction(keep, "cut_by_plane")
    if normal is None:
        normal = np.random.default_rng(random_state).normal(size=3)
    normal = np.asarray(normal, dtype=float).reshape(-1)
    if normal.shape != (3,) or not np.all(np.isfinite(normal)) or np.linalg.norm(normal) == 0:
        raise ParameterError(f"cut_by_plane: normal must be a finite, non-zero 3-vector, got {normal!r}.")
    height = mesh.vertices @ (normal / np.linalg.norm(normal))
    return submesh(mesh, _faces_below(mesh, height, keep), name=f"{mesh.name} (cut)")


def remove_balls(mesh: MeshLike, *, keep: float = 0.7, n_balls: int = 3,
                 random_state: int | None = 0) -> tuple[Mesh, np.ndarray]:
    """``mesh`` without ``n_balls`` geodesic balls around random vertices, keeping ``keep`` of the area.

    The balls share one radius :math:`r`, the least for which the faces
    with :math:`\\min_c d(x, c) \\ge r` hold ``keep`` of the area;
    :math:`d` is the heat-method geodesic distance.

    Parameters
    ----------
    mesh : path, Mesh, trimesh.Trimesh or (vertices, faces)
    keep : float
        Fraction of the area to keep, in (0, 1).
    n_balls : int
        Number of balls, at least 1.
    random_state : int or None
        Seed of the centres.

    Returns
    -------
    part : Mesh
    kept : (p,) int
        Index in ``mesh`` of each vertex of ``part``.
    """
    mesh = as_mesh(mesh)
    keep = _keep_fraction(keep, "remove_balls")
    n_balls = check_int("n_balls", n_balls, minimum=1, maximum=mesh.n_vertices)
    centres = np.random.default_rng(random_state).choice(mesh.n_vertices, n_balls, replace=False)
    nearest = geodesic_solver(mesh.vertices, mesh.faces, "heat").distances(centres).min(axis=0)
    return submesh(mesh, _faces_below(mesh, -nearest, keep), name=f"{mesh.name} (balls removed)")


def punch_holes(mesh: MeshLike, *, n_holes: int = 8, hole_area: float = 0.005,
                random_state: int | None = 0) -> tuple[Mesh, np.ndarray]:
    """``mesh`` with ``n_holes`` small holes: geodesic discs of ``hole_area`` of the area each.

    Centres are spread by geodesic farthest-point sampling (the first drawn
    with ``random_state``), so the holes do not merge; a disc of area :math:`a A`
    has geodesic radius :math:`r = \\sqrt{a A / \\pi}`.

    Parameters
    ----------
    mesh : path, Mesh, trimesh.Trimesh or (vertices, faces)
    n_holes : int
        Number of holes, at least 1.
    hole_area : float
        Area of each hole as a fraction of the total, in (0, 0.1].
    random_state : int or None

    Returns
    -------
    holed : Mesh
    kept : (p,) int
        Index in ``mesh`` of each vertex of ``holed``.
    """
    from .landmarks import farthest_point_sampling

    mesh = as_mesh(mesh)
    n_holes = check_int("n_holes", n_holes, minimum=1, maximum=mesh.n_vertices)
    if isinstance(hole_area, bool) or not isinstance(hole_area, (int, float)) or not 0.0 < hole_area <= 0.1:
        raise ParameterError(f"punch_holes: hole_area must be in (0, 0.1] (a fraction of the area), got {hole_area!r}.")
    radius = float(np.sqrt(hole_area * mesh.area / np.pi))
    solver = geodesic_solver(mesh.vertices, mesh.faces, "heat")
    centres = farthest_point_sampling(lambda i: solver.distances(np.array([i]))[0], mesh.n_vertices, n_holes,
                                      random_state=random_state)
    inside = (centres.distances.min(axis=0) < radius)[mesh.faces].mean(axis=1) > 0.5
    return submesh(mesh, ~inside, name=f"{mesh.name} (holes)")
