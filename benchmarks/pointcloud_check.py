"""Point clouds against meshes on the same TOSCA pairs (issue 15, item 1), side by side in one run.

For a class-stratified sample of within-class TOSCA pairs (``tosca5k``, ~5000
vertices), ``meshcorr.match`` (default settings) runs on three versions of
each pair:

- ``mesh``: the two meshes;
- ``vertices``: the two meshes' vertices as point clouds (``(n, 3)`` arrays);
- ``resampled``: ``--points`` (5000) points sampled anew on each surface with
  a non-uniform density (area-proportional, times a weight growing linearly
  from 0.2 to 1 along the longest side of the bounding box: a fivefold change
  of density) and Gaussian noise of ``--noise`` (1 %) of the bounding-box
  diagonal on every coordinate, with a fixed seed.

Error: the Princeton protocol at the 5000 template points of the ``.vts``
ground truth, on the **target mesh**: geodesic distance between the predicted
and the true target vertex divided by sqrt(target mesh area). A cloud's
point stands for the mesh vertex nearest to it (for a resampled point: to its
position before the noise), and a template point of the source for the cloud
point nearest to its vertex. Flipped: the map is closer to the mirrored truth
(``.sym.vts``). Seconds: wall time of ``meshcorr.match``, the three versions
of a pair one after the other (ratios only mean something within one run).

Usage::

    nice -n 10 python benchmarks/pointcloud_check.py [--pairs 8] [--points 5000] [--noise 0.01]

Needs ``../shared/data`` beside the repository; exits with a message when it
is absent.
"""

from __future__ import annotations

import argparse
import platform
import sys
import time
import warnings
from pathlib import Path

import numpy as np
from scipy.spatial import cKDTree

import meshcorr
from meshcorr.evaluation.benchmark import stratified_sample
from meshcorr.evaluation.metrics import GeodesicCache, geodesic_errors
from meshcorr.evaluation.ground_truth import read_vts
from meshcorr.core.mesh import Mesh, as_mesh

DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "tosca5k"
VERSIONS = ("mesh", "vertices", "resampled")


def resample(mesh: Mesh, n_points: int, noise: float, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """Noisy, non-uniform surface samples (module docstring) and the mesh vertex nearest to each clean sample."""
    V, F = mesh.vertices, mesh.faces
    corners = V[F]
    area = 0.5 * np.linalg.norm(np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]), axis=1)
    lo, hi = V.min(axis=0), V.max(axis=0)
    axis = int(np.argmax(hi - lo))
    along = (corners[:, :, axis].mean(axis=1) - lo[axis]) / (hi[axis] - lo[axis])
    weight = area * (0.2 + 0.8 * along)
    face = rng.choice(len(F), size=n_points, p=weight / weight.sum())
    r1, r2 = np.sqrt(rng.random(n_points)), rng.random(n_points)
    bary = np.stack([1 - r1, r1 * (1 - r2), r1 * r2], axis=1)
    clean = np.einsum("nk,nkc->nc", bary, corners[face])
    noisy = clean + rng.normal(scale=noise * np.linalg.norm(hi - lo), size=clean.shape)
    return noisy, cKDTree(V).query(clean)[1]


def score(target: Mesh, predicted: np.ndarray, truth: np.ndarray, sym: np.ndarray, cache: GeodesicCache):
    """Mean normalised geodesic error against the truth, and whether the mirrored truth is closer."""
    error = float(geodesic_errors(target, predicted, truth, cache=cache).mean())
    mirrored = float(geodesic_errors(target, predicted, sym, cache=cache).mean())
    return error, mirrored < error


