"""Checks of the partial mode: its options, the roles of part and whole, and undeclared partiality.

A part (one side of a scan, a shape cut by a plane) is matched into the
whole by :mod:`meshcorr.pipeline.partial`; these checks say before (and,
for the area, after) the work whether the declared roles can be right:
options that do not go with ``partial`` (:func:`check_partial_options`),
a cloud, a closed part or swapped roles (:func:`check_roles`), a part
larger than the whole (:func:`check_part_not_larger`), and, without
``partial``, a shape that looks like a part of the other
(:func:`partiality_suspicion`: the warning naming the mode to use).
"""

from __future__ import annotations

from typing import Callable

import numpy as np

from ..core.boundary import enclosed_areas, mesh_boundary
from ..core.holes import LARGE_HOLE, large_closed_loops, unfilled
from ..core.mesh import Mesh
from ..core.sampling import farthest_point_sampling
from ..errors import PartialityError

RowFn = Callable[[int], np.ndarray]

#: The values of ``match(..., partial=...)`` besides None: which side is the part.
PARTIAL_MODES = ("source", "target")
#: A declared part whose area, in the whole's units, exceeds the whole's by more than this is refused.
LARGER_TOLERANCE = 1.15
#: Undeclared partiality is suspected (:func:`partiality_suspicion`) when one shape has an open boundary loop
#: enclosing at least this share of its area (:func:`meshcorr.core.boundary.enclosed_areas`), the other's
#: loops at most :data:`SUSPICIOUS_RATIO` of it, and either the loop encloses at least
#: :data:`meshcorr.core.holes.LARGE_HOLE` of the area (a cut by itself) or the shapes' area / diameter^2
#: differ by more than the factor :data:`SUSPICIOUS_SHAPE`.
SUSPICIOUS_BOUNDARY = 0.015
SUSPICIOUS_RATIO = 0.5
SUSPICIOUS_SHAPE = 1.15

def check_partial_options(partial, method: str, changed: dict) -> None:
    """Refuse ``partial`` values and options that do not go together (raised by :func:`meshcorr.match`).

    Parameters
    ----------
    partial : None, "source" or "target"
    method : str
    changed : dict
        The options of the call that differ from their defaults.

    Raises
    ------
    PartialityError
        An unknown ``partial``, a ``method`` other than "spectral", ``bijective=True``, a ``symmetry``
        other than "auto", or ``extremities=False`` without landmarks.
    """
    if partial is None:
        return
    if partial not in PARTIAL_MODES:
        raise PartialityError(f"The 'partial' parameter must be None, 'source' (the source is a part of the "
                              f"target) or 'target' (the reverse). Got {partial!r} instead.")
    if method != "spectral":
        raise PartialityError(f"partial={partial!r} is a mode of the spectral method; the baseline {method!r} "
                              "has none. Use method='spectral' (the default).")
    if changed.get("bijective"):
        raise PartialityError("A map from a part of a shape into the whole cannot be one-to-one: remove "
                              "bijective=True (--bijective) or partial.")
    if "symmetry" in changed:
        raise PartialityError(f"partial={partial!r} chooses between a map and its mirror image by orientation "
                              f"(symmetry='auto'); symmetry={changed['symmetry']!r} is not available. The mirror "
                              "image is result.alternative_map (--alternative-out).")
    if changed.get("extremities") is False and changed.get("landmarks") is None:
        raise PartialityError("partial matching starts from matched extremities or from landmarks: keep "
                              "extremities=True (drop --no-extremities) or give landmarks=[(i, j), ...] "
                              "(--landmarks FILE).")


