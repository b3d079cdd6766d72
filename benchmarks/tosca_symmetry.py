"""Left/right flips and refinement on TOSCA-5k (issue 6), against pyFM on the same pairs.

For a deterministic class-stratified sample of ``test_pairs.txt``
(:func:`meshcorr.evaluation.benchmark.stratified_sample`: classes in turn, so 40 pairs
cover all 8 classes), runs

- ``default``: ``meshcorr.match`` with default settings (``symmetry="auto"``,
  ZoomOut refinement on);
- ``cost``: ``symmetry="cost"`` (the paper's pure-cost choice), refined;
- ``no-refine``: default settings with ``refine=False``;
- ``pyfm``: pyFM's automatic functional-map pipeline (``pip install pyfmaps``):
  WKS descriptors, descriptor preservation + Laplacian and descriptor
  commutativity + the orientation-preserving term, then ZoomOut; no landmarks.

and reports per method: flip rate (a map is flipped when its mean error
against the mirrored truth ``.sym.vts`` is smaller than against the truth),
mean geodesic error with flips counted, mean error over the unflipped pairs,
and seconds per pair (the map only, not the evaluation).

``cost`` reuses ``default`` when ``auto`` chose the cheapest configuration
(same code path, same seed). Rows are appended to a CSV as they finish, so an interrupted run resumes.

Usage::

    nice -n 10 python benchmarks/tosca_symmetry.py [--pairs 40] [--out benchmarks/cache/symmetry.csv]
    nice -n 10 python benchmarks/tosca_symmetry.py --anchor-study 8

Needs the TOSCA data beside the repository (``../shared/data/tosca5k``);
exits with a message when it is absent. pyFM is optional (``--methods``).
"""

from __future__ import annotations

import argparse
import csv
import os
import platform
import sys
import time
from pathlib import Path

import numpy as np

import meshcorr
from meshcorr.evaluation.benchmark import load_dataset, shape_class, stratified_sample
from meshcorr.evaluation.metrics import GeodesicCache, evaluate_map
from meshcorr.evaluation.ground_truth import load_ground_truth
from meshcorr.core.mesh import as_mesh
from meshcorr.pipeline.run import REFINE_K
from meshcorr.stages.refine import refine_map

DEFAULT_DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "tosca5k"
METHODS = ("default", "cost", "no-refine", "pyfm")
FIELDS = ["source", "target", "class", "method", "mean_error", "sym_mean_error", "flipped", "seconds",
          "chosen_rank", "n_candidates", "orientation_chosen", "orientation_alternative"]


def pyfm_map(source, target, landmarks: np.ndarray | None = None, *, k_process: int = 120, k_fit: int = 30,
             zoomout_steps: int = 15, w_orient: float = 0.1) -> np.ndarray:
    """pyFM's automatic pipeline, source vertex -> target vertex (see the module docstring).

    ``landmarks``: optional (L, 2) (source vertex, target vertex) pairs, given to pyFM's
    preprocessing as landmark descriptors.
    """
    from pyFM.functional import FunctionalMapping
    from pyFM.mesh import TriMesh

    # pyFM's p2p_21 maps mesh 2's vertices to mesh 1's: mesh 2 is our source.
    mesh1 = TriMesh(np.array(target.vertices), np.array(target.faces), area_normalize=True)
    mesh2 = TriMesh(np.array(source.vertices), np.array(source.faces), area_normalize=True)
    model = FunctionalMapping(mesh1, mesh2)
    process = dict(n_descr=100, descr_type="WKS", k_process=k_process, subsample_step=5)
    if landmarks is not None:
        process["landmarks"] = np.asarray(landmarks)[:, ::-1]  # pyFM: (mesh1 vertex, mesh2 vertex)
    model.preprocess(**process)
    model.fit(K=(k_fit, k_fit), w_descr=1e0, w_lap=1e-2, w_dcomm=1e-1, w_orient=w_orient)
    fm = model.zoomout_refine(nit=zoomout_steps, step=5, subsample=1000)
    return np.asarray(model.get_p2p(fm), dtype=np.int64)


