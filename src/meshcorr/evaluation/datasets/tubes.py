"""A capsule with asymmetric bumps, optionally bent into a circular arc (:func:`tube`)."""

from __future__ import annotations

from numbers import Real

import numpy as np

from ...errors import ParameterError
from .shape import SyntheticShape, int_parameter, positive_parameter, seed_parameter
from .capsule import cap_rings, capsule_chart, capsule_surface

__all__ = ["tube"]

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
    n_along = int_parameter(n_along, "n_along", func, 2)
    n_around = int_parameter(n_around, "n_around", func, 3)
    length = positive_parameter(length, "length", func)
    radius = positive_parameter(radius, "radius", func)
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
    random_state = seed_parameter(random_state, func)

    spacing = length / (n_along - 1)
    t_min, t_max = -np.pi * radius / 2.0, length + np.pi * radius / 2.0
    t0, c0 = cap_rings(radius, spacing, n_around, "start")
    t1, c1 = cap_rings(radius, spacing, n_around, "end")
    ring_t = np.concatenate([t0, np.linspace(0.0, length, n_along), length + t1])
    ring_counts = np.concatenate([c0, np.full(n_along, n_around), c1])
    params, faces = capsule_chart(ring_t, ring_counts, t_min, t_max, random_state)

    bump_table = np.zeros((0, 4))
    if bumps:
        bump_table = _TUBE_BUMPS * [length, 1.0, 1.0, radius]
    vertices = capsule_surface(
        params,
        length=length,
        radius=radius,
        pieces=[(length, float(bend), 0.0)],
        profile=np.ones_like,
        bumps=bump_table,
    )
    name = f"tube-{n_along}x{n_around}-bend{float(bend):.3g}"
    return SyntheticShape(vertices, faces, params, name)