def partiality_suspicion(source: Mesh, target: Mesh, source_diameter: float, target_diameter: float) -> str:
    """Why one shape looks like a part of the other, or why a hole closed on it looks like a cut, or "".

    The warning of undeclared partiality. Scale is free, so areas cannot be
    compared directly. Two scale-free signs:

    - **an open boundary on one side**: a boundary loop of one shape encloses
      at least :data:`SUSPICIOUS_BOUNDARY` of its area
      (:func:`meshcorr.core.boundary.enclosed_areas`: the area of a flat cap
      of the loop, which unlike the loop's length does not grow when the
      loop zigzags along a coarse mesh's edges) and the other's loops at
      most :data:`SUSPICIOUS_RATIO` as much;
    - **area against diameter**: :math:`\\rho = (A_S / D_S^2) / (A_T / D_T^2)`,
      with :math:`D` the largest geodesic distance, is outside
      :math:`[1 / s, s]` with :math:`s` = :data:`SUSPICIOUS_SHAPE`: a cut
      takes area away faster than diameter, or takes away a limb and with
      it much of the diameter.

    The first must hold, and either the second or a loop enclosing at least
    :data:`meshcorr.core.holes.LARGE_HOLE` of the area (a cut along a body's
    long axis takes area but not diameter: :math:`\\rho` stayed 1.05 for a
    TOSCA shape cut to 70 % that way). Measured on TOSCA 5k
    (``benchmarks/partiality_check.py``, ``benchmarks/RESULTS-partial.md``):
    :math:`\\rho` is outside the range for 11 of 76 pairs of whole shapes
    of one class, which is why it is not enough alone; holes of 0.5-2 % of
    the area enclose at most 0.021 of it; plane cuts to 60-70 % warn in 92-100 %
    of the cases, to 90 % in a third to two thirds (the default mode often maps
    those well).

    When neither shape looks like a part but the hole filling
    (:func:`meshcorr.core.holes.fill_holes`) closed a loop enclosing at least
    :data:`meshcorr.core.holes.LARGE_HOLE` of a shape's area (both shapes cut,
    say), that is said instead: one warning per match.

    Parameters
    ----------
    source, target : Mesh
        As matched: with their holes closed or not (the signs are measured on the meshes as given,
        :func:`meshcorr.core.holes.unfilled`).
    source_diameter, target_diameter : float
        Largest geodesic distance on each (e.g. :attr:`meshcorr.spectral.spectrum.Spectrum.max_geodesic`).
    """
    side, evidence = part_evidence({"source": unfilled(source), "target": unfilled(target)},
                                   {"source": source_diameter, "target": target_diameter})
    if side is None:
        return _closed_cuts({"source": source, "target": target})
    other = "target" if side == "source" else "source"
    closed = len(large_closed_loops(source if side == "source" else target)[0]) > 0
    closed = ", and its cut was closed as a hole" if closed else ""
    return (f"{evidence}: the {side} looks like a part of the {other} (one side of a scan, a cut){closed}. A "
            f"whole-to-whole map of a part can be wrong everywhere; if it is a part, match with "
            f"partial={side!r} (meshcorr match --partial {side}).")


def _closed_cuts(meshes: dict) -> str:
    """The warning of holes closed that look like cuts (:func:`meshcorr.core.holes.large_closed_loops`), or ""."""
    found = {role: large_closed_loops(mesh) for role, mesh in meshes.items()}
    roles = [role for role, (lengths, _) in found.items() if len(lengths)]
    if not roles:
        return ""
    said = "; ".join(f"on the {role} ({meshes[role].name}), a loop {found[role][0][0]:.2f} x sqrt(its area) long "
                     f"enclosing {found[role][1][0]:.0%} of its area" for role in roles)
    modes = " or ".join(f"partial={role!r} (--partial {role})" for role in roles)
    return (f"Closed holes that look like cuts: {said} (holes of whole shapes enclose under {LARGE_HOLE:.0%}). "
            f"A part matched as a whole shape maps badly: if the {' or the '.join(roles)} is a part of the other "
            f"shape, match with {modes}; fill_holes=False (--no-fill-holes) leaves the holes open.")


def part_evidence(meshes: dict, diameters: dict) -> tuple[str | None, str]:
    """Which of two named shapes looks like a part of the other, and why (:func:`partiality_suspicion`).

    Parameters
    ----------
    meshes : dict
        Two shapes by role, e.g. ``{"source": Mesh, "target": Mesh}``, with their holes open.
    diameters : dict
        Their largest geodesic distances, by the same roles.

    Returns
    -------
    side : str or None
        The role of the shape that looks like a part; None if neither does.
    evidence : str
        The measures, as a sentence (empty when ``side`` is None).
    """
    (first, second) = list(meshes)
    enclosed = {role: float(enclosed_areas(mesh).max(initial=0.0)) for role, mesh in meshes.items()}
    side = max(enclosed, key=enclosed.get)
    other = second if side == first else first
    if enclosed[side] < SUSPICIOUS_BOUNDARY or enclosed[other] > SUSPICIOUS_RATIO * enclosed[side]:
        return None, ""
    shape = {role: mesh.area / max(diameters[role], 1e-300) ** 2 for role, mesh in meshes.items()}
    rho = shape[side] / shape[other]
    if enclosed[side] < LARGE_HOLE and 1.0 / SUSPICIOUS_SHAPE <= rho <= SUSPICIOUS_SHAPE:
        return None, ""
    boundary = mesh_boundary(meshes[side])
    loop = int(np.argmax(enclosed_areas(meshes[side])))
    return side, (f"The {side} has an open boundary loop enclosing {enclosed[side]:.0%} of its area "
                  f"({boundary.lengths[loop] / np.sqrt(boundary.area):.2f} x sqrt(its area) long), the {other} "
                  f"{'none' if enclosed[other] == 0 else f'at most {enclosed[other]:.1%}'}, and their area / "
                  f"diameter^2 differ by a factor {max(rho, 1 / rho):.2f}")


