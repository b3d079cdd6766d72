"""Partial shapes (issue 15, item 2): a part of one TOSCA shape against another whole shape.

:func:`partial_case` runs one case and is meant to be reused (``benchmarks/scans.py``): the
source (or, with ``side="target"``, the target) is cut to ``keep`` of its area by a plane
(:func:`meshcorr.evaluation.cuts.cut_by_plane`) or by removing geodesic balls
(:func:`meshcorr.evaluation.cuts.remove_balls`), and matched against the other, whole shape with
``meshcorr.match(..., partial=...)``.

Error protocol: the TOSCA template samples that exist on the part (``.vts`` ground truth
restricted as ``truth[kept]``), geodesic error on the target divided by sqrt(target area),
flips counted (the map is ``flipped`` when its mean error against the mirrored truth
``.sym.vts`` is smaller). With ``side="target"`` the target is the part and errors are
measured on it. ``iou`` compares the reported matched region of the whole shape with the
true one at the template samples.

Usage::

    nice -n 10 python benchmarks/partial_check.py [--pairs 12] [--modes default partial] \\
        [--out benchmarks/cache/partial.csv]

Needs ``../shared/data/tosca5k`` beside the repository; exits with a message when it is absent.
"""

from __future__ import annotations

import argparse
import csv
import sys
import time
import warnings
from pathlib import Path

import numpy as np

import meshcorr
from meshcorr.evaluation.benchmark import load_dataset, shape_class, stratified_sample
from meshcorr.evaluation.cuts import cut_by_plane, remove_balls
from meshcorr.evaluation.metrics import GeodesicCache, geodesic_errors
from meshcorr.evaluation.ground_truth import read_vts
from meshcorr.core.mesh import as_mesh

DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "tosca5k"
FIELDS = ["source", "target", "class", "cut", "keep", "kept_area", "side", "mode", "mean_error",
          "sym_mean_error", "flipped", "iou", "matched_fraction", "unmapped", "n_points", "seconds", "warned"]


#: A part must keep at least this share of the asked area (a cut can split off pieces; the largest is kept).
MIN_KEPT = 0.85
#: Seeds tried, ``seed + 1000 t``, before the last part is kept whatever its area.
TRIES = 5


def make_part(mesh, cut: str, keep: float, seed: int):
    """``(part, kept)`` of ``mesh``: ``cut`` is "plane" or "balls".

    Cuts that leave less than :data:`MIN_KEPT` of the asked area (the balls split the shape and the
    largest piece is small) are drawn again with the next seed, so parts hold 60-90 % of the area.
    """
    if cut not in ("plane", "balls"):
        raise ValueError(f"cut must be 'plane' or 'balls', got {cut!r}")
    for t in range(TRIES):
        if cut == "plane":
            part, kept = cut_by_plane(mesh, keep=keep, random_state=seed + 1000 * t)
        else:
            part, kept = remove_balls(mesh, keep=keep, n_balls=3, random_state=seed + 1000 * t)
        if part.area >= MIN_KEPT * keep * mesh.area:
            break
    return part, kept


