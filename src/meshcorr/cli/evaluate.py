"""``meshcorr evaluate``: score a vertex map against ground truth."""

from __future__ import annotations

import argparse
import json
import sys

from ..geodesics import GEODESIC_METHODS

HELP = "score a vertex map against ground truth (geodesic error)"

DESCRIPTION = """\
Score MAP (line i = the 0-based TARGET vertex matched to SOURCE vertex i, as
written by 'meshcorr match'; or a .npy array) against ground truth, with the
Princeton protocol (Kim et al. 2011): for each ground-truth pair, the geodesic
distance on TARGET between the predicted and the true vertex, divided by
sqrt(area of TARGET). Prints the mean error, the fraction of points under
each threshold and the paper's total geodesic error (the plain sum), and
measures that need no truth: coverage (share of TARGET's area reached),
bijectivity (distinct images / mapped vertices) and continuity (mean ratio of
an edge's image length to its length, both over sqrt(area); about 1 for a
smooth map, larger where the map tears).

Ground truth (--gt):
  identity          vertex i <-> vertex i (meshes with one connectivity)
  A.vts B.vts       TOSCA format: line k of each file is the 1-based vertex
                    matching template sample k
  PAIRS             a text file of 0-based pairs 'i j' per line, or one
                    target index per line (a dense map)
--sym gives the left/right mirrored truth the same way; with a .vts pair in
--gt, one file (B.sym.vts) is enough. The map is then called flipped when it
is closer to the mirrored truth than to the direct one.
"""


def add_parser(sub) -> None:
    p = sub.add_parser("evaluate", help=HELP, description=DESCRIPTION,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("source", metavar="SOURCE", help="mesh or point cloud whose vertices were mapped")
    p.add_argument("target", metavar="TARGET", help="mesh or point cloud they were mapped onto")
    p.add_argument("map", metavar="MAP", help="the vertex map (.txt one index per line, or .npy)")
    p.add_argument("--gt", action="append", required=True, metavar="GT",
                   help="ground truth: 'identity', a file of 0-based pairs, or a .vts pair given as "
                        "--gt SOURCE.vts --gt TARGET.vts")
    p.add_argument("--sym", action="append", metavar="SYMGT",
                   help="mirrored ground truth, same forms (or only TARGET.sym.vts after a .vts pair)")
    p.add_argument("--geodesic", choices=GEODESIC_METHODS, default="heat",
                   help="geodesic solver for the errors (default: heat)")
    p.add_argument("--thresholds", default="0.05,0.1,0.25",
                   help="comma-separated normalised errors to report (default: 0.05,0.1,0.25)")
    p.add_argument("--curve", metavar="PNG",
                   help="also save the cumulative error curve (needs meshcorr[plot])")
    p.add_argument("--json", action="store_true", help="print the report as JSON on stdout")
    p.set_defaults(run=run)


def _thresholds(text: str) -> list[float]:
    from .._params import check_float
    from ..errors import ParameterError

    try:
        values = [float(part) for part in text.split(",") if part.strip()]
    except ValueError as exc:
        raise ParameterError(f"--thresholds must be comma-separated numbers; got {text!r}.") from exc
    if not values:
        raise ParameterError("--thresholds must name at least one number.")
    return [check_float("thresholds", v, minimum=0.0) for v in values]


def _sym_spec(gt: list[str], sym: list[str]) -> list[str]:
    """A lone TARGET.sym.vts after a .vts pair borrows the source's .vts file."""
    if len(sym) == 1 and sym[0].lower().endswith(".vts") and len(gt) == 2:
        return [gt[0], sym[0]]
    return sym


def run(args) -> int:
    from ..errors import ParameterError
    from ..evaluation import cumulative_curve, evaluate_map, map_quality, scalar_summary
    from ..ground_truth import load_ground_truth
    from ..io import check_outputs, read_mesh
    from ._mapfile import read_checked_map
    from ..mesh import Mesh, as_mesh

    thresholds = _thresholds(args.thresholds)
    if args.curve:
        from ..plots import require_matplotlib

        check_outputs({"--curve": args.curve}, {"SOURCE": args.source, "TARGET": args.target, "MAP": args.map})
        require_matplotlib()
    source = read_mesh(args.source, name=f"SOURCE {args.source}")
    n_source = len(source[0])
    target = as_mesh(args.target, name=f"TARGET {args.target}")
    mapping = read_checked_map(args.map, n_source, target.n_vertices)
    truth = load_ground_truth(args.gt, n_source=n_source, n_target=target.n_vertices)
    sym = (load_ground_truth(_sym_spec(args.gt, args.sym), n_source=n_source,
                             n_target=target.n_vertices) if args.sym else None)
    report = evaluate_map(target, mapping, truth, sym_truth=sym, thresholds=thresholds,
                          geodesic=args.geodesic)
    if args.curve:
        from ..plots import plot_cumulative_curves

        curves = {"direct truth": cumulative_curve(report["errors"])}
        if sym is not None:
            curves["mirrored truth"] = cumulative_curve(report["sym_errors"])
        plot_cumulative_curves(args.curve, curves, title=f"{args.map} on {args.target}")
    summary = scalar_summary(report)
    summary.update(map_quality(Mesh(*source, name=args.source), target, mapping))
    summary.update(source=args.source, target=args.target, map=args.map, geodesic=args.geodesic)
    if args.json:
        json.dump(summary, sys.stdout, indent=2)
        sys.stdout.write("\n")
        return 0
    under = " / ".join(f"{100 * v:.1f} %" for v in report["under"].values())
    print(f"points evaluated:      {report['n_points']}"
          + (f" ({report['n_unmapped']} unmapped, counted as misses)" if report["n_unmapped"] else ""))
    print(f"mean geodesic error:   {report['mean_error']:.4f}  (divided by sqrt(area of TARGET) "
          f"= {report['sqrt_area']:.4g})")
    print(f"under {' / '.join(report['under'])}: {under}")
    print(f"total geodesic error:  {report['total_error']:.6g} (TARGET units; "
          f"{report['total_error_normalized']:.4g} normalised)")
    print(f"coverage:              {100 * summary['coverage']:.1f} % of TARGET's area reached; "
          f"bijectivity {summary['bijectivity']:.3f}")
    print(f"continuity:            {summary['continuity']:.3f} (edge-length ratio; "
          f"{100 * summary['torn_edges']:.1f} % of edges torn)")
    if sym is not None:
        verdict = "FLIPPED (closer to the mirrored truth)" if report["flipped"] else "not flipped"
        print(f"vs mirrored truth:     {report['sym_mean_error']:.4f} -> {verdict}")
    return 0
