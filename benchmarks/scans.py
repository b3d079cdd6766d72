"""Scans as they come (issue 15): point clouds, partial shapes and holes, against the clean meshes.

For a fixed, class-stratified sample of TOSCA 5k pairs (``test_pairs.txt``)
and Sumner's cat and lion poses (reference -> pose, identity truth), each pair
is matched as:

- ``clean``: the two meshes;
- ``cloud``: both sides as point clouds of their vertices (no faces);
- ``cloud-noisy``: both sides as clouds resampled from the surface, as many
  points as vertices, with a density that varies 4x along a random direction
  and Gaussian noise of 1 % of the bounding-box diagonal;
- ``partial-plane``: the source cut by a random plane to 60-90 % of its area
  (:func:`meshcorr.evaluation.cuts.cut_by_plane`), against the whole target;
- ``partial-balls``: the source without 3 geodesic balls, 60-90 % of its area
  kept (:func:`meshcorr.evaluation.cuts.remove_balls`), against the whole target;
- ``holes``: both meshes with 5-10 holes of 0.5 % of the area each
  (:func:`meshcorr.evaluation.cuts.punch_holes`);
- ``noise``: both meshes with each vertex moved along its normal by Gaussian
  noise of 0.5 % of the bounding-box diagonal (about half an edge at 5000
  vertices), the connectivity kept;
- ``denser-target``: the target subdivided once (each triangle split in four
  at its edge midpoints, about 4x the vertices; the surface unchanged), the
  source as it is: another resolution, and the scalable mode on one side.

Every case is scored on the **original** target mesh, at the ground-truth
points that exist on the case's source: the mean geodesic error divided by
sqrt(target area), flips counted and forgiven (mirrored truth), as in
``benchmarks/robustness.py``. A cloud point stands for the mesh vertex nearest
to the surface point it was sampled from. Methods: ``meshcorr`` (default
settings, plus ``partial="source"`` on the partial cases), ``meshcorr-plain``
(default settings on the partial cases, i.e. without the partial mode) and
pyFM's automatic pipeline on the mesh cases of a few pairs (it takes no point
clouds). A case that meshcorr refuses (MeshcorrError) is recorded with its
message instead of an error.

Rows are appended to a CSV as they finish, so an interrupted run resumes.
Usage::

    nice -n 10 python benchmarks/scans.py [--quick] [--methods meshcorr meshcorr-plain pyfm] \\
        [--out benchmarks/cache/scans.csv] [--report benchmarks/cache/scans.md]

Needs ``../shared/data`` beside the repository; exits with a message when it
is absent.
"""

from __future__ import annotations

import argparse
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from scipy.spatial import cKDTree

import meshcorr
from meshcorr.evaluation import cuts as cuts
from meshcorr.errors import MeshcorrError
from meshcorr.evaluation.metrics import GeodesicCache
from meshcorr.core.mesh import Mesh, as_mesh
from robustness import (DATA, Pair, _spread, appending, markdown, previous_rows, publish, score_points, summarize,
                        tosca_pairs)

CASES = ("clean", "cloud", "cloud-noisy", "partial-plane", "partial-balls", "holes", "noise", "denser-target")
MESH_CASES = ("clean", "partial-plane", "partial-balls", "holes", "noise", "denser-target")
PARTIAL_CASES = ("partial-plane", "partial-balls")
FIELDS = ["set", "data", "source", "target", "method", "status", "mean_error", "forgiven_error", "flipped",
          "partial", "seconds", "n_points", "kept_area"]
N_SUMNER_POINTS = 1000


@dataclass
class Case:
    """One input pair derived from a benchmark pair, and how to score its map.

    ``source_points[i]`` is the source-input index of truth point ``keep[i]``
    of the pair; ``target_vertex[j]`` the original target vertex that
    target-input index ``j`` stands for.
    """

    name: str
    source: object
    target: object
    source_points: np.ndarray
    keep: np.ndarray
    target_vertex: np.ndarray
    options: dict = field(default_factory=dict)
    kept_area: float = 1.0


