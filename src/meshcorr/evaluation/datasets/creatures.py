"""A compact "starfish": a round body with five limbs of different lengths, bending at hinges (:func:`creature`).

Each vertex comes from a unit vector ``u`` (``params = (polar angle, azimuth)``);
a fixed conformal map sends ``u`` to the rest pose and the poses bend the limbs
(:mod:`meshcorr.evaluation.datasets`, "The charts").
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from numbers import Real

import numpy as np

from ...errors import ParameterError
from .shape import SyntheticShape, int_parameter, seed_parameter
from .capsule import centre_line

__all__ = ["creature", "creature_directions", "creature_rest"]

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


def creature_rest(u: np.ndarray) -> np.ndarray:
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
        x = creature_rest(u)
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


def creature_directions(params: np.ndarray) -> np.ndarray:
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
    u = creature_directions(params)  # exactly what ground_truth will see
    faces = _sphere_delaunay(u)
    rest = creature_rest(u)
    for array in (params, faces, rest):
        array.flags.writeable = False
    return params, faces, rest


def _creature_pose(rest: np.ndarray, labels: np.ndarray, angles) -> np.ndarray:
    """Bend every limb at its hinges; body and fillets stay put.

    Each limb is carried by its axis, bent into circular arcs at the hinges
    (see :func:`centre_line`): a point at height ``z`` along the rest axis
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
        point, tangent, normal, binormal = centre_line(z, pieces)
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
    resolution = int_parameter(resolution, "resolution", func, 1, _CREATURE_MAX_RESOLUTION)
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
    random_state = seed_parameter(random_state, func)
    params, faces, rest = _creature_mesh(resolution, random_state)
    labels = _creature_labels(creature_directions(params))
    vertices = _creature_pose(rest, labels, angles)
    return SyntheticShape(vertices, faces, params, f"creature-r{resolution}-{pose_name}",
                          chart="creature")
