"""A thin, immutable triangle-mesh (or point-cloud) object and the conversion of user input into it.

Geometry lives in free functions on ``(V, F)`` arrays (:mod:`meshcorr.core.geodesics`,
:mod:`meshcorr.core.validate`); :class:`Mesh` only holds validated, read-only
arrays and caches derived data keyed on the parameters that produced it.
A point cloud is a :class:`Mesh` with no faces (:attr:`Mesh.is_cloud`;
:mod:`meshcorr.core.pointcloud` says what changes for it).
"""

from __future__ import annotations

import os
from typing import Any, Union

import numpy as np

from ..errors import MeshError
from .geodesics import ProgressFn, pairwise_geodesics
from .pointcloud import validate_cloud
from .store import ShapeStore
from .validate import check_scale, check_vertex_count, select_component, validate_mesh
from .geodesics import DEFAULT_GEODESIC


class Mesh:
    """A validated triangle mesh, or a point cloud (no faces).

    Parameters
    ----------
    vertices : (n, 3) float
    faces : (m, 3) int
        ``m = 0`` for a point cloud.
    name : str
        Used in messages.
    kept : (n,) int, optional
        Original index of each vertex when vertices were dropped on input
        (``largest_component=True``); ``arange(n)`` otherwise.
    n_original : int, optional
        Vertices of the input, plus the caps (default ``n``).
    n_caps : int
        Vertices added at the end to close holes (:func:`meshcorr.core.holes.fill_holes`):
        their ``kept`` values are ``n_input ... n_original - 1``.

    Notes
    -----
    The arrays are made read-only, so cached derived data (keyed on the
    solver name) can never go stale.
    """

    def __init__(self, vertices: np.ndarray, faces: np.ndarray, *, name: str = "mesh",
                 kept: np.ndarray | None = None, n_original: int | None = None, n_caps: int = 0) -> None:
        faces = np.asarray(faces)
        if faces.size and not np.issubdtype(faces.dtype, np.integer):  # 0.5 would be truncated silently
            raise MeshError(f"{name}: faces must be integer vertex indices; got dtype {faces.dtype}.")
        self.vertices = np.array(vertices, dtype=np.float64)
        self.faces = np.array(faces, dtype=np.int64)
        if self.faces.size == 0:  # a point cloud
            self.faces = self.faces.reshape(0, 3)
        # The checks every later step relies on (as_mesh validates fully: manifold, components, ...).
        if self.vertices.ndim != 2 or self.vertices.shape[1] != 3 or self.faces.ndim != 2 or self.faces.shape[1] != 3:
            raise MeshError(f"{name}: vertices must be (n, 3) and faces (m, 3); got {self.vertices.shape} and "
                            f"{self.faces.shape}.")
        if not np.isfinite(self.vertices).all():
            raise MeshError(f"{name}: NaN or infinite vertex coordinates; repair the mesh (as_mesh names them).")
        check_scale(self.vertices, name)
        outside = self.faces[(self.faces < 0) | (self.faces >= len(self.vertices))]
        if outside.size:
            raise MeshError(f"{name}: a face names vertex {int(outside[0])}, outside 0..{len(self.vertices) - 1}.")
        self.kept = np.arange(len(self.vertices)) if kept is None else np.asarray(kept, dtype=np.int64)
        self.n_original = len(self.vertices) if n_original is None else int(n_original)
        self.n_caps = int(n_caps)
        for array in (self.vertices, self.faces, self.kept):
            array.flags.writeable = False
        self.name = name
        #: Quantities derived from this shape alone, keyed by what produced them (meshcorr.core.store).
        self.store = ShapeStore()

    @property
    def n_vertices(self) -> int:
        return len(self.vertices)

    @property
    def n_input(self) -> int:
        """Vertices of the input the mesh was made from (``n_original`` without the caps)."""
        return self.n_original - self.n_caps

    @property
    def is_cloud(self) -> bool:
        """Whether this is a point cloud (no faces)."""
        return len(self.faces) == 0

    @property
    def area(self) -> float:
        """Total surface area: of the triangles, or of a point cloud its vertex areas' sum
        (:func:`meshcorr.core.laplacian.vertex_areas`)."""
        if self.is_cloud:
            from .laplacian import vertex_areas

            return float(vertex_areas(self).sum())
        v = self.vertices[self.faces]
        return float(0.5 * np.linalg.norm(np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0]), axis=1).sum())

    def geodesic_matrix(self, method: str = DEFAULT_GEODESIC, progress: ProgressFn | None = None) -> np.ndarray:
        """All-pairs geodesic distances ``(n, n)``, cached per solver, read-only."""
        key = ("geodesic_matrix", method)
        if key not in self.store:
            D = pairwise_geodesics(self.vertices, self.faces, method, progress=progress)
            D.flags.writeable = False
            self.store.put(key, D)
        return self.store[key]

    def __repr__(self) -> str:
        if self.is_cloud:
            return f"Mesh(name={self.name!r}, n_vertices={self.n_vertices}, point cloud)"
        return f"Mesh(name={self.name!r}, n_vertices={self.n_vertices}, n_faces={len(self.faces)})"


