"""Undeclared partiality (issue 31, item 8): the signs of a part on whole shapes, holes and plane cuts.

For every TOSCA 5k shape this measures the scale-free signs that
:func:`meshcorr.stages.part_checks.part_evidence` and
:func:`meshcorr.core.holes.fill_holes` look at:

- ``longest``: the longest boundary loop / sqrt(area) (``mesh_boundary(m).longest``);
- ``rho``: (area / diameter^2) of the case over that of another whole shape of its
  class (the next file of the class, cyclically), diameters the largest geodesic distance
  on the meshes as given (holes open);
- ``enclosed``: the largest share of the area a boundary loop encloses
  (:func:`meshcorr.core.boundary.enclosed_areas`);

on the shape as it is (``whole``: TOSCA has no holes, so this is the closed surface), with
8 holes of 0.5 % of the area (``holes8``), 4 holes of 1 % (``holes4``) and 3 holes of 2 %
(``holes3``) (:func:`meshcorr.evaluation.cuts.punch_holes`), and cut by planes to 60, 70, 80
and 90 % of its area (:func:`meshcorr.evaluation.cuts.cut_by_plane`) with six normals: both
ways along the shape's first principal axis (``across``: the plane crosses the long axis,
taking the head or the legs) and along its second and third axes (``along``: the plane
contains the long axis, taking one side, the front or the back).

For each case it reports whether the check of a pair (case against the other whole shape of
its class) warns before this fix (``old``: a loop of at least 0.5 x sqrt(area), the other's at
most half as long, *and* rho outside [1/1.15, 1.15]) and after it (``new``:
:func:`meshcorr.stages.part_checks.part_evidence` names the case), and whether the hole filling
would close a loop that looks like a cut (``hole_warns``:
:func:`meshcorr.core.holes.large_closed_loops`, which the match reports when the check does not). Constants are chosen on the shapes
with an even file number (``cat0``, ``cat2``, ...) and reported separately on the odd ones.

Usage::

    nice -n 10 python benchmarks/partiality_check.py [--shapes cat0 david1] [--csv out.csv]

Needs ``../shared/data/tosca5k`` beside the repository; exits 0 with a message when it is absent.
"""

from __future__ import annotations

import argparse
import csv
import re
import sys
from pathlib import Path

import numpy as np

DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "tosca5k"
KEEPS = (0.6, 0.7, 0.8, 0.9)
HOLES = {"holes8": (8, 0.005), "holes4": (4, 0.01), "holes3": (3, 0.02)}
FIELDS = ["shape", "half", "case", "direction", "keep", "kept_area", "longest", "enclosed", "rho", "old", "new", "hole_warns"]


def _number(name: str) -> int:
    return int(re.sub(r"\D", "", name) or 0)


def _diameter(mesh) -> float:
    from meshcorr.stages.part_checks import geodesic_diameter, geodesic_rows

    return geodesic_diameter(geodesic_rows(mesh), mesh.n_vertices)


def _directions(mesh) -> dict:
    """Six plane normals: +-the first principal axis (across), +-the second and third (along)."""
    centred = mesh.vertices - mesh.vertices.mean(axis=0)
    axes = np.linalg.svd(centred, full_matrices=False)[2]
    return {"across+": axes[0], "across-": -axes[0], "along2+": axes[1], "along2-": -axes[1],
            "along3+": axes[2], "along3-": -axes[2]}


def _row(shape: str, case: str, direction: str, keep: float, mesh, whole, other, other_diameter: float) -> dict:
    from meshcorr.core.boundary import enclosed_areas, mesh_boundary
    from meshcorr.core.holes import fill_holes, large_closed_loops
    from meshcorr.stages.part_checks import SUSPICIOUS_SHAPE, part_evidence

    diameter = _diameter(mesh)
    longest, other_longest = mesh_boundary(mesh).longest, mesh_boundary(other).longest
    rho = (mesh.area / diameter ** 2) / (other.area / other_diameter ** 2)
    # Before this fix: a loop of 0.5 x sqrt(area), the other's half as long, and rho outside the range.
    old = (longest >= 0.5 and other_longest <= 0.5 * longest) and not 1 / SUSPICIOUS_SHAPE <= rho <= SUSPICIOUS_SHAPE
    side, _ = part_evidence({"case": mesh, "other": other}, {"case": diameter, "other": other_diameter})
    return dict(shape=shape, half="even" if _number(shape) % 2 == 0 else "odd", case=case, direction=direction,
                keep=keep, kept_area=round(mesh.area / whole.area, 3), longest=round(longest, 3),
                enclosed=round(float(enclosed_areas(mesh).max(initial=0.0)), 4), rho=round(rho, 3), old=old,
                new=side == "case", hole_warns=len(large_closed_loops(fill_holes(mesh))[0]) > 0)