def geodesic_rows(mesh: Mesh, geodesic: str = "heat") -> RowFn:
    """``rows(i)``: geodesic distances from vertex i in the mesh's own units, ``(n,)``.

    Solved on demand (one single-source solve each) and kept on the mesh,
    per solver, so later matches of the same mesh reuse them.
    """
    from ..spectral.nystrom import sampled_rows

    key = ("geodesic_rows", geodesic)
    if key not in mesh.store:
        mesh.store.put(key, sampled_rows(mesh, geodesic, {}, 1.0))
    return mesh.store[key]


def geodesic_diameter(rows: RowFn, n_vertices: int, *, random_state: int | None = 0) -> float:
    """The largest geodesic distance, from a few farthest-point sweeps (a lower bound, tight in practice)."""
    return farthest_point_sampling(rows, n_vertices, min(4, n_vertices), random_state=random_state).diameter


def check_part_not_larger(part: Mesh, whole: Mesh, scale: float, *, role: str) -> None:
    """Refuse a declared part whose area, in the whole's units, exceeds the whole's.

    Raises
    ------
    PartialityError
        When :math:`s^2 \\operatorname{area}(P) >` :data:`LARGER_TOLERANCE`
        :math:`\\operatorname{area}(W)`, :math:`s` the scale fitted to the map's
        geodesic distances (:func:`meshcorr.stages.part_distortion.fitted_distortion`). A map from a larger
        shape into a smaller one squashes distances, so this catches only
        clear cases; :func:`check_roles` catches the others before the work.
    """
    ratio = scale ** 2 * part.area / whole.area
    if ratio > LARGER_TOLERANCE:
        other = "target" if role == "source" else "source"
        raise PartialityError(
            f"partial={role!r} declares the {role} a part of the {other}, but the {role} is larger: "
            f"{ratio:.2f} times the {other}'s area once both are at one scale (fitted to their geodesic "
            f"distances). If the {other} is the part, use partial={other!r}; if neither is, partial=None.")


def check_roles(part: Mesh, whole: Mesh, part_rows: RowFn, whole_rows: RowFn, *, role: str) -> None:
    """Refuse a point cloud, a declared part that is closed, or one that the declared whole looks like a part of.

    A cloud has no boundary to tell the cut by (partial clouds are not
    handled). A closed surface is no proper part of a connected one. And when the
    declared whole has the long open boundary and the area / diameter^2 of
    a part of the declared part (:func:`partiality_suspicion` with the roles
    swapped), the roles were given the wrong way round.

    Raises
    ------
    PartialityError
        Naming the mode to use instead.
    """
    other = "target" if role == "source" else "source"
    clouds = [mesh.name for mesh in (part, whole) if mesh.is_cloud]
    if clouds:
        which = "is a point cloud" if len(clouds) == 1 else "are point clouds"
        raise PartialityError(
            f"partial={role!r} needs triangle meshes: {', '.join(clouds)} {which}, whose boundary (the cut) "
            "cannot be told from its surface. Mesh the cloud first (e.g. screened Poisson reconstruction in "
            "MeshLab), or match whole shapes (partial=None).")
    if mesh_boundary(part).n_loops == 0:
        raise PartialityError(
            f"partial={role!r} declares the {role} ({part.name}) a part of the {other}, but it is a closed "
            f"surface, and a closed surface cannot be a part of another connected one. If the {other} is "
            f"the part, use partial={other!r}; if both are whole, partial=None.")
    side, evidence = part_evidence({role: part, other: whole},
                                   {role: geodesic_diameter(part_rows, part.n_vertices),
                                    other: geodesic_diameter(whole_rows, whole.n_vertices)})
    if side == other:
        raise PartialityError(
            f"partial={role!r} declares the {role} a part of the {other}, but the {other} looks like the part. "
            f"{evidence}. If the {other} is the part, use partial={other!r}; if both are whole, partial=None.")