def sumner_pairs(root: Path, n_poses: int) -> list[Pair]:
    """Cat and lion reference -> pose 1..n, identity truth at a seeded sample of vertices."""
    pairs = []
    for animal in ("cat", "lion"):
        reference = root / f"{animal}-poses" / f"{animal}-reference.obj"
        n_vertices = as_mesh(reference).n_vertices
        points = np.sort(np.random.default_rng(0).choice(n_vertices, N_SUMNER_POINTS, replace=False))
        for pose in range(1, n_poses + 1):
            name = f"{animal}-{pose:02d}"
            pairs.append(Pair("sumner", f"{animal}-reference", name, reference,
                              root / f"{animal}-poses" / f"{name}.obj", points, points, None))
    return pairs


def noisy_cloud(mesh: Mesh, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """As many surface samples as vertices, density varying 4x, 1 % noise; and each sample's nearest vertex."""
    corners = mesh.vertices[mesh.faces]
    areas = 0.5 * np.linalg.norm(np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]), axis=1)
    direction = rng.normal(size=3)
    height = corners.mean(axis=1) @ (direction / np.linalg.norm(direction))
    height = (height - height.min()) / np.ptp(height)
    weights = areas * (0.25 + 0.75 * height)
    chosen = rng.choice(len(areas), mesh.n_vertices, p=weights / weights.sum())
    u, v = rng.random((2, mesh.n_vertices))
    flip = u + v > 1
    u[flip], v[flip] = 1 - u[flip], 1 - v[flip]
    tri = corners[chosen]
    clean = tri[:, 0] + u[:, None] * (tri[:, 1] - tri[:, 0]) + v[:, None] * (tri[:, 2] - tri[:, 0])
    diagonal = np.linalg.norm(np.ptp(mesh.vertices, axis=0))
    cloud = clean + rng.normal(scale=0.01 * diagonal, size=clean.shape)
    return cloud, cKDTree(mesh.vertices).query(clean)[1]


