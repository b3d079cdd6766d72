"""A thin, immutable triangle-mesh object and the conversion of user input into it.

Geometry lives in free functions on ``(V, F)`` arrays (:mod:`meshcorr.geodesics`,
:mod:`meshcorr.validate`); :class:`Mesh` only holds validated, read-only
arrays and caches derived data keyed on the parameters that produced it.
"""

from __future__ import annotations

import os
from typing import Any, Union

import numpy as np

from .errors import MeshError
from .geodesics import ProgressFn, pairwise_geodesics
from .validate import validate_mesh


class Mesh:
    """A validated triangle mesh.

    Parameters
    ----------
    vertices : (n, 3) float
    faces : (m, 3) int
    name : str
        Used in messages.
    kept : (n,) int, optional
        Original index of each vertex when vertices were dropped on input
        (``largest_component=True``); ``arange(n)`` otherwise.

    Notes
    -----
    The arrays are made read-only, so cached derived data (keyed on the
    solver name) can never go stale.
    """

    def __init__(self, vertices: np.ndarray, faces: np.ndarray, *, name: str = "mesh",
                 kept: np.ndarray | None = None, n_original: int | None = None) -> None:
        self.vertices = np.array(vertices, dtype=np.float64)
        self.faces = np.array(faces, dtype=np.int64)
        self.kept = np.arange(len(self.vertices)) if kept is None else np.asarray(kept, dtype=np.int64)
        self.n_original = len(self.vertices) if n_original is None else int(n_original)
        for array in (self.vertices, self.faces, self.kept):
            array.flags.writeable = False
        self.name = name
        self._cache: dict[tuple, Any] = {}

    @property
    def n_vertices(self) -> int:
        return len(self.vertices)

    @property
    def area(self) -> float:
        """Total surface area."""
        v = self.vertices[self.faces]
        return float(0.5 * np.linalg.norm(np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0]), axis=1).sum())

    def geodesic_matrix(self, method: str = "heat", progress: ProgressFn | None = None) -> np.ndarray:
        """All-pairs geodesic distances ``(n, n)``, cached per solver, read-only."""
        key = ("geodesic_matrix", method)
        if key not in self._cache:
            D = pairwise_geodesics(self.vertices, self.faces, method, progress=progress)
            D.flags.writeable = False
            self._cache[key] = D
        return self._cache[key]

    def __repr__(self) -> str:
        return f"Mesh(name={self.name!r}, n_vertices={self.n_vertices}, n_faces={len(self.faces)})"


MeshLike = Union[str, os.PathLike, Mesh, tuple, Any]


def as_mesh(obj: MeshLike, *, name: str | None = None, largest_component: bool = False,
            min_vertices: int = 3, reason: str = "") -> Mesh:
    """Turn a path, a trimesh object, a ``(V, F)`` pair or a :class:`Mesh` into a validated Mesh.

    Parameters
    ----------
    obj : str, PathLike, Mesh, trimesh.Trimesh or (vertices, faces)
    name : str, optional
        Name used in messages; defaults to the file name.
    largest_component : bool
        Keep only the largest connected component instead of raising.
    min_vertices : int
        Fewer vertices raise :class:`MeshError` (``reason`` says why).

    Returns
    -------
    mesh : Mesh
    """
    if isinstance(obj, Mesh):
        if obj.n_vertices < min_vertices:
            raise MeshError(f"{obj.name} has {obj.n_vertices} vertices; at least {min_vertices} are needed. {reason}")
        return obj
    if isinstance(obj, (str, os.PathLike)):
        from .io import read_mesh

        name = name or os.path.basename(os.fspath(obj))
        vertices, faces = read_mesh(obj, name=name)
    elif hasattr(obj, "vertices") and hasattr(obj, "faces"):
        vertices, faces = np.asarray(obj.vertices), np.asarray(obj.faces)
    elif isinstance(obj, (tuple, list)) and len(obj) == 2:
        vertices, faces = obj  # validate_mesh converts them (a ragged list raises MeshError)
    else:
        raise MeshError(
            f"Cannot make a mesh out of {type(obj).__name__}: give a file path, a trimesh.Trimesh, "
            "a meshcorr.Mesh or a (vertices, faces) pair."
        )
    name = name or "mesh"
    n_original = len(vertices)
    vertices, faces, kept = validate_mesh(vertices, faces, min_vertices=min_vertices,
                                          largest_component=largest_component, name=name, reason=reason)
    return Mesh(vertices, faces, name=name, kept=kept, n_original=n_original)
