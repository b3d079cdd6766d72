"""``meshcorr evaluate``: score a vertex map against ground truth."""

from __future__ import annotations

import argparse
import json
import sys

import numpy as np

from ..core.geodesics import GEODESIC_METHODS

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

TARGET must be one connected surface (geodesic errors); for a map made with
'meshcorr match --largest-component', pass --largest-component here too: the
errors are measured on TARGET's largest piece (map entries and true vertices
elsewhere are counted as misses / left out, and said so).
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
                   help="also save the cumulative error curve as a .png (needs meshcorr[plot])")
    p.add_argument("--largest-component", action="store_true",
                   help="measure on TARGET's largest connected piece (default: a TARGET of several "
                        "pieces is refused)")
    p.add_argument("--json", action="store_true", help="print the report as JSON on stdout")
    p.set_defaults(run=run)


def _thresholds(text: str) -> list[float]:
    from ..runtime.checks import check_float
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


def _restrict_to_piece(target, mapping: np.ndarray, truths: list, quiet: bool, where: str):
    """The map and truths renumbered onto TARGET's kept piece (``target.kept``): map entries elsewhere
    become -1 (misses), truth pairs elsewhere are left out; each change is said on stderr."""
    from ..evaluation.ground_truth import GroundTruth

    new_index = np.full(target.n_original, -1, dtype=np.int64)
    new_index[target.kept] = np.arange(target.n_vertices)
    mapped = mapping >= 0
    off = int((mapped & (new_index[np.maximum(mapping, 0)] < 0)).sum())
    mapping = np.where(mapped, new_index[np.maximum(mapping, 0)], -1)
    if not quiet:
        print(f"meshcorr: measuring on the largest piece of {where}: {target.n_vertices} of its "
              f"{target.n_original} vertices; {off} map entries point elsewhere (counted as misses)",
              file=sys.stderr)
    restricted = []
    for truth in truths:
        if truth is None:
            restricted.append(None)
            continue
        keep = new_index[truth.target] >= 0
        if not keep.any():
            from ..errors import InputError

            raise InputError(f"No ground-truth pair of {truth.description or '--gt'} lies on the largest "
                             f"piece of {where}: there is nothing to score there.")
        if not keep.all() and not quiet:
            print(f"meshcorr: {int((~keep).sum())} of {keep.size} ground-truth pairs of "
                  f"{truth.description or '--gt'} lie on other pieces: left out", file=sys.stderr)
        restricted.append(GroundTruth(truth.source[keep], new_index[truth.target[keep]], truth.description))
    return mapping, restricted


def _finite(value):
    """``value`` with every NaN or infinite float replaced by None (JSON has no NaN: jq and browsers
    refused the report)."""
    if isinstance(value, dict):
        return {key: _finite(item) for key, item in value.items()}
    if isinstance(value, (list, tuple)):
        return [_finite(item) for item in value]
    if isinstance(value, float) and not np.isfinite(value):
        return None
    return value


def run(args) -> int:
    from ..core.mesh import Mesh
    from ..evaluation.metrics import GeodesicCache, cumulative_curve, evaluate_map, map_quality, scalar_summary
    from .match import reporting

    thresholds = _thresholds(args.thresholds)
    if args.curve:
        _check_curve(args)
    source, target, mapping, truth, sym = _read_inputs(args)
    # The geodesic solves take minutes on a large TARGET with a dense truth: say how far they are.
    # A phase per truth, each with its own label ("geodesic errors", then "... (mirrored truth)").
    with reporting(args, f"{args.map} on {args.target}") as progress:
        cache = GeodesicCache(args.geodesic, progress=progress)
        report = evaluate_map(target, mapping, truth, sym_truth=sym, thresholds=thresholds,
                              geodesic=args.geodesic, cache=cache)
    summary = scalar_summary(report)
    summary.update(map_quality(Mesh(*source, name=args.source), target, mapping))
    summary.update(source=args.source, target=args.target, map=args.map, geodesic=args.geodesic)
    if args.curve:  # the last work: an interrupt before it leaves no curve behind
        from ..viz.plots import plot_cumulative_curves

        curves = {"direct truth": cumulative_curve(report["errors"])}
        if sym is not None:
            curves["mirrored truth"] = cumulative_curve(report["sym_errors"])
        plot_cumulative_curves(args.curve, curves, title=f"{args.map} on {args.target}")
    if args.json:  # strict JSON: an error that cannot be measured (no truth point mapped) is null, not NaN
        json.dump(_finite(summary), sys.stdout, indent=2, allow_nan=False)
        sys.stdout.write("\n")
        return 0
    _print_report(report, summary, sym is not None)
    return 0


def _check_curve(args) -> None:
    """--curve: a PNG path that does not overwrite an input, and matplotlib installed; before any work."""
    from ..io import check_outputs
    from ..viz.plots import require_matplotlib
    from .show import check_png, truth_inputs

    check_png(args.curve, "--curve")
    check_outputs({"--curve": args.curve},
                  {"SOURCE": args.source, "TARGET": args.target, "MAP": args.map,
                   **truth_inputs(args.gt), **truth_inputs(args.sym, "--sym")})
    require_matplotlib()


def _read_inputs(args):
    """``(source, target, mapping, truth, sym)``: SOURCE as read (vertices, faces), the TARGET mesh, MAP and the truth.

    With --largest-component the map and the truth are restricted to TARGET's largest piece.
    """
    from ..core.mesh import as_mesh
    from ..errors import InputError
    from ..evaluation.ground_truth import load_ground_truth
    from ..io import read_mesh
    from ._mapfile import read_checked_map
    from .show import one_surface

    source = read_mesh(args.source, name=f"SOURCE {args.source}")
    n_source = len(source[0])
    if args.largest_component:
        target = as_mesh(args.target, name=f"TARGET {args.target}", largest_component=True)
    else:
        target = one_surface(args.target, "TARGET", "Geodesic errors need one connected surface: pass "
                             "--largest-component to measure on its largest piece (as 'meshcorr match "
                             "--largest-component' maps onto it).")
    n_target = target.n_original if args.largest_component else target.n_vertices
    mapping = read_checked_map(args.map, n_source, n_target)
    if not (mapping >= 0).any():
        raise InputError(f"{args.map} maps no SOURCE vertex (every entry is -1): there is nothing to "
                         "score. Check that it is the map you meant.")
    truth = load_ground_truth(args.gt, n_source=n_source, n_target=n_target)
    sym = (load_ground_truth(_sym_spec(args.gt, args.sym), n_source=n_source,
                             n_target=n_target) if args.sym else None)
    if target.n_vertices < n_target:
        mapping, (truth, sym) = _restrict_to_piece(target, mapping, [truth, sym], args.quiet, args.target)
        if not (mapping >= 0).any():
            raise InputError(f"{args.map} maps no SOURCE vertex onto the largest piece of {args.target}: "
                             "there is nothing to score there.")
    return source, target, mapping, truth, sym


def _print_report(report: dict, summary: dict, mirrored: bool) -> None:
    """The scores on stdout, one line each (the text form; --json writes ``summary``)."""
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
    if mirrored:
        verdict = "FLIPPED (closer to the mirrored truth)" if report["flipped"] else "not flipped"
        print(f"vs mirrored truth:     {report['sym_mean_error']:.4f} -> {verdict}")