MeshLike = Union[str, os.PathLike, Mesh, tuple, Any]


def as_mesh(obj: MeshLike, *, name: str | None = None, largest_component: bool = False,
            min_vertices: int = 3, reason: str = "") -> Mesh:
    """Turn user input into a validated Mesh (a triangle mesh or a point cloud).

    Parameters
    ----------
    obj : str, PathLike, Mesh, trimesh.Trimesh, trimesh.PointCloud, (vertices, faces) or (n, 3) array
        A file (a mesh; a point cloud: a mesh file without faces, PLY of
        points, ``.xyz`` or ``.npy``, see :func:`meshcorr.io.read_mesh`), a
        trimesh object, a pair of arrays (``faces`` empty for a cloud) or
        the points of a cloud.
    name : str, optional
        Name used in messages; defaults to the file name.
    largest_component : bool
        Keep only the largest connected component (of a cloud: the largest
        cluster of its neighbour graph) instead of raising.
    min_vertices : int
        Fewer vertices raise :class:`MeshError` (``reason`` says why).

    Returns
    -------
    mesh : Mesh
        ``mesh.is_cloud`` for a point cloud, validated by
        :func:`meshcorr.core.pointcloud.validate_cloud` (meshes by
        :func:`meshcorr.core.validate.validate_mesh`).
    """
    if isinstance(obj, Mesh):
        if obj.n_vertices < min_vertices:
            raise MeshError(f"{obj.name} has {obj.n_vertices} vertices; at least {min_vertices} are needed. {reason}")
        if obj.is_cloud or obj.n_caps or ("connected",) in obj.store:
            return obj
        # A Mesh made directly, not by as_mesh: its components are checked as any input's (this raises
        # without largest_component).
        vertices, faces, kept = select_component(obj.vertices, obj.faces, largest_component, obj.name)
        if len(kept) == obj.n_vertices:
            obj.store.put(("connected",), True)
            return obj
        check_vertex_count(len(kept), min_vertices, obj.name, reason)
        return Mesh(vertices, faces, name=obj.name, kept=obj.kept[kept], n_original=obj.n_original)
    if isinstance(obj, (str, os.PathLike)):
        from ..io import read_mesh

        name = name or os.path.basename(os.fspath(obj))
        vertices, faces = read_mesh(obj, name=name)
    elif hasattr(obj, "vertices") and hasattr(obj, "faces"):
        vertices, faces = np.asarray(obj.vertices), np.asarray(obj.faces)
    elif hasattr(obj, "vertices") and type(obj).__name__ == "PointCloud":  # trimesh.PointCloud
        vertices, faces = np.asarray(obj.vertices), np.zeros((0, 3), dtype=np.int64)
    elif isinstance(obj, np.ndarray) and obj.ndim == 2:
        vertices, faces = obj, np.zeros((0, 3), dtype=np.int64)
    elif isinstance(obj, (tuple, list)) and len(obj) == 2:
        vertices, faces = obj  # validate_mesh converts them (a ragged list raises MeshError)
    else:
        raise MeshError(
            f"Cannot make a mesh out of {type(obj).__name__}: give a file path, a trimesh.Trimesh or "
            "trimesh.PointCloud, a meshcorr.Mesh, a (vertices, faces) pair or an (n, 3) array of points."
        )
    name = name or "mesh"
    n_original = len(vertices)
    if _no_faces(faces):
        points, kept = validate_cloud(vertices, min_vertices=min_vertices, largest_component=largest_component,
                                      name=name, reason=reason)
        return Mesh(points, np.zeros((0, 3), dtype=np.int64), name=name, kept=kept, n_original=n_original)
    vertices, faces, kept = validate_mesh(vertices, faces, min_vertices=min_vertices,
                                          largest_component=largest_component, name=name, reason=reason)
    return Mesh(vertices, faces, name=name, kept=kept, n_original=n_original)


def _no_faces(faces) -> bool:
    """Whether ``faces`` holds no face at all (an empty array or list): the input is a point cloud."""
    try:
        return np.asarray(faces).size == 0
    except ValueError:  # ragged: validate_mesh says where
        return False