def partial_case(source, target, source_vts: np.ndarray, target_vts: np.ndarray,
                 target_sym_vts: np.ndarray | None = None, *, cut: str = "plane", keep: float = 0.7,
                 seed: int = 0, side: str = "source", partial: bool = True, cache: GeodesicCache | None = None,
                 **match_options) -> dict:
    """One partial case: cut ``side`` of the pair, match, score (module docstring).

    Parameters
    ----------
    source, target : Mesh or path
        The whole shapes.
    source_vts, target_vts : (s,) int
        0-based vertex of each template sample on each shape (``read_vts(...) `` of TOSCA's
        1-based files); ``target_sym_vts`` the target's mirrored one, for flips.
    cut, keep, seed
        How the part is made (:func:`make_part`).
    side : {"source", "target"}
        Which shape is cut.
    partial : bool
        Declare it (``partial=side``) or match in the default whole-to-whole mode.
    cache : GeodesicCache, optional
        Geodesic rows of the whole target, shared between cases.

    Returns
    -------
    row : dict
        ``mean_error``, ``sym_mean_error``, ``flipped``, ``iou`` (matched region against the
        truth at the template samples, partial mode only), ``matched_fraction``, ``unmapped``
        (share of the part's truth points the map leaves out), ``n_points``, ``seconds``,
        ``kept_area`` and ``warned`` (a PartialShapeWarning was raised).
    """
    source, target = as_mesh(source, name="source"), as_mesh(target, name="target")
    whole, other = (source, target) if side == "source" else (target, source)
    part, kept = make_part(whole, cut, keep, seed)
    lookup = np.full(whole.n_vertices, -1, dtype=np.int64)
    lookup[kept] = np.arange(len(kept))
    whole_vts, other_vts = (source_vts, target_vts) if side == "source" else (target_vts, source_vts)
    on_part = lookup[whole_vts] >= 0
    start = time.perf_counter()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        declared = {"partial": side} if partial else {}
        pair = (part, target) if side == "source" else (source, part)
        result = meshcorr.match(*pair, **declared, **match_options)
    seconds = time.perf_counter() - start
    warned = any(type(w.message).__name__ == "PartialShapeWarning" for w in caught)
    if side == "source":
        src_points = lookup[source_vts[on_part]]
        true_t, sym_t, scored_on = target_vts[on_part], None, target
        if target_sym_vts is not None:
            sym_t = target_sym_vts[on_part]
    else:
        src_points = source_vts[on_part]
        true_t, scored_on = lookup[target_vts[on_part]], part
        sym_t = None
        if target_sym_vts is not None:
            sym = lookup[target_sym_vts[on_part]]
            sym_t = sym  # may hold -1 where the mirrored point is not on the part
    predicted = result.map[src_points]
    mapped = predicted >= 0
    errors = np.full(len(predicted), np.nan)
    errors[mapped] = geodesic_errors(scored_on, predicted[mapped], true_t[mapped],
                                     cache=cache if side == "source" else None)
    row = dict(kept_area=part.area / whole.area, mean_error=float(np.nanmean(errors)) if mapped.any() else np.nan,
               unmapped=float(1 - mapped.mean()), n_points=int(on_part.sum()), seconds=seconds, warned=warned,
               sym_mean_error=np.nan, flipped=False, iou=np.nan, matched_fraction=np.nan)
    if sym_t is not None:
        ok = mapped & (sym_t >= 0)
        sym_errors = geodesic_errors(scored_on, predicted[ok], sym_t[ok],
                                     cache=cache if side == "source" else None)
        row["sym_mean_error"] = float(sym_errors.mean()) if ok.any() else np.nan
        row["flipped"] = bool(row["sym_mean_error"] < np.nanmean(errors[ok])) if ok.any() else False
    region = getattr(result, "matched_region", None)
    if region is not None:
        # The whole shape's samples: truly matched where the sample lies on the part.
        predicted_in = region[other_vts]
        union = np.sum(predicted_in | on_part)
        row["iou"] = float(np.sum(predicted_in & on_part) / max(union, 1))
        row["matched_fraction"] = float(result.matched_area_fraction)
    return row


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--data", type=Path, default=DATA)
    parser.add_argument("--pairs", type=int, default=12, help="class-stratified pairs (default 12)")
    parser.add_argument("--cuts", nargs="+", default=["plane", "balls"])
    parser.add_argument("--keeps", nargs="+", type=float, default=[0.6, 0.75, 0.9])
    parser.add_argument("--modes", nargs="+", default=["default", "partial"], choices=["default", "partial"])
    parser.add_argument("--side", default="source", choices=["source", "target"])
    parser.add_argument("--out", type=Path, default=None, help="CSV of the rows (appended; resumes)")
    args = parser.parse_args(argv)
    if not args.data.is_dir():
        print(f"partial_check: {args.data} is absent: nothing to measure (the TOSCA data lives beside "
              "the checkout, see the README's 'Data and licences').", file=sys.stderr)
        return 0
    dataset = load_dataset(args.data)
    pairs = stratified_sample(dataset.pairs, args.pairs, random_state=0)
    done = set()
    if args.out is not None and args.out.is_file():
        with open(args.out) as f:
            done = {(r["source"], r["target"], r["cut"], r["keep"], r["side"], r["mode"]) for r in csv.DictReader(f)}
    rows = []
    for index, (a, b) in enumerate(pairs):
        source, target = as_mesh(dataset.mesh_path(a), name=a), as_mesh(dataset.mesh_path(b), name=b)
        va, vb = read_vts(dataset.vts_path(a)), read_vts(dataset.vts_path(b))
        vb_sym = read_vts(dataset.vts_path(b, sym=True))
        cache = GeodesicCache()
        for number, cut in enumerate(args.cuts):
            keep = args.keeps[(index + number) % len(args.keeps)]
            rows += _cases(args, done, a, b, source, target, va, vb, vb_sym, cache, cut, keep, seed=index)
    for mode in args.modes:
        mine = [r for r in rows if r["mode"] == mode]
        if mine:
            print(f"{mode:8}: {len(mine)} cases, mean error {np.mean([r['mean_error'] for r in mine]):.3f}, "
                  f"median {np.median([r['mean_error'] for r in mine]):.3f}, flips {sum(r['flipped'] for r in mine)}, "
                  f"worst {max(r['mean_error'] for r in mine):.3f}, {np.mean([r['seconds'] for r in mine]):.2f} s "
                  f"per case, warned {sum(r['warned'] for r in mine)}")
    return 0


def _cases(args, done, a, b, source, target, va, vb, vb_sym, cache, cut, keep, *, seed):
    """The rows of one pair and one cut, each mode (printed, and appended to ``args.out``)."""
    rows = []
    for mode in args.modes:
        key = (a, b, cut, f"{keep:g}", args.side, mode)
        if key in done:
            continue
        row = partial_case(source, target, va, vb, vb_sym, cut=cut, keep=keep, seed=seed,
                           side=args.side, partial=mode == "partial", cache=cache)
        row.update(source=a, target=b, **{"class": shape_class(a)}, cut=cut, keep=f"{keep:g}",
                   side=args.side, mode=mode)
        rows.append(row)
        print(f"{a:>10} -> {b:<10} {cut:5} {keep:.2f} ({row['kept_area']:.2f}) {mode:8} "
              f"err {row['mean_error']:.3f} sym {row['sym_mean_error']:.3f} flip {int(row['flipped'])} "
              f"iou {row['iou']:.2f} frac {row['matched_fraction']:.2f} warn {int(row['warned'])} "
              f"{row['seconds']:.1f} s", flush=True)
        if args.out is not None:
            new = not args.out.is_file()
            args.out.parent.mkdir(parents=True, exist_ok=True)
            with open(args.out, "a", newline="") as f:
                writer = csv.DictWriter(f, FIELDS)
                if new:
                    writer.writeheader()
                writer.writerow({k: (f"{v:.4f}" if isinstance(v, float) else v) for k, v in row.items()
                                 if k in FIELDS})
    return rows


if __name__ == "__main__":
    sys.exit(main())
