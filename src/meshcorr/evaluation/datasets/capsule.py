"""The capsule chart of :func:`~meshcorr.evaluation.datasets.tube` and :func:`~meshcorr.evaluation.datasets.figure`: centre line, surface and triangulation.

A vertex carries ``(t, theta)``: ``t`` the arc length along a meridian of the
reference capsule of radius ``r`` around a centre line of length ``L``
(``-pi r / 2`` to ``L + pi r / 2``), ``theta`` the angle around the centre line
in a parallel-transported frame (:mod:`meshcorr.evaluation.datasets`, "The charts").
"""

from __future__ import annotations

import numpy as np

from .shape import JITTER

__all__ = ["cap_rings", "capsule_chart", "capsule_surface", "centre_line", "chart_embedding"]

def chart_embedding(params: np.ndarray, t_min: float, t_max: float) -> np.ndarray:
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


def centre_line(s: np.ndarray, pieces: list[tuple[float, float, float]]):
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
        Chart embedding of the vertices (see :func:`chart_embedding`).
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
    centres = chart_embedding(bumps[:, :2], t_min, t_max)
    for centre, amplitude, width in zip(centres, bumps[:, 2], bumps[:, 3]):
        d2 = np.sum((points - centre) ** 2, axis=1)
        field += amplitude * np.exp(-d2 / (2.0 * width**2))
    return field


def capsule_surface(params, *, length, radius, pieces, profile, bumps) -> np.ndarray:
    """Positions of chart points on the posed, bumped surface.

    Parameters
    ----------
    params : (n, 2) float
        Chart coordinates.
    length, radius : float
        Centre-line length and reference radius of the chart.
    pieces : list of (length, turning angle, plane angle)
        The posed centre line (see :func:`centre_line`).
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
    point, tangent, normal, binormal = centre_line(s, pieces)
    alpha = (np.minimum(t, 0.0) + np.maximum(t - length, 0.0)) / radius
    direction = np.cos(alpha)[:, None] * (
        np.cos(theta)[:, None] * normal + np.sin(theta)[:, None] * binormal
    ) + np.sin(alpha)[:, None] * tangent
    reference = chart_embedding(params, t_min, t_max)
    r = radius * profile(t) * (1.0 + _bump_field(reference, bumps, t_min, t_max))
    return point + r[:, None] * direction


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


def capsule_chart(ring_t: np.ndarray, ring_counts: np.ndarray, t_min: float, t_max: float,
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
        Seed of the in-chart jitter (up to ``JITTER`` times the distance to
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
            t_ring = t_ring + JITTER * spacing * rng.uniform(-1.0, 1.0, count)
            theta = theta + JITTER * step * rng.uniform(-1.0, 1.0, count)
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


def cap_rings(radius: float, spacing: float, base_count, end: str):
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
