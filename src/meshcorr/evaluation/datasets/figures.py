"""A tube-shaped creature articulated at three hinges (:func:`figure`)."""

from __future__ import annotations

from numbers import Real

import numpy as np

from ...errors import ParameterError
from .shape import SyntheticShape, int_parameter, seed_parameter
from .capsule import cap_rings, capsule_chart, capsule_surface

__all__ = ["figure"]

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
    resolution = int_parameter(resolution, "resolution", func, 1)
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
    random_state = seed_parameter(random_state, func)

    length, radius = _FIGURE_LENGTH, _FIGURE_RADIUS
    n_around = 8 + 4 * resolution
    spacing_around = 2.0 * np.pi * radius / n_around
    spacing = spacing_around * np.sqrt(3.0) / 2.0
    t_min, t_max = -np.pi * radius / 2.0, length + np.pi * radius / 2.0
    # cylinder rings; their counts follow the radius profile
    n_along = max(2, int(round(length / spacing)) + 1)
    t_body = np.linspace(0.0, length, n_along)
    body_counts = np.maximum(3, np.round(n_around * _figure_profile(t_body))).astype(int)
    t0, c0 = cap_rings(radius, spacing, n_around * _figure_profile(0.0), "start")
    t1, c1 = cap_rings(radius, spacing, n_around * _figure_profile(length), "end")
    ring_t = np.concatenate([t0, t_body, length + t1])
    ring_counts = np.concatenate([c0, body_counts, c1])
    params, faces = capsule_chart(ring_t, ring_counts, t_min, t_max, random_state)
    vertices = capsule_surface(
        params,
        length=length,
        radius=radius,
        pieces=_figure_pieces(angles),
        profile=_figure_profile,
        bumps=_FIGURE_BUMPS,
    )
    return SyntheticShape(vertices, faces, params, f"figure-r{resolution}-{pose_name}")
