"""Speed and accuracy of the ZoomOut refinement, before vs after (issue 5).

Runs, side by side in one process and on the same start maps, the
refinement of :mod:`meshcorr.stages.refine` as it stands and as it was at a git
revision (``--before``, loaded from ``git show REV:src/meshcorr/refine.py``),
each on fresh meshes (no shared eigenbasis cache). The start map is the
default pipeline's map with ``refine=False`` (cached in
``benchmarks/cache/refine``), so both refine exactly what the pipeline would.
Reports per pair: seconds of each (and the ratio), mean geodesic error of
the start map and of both refined maps, and the fraction of vertices on
which the two refined maps agree.

Pairs: ``--tosca N`` TOSCA 5k pairs (one per class first,
:func:`meshcorr.evaluation.benchmark.stratified_sample`), all ground-truth points; the
Sumner cat-reference -> cat-01 pair subdivided twice (115 282 vertices,
truth the identity, 1000 seeded points) as ``benchmarks/scale.py`` builds it.

Usage::

    nice -n 10 python benchmarks/refine_speed.py [--tosca 8] [--no-large] [--before d691c85]

Needs ``../shared/data`` beside the repository; exits with a message when absent.
"""

from __future__ import annotations

import argparse
import importlib.util
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import meshcorr
from meshcorr.stages import refine as refine
from meshcorr.evaluation.benchmark import load_dataset, stratified_sample
from meshcorr.evaluation.metrics import geodesic_errors
from meshcorr.core.mesh import Mesh, as_mesh

HERE = Path(__file__).resolve().parent
DEFAULT_DATA = HERE.parent.parent / "shared" / "data"
CACHE = HERE / "cache" / "refine"


def load_before(rev: str):
    """The refine module at git revision ``rev``, imported as ``meshcorr._refine_before``."""
    text = subprocess.run(["git", "show", f"{rev}:src/meshcorr/refine.py"], cwd=HERE.parent, check=True,
                          capture_output=True, text=True).stdout
    path = Path(tempfile.mkdtemp()) / "refine_before.py"
    path.write_text(text)
    spec = importlib.util.spec_from_file_location("meshcorr._refine_before", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def start_map(name: str, source: Mesh, target: Mesh) -> np.ndarray:
    path = CACHE / f"{name}.start.npy"
    if not path.exists():
        path.parent.mkdir(parents=True, exist_ok=True)
        np.save(path, meshcorr.match(source, target, refine=False, random_state=0).map)
    return np.load(path)


def fresh(mesh: Mesh) -> Mesh:
    return Mesh(mesh.vertices, mesh.faces, name=mesh.name)


def compare(name, source, target, truth, before, runs: int) -> dict:
    src_pts, tgt_pts = truth
    start = start_map(name, source, target)
    assert source.n_vertices == source.n_original and target.n_vertices == target.n_original
    row = {"pair": name, "n": source.n_vertices,
           "start": float(geodesic_errors(target, start[src_pts], tgt_pts).mean())}
    maps = {}
    for label, module in (("before", before), ("after", refine)):
        seconds = []
        for _ in range(runs):
            s, t = fresh(source), fresh(target)
            tic = time.perf_counter()
            maps[label], _ = module.refine_map(s, t, start, k=40, random_state=0)
            seconds.append(time.perf_counter() - tic)
        row[f"{label}_s"] = float(np.median(seconds))
        row[f"{label}_err"] = float(geodesic_errors(target, maps[label][src_pts], tgt_pts).mean())
    row["agree"] = float(np.mean(maps["before"] == maps["after"]))
    print(row, file=sys.stderr, flush=True)
    return row


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", type=Path, default=DEFAULT_DATA)
    parser.add_argument("--tosca", type=int, default=8, help="TOSCA pairs (stratified sample)")
    parser.add_argument("--runs", type=int, default=3, help="timed runs per TOSCA pair (median)")
    parser.add_argument("--no-large", action="store_true", help="skip the 115k pair")
    parser.add_argument("--before", default="d691c85", help="git revision of the 'before' refine.py")
    args = parser.parse_args(argv)
    if not (args.data / "tosca5k").is_dir():
        print(f"benchmarks/refine_speed.py: no data at {args.data}; skipped.", file=sys.stderr)
        return 0
    before = load_before(args.before)
    rows = []
    dataset = load_dataset(args.data / "tosca5k")
    for a, b in stratified_sample(dataset.pairs, args.tosca):
        source, target = as_mesh(dataset.mesh_path(a)), as_mesh(dataset.mesh_path(b))
        vts = [np.loadtxt(dataset.vts_path(s), dtype=np.int64) - 1 for s in (a, b)]
        rows.append(compare(f"{a}-{b}", source, target, vts, before, args.runs))
    if not args.no_large:
        sys.path.insert(0, str(HERE))
        import scale

        pair = next(p for p in scale.prepare_pairs(args.data) if p["name"] == "sumner-cat-x2")
        source, target = as_mesh(pair["source"]), as_mesh(pair["target"])
        pts = np.random.default_rng(0).choice(source.n_vertices, scale.MAX_EVAL_POINTS, replace=False)
        rows.append(compare(pair["name"], source, target, (pts, pts), before, 1))
    print("| pair | n | before s | after s | before / after | error: start | before | after | same map |")
    print("|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        print(f"| {r['pair']} | {r['n']} | {r['before_s']:.2f} | {r['after_s']:.2f} | "
              f"{r['before_s'] / r['after_s']:.1f}x | {r['start']:.4f} | {r['before_err']:.4f} | "
              f"{r['after_err']:.4f} | {100 * r['agree']:.2f} % |")
    small = [r for r in rows if r["n"] < 20_000]
    if small:
        print(f"| TOSCA mean ({len(small)}) | | {np.mean([r['before_s'] for r in small]):.2f} | "
              f"{np.mean([r['after_s'] for r in small]):.2f} | | {np.mean([r['start'] for r in small]):.4f} | "
              f"{np.mean([r['before_err'] for r in small]):.4f} | {np.mean([r['after_err'] for r in small]):.4f} | |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