def measure(names: list[str]) -> list[dict]:
    """The rows of every case of every shape (module docstring)."""
    from meshcorr.core.mesh import as_mesh
    from meshcorr.evaluation.benchmark import shape_class
    from meshcorr.evaluation.cuts import cut_by_plane, punch_holes

    by_class: dict = {}
    for name in names:
        by_class.setdefault(shape_class(name), []).append(name)
    rows = []
    for name in names:
        members = by_class[shape_class(name)]
        other_name = members[(members.index(name) + 1) % len(members)]
        whole = as_mesh(str(DATA / f"{name}.off"), name=name)
        other = as_mesh(str(DATA / f"{other_name}.off"), name=other_name)
        other_diameter = _diameter(other)
        rows.append(_row(name, "whole", "", 1.0, whole, whole, other, other_diameter))
        for case, (count, share) in HOLES.items():
            holed, _ = punch_holes(whole, n_holes=count, hole_area=share, random_state=_number(name))
            rows.append(_row(name, case, "", 1.0, holed, whole, other, other_diameter))
        for direction, normal in _directions(whole).items():
            for keep in KEEPS:
                part, _ = cut_by_plane(whole, keep=keep, normal=normal)
                rows.append(_row(name, "cut", direction, keep, part, whole, other, other_diameter))
        print(f"{name}: done", file=sys.stderr, flush=True)
    return rows


def _share(rows: list[dict], key: str) -> str:
    return f"{sum(row[key] for row in rows)}/{len(rows)}" if rows else "-"


def report(rows: list[dict]) -> str:
    """Markdown tables: the largest loop of whole and holed shapes, and how many cuts each check catches."""
    lines = ["| half | case | n | longest loop: max | median | enclosed: max | old warns | new warns | "
             "hole filling warns |", "|---|---|---|---|---|---|---|---|---|"]
    for half in ("even", "odd"):
        for case in ("whole", *HOLES):
            sel = [row for row in rows if row["half"] == half and row["case"] == case]
            if sel:
                values = [row["longest"] for row in sel]
                lines.append(f"| {half} | {case} | {len(sel)} | {max(values):.3f} | {np.median(values):.3f} | "
                             f"{max(row['enclosed'] for row in sel):.4f} | {_share(sel, 'old')} | {_share(sel, 'new')} | {_share(sel, 'hole_warns')} |")
    lines += ["", "| half | cut | keep | n | longest loop: min | median | enclosed: min | median | "
              "rho in [1/1.15, 1.15] | old warns | new warns | hole filling warns |",
              "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for half in ("even", "odd"):
        for kind in ("across", "along"):
            for keep in KEEPS:
                sel = [row for row in rows if row["half"] == half and row["case"] == "cut"
                       and row["direction"].startswith(kind) and row["keep"] == keep]
                if sel:
                    values = [row["longest"] for row in sel]
                    enclosed = [row["enclosed"] for row in sel]
                    inside = sum(1 / 1.15 <= row["rho"] <= 1.15 for row in sel)
                    lines.append(f"| {half} | {kind} | {keep} | {len(sel)} | {min(values):.3f} | "
                                 f"{np.median(values):.3f} | {min(enclosed):.4f} | {np.median(enclosed):.4f} | {inside} | {_share(sel, 'old')} | "
                                 f"{_share(sel, 'new')} | {_share(sel, 'hole_warns')} |")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--shapes", nargs="*", help="file names without .off (default: every shape)")
    parser.add_argument("--csv", type=Path, help="also write every row to this CSV file")
    args = parser.parse_args(argv)
    if not DATA.is_dir():
        print(f"partiality_check: {DATA} is absent (TOSCA 5k); nothing to measure.")
        return 0
    names = args.shapes or sorted((path.stem for path in DATA.glob("*.off")),
                                  key=lambda name: (re.sub(r"\d", "", name), _number(name)))
    rows = measure(names)
    if args.csv:
        with open(args.csv, "w", newline="") as handle:
            writer = csv.DictWriter(handle, fieldnames=FIELDS)
            writer.writeheader()
            writer.writerows(rows)
    print(report(rows))
    return 0


if __name__ == "__main__":
    sys.exit(main())