def run_pair(a: str, b: str, args, cache: GeodesicCache) -> dict:
    source, target = as_mesh(DATA / f"{a}.off", name=a), as_mesh(DATA / f"{b}.off", name=b)
    vts_a, vts_b = read_vts(DATA / "corres" / f"{a}.vts"), read_vts(DATA / "corres" / f"{b}.vts")
    sym_b = read_vts(DATA / "corres" / f"{b}.sym.vts")
    rng = np.random.default_rng(args.seed)
    cloud_a, owner_a = resample(source, args.points, args.noise, rng)
    cloud_b, owner_b = resample(target, args.points, args.noise, rng)
    # Template point k of the source: the resampled source point nearest to its vertex.
    start_a = cKDTree(source.vertices[owner_a]).query(source.vertices[vts_a])[1]
    inputs = {"mesh": (str(DATA / f"{a}.off"), str(DATA / f"{b}.off")),
              "vertices": (np.array(source.vertices), np.array(target.vertices)),
              "resampled": (cloud_a, cloud_b)}
    row = {"pair": f"{a} -> {b}"}
    for version in VERSIONS:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            start = time.perf_counter()
            result = meshcorr.match(*inputs[version], random_state=args.seed)
            seconds = time.perf_counter() - start
        if version == "resampled":
            predicted = owner_b[result.map[start_a]]
        else:
            predicted = result.map[vts_a]
        error, flipped = score(target, predicted, vts_b, sym_b, cache)
        row[version] = dict(error=error, flipped=flipped, seconds=seconds, reliable=result.orientation_reliable,
                            warnings=len(caught))
        print(f"  {a} -> {b} {version:10s} error {error:.4f} {'FLIPPED ' if flipped else ''}"
              f"{seconds:5.2f} s reliable={result.orientation_reliable} warnings={len(caught)}", file=sys.stderr)
    return row


def report(rows: list[dict], args) -> str:
    lines = [f"TOSCA 5k, {len(rows)} pairs; resampled: {args.points} points, noise {100 * args.noise:g} % of the "
             f"bounding-box diagonal, density x5 along the longest side; seed {args.seed}; "
             f"{platform.node()}, {time.strftime('%Y-%m-%d')}", "",
             "| pair | " + " | ".join(f"{v} error | {v} s" for v in VERSIONS) + " |",
             "|---|" + "---|---|" * len(VERSIONS)]
    for row in rows:
        cells = [f"{row[v]['error']:.4f}{' (flip)' if row[v]['flipped'] else ''} | {row[v]['seconds']:.2f}"
                 for v in VERSIONS]
        lines.append(f"| {row['pair']} | " + " | ".join(cells) + " |")
    means = {v: np.mean([row[v]["error"] for row in rows]) for v in VERSIONS}
    seconds = {v: np.mean([row[v]["seconds"] for row in rows]) for v in VERSIONS}
    flips = {v: sum(row[v]["flipped"] for row in rows) for v in VERSIONS}
    unreliable = {v: sum(not row[v]["reliable"] for row in rows) for v in VERSIONS}
    lines.append("| **mean** | " + " | ".join(f"**{means[v]:.4f}** | **{seconds[v]:.2f}**" for v in VERSIONS) + " |")
    lines += ["", "| | " + " | ".join(VERSIONS) + " |", "|---|---|---|---|",
              "| mean error / mesh's | " + " | ".join(f"{means[v] / means['mesh']:.2f}" for v in VERSIONS) + " |",
              "| full flips | " + " | ".join(str(flips[v]) for v in VERSIONS) + " |",
              "| orientation unreliable | " + " | ".join(str(unreliable[v]) for v in VERSIONS) + " |",
              "| seconds / mesh's | " + " | ".join(f"{seconds[v] / seconds['mesh']:.2f}" for v in VERSIONS) + " |"]
    return "\n".join(lines)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--pairs", type=int, default=8, help="pairs, stratified over the classes (default 8)")
    parser.add_argument("--points", type=int, default=5000, help="points of each resampled cloud (default 5000)")
    parser.add_argument("--noise", type=float, default=0.01, help="noise, fraction of the bounding-box diagonal")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    if not DATA.is_dir():
        print(f"pointcloud_check: {DATA} not found: this benchmark needs the TOSCA data in ../shared/data.",
              file=sys.stderr)
        return 0
    listed = [tuple(line.split()) for line in (DATA / "test_pairs.txt").read_text().splitlines()
              if len(line.split()) == 2]
    pairs = stratified_sample(listed, args.pairs, random_state=args.seed)
    cache = GeodesicCache("heat", max_meshes=4)
    rows = [run_pair(a, b, args, cache) for a, b in pairs]
    print(report(rows, args))
    return 0


if __name__ == "__main__":
    sys.exit(main())
