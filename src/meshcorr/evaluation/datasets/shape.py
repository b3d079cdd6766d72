"""The synthetic shape: a triangle mesh with chart coordinates, and the generators' parameter checks."""

from __future__ import annotations

from dataclasses import dataclass
from numbers import Integral, Real

import numpy as np

from ...errors import MeshError, ParameterError

__all__ = ["CHARTS", "JITTER", "SyntheticShape", "int_parameter", "positive_parameter", "seed_parameter", "shape_parameter"]

#: Jitter of the chart coordinates, as a fraction of the local vertex spacing.
JITTER = 0.2
#: The kinds of chart a SyntheticShape's params can be (see SyntheticShape.chart).
CHARTS = ("capsule", "creature")


@dataclass(frozen=True, eq=False)
class SyntheticShape:
    """A synthetic triangle mesh with chart coordinates for every vertex.

    Attributes
    ----------
    vertices : (n, 3) float64
        Vertex positions (read-only).
    faces : (m, 3) int64
        Triangles as 0-based vertex indices, counter-clockwise seen from
        outside (read-only).
    params : (n, 2) float64
        Chart coordinates of each vertex (see the module docstring); the same
        chart for every pose and resolution of a family (read-only).
    name : str
        A short description, e.g. ``"figure-r2-bent"``.
    chart : {"capsule", "creature"}, default "capsule"
        How ``params`` are read: ``(t, theta)`` on a reference capsule
        (:func:`tube`, :func:`figure`) or ``(polar angle, azimuth)`` of the
        unit-sphere direction the vertex was made from (:func:`creature`).
    """

    vertices: np.ndarray
    faces: np.ndarray
    params: np.ndarray
    name: str
    chart: str = "capsule"

    def __post_init__(self) -> None:
        vertices = np.array(self.vertices, dtype=np.float64)
        faces = np.array(self.faces, dtype=np.int64)
        params = np.array(self.params, dtype=np.float64)
        if vertices.ndim != 2 or vertices.shape[1] != 3:
            raise MeshError(
                f"SyntheticShape vertices must have shape (n, 3). Got {vertices.shape} instead."
            )
        if faces.ndim != 2 or faces.shape[1] != 3:
            raise MeshError(
                f"SyntheticShape faces must have shape (m, 3). Got {faces.shape} instead."
            )
        if params.shape != (len(vertices), 2):
            raise MeshError(
                f"SyntheticShape params must have shape ({len(vertices)}, 2). "
                f"Got {params.shape} instead."
            )
        if faces.size and (faces.min() < 0 or faces.max() >= len(vertices)):
            raise MeshError("SyntheticShape faces index vertices that do not exist.")
        if self.chart not in CHARTS:
            raise MeshError(
                f"SyntheticShape chart must be one of {list(CHARTS)}. Got {self.chart!r} instead."
            )
        for array in (vertices, faces, params):
            array.flags.writeable = False
        object.__setattr__(self, "vertices", vertices)
        object.__setattr__(self, "faces", faces)
        object.__setattr__(self, "params", params)
        object.__setattr__(self, "name", str(self.name))

    @property
    def n_vertices(self) -> int:
        """Number of vertices."""
        return len(self.vertices)

    def __repr__(self) -> str:  # not the dataclass's: it printed every array (17 000 characters at 500 vertices)
        return (f"SyntheticShape(name={self.name!r}, n_vertices={self.n_vertices}, n_faces={len(self.faces)}, "
                f"chart={self.chart!r})")


def int_parameter(value, name: str, func: str, low: int, high: int | None = None) -> int:
    ok = isinstance(value, Integral) and not isinstance(value, bool)
    ok = ok and value >= low and (high is None or value <= high)
    if not ok:
        bound = f">= {low}" if high is None else f"in [{low}, {high}]"
        raise ParameterError(
            f"The '{name}' parameter of {func} must be an int {bound}. Got {value!r} instead."
        )
    return int(value)


def positive_parameter(value, name: str, func: str) -> float:
    ok = isinstance(value, Real) and not isinstance(value, bool)
    ok = ok and np.isfinite(value) and value > 0
    if not ok:
        raise ParameterError(
            f"The '{name}' parameter of {func} must be a finite float > 0. Got {value!r} instead."
        )
    return float(value)


def seed_parameter(value, func: str) -> int | None:
    if value is None:
        return None
    if isinstance(value, Integral) and not isinstance(value, bool) and value >= 0:
        return int(value)
    raise ParameterError(
        f"The 'random_state' parameter of {func} must be an int >= 0 or None. "
        f"Got {value!r} instead."
    )


def shape_parameter(value, name: str, func: str) -> SyntheticShape:
    if not isinstance(value, SyntheticShape):
        raise ParameterError(
            f"The '{name}' parameter of {func} must be a SyntheticShape. "
            f"Got {type(value).__name__} instead."
        )
    return value