def load_pair(dataset, a: str, b: str):
    """Meshes, ground truth and mirrored ground truth of one pair."""
    source = as_mesh(dataset.mesh_path(a), name=a)
    target = as_mesh(dataset.mesh_path(b), name=b)
    vts = [dataset.vts_path(a), dataset.vts_path(b)]
    truth = load_ground_truth(vts, n_source=source.n_vertices, n_target=target.n_vertices)
    sym = load_ground_truth([vts[0], dataset.vts_path(b, sym=True)], n_source=source.n_vertices,
                            n_target=target.n_vertices)
    return source, target, truth, sym


def run_pair(dataset, a: str, b: str, *, methods: tuple) -> list[dict]:
    source, target, truth, sym = load_pair(dataset, a, b)
    maps, seconds, info = {}, {}, {}

    def timed(name, run):
        start = time.perf_counter()
        result = run()
        seconds[name] = time.perf_counter() - start
        maps[name] = result if isinstance(result, np.ndarray) else result.map
        return result

    if "default" in methods or "cost" in methods:
        result = timed("default", lambda: meshcorr.match(source, target))
        chosen = next(c for c in result.candidates if c["chosen"])
        other = [c for c in result.candidates if c["alternative"]]
        info["default"] = dict(chosen_rank=chosen["rank"], n_candidates=len(result.candidates),
                               orientation_chosen=chosen["orientation"],
                               orientation_alternative=other[0]["orientation"] if other else "")
        if "cost" in methods:
            if chosen["rank"] == 0:  # "cost" takes rank 0 by the same code path: the same map
                maps["cost"], seconds["cost"] = maps["default"], seconds["default"]
            else:
                timed("cost", lambda: meshcorr.match(source, target, symmetry="cost"))
            info["cost"] = dict(chosen_rank=0, n_candidates=len(result.candidates))
        if "default" not in methods:
            del maps["default"]
    if "no-refine" in methods:
        timed("no-refine", lambda: meshcorr.match(source, target, refine=False))
    if "pyfm" in methods:
        timed("pyfm", lambda: pyfm_map(source, target))

    cache = GeodesicCache("heat")
    rows = []
    for name, mapping in maps.items():
        report = evaluate_map(target, mapping, truth, sym_truth=sym, cache=cache)
        rows.append(dict(source=a, target=b, **{"class": shape_class(a)}, method=name,
                         mean_error=report["mean_error"], sym_mean_error=report["sym_mean_error"],
                         flipped=int(report["flipped"]), seconds=seconds[name], **info.get(name, {})))
    return rows


def anchor_study(dataset, pairs) -> str:
    """Mean error (unrefined, flips forgiven and counted) with the anchor term scaled or not."""
    settings = {"embedding scale (default)": {}, "geodesic / max (paper)": {"anchor_scale": "geodesic"},
                "no anchors": {"n_anchors": 0}}
    errors: dict = {name: [] for name in settings}
    for a, b in pairs:
        source, target, truth, sym = load_pair(dataset, a, b)
        cache = GeodesicCache("heat")
        for name, options in settings.items():
            report = evaluate_map(target, meshcorr.match(source, target, refine=False, **options).map, truth,
                                  sym_truth=sym, cache=cache)
            errors[name].append((report["mean_error"], report["best_mean_error"]))
        print(f"anchors {a}-{b}: " + ", ".join(f"{n} {e[-1][0]:.4f}" for n, e in errors.items()),
              file=sys.stderr, flush=True)
    lines = [f"| anchor term ({len(pairs)} pairs, no refinement) | mean error | forgiving flips |", "|---|---|---|"]
    for name, values in errors.items():
        v = np.array(values)
        lines.append(f"| {name} | {v[:, 0].mean():.4f} | {v[:, 1].mean():.4f} |")
    return "\n".join(lines)


