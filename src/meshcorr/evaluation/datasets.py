"""Synthetic shapes with known ground-truth correspondence.

Every generator here builds a closed, genus-0, consistently and outwardly
oriented triangle mesh from a fixed two-dimensional *chart*, so that tests and
benchmarks need no downloaded data:

- :func:`creature` -- a compact "starfish": a round body with five limbs of
  clearly different lengths and thicknesses, each bending at hinges. Its
  spectral embedding is well conditioned (distinct top eigenvalues, no
  intrinsic symmetry), so it is the shape for end-to-end tests of the
  spectral pipeline; the bundled example pair is made from it;
- :func:`tube` -- a capsule with asymmetric bumps, optionally bent into a
  circular arc;
- :func:`figure` -- a tube-shaped creature: a capsule with a head, a neck, a
  tapering tail and limb-like protrusions, articulated at three hinges. Thin
  and nearly round in cross-section, it has three nearly equal eigenvalues in
  the spectral embedding (they mix between poses), so it suits tests of
  meshes and ground truth rather than of matching;
- :func:`sphere` -- an icosphere, for checking geodesic solvers against the
  great-circle formula;
- :func:`rigid_copy` -- a rotated, translated, scaled and re-indexed copy
  with its ground truth;
- :func:`ground_truth` -- the correspondence between two shapes of one family
  (different poses and/or resolutions);
- :func:`save_example_pair` -- writes the bundled example pair.

The charts
----------
A shape's ``chart`` attribute says how its ``params`` are read.

``"capsule"`` (:func:`tube`, :func:`figure`): each vertex carries chart
coordinates ``params[i] = (t, theta)``. ``t`` is the arc length along a
meridian of the *reference capsule* (the straight, unbumped capsule of radius
``r`` around a centre line of length ``L``): ``t`` runs from ``-pi r / 2``
(pole at the start) through ``[0, L]`` (the cylinder, where ``t`` equals the
arc length ``s`` along the centre line) to ``L + pi r / 2`` (pole at the
end). ``theta`` in ``[0, 2 pi)`` is the angle around the centre line,
measured from the normal of a parallel-transported (twist-free) frame, so it
is the same material direction in every pose.

``"creature"`` (:func:`creature`): each vertex comes from a unit vector
``u``, stored as ``params[i] = (polar angle, azimuth)`` about the z axis. A
fixed conformal map sends ``u`` to the creature's rest pose (body sphere
scaled; each limb's cap of the sphere stretched along the limb), and the
poses bend the limbs.

Bumps, radius profiles and poses are functions of the chart only, so every
pose and every resolution of a family samples one surface, and poses of one
resolution share vertices, faces and ``params`` exactly (their ground truth
is the identity).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from numbers import Integral, Real
from pathlib import Path

import numpy as np
from scipy.spatial import cKDTree

from meshcorr.errors import MeshError, ParameterError

__all__ = [
    "SyntheticShape",
    "creature",
    "figure",
    "ground_truth",
    "rigid_copy",
    "save_example_pair",
    "sphere",
    "tube",
]

# Jitter of the chart coordinates, as a fraction of the local vertex spacing.
_JITTER = 0.2
# The kinds of chart a SyntheticShape's params can be (see SyntheticShape.chart).
_CHARTS = ("capsule", "creature")


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
        if self.chart not in _CHARTS:
            raise MeshError(
                f"SyntheticShape chart must be one of {list(_CHARTS)}. Got {self.chart!r} instead."
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


# --------------------------------------------------------------------------
# parameter checks
# --------------------------------------------------------------------------


def _check_int(value, name: str, func: str, low: int, high: int | None = None) -> int:
    ok = isinstance(value, Integral) and not isinstance(value, bool)
    ok = ok and value >= low and (high is None or value <= high)
    if not ok:
        bound = f">= {low}" if high is None else f"in [{low}, {high}]"
        raise ParameterError(
            f"The '{name}' parameter of {func} must be an int {bound}. Got {value!r} instead."
        )
    return int(value)


def _check_positive(value, name: str, func: str) -> float:
    ok = isinstance(value, Real) and not isinstance(value, bool)
    ok = ok and np.isfinite(value) and value > 0
    if not ok:
        raise ParameterError(
            f"The '{name}' parameter of {func} must be a finite float > 0. Got {value!r} instead."
        )
    return float(value)


def _check_random_state(value, func: str) -> int | None:
    if value is None:
        return None
    if isinstance(value, Integral) and not isinstance(value, bool) and value >= 0:
        return int(value)
    raise ParameterError(
        f"The 'random_state' parameter of {func} must be an int >= 0 or None. "
        f"Got {value!r} instead."
    )


def _check_shape(value, name: str, func: str) -> SyntheticShape:
    if not isinstance(value, SyntheticShape):
        raise ParameterError(
            f"The '{name}' parameter of {func} must be a SyntheticShape. "
            f"Got {type(value).__name__} instead."
        )
    return value


# --------------------------------------------------------------------------
# chart, centre line and surface
# --------------------------------------------------------------------------


def _chart_embedding(params: np.ndarray, t_min: float, t_max: float) -> np.ndarray:
    """Positions of chart points on the straight, unbumped reference capsule.

    Parameters
    ----------
    params : (n, 2) float
        Chart coordinates ``(t, theta)``.
    t_min, t_max : float
        The chart's poles; the capsule radius is ``-2 t_min / pi`` and the
        centre line runs from 0 to ``t_max - pi r / 2``.

    Returns
    -------
    points : (n, 3) float
        The reference capsule lies along the x axis. Chordal distances between
        these points approximate surface distances on every shape of the
        family; ``theta`` is periodic and meaningless at the poles, as it
        should be.
    """
    radius = -2.0 * t_min / np.pi
    length = t_max - np.pi * radius / 2.0
    t, theta = params[:, 0], params[:, 1]
    alpha = (np.minimum(t, 0.0) + np.maximum(t - length, 0.0)) / radius
    x = np.clip(t, 0.0, length) + radius * np.sin(alpha)
    rho = radius * np.cos(alpha)
    return np.column_stack([x, rho * np.cos(theta), rho * np.sin(theta)])


def _rotate(vectors: np.ndarray, axis: np.ndarray, angle: float) -> np.ndarray:
    """Rotate row vectors about a unit axis by an angle (Rodrigues)."""
    c, s = np.cos(angle), np.sin(angle)
    return (
        vectors * c
        + np.cross(axis, vectors) * s
        + np.outer(vectors @ axis, axis) * (1.0 - c)
    )


def _centre_line(s: np.ndarray, pieces: list[tuple[float, float, float]]):
    """Position and parallel-transported frame along a piecewise-circular curve.

    Parameters
    ----------
    s : (k,) float
        Arc lengths in ``[0, sum of piece lengths]``.
    pieces : list of (length, turning angle, plane angle)
        Consecutive pieces of the centre line. A piece of turning angle ``phi``
        is a circular arc of curvature ``phi / length`` bending towards
        ``cos(psi) N + sin(psi) B`` of the frame at its start (``phi = 0`` is a
        straight segment). The curve starts at the origin along +x with
        ``N = +y``, ``B = +z``.

    Returns
    -------
    point, tangent, normal, binormal : (k, 3) float
        The frame is parallel transported (no twist), so a fixed angle
        ``theta`` in the ``(N, B)`` plane is the same material line on the
        tube in every pose.
    """
    s = np.asarray(s, dtype=np.float64)
    out = [np.zeros((len(s), 3)) for _ in range(4)]
    position = np.zeros(3)
    frame = np.eye(3)  # rows: T, N, B
    start = 0.0
    for number, (length, phi, psi) in enumerate(pieces):
        last = number == len(pieces) - 1
        mask = (s >= start) & ((s < start + length) | last)
        d = s[mask] - start
        tangent, normal, binormal = frame
        towards = np.cos(psi) * normal + np.sin(psi) * binormal
        side = -np.sin(psi) * normal + np.cos(psi) * binormal  # = T x towards
        kappa = phi / length
        angle = kappa * d
        if phi == 0.0:
            along, across = d, np.zeros_like(d)
        else:
            along, across = np.sin(angle) / kappa, (1.0 - np.cos(angle)) / kappa
        out[0][mask] = position + np.outer(along, tangent) + np.outer(across, towards)
        t_new = np.outer(np.cos(angle), tangent) + np.outer(np.sin(angle), towards)
        u_new = np.outer(-np.sin(angle), tangent) + np.outer(np.cos(angle), towards)
        out[1][mask] = t_new
        out[2][mask] = np.cos(psi) * u_new - np.sin(psi) * side
        out[3][mask] = np.sin(psi) * u_new + np.cos(psi) * side
        # frame and position at the end of this piece
        a = phi
        if phi == 0.0:
            position = position + length * tangent
        else:
            position = position + (np.sin(a) * tangent + (1.0 - np.cos(a)) * towards) / kappa
        frame = _rotate(frame, side, a)
        start += length
    return tuple(out)


def _bump_field(points: np.ndarray, bumps: np.ndarray, t_min: float, t_max: float) -> np.ndarray:
    """Sum of Gaussian bumps, measured on the reference capsule.

    Parameters
    ----------
    points : (n, 3) float
        Chart embedding of the vertices (see :func:`_chart_embedding`).
    bumps : (b, 4) float
        Rows ``(t, theta, amplitude, width)``: a bump's centre in the chart,
        its height relative to the local radius and its standard deviation
        (a length, measured on the reference capsule).

    Returns
    -------
    field : (n,) float
    """
    field = np.zeros(len(points))
    if len(bumps) == 0:
        return field
    centres = _chart_embedding(bumps[:, :2], t_min, t_max)
    for centre, amplitude, width in zip(centres, bumps[:, 2], bumps[:, 3]):
        d2 = np.sum((points - centre) ** 2, axis=1)
        field += amplitude * np.exp(-d2 / (2.0 * width**2))
    return field


def _surface(params, *, length, radius, pieces, profile, bumps) -> np.ndarray:
    """Positions of chart points on the posed, bumped surface.

    Parameters
    ----------
    params : (n, 2) float
        Chart coordinates.
    length, radius : float
        Centre-line length and reference radius of the chart.
    pieces : list of (length, turning angle, plane angle)
        The posed centre line (see :func:`_centre_line`).
    profile : callable (n,) -> (n,)
        Radius multiplier as a function of ``t``.
    bumps : (b, 4) float
        See :func:`_bump_field`.

    Returns
    -------
    vertices : (n, 3) float
        ``C(s) + radius * profile(t) * (1 + bumps(t, theta)) * d(t, theta)``:
        a point on the centre line plus a radial offset in its normal plane
        (cylinder) or on a hemisphere around the end point (caps).
    """
    t_min, t_max = -np.pi * radius / 2.0, length + np.pi * radius / 2.0
    t, theta = params[:, 0], params[:, 1]
    s = np.clip(t, 0.0, length)
    point, tangent, normal, binormal = _centre_line(s, pieces)
    alpha = (np.minimum(t, 0.0) + np.maximum(t - length, 0.0)) / radius
    direction = np.cos(alpha)[:, None] * (
        np.cos(theta)[:, None] * normal + np.sin(theta)[:, None] * binormal
    ) + np.sin(alpha)[:, None] * tangent
    reference = _chart_embedding(params, t_min, t_max)
    r = radius * profile(t) * (1.0 + _bump_field(reference, bumps, t_min, t_max))
    return point + r[:, None] * direction


# --------------------------------------------------------------------------
# meshing the chart
# --------------------------------------------------------------------------


def _stitch(ring_a: np.ndarray, angles_a: np.ndarray, ring_b: np.ndarray, angles_b: np.ndarray):
    """Triangulate the band between two closed rings of vertices.

    Parameters
    ----------
    ring_a, ring_b : (p,), (q,) int
        Vertex indices of two consecutive rings (``a`` nearer the start pole),
        in increasing angle.
    angles_a, angles_b : (p,), (q,) float
        Their angles ``theta``, increasing.

    Returns
    -------
    faces : (p + q, 3) int
        The zipper triangulation: walk both rings by increasing angle, always
        advancing the ring whose next vertex comes first. Oriented outwards
        for the chart's orientation (``t`` along +x, ``theta`` right-handed
        about +x).
    """
    p, q = len(ring_a), len(ring_b)
    # start ring b at the vertex nearest in angle to a[0]; unwrap both rings
    start = int(np.argmin(np.abs(np.angle(np.exp(1j * (angles_b - angles_a[0]))))))
    order_b = np.roll(np.arange(q), -start)
    ua = np.unwrap(np.concatenate([angles_a, angles_a[:1] + 2 * np.pi]))
    ub = np.unwrap(np.concatenate([angles_b[order_b], angles_b[order_b[:1]] + 2 * np.pi]))
    ub += 2 * np.pi * np.round((ua[0] - ub[0]) / (2 * np.pi))
    faces = []
    i = j = 0
    while i < p or j < q:
        if j == q or (i < p and ua[i + 1] < ub[j + 1]):
            faces.append((ring_a[i % p], ring_a[(i + 1) % p], ring_b[order_b[j % q]]))
            i += 1
        else:
            faces.append((ring_a[i % p], ring_b[order_b[(j + 1) % q]], ring_b[order_b[j % q]]))
            j += 1
    return np.array(faces, dtype=np.int64)


def _capsule_chart(ring_t: np.ndarray, ring_counts: np.ndarray, t_min: float, t_max: float,
                   random_state: int | None):
    """Chart coordinates and faces of a capsule mesh made of rings.

    Parameters
    ----------
    ring_t : (k,) float
        Chart ``t`` of each ring, increasing, strictly between the poles.
    ring_counts : (k,) int
        Number of vertices on each ring (>= 3).
    t_min, t_max : float
        The poles.
    random_state : int or None
        Seed of the in-chart jitter (up to ``_JITTER`` times the distance to
        the nearer neighbouring ring along ``t``, and times the ring's angular
        step along ``theta``); ``None`` for none.

    Returns
    -------
    params : (n, 2) float
        Pole at ``t_min`` first, then the rings in order, then the pole at
        ``t_max``; ``theta`` of the poles is 0.
    faces : (m, 3) int64
    """
    rng = None if random_state is None else np.random.default_rng(random_state)
    gaps = np.diff(np.concatenate([[t_min], ring_t, [t_max]]))
    spacing_t = np.minimum(gaps[:-1], gaps[1:])
    params = [np.array([[t_min, 0.0]])]
    rings, ring_angles = [], []
    next_index = 1
    for k, (t, count, spacing) in enumerate(zip(ring_t, ring_counts, spacing_t)):
        step = 2.0 * np.pi / count
        theta = step * (np.arange(count) + 0.5 * (k % 2))
        t_ring = np.full(count, t)
        if rng is not None:
            t_ring = t_ring + _JITTER * spacing * rng.uniform(-1.0, 1.0, count)
            theta = theta + _JITTER * step * rng.uniform(-1.0, 1.0, count)
        theta = np.mod(theta, 2.0 * np.pi)
        order = np.argsort(theta, kind="stable")
        theta, t_ring = theta[order], t_ring[order]
        params.append(np.column_stack([t_ring, theta]))
        rings.append(np.arange(next_index, next_index + count))
        ring_angles.append(theta)
        next_index += count
    params.append(np.array([[t_max, 0.0]]))
    pole_end = next_index

    faces = []
    first, last = rings[0], rings[-1]
    faces.append(np.column_stack([np.zeros_like(first), np.roll(first, -1), first]))
    for a, b, angles_a, angles_b in zip(rings[:-1], rings[1:], ring_angles[:-1], ring_angles[1:]):
        faces.append(_stitch(a, angles_a, b, angles_b))
    faces.append(np.column_stack([last, np.roll(last, -1), np.full_like(last, pole_end)]))
    return np.concatenate(params), np.concatenate(faces).astype(np.int64)


def _cap_rings(radius: float, spacing: float, base_count, end: str):
    """Ring positions and counts on one hemispherical cap of the chart.

    Returns the rings strictly between the pole and the cap's rim, ordered by
    increasing ``t``; their counts follow the ring circumference.
    """
    quarter = np.pi * radius / 2.0
    n_cap = max(1, int(round(quarter / spacing)))
    depth = quarter * np.arange(1, n_cap) / n_cap  # distance from the pole
    counts = np.maximum(3, np.round(base_count * np.sin(depth / radius))).astype(int)
    if end == "start":
        return depth - quarter, counts
    return (quarter - depth)[::-1], counts[::-1]


# --------------------------------------------------------------------------
# tube
# --------------------------------------------------------------------------

# (t as a fraction of the length, theta, relative height, width / radius)
_TUBE_BUMPS = np.array([
    [0.20, 0.40, 0.30, 0.55],
    [0.52, 2.55, 0.45, 0.75],
    [0.81, 4.30, 0.22, 0.45],
])


def tube(*, n_along: int = 40, n_around: int = 16, length: float = 4.0, radius: float = 0.5,
         bend: float = 0.0, bumps: bool = True, random_state: int | None = 0) -> SyntheticShape:
    """A closed capsule around a straight or circularly bent centre line.

    The surface is the set of points at distance ``radius`` (times the bump
    factor) from a centre line of arc length ``length``: a cylinder closed by
    two hemispheres, so its end-to-end extent is ``length + 2 radius`` when
    straight. Bending keeps the centre line's arc length and carries each
    cross-section rigidly with a twist-free frame; the surface is then only
    approximately isometric to the straight one (lengths along the tube
    change by the factor ``1 - kappa rho cos(theta)``, which averages to 1
    around each ring).

    Parameters
    ----------
    n_along : int, default 40
        Number of vertex rings on the cylinder, its two rims included (>= 2).
        The caps get rings at about the same spacing.
    n_around : int, default 16
        Number of vertices on each cylinder ring (>= 3); cap rings have fewer,
        in proportion to their circumference. About ``n_around * (n_along - 1
        + 2 * radius * (n_along - 1) / length)`` vertices in all: 788 by
        default, 190 for ``n_along=12, n_around=14`` and 19,900 for
        ``n_along=200, n_around=80``.
    length : float, default 4.0
        Arc length of the centre line (> 0).
    radius : float, default 0.5
        Radius of the tube (> 0).
    bend : float, default 0.0
        Total turning angle of the centre line in radians (0 = straight), as
        one circular arc in the xy plane. ``|bend|`` must be at most
        ``min(pi, 0.5 * length / radius)`` so that the surface cannot fold or
        touch itself.
    bumps : bool, default True
        Add three smooth radial bumps of different heights and widths at
        fixed, asymmetric chart positions, so that the shape has no intrinsic
        symmetry (no end-to-end, mirror or rotational one).
    random_state : int or None, default 0
        Seed of a small jitter of the vertices' chart coordinates (20 % of the
        local spacing) that makes the mesh irregular; ``None`` gives the
        regular mesh. The bumps do not depend on it.

    Returns
    -------
    shape : SyntheticShape
        ``params`` are the chart coordinates ``(t, theta)`` (module
        docstring). Shapes with equal ``n_along``, ``n_around``, ``length``,
        ``radius`` and ``random_state`` share faces and ``params`` for every
        ``bend``.
    """
    func = "tube"
    n_along = _check_int(n_along, "n_along", func, 2)
    n_around = _check_int(n_around, "n_around", func, 3)
    length = _check_positive(length, "length", func)
    radius = _check_positive(radius, "radius", func)
    max_bend = min(np.pi, 0.5 * length / radius)
    if not (isinstance(bend, Real) and not isinstance(bend, bool) and np.isfinite(bend)
            and abs(bend) <= max_bend):
        raise ParameterError(
            f"The 'bend' parameter of tube must be a float with |bend| <= "
            f"min(pi, 0.5 * length / radius) = {max_bend:.4g}. Got {bend!r} instead."
        )
    if not isinstance(bumps, (bool, np.bool_)):
        raise ParameterError(
            f"The 'bumps' parameter of tube must be a bool. Got {bumps!r} instead."
        )
    random_state = _check_random_state(random_state, func)

    spacing = length / (n_along - 1)
    t_min, t_max = -np.pi * radius / 2.0, length + np.pi * radius / 2.0
    t0, c0 = _cap_rings(radius, spacing, n_around, "start")
    t1, c1 = _cap_rings(radius, spacing, n_around, "end")
    ring_t = np.concatenate([t0, np.linspace(0.0, length, n_along), length + t1])
    ring_counts = np.concatenate([c0, np.full(n_along, n_around), c1])
    params, faces = _capsule_chart(ring_t, ring_counts, t_min, t_max, random_state)

    bump_table = np.zeros((0, 4))
    if bumps:
        bump_table = _TUBE_BUMPS * [length, 1.0, 1.0, radius]
    vertices = _surface(
        params,
        length=length,
        radius=radius,
        pieces=[(length, float(bend), 0.0)],
        profile=np.ones_like,
        bumps=bump_table,
    )
    name = f"tube-{n_along}x{n_around}-bend{float(bend):.3g}"
    return SyntheticShape(vertices, faces, params, name)


# --------------------------------------------------------------------------
# figure
# --------------------------------------------------------------------------

_FIGURE_LENGTH = 7.0
_FIGURE_RADIUS = 0.45
# (t, theta, relative height, width): an ear, a dorsal fin, a front and a hind leg
_FIGURE_BUMPS = np.array([
    [0.45, 5.60, 0.30, 0.18],
    [2.25, 1.45, 0.35, 0.30],
    [2.45, 3.95, 1.00, 0.28],
    [4.60, 4.70, 0.70, 0.24],
])
# hinges: (start s, length, plane angle psi); a pose gives each one's turning angle
_FIGURE_HINGES = [(1.0, 0.9, 0.0), (3.0, 1.0, np.pi / 2), (5.2, 1.2, 0.0)]
_FIGURE_POSES = {
    "rest": (0.0, 0.0, 0.0),
    "bent": (0.9, -0.7, 1.3),
    "curled": (1.2, 0.6, 1.6),
}


def _smoothstep(x: np.ndarray) -> np.ndarray:
    x = np.clip(x, 0.0, 1.0)
    return x * x * (3.0 - 2.0 * x)


def _figure_profile(t: np.ndarray) -> np.ndarray:
    """Radius multiplier of the figure along ``t``: head, neck, belly, tapering tail."""
    t = np.asarray(t, dtype=np.float64)
    return (
        1.0
        + 0.35 * np.exp(-0.5 * ((t - 0.45) / 0.45) ** 2)  # head
        - 0.22 * np.exp(-0.5 * ((t - 1.45) / 0.30) ** 2)  # neck
        + 0.12 * np.exp(-0.5 * ((t - 3.40) / 1.00) ** 2)  # belly
        - 0.40 * _smoothstep((t - 4.8) / 2.0)  # tail
    )


def _figure_pieces(angles) -> list[tuple[float, float, float]]:
    pieces, s = [], 0.0
    for (start, span, psi), phi in zip(_FIGURE_HINGES, angles):
        pieces.append((start - s, 0.0, 0.0))
        pieces.append((span, float(phi), psi))
        s = start + span
    pieces.append((_FIGURE_LENGTH - s, 0.0, 0.0))
    return pieces


def figure(*, resolution: int = 1, pose: str | float = "rest",
           random_state: int | None = 0) -> SyntheticShape:
    """An articulated, intrinsically asymmetric "creature" for correspondence tests.

    A single closed tube (genus 0) along a centre line of length 7: a bulbous
    head, a thin neck, a belly and a tail tapering to 60 % of the body
    radius (0.45), with four protrusions of different sizes at asymmetric
    angles (an ear, a dorsal fin, a long front leg, a shorter hind leg). The
    centre line has three hinges (neck, waist, tail; circular arcs of length
    0.9-1.2, the waist bending out of the plane of the other two). A pose sets
    the hinges' turning angles; the straight parts move rigidly, so poses are
    near-isometric bends with the same vertex indexing.

    Parameters
    ----------
    resolution : int, default 1
        Level of detail (>= 1): rings of about ``8 + 4 * resolution`` vertices
        at the body radius with near-equilateral triangles. Resolutions 1, 2,
        3, 4 give 448, 832, 1274, 1844 vertices; resolution 18 gives 20,411.
    pose : {"rest", "bent", "curled"} or float, default "rest"
        ``"rest"`` is straight; ``"bent"`` turns the hinges by (0.9, -0.7,
        1.3) radians, ``"curled"`` by (1.2, 0.6, 1.6). A float ``p`` in
        ``[-1, 1]`` gives ``p`` times the ``"bent"`` angles (``0.0`` is
        ``"rest"``, ``1.0`` is ``"bent"``).
    random_state : int or None, default 0
        Seed of a small jitter of the vertices' chart coordinates (20 % of the
        local spacing) that makes the mesh irregular; ``None`` gives the
        regular mesh. Geometry and poses do not depend on it.

    Returns
    -------
    shape : SyntheticShape
        Shapes with equal ``resolution`` and ``random_state`` share faces and
        ``params`` in every pose (ground truth = identity); different
        resolutions have different vertex counts and share the chart.
    """
    func = "figure"
    resolution = _check_int(resolution, "resolution", func, 1)
    if isinstance(pose, str):
        if pose not in _FIGURE_POSES:
            raise ParameterError(
                f"The 'pose' parameter of figure must be one of {sorted(_FIGURE_POSES)} "
                f"or a float in [-1, 1]. Got {pose!r} instead."
            )
        angles = _FIGURE_POSES[pose]
        pose_name = pose
    elif isinstance(pose, Real) and not isinstance(pose, bool) and np.isfinite(pose) \
            and abs(pose) <= 1.0:
        angles = tuple(float(pose) * a for a in _FIGURE_POSES["bent"])
        pose_name = f"pose{float(pose):.3g}"
    else:
        raise ParameterError(
            f"The 'pose' parameter of figure must be one of {sorted(_FIGURE_POSES)} "
            f"or a float in [-1, 1]. Got {pose!r} instead."
        )
    random_state = _check_random_state(random_state, func)

    length, radius = _FIGURE_LENGTH, _FIGURE_RADIUS
    n_around = 8 + 4 * resolution
    spacing_around = 2.0 * np.pi * radius / n_around
    spacing = spacing_around * np.sqrt(3.0) / 2.0
    t_min, t_max = -np.pi * radius / 2.0, length + np.pi * radius / 2.0
    # cylinder rings; their counts follow the radius profile
    n_along = max(2, int(round(length / spacing)) + 1)
    t_body = np.linspace(0.0, length, n_along)
    body_counts = np.maximum(3, np.round(n_around * _figure_profile(t_body))).astype(int)
    t0, c0 = _cap_rings(radius, spacing, n_around * _figure_profile(0.0), "start")
    t1, c1 = _cap_rings(radius, spacing, n_around * _figure_profile(length), "end")
    ring_t = np.concatenate([t0, t_body, length + t1])
    ring_counts = np.concatenate([c0, body_counts, c1])
    params, faces = _capsule_chart(ring_t, ring_counts, t_min, t_max, random_state)
    vertices = _surface(
        params,
        length=length,
        radius=radius,
        pieces=_figure_pieces(angles),
        profile=_figure_profile,
        bumps=_FIGURE_BUMPS,
    )
    return SyntheticShape(vertices, faces, params, f"figure-r{resolution}-{pose_name}")


# --------------------------------------------------------------------------
# creature
# --------------------------------------------------------------------------

_CREATURE_BODY = 0.7  # radius of the body sphere
_CREATURE_FILLET = 0.25  # radius of the fillets joining the limbs to the body
# Limbs: (direction, bend direction, radius, length beyond the body sphere, hinges).
# A hinge is (start, end, plane angle psi): start and end as fractions of the
# limb's cylindrical part (from the fillet to the tip cap); psi turns its
# bending plane about the limb axis from the limb's bend direction.
_CREATURE_LIMBS = (
    ((1.0, 0.2, 0.1), (0.0, -1.0, 0.3), 0.20, 3.0, ((0.02, 0.32, 0.0), (0.55, 0.78, 1.2))),
    ((-0.3, 1.0, 0.2), (1.0, 0.3, 0.0), 0.26, 2.0, ((0.03, 0.55, 0.0),)),
    ((-0.4, -0.6, 0.8), (-1.0, 0.5, 0.0), 0.18, 1.4, ((0.03, 0.60, 0.0),)),
    ((0.1, -0.5, -0.9), (-1.0, 0.0, 0.2), 0.30, 1.0, ((0.03, 0.80, 0.0),)),
    ((-1.0, 0.1, -0.5), (0.0, 1.0, 0.0), 0.22, 0.7, ((0.03, 0.90, 0.0),)),
)
# turning angle of every hinge, limb by limb
_CREATURE_POSES = {
    "rest": ((0.0, 0.0), (0.0,), (0.0,), (0.0,), (0.0,)),
    "bent": ((0.7, 0.5), (0.7,), (0.7,), (0.6,), (0.45,)),
    "curled": ((1.1, 0.9), (1.1,), (1.1,), (0.9,), (0.6,)),
}
_CREATURE_MAX_RESOLUTION = 6
_CREATURE_RELAX_STEPS = (12, 3)  # smoothing steps, steps per re-triangulation
# Width of one band of the banded spherical Delaunay triangulation, in the
# conformal coordinate w = log tan(angle to the limb axis / 2).
_CREATURE_BAND = 6.0


@dataclass(frozen=True, eq=False)
class _Limb:
    """Geometry of one limb of :func:`creature` (see :func:`_creature_limb`)."""

    frame: np.ndarray  # rows: axis d, bend direction n, b = d x n
    radius: float  # a
    fillet: float  # f
    z_fillet: float  # where the cylinder meets the fillet, along d from the body centre
    z_cap: float  # centre of the tip hemisphere
    cap_angle: float  # Theta: the limb's cap {angle(u, d) < Theta} on the unit sphere
    turn: float  # alpha = pi / 2 - Theta, the fillet's turning angle
    w_tip: float  # conformal coordinate of the tip-cap / cylinder junction
    w_cylinder: float  # ... of the cylinder / fillet junction
    w_base: float  # ... of the fillet / body junction, log tan(Theta / 2)
    hinges: tuple  # ((z start, arc length, psi), ...)
    area: float


def _creature_limb(direction, towards, radius, length, hinges) -> _Limb:
    """Precompute one limb: a capsule along ``direction`` joined to the body by a torus.

    In a half-plane through the limb axis (``rho`` from the axis, ``z`` along
    it), the meridian runs from the tip: a quarter circle of radius ``a`` about
    ``(0, z_cap)``, the cylinder ``rho = a`` down to ``z_fillet``, a circular
    fillet of radius ``f`` about ``(a + f, z_fillet)`` tangent to both the
    cylinder and the body sphere (radius ``R``), then the body sphere.
    """
    body, f, a = _CREATURE_BODY, _CREATURE_FILLET, float(radius)
    d = np.asarray(direction, dtype=np.float64)
    d = d / np.linalg.norm(d)
    n = np.asarray(towards, dtype=np.float64)
    n = n - (n @ d) * d
    n = n / np.linalg.norm(n)
    z_fillet = np.sqrt((body + f) ** 2 - (a + f) ** 2)
    cap_angle = np.arctan2(a + f, z_fillet)
    turn = np.pi / 2.0 - cap_angle
    z_cap = body + length - a
    cylinder = z_cap - z_fillet
    w_base = np.log(np.tan(cap_angle / 2.0))
    w_cylinder = w_base - _fillet_w(turn, a, f)
    w_tip = w_cylinder - cylinder / a
    area = 2 * np.pi * (a * a + a * cylinder + f * ((a + f) * turn - f * np.sin(turn)))
    table = tuple(
        (z_fillet + start * cylinder, (end - start) * cylinder, float(psi))
        for start, end, psi in hinges
    )
    return _Limb(np.stack([d, n, np.cross(d, n)]), a, f, z_fillet, z_cap, cap_angle, turn,
                 w_tip, w_cylinder, w_base, table, area)


def _fillet_w(gamma, a: float, f: float):
    """Conformal coordinate gained along the fillet up to its turning angle ``gamma``.

    The integral of ``d sigma / rho`` with ``rho = a + f - f cos(gamma)``,
    ``d sigma = f d gamma``.
    """
    s = np.sqrt(a * a + 2.0 * a * f)
    k = np.sqrt((a + 2.0 * f) / a)
    return 2.0 * f / s * np.arctan(k * np.tan(np.asarray(gamma) / 2.0))


_CREATURE = tuple(_creature_limb(*limb) for limb in _CREATURE_LIMBS)


def _limb_coordinates(u: np.ndarray, limb: _Limb):
    """Angle ``theta`` to the limb axis, conformal coordinate ``w`` and azimuth ``phi``."""
    d, n, b = limb.frame
    theta = np.arctan2(np.linalg.norm(np.cross(u, d), axis=1), u @ d)
    w = np.log(np.tan(np.maximum(theta, 1e-300) / 2.0))
    return theta, w, np.arctan2(u @ b, u @ n)


def _creature_labels(u: np.ndarray) -> np.ndarray:
    """Limb index of each chart point (-1 for the body)."""
    labels = np.full(len(u), -1, dtype=np.int64)
    for index, limb in enumerate(_CREATURE):
        theta, _, _ = _limb_coordinates(u, limb)
        labels[theta < limb.cap_angle] = index
    return labels


def _limb_profile(w: np.ndarray, limb: _Limb):
    """Meridian point ``(rho, z)`` of the limb at conformal coordinate ``w`` (<= w_base)."""
    a, f = limb.radius, limb.fillet
    rho, z = np.empty_like(w), np.empty_like(w)
    tip = w <= limb.w_tip
    beta = 2.0 * np.arctan(np.exp(w[tip] - limb.w_tip))  # angle from the tip
    rho[tip] = a * np.sin(beta)
    z[tip] = limb.z_cap + a * np.cos(beta)
    cylinder = (w > limb.w_tip) & (w <= limb.w_cylinder)
    rho[cylinder] = a
    z[cylinder] = limb.z_cap - a * (w[cylinder] - limb.w_tip)
    fillet = w > limb.w_cylinder
    s = np.sqrt(a * a + 2.0 * a * f)
    k = np.sqrt((a + 2.0 * f) / a)
    gamma = 2.0 * np.arctan(np.tan((w[fillet] - limb.w_cylinder) * s / (2.0 * f)) / k)
    rho[fillet] = a + f - f * np.cos(gamma)
    z[fillet] = limb.z_fillet - f * np.sin(gamma)
    return rho, z


def _limb_sigma(limb: _Limb, count: int = 4001):
    """Meridian arc length ``sigma`` from the tip, with ``w`` and ``rho``, on a fine grid."""
    a, f = limb.radius, limb.fillet
    s1 = np.pi * a / 2.0
    s2 = s1 + (limb.z_cap - limb.z_fillet)
    sigma = np.linspace(0.0, s2 + f * limb.turn, count)
    sigma[0] = 1e-9 * a
    w = np.empty_like(sigma)
    tip, cylinder, fillet = sigma <= s1, (sigma > s1) & (sigma <= s2), sigma > s2
    w[tip] = limb.w_tip + np.log(np.tan(sigma[tip] / (2.0 * a)))
    w[cylinder] = limb.w_tip + (sigma[cylinder] - s1) / a
    w[fillet] = limb.w_cylinder + _fillet_w((sigma[fillet] - s2) / f, a, f)
    rho, _ = _limb_profile(w, limb)
    return sigma, w, rho


def _creature_rest(u: np.ndarray) -> np.ndarray:
    """Rest-pose surface points of unit chart directions ``u``.

    The body is the sphere of radius ``R`` (``x = R u``). In a limb's cap the
    map keeps the azimuth about the limb axis and sends the conformal
    coordinate ``w = log tan(theta / 2)`` to the meridian point with the same
    ``w = integral d sigma / rho``, so the chart is conformal everywhere
    (and continuous, with scale ``R``, across the caps' rims).
    """
    x = _CREATURE_BODY * u
    labels = _creature_labels(u)
    for index, limb in enumerate(_CREATURE):
        mask = labels == index
        if not mask.any():
            continue
        d = limb.frame[0]
        theta, w, _ = _limb_coordinates(u[mask], limb)
        rho, z = _limb_profile(w, limb)
        radial = u[mask] - np.outer(u[mask] @ d, d)
        radial /= np.maximum(np.linalg.norm(radial, axis=1), 1e-300)[:, None]
        x[mask] = np.outer(z, d) + rho[:, None] * radial
    return x


def _creature_area() -> tuple[float, np.ndarray]:
    """Surface areas of the body (outside the limbs' caps) and of each limb."""
    body = 4 * np.pi * _CREATURE_BODY**2 - sum(
        2 * np.pi * _CREATURE_BODY**2 * (1 - np.cos(limb.cap_angle)) for limb in _CREATURE
    )
    return body, np.array([limb.area for limb in _CREATURE])


def _r2_sequence(count: int, offset: int = 0) -> np.ndarray:
    """A low-discrepancy sequence in the unit square (Roberts' R2 sequence)."""
    g = 1.32471795724474602596  # plastic number
    k = np.arange(offset + 1, offset + count + 1)[:, None]
    return np.mod(0.5 + k * np.array([1.0 / g, 1.0 / g**2]), 1.0)


def _creature_sample(n: int, random_state: int | None) -> np.ndarray:
    """Chart directions whose images are spread uniformly over the rest surface."""
    rng = None if random_state is None else np.random.default_rng(random_state)

    def unit_square(count, offset):
        if rng is None:
            return _r2_sequence(count, offset)
        return rng.uniform(0.0, 1.0, size=(count, 2))

    body_area, limb_areas = _creature_area()
    total = body_area + limb_areas.sum()
    limb_counts = np.round(n * limb_areas / total).astype(int)
    body_count = n - limb_counts.sum()
    # body: area-uniform points of the sphere outside the caps
    points, offset = [], 0
    kept = np.zeros((0, 3))
    while len(kept) < body_count:
        z, phi = unit_square(2 * body_count, offset).T
        offset += 2 * body_count
        z = 2.0 * z - 1.0
        r = np.sqrt(1.0 - z * z)
        u = np.column_stack([r * np.cos(2 * np.pi * phi), r * np.sin(2 * np.pi * phi), z])
        kept = np.concatenate([kept, u[_creature_labels(u) == -1]])
    points.append(kept[:body_count])
    # limbs: meridian arc length with density proportional to rho, uniform azimuth
    for number, (limb, count) in enumerate(zip(_CREATURE, limb_counts)):
        sigma, w, rho = _limb_sigma(limb)
        cdf = np.concatenate([[0.0], np.cumsum(0.5 * (rho[1:] + rho[:-1]) * np.diff(sigma))])
        p, phi = unit_square(count, 7919 * (number + 1)).T
        theta = 2.0 * np.arctan(np.exp(np.interp(p * cdf[-1], cdf, w)))
        phi = 2 * np.pi * phi
        d, nn, b = limb.frame
        points.append(np.outer(np.cos(theta), d) + np.sin(theta)[:, None]
                      * (np.outer(np.cos(phi), nn) + np.outer(np.sin(phi), b)))
    u = np.concatenate(points)
    return u / np.linalg.norm(u, axis=1, keepdims=True)


def _oriented_hull(points: np.ndarray) -> np.ndarray:
    """Convex hull facets of points on a unit sphere, counter-clockwise seen from outside.

    Each facet is oriented along the hull's outward normal, which also
    orients the facets of a hull of points covering only part of the sphere.
    """
    from scipy.spatial import ConvexHull

    hull = ConvexHull(points)
    faces = hull.simplices.astype(np.int64)
    a, b, c = (points[faces[:, k]] for k in range(3))
    flip = np.einsum("ij,ij->i", np.cross(b - a, c - a), hull.equations[:, :3]) < 0
    faces[flip] = faces[flip][:, ::-1]
    return faces


def _sphere_delaunay(u: np.ndarray) -> np.ndarray:
    """Spherical Delaunay triangulation of the chart directions, band by band.

    A limb's chart shrinks exponentially towards its tip (the conformal
    coordinate ``w`` grows by ``length / radius`` along it), so one convex
    hull would lose the tip's points to rounding. Spherical Delaunay
    triangulations are invariant under Moebius maps, so each band of width
    ``_CREATURE_BAND`` in ``w`` is triangulated after the Moebius map
    ``tan(theta / 2) -> tan(theta / 2) exp(-w_centre)`` about the limb axis,
    which spreads the band over the sphere; a triangle is taken from the
    band (or from the plain hull, band 0) that holds the mean ``w`` of its
    deepest vertex's limb. Triangles are counter-clockwise seen from outside.
    """
    labels = _creature_labels(u)
    coordinates = [_limb_coordinates(u, limb) for limb in _CREATURE]
    depth = np.full(len(u), np.inf)  # w in the vertex's own limb, inf on the body
    for index, (_, w, _) in enumerate(coordinates):
        depth[labels == index] = w[labels == index]

    def owners(faces):
        deepest = labels[faces[np.arange(len(faces)), np.argmin(depth[faces], axis=1)]]
        band = np.zeros(len(faces), dtype=np.int64)
        for index, (_, w, _) in enumerate(coordinates):
            mask = deepest == index
            band[mask] = np.minimum(0, np.round(w[faces[mask]].mean(axis=1) / _CREATURE_BAND))
        deepest[band == 0] = -1
        return deepest, band

    faces = _oriented_hull(u)
    limb_of, band = owners(faces)
    kept = [faces[band == 0]]
    for index, (_, w, phi) in enumerate(coordinates):
        inside = labels == index
        if not inside.any():
            continue
        lowest = int(np.round(depth[inside].min() / _CREATURE_BAND))
        for number in range(-1, lowest - 1, -1):
            centre = number * _CREATURE_BAND
            select = np.flatnonzero(inside & (np.abs(depth - centre) < _CREATURE_BAND + 1.5))
            if len(select) < 4:
                continue
            zoomed = 2.0 * np.arctan(np.exp(w[select] - centre))
            points = np.column_stack([
                np.sin(zoomed) * np.cos(phi[select]),
                np.sin(zoomed) * np.sin(phi[select]),
                np.cos(zoomed),
            ])
            faces = select[_oriented_hull(points)]
            limb_of, band = owners(faces)
            kept.append(faces[(limb_of == index) & (band == number)])
    return np.concatenate(kept)


def _creature_relax(u: np.ndarray, steps: int, every: int) -> np.ndarray:
    """Spread the chart points evenly over the rest surface (area-weighted smoothing).

    Each step moves every point to the mean chart centroid of its triangles,
    weighted by their areas on the rest surface: a discrete Lloyd iteration
    that evens out the triangles' sizes and shapes on the surface. The
    triangulation is redone every ``every`` steps.
    """
    n = len(u)
    for step in range(steps):
        if step % every == 0:
            faces = _sphere_delaunay(u)
        x = _creature_rest(u)
        area = np.linalg.norm(np.cross(x[faces[:, 1]] - x[faces[:, 0]],
                                       x[faces[:, 2]] - x[faces[:, 0]]), axis=1)
        centroid = u[faces].mean(axis=1)
        weight = np.bincount(faces.ravel(), np.repeat(area, 3), minlength=n)
        shift = np.zeros_like(u)
        for corner in range(3):
            offset = area[:, None] * (centroid - u[faces[:, corner]])
            for axis in range(3):
                shift[:, axis] += np.bincount(faces[:, corner], offset[:, axis], minlength=n)
        u = u + shift / weight[:, None]
        u /= np.linalg.norm(u, axis=1, keepdims=True)
    return u


def _creature_params(u: np.ndarray) -> np.ndarray:
    """Chart directions as ``(polar angle, azimuth)`` about the z axis."""
    polar = np.arctan2(np.hypot(u[:, 0], u[:, 1]), u[:, 2])
    return np.column_stack([polar, np.mod(np.arctan2(u[:, 1], u[:, 0]), 2.0 * np.pi)])


def _creature_directions(params: np.ndarray) -> np.ndarray:
    """Inverse of :func:`_creature_params`: unit chart directions."""
    polar, azimuth = params[:, 0], params[:, 1]
    return np.column_stack([
        np.sin(polar) * np.cos(azimuth), np.sin(polar) * np.sin(azimuth), np.cos(polar)
    ])


@lru_cache(maxsize=16)
def _creature_mesh(resolution: int, random_state: int | None):
    """Chart ``params``, faces and rest vertices of one creature tessellation (cached)."""
    n = 500 * 2 ** (resolution - 1)
    u = _creature_relax(_creature_sample(n, random_state), *_CREATURE_RELAX_STEPS)
    params = _creature_params(u)
    u = _creature_directions(params)  # exactly what ground_truth will see
    faces = _sphere_delaunay(u)
    rest = _creature_rest(u)
    for array in (params, faces, rest):
        array.flags.writeable = False
    return params, faces, rest


def _creature_pose(rest: np.ndarray, labels: np.ndarray, angles) -> np.ndarray:
    """Bend every limb at its hinges; body and fillets stay put.

    Each limb is carried by its axis, bent into circular arcs at the hinges
    (see :func:`_centre_line`): a point at height ``z`` along the rest axis
    and offset ``(p_n, p_b)`` from it goes to ``C(z) + p_n N(z) + p_b B(z)``
    (beyond the last piece, along the end tangent). The parts between the
    hinges move rigidly; the cylinder within a hinge stretches on the outside
    of the bend and shrinks on the inside by the factor ``1 - kappa rho cos``.
    """
    vertices = np.array(rest, dtype=np.float64)
    for index, (limb, phis) in enumerate(zip(_CREATURE, angles)):
        mask = labels == index
        if not mask.any() or not any(phis):
            continue
        local = rest[mask] @ limb.frame.T  # (z, p_n, p_b)
        pieces, s = [], 0.0
        for (start, span, psi), phi in zip(limb.hinges, phis):
            pieces += [(start - s, 0.0, 0.0), (span, float(phi), psi)]
            s = start + span
        end = limb.z_cap + 2.0 * limb.radius
        pieces.append((end - s, 0.0, 0.0))
        z = np.clip(local[:, 0], 0.0, end)
        point, tangent, normal, binormal = _centre_line(z, pieces)
        moved = (point + (local[:, 0] - z)[:, None] * tangent
                 + local[:, 1:2] * normal + local[:, 2:3] * binormal)
        vertices[mask] = moved @ limb.frame
    return vertices


def creature(*, resolution: int = 1, pose: str | float = "rest",
             random_state: int | None = 0) -> SyntheticShape:
    """A compact, asymmetric, articulated "starfish" with a well-separated spectrum.

    A body sphere of radius 0.7 with five limbs: capsules of radii 0.20,
    0.26, 0.18, 0.30, 0.22 reaching 3.0, 2.0, 1.4, 1.0, 0.7 beyond the body,
    pointing in five directions with no plane of symmetry, each joined to the
    body by a fillet of radius 0.25. The surface is closed, genus 0 and
    C1-smooth; no two limbs touch in any pose. Its intrinsic shape is
    star-like with arms of clearly different lengths, so the top eigenvalues
    of the geodesic Gaussian affinity of :mod:`meshcorr.spectral.embedding` are well
    apart (about 465, 19.1, 10.4, 5.5, 1.41, 0.42 at resolution 1) and every
    eigenvector's sign matters: unlike :func:`figure`, a thin tube whose
    eigenvalues 3-5 nearly coincide, it suits tests of the spectral pipeline.

    Each limb bends at a hinge near its base (the longest one also midway):
    its axis turns along a circular arc and carries the cross-sections with
    it, so the parts between hinges move rigidly and a pose is a
    near-isometric bend with the same vertices and faces (most edges keep
    their length exactly; mean change 2.4 % for ``"bent"``, 3.7 % for
    ``"curled"``).

    The mesh is made in the chart: a conformal map from the unit sphere to
    the rest pose (the identity, scaled, on the body; along each limb a
    Mercator-like map that keeps the azimuth about the limb axis). Points are
    spread evenly over the surface (area-proportional sampling and a few
    area-weighted Lloyd steps) and triangulated by their spherical Delaunay
    triangulation, so triangles are near-equilateral on the surface (smallest
    angle above 15 degrees).

    Parameters
    ----------
    resolution : int, default 1
        Level of detail, 1 to 6: exactly ``500 * 2**(resolution - 1)``
        vertices (500, 1,000, 2,000, 4,000, 8,000, 16,000), mean edge length
        about 0.2 at resolution 1, shrinking by ``sqrt(2)`` per level.
    pose : {"rest", "bent", "curled"} or float, default "rest"
        ``"rest"`` has straight limbs; ``"bent"`` turns the hinges by 0.45 to
        0.7 radians, ``"curled"`` by 0.6 to 1.1. A float ``p`` in ``[-1, 1]``
        gives ``p`` times the ``"bent"`` angles (``0.0`` is ``"rest"``,
        ``1.0`` is ``"bent"``; negative values bend the other way).
    random_state : int or None, default 0
        Seed of the random initial points; ``None`` starts from a
        low-discrepancy (R2) sequence instead. Either way the result is
        deterministic; geometry and poses do not depend on it.

    Returns
    -------
    shape : SyntheticShape
        With ``chart="creature"``: ``params`` are the ``(polar angle,
        azimuth)`` about the z axis of each vertex's chart direction ``u``.
        Shapes with equal ``resolution`` and ``random_state`` share faces and
        ``params`` in every pose (ground truth = identity); other
        tessellations share the chart, and :func:`ground_truth` matches them
        by nearest neighbours on the rest pose.

    Examples
    --------
    >>> rest = creature(resolution=1)
    >>> bent = creature(resolution=2, pose="bent", random_state=1)
    >>> truth = ground_truth(rest, bent)  # (500,) indices into bent's 1,000 vertices
    """
    func = "creature"
    resolution = _check_int(resolution, "resolution", func, 1, _CREATURE_MAX_RESOLUTION)
    choices = f"one of {sorted(_CREATURE_POSES)} or a float in [-1, 1]"
    if isinstance(pose, str):
        if pose not in _CREATURE_POSES:
            raise ParameterError(
                f"The 'pose' parameter of creature must be {choices}. Got {pose!r} instead."
            )
        angles, pose_name = _CREATURE_POSES[pose], pose
    elif isinstance(pose, Real) and not isinstance(pose, bool) and np.isfinite(pose) \
            and abs(pose) <= 1.0:
        angles = tuple(tuple(float(pose) * a for a in limb) for limb in _CREATURE_POSES["bent"])
        pose_name = f"pose{float(pose):.3g}"
    else:
        raise ParameterError(
            f"The 'pose' parameter of creature must be {choices}. Got {pose!r} instead."
        )
    random_state = _check_random_state(random_state, func)
    params, faces, rest = _creature_mesh(resolution, random_state)
    labels = _creature_labels(_creature_directions(params))
    vertices = _creature_pose(rest, labels, angles)
    return SyntheticShape(vertices, faces, params, f"creature-r{resolution}-{pose_name}",
                          chart="creature")


# --------------------------------------------------------------------------
# sphere
# --------------------------------------------------------------------------


def sphere(*, subdivisions: int = 4, radius: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """An icosphere, for checking geodesic distances against great circles.

    Parameters
    ----------
    subdivisions : int, default 4
        Loop subdivisions of an icosahedron, 0 to 7: ``10 * 4**k + 2``
        vertices (642 at 3, 2562 at 4, 10242 at 5).
    radius : float, default 1.0
        Radius (> 0); every vertex lies on the sphere.

    Returns
    -------
    vertices : (n, 3) float64
    faces : (m, 3) int64
        Oriented outwards. The geodesic distance between vertices ``i`` and
        ``j`` is ``radius * arccos(<v_i, v_j> / radius**2)``.
    """
    import trimesh

    subdivisions = _check_int(subdivisions, "subdivisions", "sphere", 0, 7)
    radius = _check_positive(radius, "radius", "sphere")
    mesh = trimesh.creation.icosphere(subdivisions=subdivisions, radius=radius)
    vertices = np.asarray(mesh.vertices, dtype=np.float64)
    # project exactly onto the sphere
    vertices = radius * vertices / np.linalg.norm(vertices, axis=1, keepdims=True)
    return vertices, np.asarray(mesh.faces, dtype=np.int64)


# --------------------------------------------------------------------------
# correspondences
# --------------------------------------------------------------------------


def ground_truth(source: SyntheticShape, target: SyntheticShape) -> np.ndarray:
    """The true map from the vertices of one shape to those of another.

    Both shapes must come from one family (one chart), in any poses and at
    any resolutions. Each source vertex is sent to the target vertex nearest
    to it on the family's *reference surface*, a fixed embedding of the
    chart, with a k-d tree:

    - ``chart="capsule"`` (:func:`tube`, :func:`figure`): chart coordinates
      ``(t, theta)`` are embedded as points of the straight, unbumped capsule
      (``(x(t), rho(t) cos theta, rho(t) sin theta)`` with ``rho`` the
      capsule's ring radius, 0 at the poles). This handles the periodic
      ``theta`` and the poles, and weighs ``t`` and ``theta`` by the lengths
      they span on the surface.
    - ``chart="creature"`` (:func:`creature`): the chart directions are
      mapped onto the creature's rest pose, where the limbs keep well apart,
      so nearness in space is nearness on the surface.

    Shapes made at one resolution and seed give the identity exactly.

    Parameters
    ----------
    source : SyntheticShape
        Shape with ``n_source`` vertices.
    target : SyntheticShape
        Shape with ``n_target`` vertices.

    Returns
    -------
    truth : (n_source,) int64
        ``truth[i]`` is the target vertex corresponding to source vertex ``i``
        (the ``p2p`` direction is source -> target).

    Raises
    ------
    ParameterError
        If either argument is not a SyntheticShape or the two shapes do not
        share a chart (different generators, or capsules whose poles differ,
        e.g. tubes of different lengths).
    """
    source = _check_shape(source, "source", "ground_truth")
    target = _check_shape(target, "target", "ground_truth")
    if source.chart != target.chart:
        raise ParameterError(
            f"ground_truth needs two shapes of one family, with one chart. {source.name!r} "
            f"has a {source.chart!r} chart and {target.name!r} a {target.chart!r} chart."
        )
    if source.chart == "capsule":
        limits = []
        for shape in (source, target):
            t = shape.params[:, 0]
            limits.append((t.min(), t.max()))
        (a0, a1), (b0, b1) = limits
        scale = max(abs(a1 - a0), abs(b1 - b0))
        if not (a0 < 0 and np.isclose(a0, b0, rtol=0, atol=1e-9 * scale)
                and np.isclose(a1, b1, rtol=0, atol=1e-9 * scale)):
            raise ParameterError(
                f"ground_truth needs two shapes of one family, with one chart. The chart of "
                f"{source.name!r} spans t in [{a0:.6g}, {a1:.6g}] and that of {target.name!r} "
                f"[{b0:.6g}, {b1:.6g}]."
            )
    if source.params.shape == target.params.shape and np.array_equal(source.params, target.params):
        return np.arange(source.n_vertices, dtype=np.int64)
    if source.chart == "capsule":
        tree = cKDTree(_chart_embedding(target.params, b0, b1))
        _, nearest = tree.query(_chart_embedding(source.params, a0, a1))
    else:
        tree = cKDTree(_creature_rest(_creature_directions(target.params)))
        _, nearest = tree.query(_creature_rest(_creature_directions(source.params)))
    return np.asarray(nearest, dtype=np.int64)


def _random_rotation(rng: np.random.Generator) -> np.ndarray:
    """A rotation matrix drawn uniformly from SO(3) (QR of a Gaussian matrix)."""
    q, r = np.linalg.qr(rng.standard_normal((3, 3)))
    q = q * np.sign(np.diag(r))
    if np.linalg.det(q) < 0:
        q[:, 0] = -q[:, 0]
    return q


def rigid_copy(shape: SyntheticShape, *, rotation=None, translation=None, scale: float = 1.0,
               permute: bool = True, random_state: int | None = 0
               ) -> tuple[SyntheticShape, np.ndarray]:
    """A rotated, translated, uniformly scaled and re-indexed copy of a shape.

    The copy's vertex ``truth[i]`` sits at ``scale * rotation @ v_i +
    translation`` where ``v_i`` is vertex ``i`` of ``shape``.

    Parameters
    ----------
    shape : SyntheticShape
        The original, with ``n`` vertices.
    rotation : (3, 3) float, optional
        A proper rotation matrix (orthonormal, determinant +1). ``None`` draws
        one uniformly from the seed.
    translation : (3,) float, optional
        ``None`` draws one from the seed (standard normal per coordinate).
    scale : float, default 1.0
        Uniform scale factor (> 0, so that orientation is kept).
    permute : bool, default True
        Re-index the vertices by a random permutation (faces and ``params``
        follow); ``False`` keeps the order, so ``truth`` is the identity.
    random_state : int or None, default 0
        Seed of the rotation, translation and permutation drawn here;
        ``None`` draws fresh entropy.

    Returns
    -------
    copy : SyntheticShape
        The transformed shape; same chart as ``shape``, so
        ``ground_truth(shape, copy)`` equals ``truth``.
    truth : (n,) int64
        ``truth[i]`` is the index in ``copy`` of original vertex ``i``:
        ``copy.vertices[truth] == scale * shape.vertices @ rotation.T +
        translation`` and ``copy.faces == truth[shape.faces]``.
    """
    func = "rigid_copy"
    shape = _check_shape(shape, "shape", func)
    if random_state is not None:
        random_state = _check_random_state(random_state, func)
    rng = np.random.default_rng(random_state)
    if rotation is None:
        rotation = _random_rotation(rng)
    else:
        rotation = np.asarray(rotation, dtype=np.float64)
        if (rotation.shape != (3, 3) or not np.all(np.isfinite(rotation))
                or not np.allclose(rotation @ rotation.T, np.eye(3), atol=1e-8)
                or np.linalg.det(rotation) < 0):
            raise ParameterError(
                "The 'rotation' parameter of rigid_copy must be a (3, 3) rotation matrix "
                "(orthonormal, determinant +1) or None. Got "
                f"{np.array2string(rotation, precision=3)} instead."
            )
    if translation is None:
        translation = rng.standard_normal(3)
    else:
        translation = np.asarray(translation, dtype=np.float64)
        if translation.shape != (3,) or not np.all(np.isfinite(translation)):
            raise ParameterError(
                "The 'translation' parameter of rigid_copy must be a finite (3,) vector or "
                f"None. Got {np.array2string(translation, precision=3)} instead."
            )
    scale = _check_positive(scale, "scale", func)
    if not isinstance(permute, (bool, np.bool_)):
        raise ParameterError(
            f"The 'permute' parameter of rigid_copy must be a bool. Got {permute!r} instead."
        )

    n = shape.n_vertices
    order = rng.permutation(n) if permute else np.arange(n)  # copy vertex j = original order[j]
    truth = np.empty(n, dtype=np.int64)
    truth[order] = np.arange(n)
    moved = scale * shape.vertices @ rotation.T + translation
    copy = SyntheticShape(
        vertices=moved[order],
        faces=truth[shape.faces],
        params=shape.params[order],
        name=f"{shape.name}-rigid",
        chart=shape.chart,
    )
    return copy, truth


# --------------------------------------------------------------------------
# bundled example
# --------------------------------------------------------------------------


def save_example_pair(directory) -> tuple[Path, Path, Path]:
    """Write the bundled example pair: two poses of :func:`creature` and their ground truth.

    The source is ``creature(resolution=1, pose="rest")`` (500 vertices), the
    target ``creature(resolution=2, pose="bent", random_state=1)`` (1,000
    vertices): different poses, tessellations and vertex counts. The default
    ``meshcorr match`` maps it with a mean geodesic error of about 2 % of
    the square root of the target's area.

    Parameters
    ----------
    directory : str or path-like
        Created if missing; existing files of the same names are overwritten.

    Returns
    -------
    source_path, target_path, truth_path : Path
        ``creature_rest.off``, ``creature_bent.off`` (vertex order kept, 10
        significant digits) and ``creature_rest_to_bent.gt.txt`` (one 0-based
        target vertex index per line, line ``i`` for source vertex ``i``).
    """
    import trimesh

    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    source = creature(resolution=1, pose="rest", random_state=0)
    target = creature(resolution=2, pose="bent", random_state=1)
    truth = ground_truth(source, target)
    paths = (
        directory / "creature_rest.off",
        directory / "creature_bent.off",
        directory / "creature_rest_to_bent.gt.txt",
    )
    for shape, path in zip((source, target), paths[:2]):
        mesh = trimesh.Trimesh(shape.vertices, shape.faces, process=False)
        path.write_text(trimesh.exchange.off.export_off(mesh, digits=10))
    np.savetxt(paths[2], truth, fmt="%d")
    return paths
