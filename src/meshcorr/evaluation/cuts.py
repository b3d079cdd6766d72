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
of no kept face are dropped, and the largest connected piece is kept (a
cut can leave islands; the faces around a vertex where two sheets would
touch are dropped too). The threshold on the values is the one at which
that piece holds the asked fraction of the area, so a cut that severs a
limb or the head takes that much more elsewhere. The result is a valid
input to
:func:`meshcorr.match`. Geodesic distances come from the heat method
(:mod:`meshcorr.core.geodesics`, potpourri3d).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

from ..runtime.checks import check_int
from ..errors import ParameterError
from ..core.geodesics import geodesic_solver
from ..core.mesh import Mesh, MeshLike, as_mesh
from ..core.validate import pinched_vertices


def _face_areas(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    v = vertices[faces]
    return 0.5 * np.linalg.norm(np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0]), axis=1)


def _faces_below(mesh: Mesh, values: np.ndarray, keep: float) -> np.ndarray:
    """``(m,)`` bool: the faces of least mean vertex value whose largest connected piece holds ``keep`` of the area.

    The faces are taken in the order of their values, as few as give a
    largest piece (:func:`submesh`'s) of at least ``keep`` of the area: a cut
    that severs a limb takes more of the rest, so the part keeps the asked
    area instead of losing the limb's share. Bisection over the number of
    faces taken (the largest piece grows with it); where a severed piece
    rejoins at once, the count just below is taken if its piece is nearer
    to ``keep``. A cut whose faces of ``keep`` of the area are one piece is
    the plain area quantile.
    """
    face_values = values[mesh.faces].mean(axis=1)
    order = np.argsort(face_values, kind="stable")
    areas = _face_areas(mesh.vertices, mesh.faces)
    wanted = keep * areas.sum()

    def taken(count: int) -> np.ndarray:
        kept = np.zeros(len(face_values), dtype=bool)
        kept[order[:count]] = True
        return kept

    def piece_area(count: int) -> float:
        return float(_face_areas(mesh.vertices, _largest_piece(mesh, mesh.faces[taken(count)])).sum())

    low = int(np.searchsorted(np.cumsum(areas[order]), wanted)) + 1  # enough if the piece is all of them
    if piece_area(low) >= wanted:
        return taken(low)
    high = len(order)
    while low < high:
        middle = (low + high) // 2
        if piece_area(middle) >= wanted:
            high = middle
        else:
            low = middle + 1
    # Rejoining a severed piece adds its area at once: of the counts just below and at the asked
    # area, the one whose piece is nearer to it.
    if wanted - piece_area(low - 1) < piece_area(low) - wanted:
        low -= 1
    return taken(low)


def _keep_fraction(value, func: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not 0.0 < value < 1.0:
        raise ParameterError(f"{func}: keep must be a fraction of the area strictly between 0 and 1, got {value!r}.")
    return float(value)


def _largest_piece(mesh: Mesh, faces: np.ndarray) -> np.ndarray:
    """``(q, 3)`` int: the faces of the largest connected piece (by area) of ``faces``, no vertex pinched."""
    # Removing faces can leave two sheets touching at one vertex: drop the faces around it until none is left.
    while len(pinched := pinched_vertices(faces, mesh.n_vertices)):
        faces = faces[~np.isin(faces, pinched).any(axis=1)]
    if len(faces) == 0:
        return faces
    # Face adjacency through shared vertices: face f - vertex v incidence, squared.
    incidence = sp.csr_matrix((np.ones(faces.size), (np.repeat(np.arange(len(faces)), 3), faces.ravel())),
                              shape=(len(faces), mesh.n_vertices))
    _, labels = connected_components(incidence @ incidence.T, directed=False)
    areas = np.bincount(labels, _face_areas(mesh.vertices, faces))
    return faces[labels == np.argmax(areas)]


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
    faces = _largest_piece(mesh, mesh.faces[np.asarray(keep_faces, dtype=bool)])
    if len(faces) == 0:
        raise ParameterError(f"Nothing of {mesh.name} is left to keep: keep a larger part.")
    kept = np.unique(faces)
    reindex = np.full(mesh.n_vertices, -1, dtype=np.int64)
    reindex[kept] = np.arange(len(kept))
    part = as_mesh((mesh.vertices[kept], reindex[faces]), name=name or f"{mesh.name} (part)")
    return part, kept


def cut_by_plane(mesh: MeshLike, *, keep: float = 0.7, normal=None,
                 random_state: int | None = 0) -> tuple[Mesh, np.ndarray]:
    """The part of ``mesh`` on one side of a plane, holding ``keep`` of the area.

    The plane is :math:`\\{x : x \\cdot n = t\\}`; the vertices with
    :math:`x \\cdot n \\le t` stay, with :math:`t` the least height at
    which the largest connected piece below it holds ``keep`` of the area
    (the area-weighted ``keep`` quantile when the part is in one piece).

    Parameters
    ----------
    mesh : path, Mesh, trimesh.Trimesh or (vertices, faces)
    keep : float
        Fraction of the area to keep, in (0, 1), held by the part (its
        largest connected piece) up to one face.
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

    The balls share one radius :math:`r`, the largest for which the largest
    connected piece of the faces with :math:`\\min_c d(x, c) \\ge r` holds
    ``keep`` of the area;
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
    from ..core.sampling import farthest_point_sampling

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