def noisy_mesh(mesh: Mesh, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """The mesh's vertices moved along their normals by Gaussian noise of 0.5 % of the diagonal; its faces."""
    import trimesh

    normals = trimesh.Trimesh(mesh.vertices, mesh.faces, process=False).vertex_normals
    diagonal = np.linalg.norm(np.ptp(mesh.vertices, axis=0))
    moved = mesh.vertices + normals * rng.normal(scale=0.005 * diagonal, size=(mesh.n_vertices, 1))
    return moved, np.array(mesh.faces)


def make_case(name: str, pair: Pair, source: Mesh, target: Mesh, seed: int) -> Case:
    """The input of case ``name`` for one pair, with a seed of its own."""
    rng = np.random.default_rng(seed)
    every = np.ones(len(pair.source_points), dtype=bool)
    identity = np.arange(target.n_vertices)
    if name == "clean":
        return Case(name, source, target, pair.source_points, every, identity)
    if name == "cloud":
        return Case(name, np.array(source.vertices), np.array(target.vertices), pair.source_points, every, identity)
    if name == "cloud-noisy":
        source_cloud, source_origin = noisy_cloud(source, rng)
        target_cloud, target_origin = noisy_cloud(target, rng)
        # The source cloud's point standing for truth vertex v: the sample whose nearest vertex is nearest v.
        nearest = cKDTree(source.vertices[source_origin]).query(source.vertices[pair.source_points])[1]
        return Case(name, source_cloud, target_cloud, nearest, every, target_origin)
    if name in PARTIAL_CASES:
        keep = float(rng.uniform(0.6, 0.9))
        if name == "partial-plane":
            part, kept = cuts.cut_by_plane(source, keep=keep, random_state=seed)
        else:
            part, kept = cuts.remove_balls(source, keep=keep, n_balls=3, random_state=seed)
        return _restricted(name, pair, part, kept, target, identity, part.area / source.area)
    if name == "holes":
        holed_source, source_kept = cuts.punch_holes(source, n_holes=int(rng.integers(5, 11)), hole_area=0.005,
                                                     random_state=seed)
        holed_target, target_kept = cuts.punch_holes(target, n_holes=int(rng.integers(5, 11)), hole_area=0.005,
                                                     random_state=seed + 1)
        return _restricted(name, pair, holed_source, source_kept, holed_target, target_kept,
                           holed_source.area / source.area)
    if name == "noise":
        return Case(name, noisy_mesh(source, rng), noisy_mesh(target, rng), pair.source_points, every, identity)
    if name == "denser-target":
        import trimesh

        vertices, faces = trimesh.remesh.subdivide(target.vertices, target.faces)  # originals first
        nearest = cKDTree(target.vertices).query(vertices)[1]  # a midpoint stands for its nearest vertex
        return Case(name, source, (vertices, faces), pair.source_points, every, nearest)
    raise ValueError(f"unknown case {name!r}")


def _restricted(name, pair, source_part, source_kept, target_input, target_vertex, kept_area) -> Case:
    """A case whose source keeps only the vertices ``source_kept`` of the original source."""
    position = np.full(int(source_kept.max()) + 1 if len(source_kept) else 0, -1)
    position[source_kept] = np.arange(len(source_kept))
    inside = pair.source_points < len(position)
    inside[inside] = position[pair.source_points[inside]] >= 0
    options = {"partial": "source"} if name in PARTIAL_CASES else {}
    return Case(name, source_part, target_input, position[pair.source_points[inside]], inside, target_vertex,
                options, kept_area)


def run_method(case: Case, method: str) -> tuple[np.ndarray | None, float, str]:
    """Map of the case's source inputs (as original target vertices), seconds, and a status."""
    start = time.perf_counter()
    try:
        if method == "pyfm":
            from tosca_symmetry import pyfm_map

            mapping = pyfm_map(case.source, case.target)
        else:
            options = case.options if method == "meshcorr" else {}
            mapping = meshcorr.match(case.source, case.target, **options).map
    except MeshcorrError as error:
        return None, time.perf_counter() - start, f"unsupported: {str(error).splitlines()[0][:120]}"
    return case.target_vertex[np.asarray(mapping)], time.perf_counter() - start, "ok"


def run_pair(pair: Pair, index: int, todo: list[tuple[str, str]]) -> list[dict]:
    """Rows of the (case, method) combinations ``todo`` of one pair."""
    source = as_mesh(pair.source_path, name=pair.source_name)
    target = as_mesh(pair.target_path, name=pair.target_name)
    cache = GeodesicCache("heat")
    rows, built = [], {}
    for case_name, method in todo:
        if case_name not in built:
            built[case_name] = make_case(case_name, pair, source, target, seed=1000 * index + CASES.index(case_name))
        case = built[case_name]
        mapping, seconds, status = run_method(case, method)
        row = dict(set=case_name, data=pair.set, source=pair.source_name, target=pair.target_name, method=method,
                   status=status, seconds=round(seconds, 3), kept_area=round(case.kept_area, 3))
        if mapping is not None:
            sym = None if pair.target_sym_points is None else pair.target_sym_points[case.keep]
            row.update(score_points(target, mapping[case.source_points], pair.target_points[case.keep], sym,
                                    cache))
        rows.append(row)
    return rows


def wanted(case_name: str, method: str, pair: Pair, pyfm_subset: list[Pair]) -> bool:
    if method == "pyfm":
        return case_name in MESH_CASES and any(pair is p for p in pyfm_subset)
    if method == "meshcorr-plain":
        return case_name in PARTIAL_CASES
    return True


def ratios(rows: list[dict]) -> str:
    """Each case's mean error over the clean error on the same pairs, and the same for seconds."""
    ok = [r for r in rows if r["status"] == "ok"]
    clean = {(r["source"], r["target"], r["method"]): r for r in ok if r["set"] == "clean"}
    lines = ["| case | method | pairs | mean error | clean error, same pairs | error ratio | seconds ratio |",
             "|---|---|---|---|---|---|---|"]
    for case_name in CASES[1:]:
        for method in ("meshcorr", "meshcorr-plain", "pyfm"):
            base = "meshcorr" if method == "meshcorr-plain" else method
            sel = [(r, clean[(r["source"], r["target"], base)]) for r in ok
                   if r["set"] == case_name and r["method"] == method and (r["source"], r["target"], base) in clean]
            if not sel:
                continue
            error = np.mean([float(r["mean_error"]) for r, _ in sel])
            reference = np.mean([float(c["mean_error"]) for _, c in sel])
            speed = np.median([float(r["seconds"]) / float(c["seconds"]) for r, c in sel])
            lines.append(f"| {case_name} | {method} | {len(sel)} | {error:.4f} | {reference:.4f} | "
                         f"{error / reference:.2f} | {speed:.2f} |")
    return "\n".join(lines)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--methods", nargs="+", default=["meshcorr", "meshcorr-plain", "pyfm"],
                        choices=["meshcorr", "meshcorr-plain", "pyfm"])
    parser.add_argument("--cases", nargs="+", default=list(CASES), choices=CASES)
    parser.add_argument("--pairs", type=int, default=30, help="TOSCA pairs (class-stratified)")
    parser.add_argument("--poses", type=int, default=3, help="Sumner poses per animal")
    parser.add_argument("--quick", action="store_true", help="4 TOSCA pairs and 1 pose per animal")
    parser.add_argument("--pyfm-pairs", type=int, default=6, help="pyFM on this many pairs, spread evenly")
    parser.add_argument("--out", type=Path, default=Path("benchmarks/cache/scans.csv"))
    parser.add_argument("--report", type=Path, default=None, help="write the Markdown tables here")
    args = parser.parse_args(argv)
    if not DATA.is_dir():
        print(f"scans: {DATA} is absent; this benchmark needs ../shared/data. Skipping.", file=sys.stderr)
        return 0
    n_pairs, n_poses = (4, 1) if args.quick else (args.pairs, args.poses)
    pairs = tosca_pairs(DATA / "tosca5k", "tosca5k", n_pairs) + sumner_pairs(DATA / "sumner", n_poses)
    pyfm_subset = _spread(pairs, args.pyfm_pairs)
    rows = previous_rows(args.out)
    done = {(r["set"], r["source"], r["target"], r["method"]) for r in rows}
    with appending(args.out, FIELDS) as (handle, writer):
        for index, pair in enumerate(pairs):
            todo = [(c, m) for c in args.cases for m in args.methods
                    if wanted(c, m, pair, pyfm_subset) and (c, pair.source_name, pair.target_name, m) not in done]
            for row in run_pair(pair, index, todo) if todo else []:
                writer.writerow(row)
                handle.flush()
                rows.append(row)
                error = f"{float(row['mean_error']):.4f}" if row["status"] == "ok" else row["status"]
                print(f"{row['set']} {pair.source_name}->{pair.target_name} {row['method']}: {error}"
                      f"{' FLIP' if row.get('flipped') in (1, '1') else ''} {float(row['seconds']):.1f} s",
                      file=sys.stderr, flush=True)
    names = {(p.source_name, p.target_name) for p in pairs}
    rows = [r for r in rows if r["set"] in args.cases and r["method"] in args.methods
            and (r["source"], r["target"]) in names]
    unsupported = sorted({(r["set"], r["method"], r["status"]) for r in rows if r["status"] != "ok"})
    text = markdown(summarize([r for r in rows if r["status"] == "ok"])).replace("| set |", "| case |")
    text += "\n\nAgainst the clean meshes (same pairs, same method):\n\n" + ratios(rows)
    if unsupported:
        text += "\n\nNot supported: " + "; ".join(f"{c} / {m}: {s}" for c, m, s in unsupported)
    publish(text, "scans.py", argv, args.report)
    return 0


if __name__ == "__main__":
    sys.exit(main())