def summarize(rows: list[dict]) -> str:
    lines = ["| method | pairs | flip rate | mean error (flips counted) | mean error (unflipped pairs) "
             "| seconds per pair |", "|---|---|---|---|---|---|"]
    means = {}
    for method in METHODS:
        sel = [r for r in rows if r["method"] == method]
        if not sel:
            continue
        err = np.array([float(r["mean_error"]) for r in sel])
        flip = np.array([int(r["flipped"]) for r in sel], dtype=bool)
        secs = np.array([float(r["seconds"]) for r in sel])
        means[method] = err.mean()
        kept = f"{err[~flip].mean():.4f}" if (~flip).any() else "-"
        lines.append(f"| {method} | {len(sel)} | {flip.mean():.1%} ({flip.sum()}) | {err.mean():.4f} | {kept} "
                     f"| {secs.mean():.1f} |")
    if "default" in means and "pyfm" in means:
        lines.append(f"\nmean error ratio default / pyfm (same pairs, same run): "
                     f"{means['default'] / means['pyfm']:.3f}")
    classes = sorted({r["class"] for r in rows})
    lines.append("\nPer class (default / cost / pyfm mean error, flips counted; flips in brackets):\n")
    lines.append("| class | pairs | default | cost | no-refine | pyfm |")
    lines.append("|---|---|---|---|---|---|")
    for cls in classes:
        cells = []
        for method in ("default", "cost", "no-refine", "pyfm"):
            sel = [r for r in rows if r["method"] == method and r["class"] == cls]
            cells.append(f"{np.mean([float(r['mean_error']) for r in sel]):.4f} "
                         f"({sum(int(r['flipped']) for r in sel)})" if sel else "-")
        n = len({(r["source"], r["target"]) for r in rows if r["class"] == cls})
        lines.append(f"| {cls} | {n} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--data", type=Path, default=DEFAULT_DATA)
    parser.add_argument("--pairs", type=int, default=40, help="stratified sample size (default: 40)")
    parser.add_argument("--out", type=Path, default=Path(__file__).resolve().parent / "cache" / "symmetry.csv",
                        help="per-pair CSV, appended to and resumed from")
    parser.add_argument("--methods", default=",".join(METHODS),
                        help=f"comma-separated subset of {', '.join(METHODS)} (default: all)")
    parser.add_argument("--reverse", action="store_true",
                        help="work through the pairs last first (a second process with its own --out)")
    parser.add_argument("--summary-only", action="store_true", help="print the tables of the CSV and stop")
    parser.add_argument("--anchor-study", type=int, default=0, metavar="N",
                        help="instead: compare anchor-term scalings on a stratified sample of N pairs")
    args = parser.parse_args()
    if not (args.data / "test_pairs.txt").exists():
        print(f"TOSCA data not found at {args.data}; nothing to do.", file=sys.stderr)
        return 0
    methods = tuple(m for m in args.methods.split(",") if m)
    if set(methods) - set(METHODS):
        print(f"Unknown methods {sorted(set(methods) - set(METHODS))}; choose from {METHODS}.", file=sys.stderr)
        return 2
    if "pyfm" in methods:
        try:
            import pyFM  # noqa: F401
        except ImportError:
            print("pyFM is not installed (pip install pyfmaps); leave it out of --methods.", file=sys.stderr)
            return 1
    dataset = load_dataset(args.data)
    if args.anchor_study:
        print(anchor_study(dataset, stratified_sample(dataset.pairs, args.anchor_study, random_state=0)))
        return 0
    pairs = stratified_sample(dataset.pairs, args.pairs, random_state=0)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    rows = []
    if args.out.exists():
        with open(args.out, newline="") as f:
            rows = list(csv.DictReader(f))
    done = {(r["source"], r["target"]) for r in rows}
    if not args.summary_only:
        order = list(enumerate(pairs, 1))
        for number, (a, b) in (order[::-1] if args.reverse else order):
            if (a, b) in done:
                continue
            start = time.perf_counter()
            new = run_pair(dataset, a, b, methods=methods)
            fresh = not args.out.exists()
            with open(args.out, "a", newline="") as f:
                writer = csv.DictWriter(f, fieldnames=FIELDS)
                if fresh:
                    writer.writeheader()
                writer.writerows(new)
            rows += [{k: str(v) for k, v in r.items()} for r in new]
            text = ", ".join(f"{r['method']} {r['mean_error']:.3f}{' F' if r['flipped'] else ''}" for r in new)
            print(f"[{number}/{len(pairs)}] {a}-{b}: {text} ({time.perf_counter() - start:.0f} s)",
                  file=sys.stderr, flush=True)
    rows = [r for r in rows if (r["source"], r["target"]) in set(pairs)]
    print(f"Measured {time.strftime('%Y-%m-%d')} on {platform.machine()}, {os.cpu_count()} cores, "
          f"meshcorr {meshcorr.__version__}; {len({(r['source'], r['target']) for r in rows})} of "
          f"{len(pairs)} pairs.\n")
    print(summarize(rows))
    return 0


if __name__ == "__main__":
    sys.exit(main())
