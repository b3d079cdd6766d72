"""``meshcorr match``: compute a vertex map and write it."""

from __future__ import annotations

import argparse
import dataclasses
import json
import os
import sys
from contextlib import contextmanager

import numpy as np

from ..baselines import METHODS, SPATIAL_METHODS
from ..errors import InputError, LandmarkError, ParameterError
from ..core.geodesics import GEODESIC_METHODS
from ..spectral.modes import MODES
from ..pipeline.settings import Settings
from ..stages.reorder import REORDER_MODES
from ._mapfile import print_map
from ..runtime.progress import MATCH_PLAN, RunPlan, StderrProgress

HELP = "compute the vertex map from SOURCE to TARGET"

#: Every option's default (the one source: :class:`meshcorr.Settings`).
DEFAULTS = Settings()

DESCRIPTION = """\
Compute a dense vertex-to-vertex map from SOURCE to TARGET with the spectral
method of Jain & Zhang (2006): geodesic distances -> Gaussian affinities ->
spectral embedding scaled by sqrt(eigenvalues) -> eigenvector reordering and
sign correction -> thin-plate-spline ICP -> proximity-aided matching.

--method picks one of the paper's baselines instead: shapiro-brady (Shapiro &
Brady 1992: unscaled eigenvectors, greedy signs, nearest match),
shapiro-brady-scaled (the same with eigenvalue scaling), tps-rpm (Chui &
Rangarajan 2003), icp (robust similarity ICP, Besl & McKay 1992) or
shape-context (3D shape contexts, Belongie et al. 2002 / Frome et al. 2004).
The Shapiro-Brady variants use -k, --geodesic, --bijective and
--largest-component; the spatial ones (tps-rpm, icp, shape-context) use
--bijective, --largest-component, --seed and --no-prealign. An option set to
a value other than its default that the chosen method does not use is
refused (exit 2), naming it.

Meshes: OFF, OBJ, PLY or STL triangle meshes (vertex order is kept as in the
file; the README's "Reading meshes: input rules" says what is checked).
Point clouds, for either side: any of those files without faces (e.g. a PLY
of points), .xyz text (x y z per line; further columns are ignored) or .npy
(an (n, 3) array); --geodesic heat or dijkstra; see the README's "Point
clouds".
Output: line i of MAP holds the 0-based index of the TARGET vertex matched to
SOURCE vertex i (-1 if that vertex was not mapped, see --largest-component);
a .npy extension writes a NumPy int64 array instead, '-o -' writes the text
map on stdout. Every output path is checked before the work starts, none may
be an input, and the outputs appear together when the run ends (none on an
error or Ctrl-C).
"""


def add_parser(sub) -> None:
    p = sub.add_parser("match", help=HELP, description=DESCRIPTION,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("source", metavar="SOURCE", help="mesh or point cloud whose vertices are mapped")
    p.add_argument("target", metavar="TARGET", help="mesh or point cloud they are mapped onto")
    p.add_argument("-o", "--output", metavar="MAP",
                   help="where to write the map (.txt: one index per line; .npy: NumPy array; "
                        "'-': text on stdout); may be left out with --json")
    g = p.add_argument_group("method")
    g.add_argument("--method", choices=tuple(METHODS), default=DEFAULTS.method,
                   help=f"the spectral method or one of the paper's baselines (default: {DEFAULTS.method}; "
                        "see above for the options each uses)")
    g.add_argument("--no-prealign", dest="prealign", action="store_false",
                   help=f"do not centre, scale and rotate the inputs to their principal axes "
                        f"before a spatial method ({', '.join(SPATIAL_METHODS)})")
    g.add_argument("-k", type=int, default=DEFAULTS.k,
                   help="eigenpairs computed, 2 to 10; the embedding has k-1 dimensions "
                        f"(default: {DEFAULTS.k}, the paper's)")
    g.add_argument("--geodesic", choices=GEODESIC_METHODS, default=DEFAULTS.geodesic,
                   help="geodesic solver: heat method, fast marching, exact MMP (needs "
                        f"meshcorr[exact]) or edge Dijkstra (default: {DEFAULTS.geodesic})")
    g.add_argument("--reorder", choices=REORDER_MODES, default=DEFAULTS.reorder,
                   help=f"eigenvector reordering and sign correction (default: {DEFAULTS.reorder})")
    g.add_argument("--no-eigenvalue-scaling", dest="scale_eigenvalues", action="store_false",
                   help="use plain eigenvectors instead of scaling them by sqrt(eigenvalue)")
    g.add_argument("--icp-iterations", type=int, default=DEFAULTS.icp_iterations,
                   help="most thin-plate-spline ICP iterations; 0 skips the alignment "
                        f"(default: {DEFAULTS.icp_iterations})")
    g.add_argument("--control-points", type=int, default=DEFAULTS.n_control, dest="n_control", metavar="N",
                   help=f"control points of each thin-plate-spline fit (default: {DEFAULTS.n_control})")
    g.add_argument("--anneal", type=float, default=DEFAULTS.anneal,
                   help=f"factor by which the TPS smoothing shrinks each ICP iteration (default: {DEFAULTS.anneal:g})")
    g.add_argument("--anchors", type=int, default=DEFAULTS.n_anchors, dest="n_anchors",
                   help=f"anchor pairs h for proximity-aided matching; 0 disables it (default: {DEFAULTS.n_anchors})")
    g.add_argument("--alpha", type=float, default=DEFAULTS.anchor_weight, dest="anchor_weight",
                   help=f"weight of each anchor's geodesic term (default: {DEFAULTS.anchor_weight:g})")
    g.add_argument("--bijective", action="store_true",
                   help="one-to-one map by linear assignment (needs equal vertex counts)")
    g.add_argument("--largest-component", action="store_true",
                   help="map only the largest connected component of each mesh instead of "
                        "failing on meshes with several components")
    g.add_argument("--seed", type=seed, default=DEFAULTS.random_state,
                   help=f"random seed, an integer >= 0 (default: {DEFAULTS.random_state})")
    g.add_argument("--symmetry", choices=("auto", "cost", "mirror"), default=DEFAULTS.symmetry,
                   help="choice among near-tied eigenvector configurations: auto keeps the "
                        "orientation-preserving map whose curvature agrees best, then makes the whole-map "
                        "choice with the extremities and --landmarks (resolves the left/right mirror and "
                        "front/back half turns); cost keeps the cheapest configuration (the paper); mirror "
                        "the configuration of the other orientation than auto's (the same map as cost when "
                        "that is the cheapest). cost and mirror skip the whole-map choice and do not go "
                        "with --landmarks (default: auto)")
    g.add_argument("--refine", action=argparse.BooleanOptionalAction, default=DEFAULTS.refine,
                   help="refine the map by ZoomOut spectral upsampling (default: on)")
    g.add_argument("--refine-k", type=int, default=DEFAULTS.refine_k, metavar="K",
                   help=f"Laplace-Beltrami basis size the refinement ends with (default: {DEFAULTS.refine_k})")
    g.add_argument("--landmarks", metavar="FILE", dest="landmarks_file",
                   help="vertices known to correspond: one 'source_index target_index' pair a line, "
                        "0-based; they settle the left/right choice and are mapped exactly "
                        "(the Nystrom sample count, once --landmarks N, is --samples N)")
    g.add_argument("--landmarks-vts", nargs=2, metavar=("SOURCE.vts", "TARGET.vts"),
                   help="landmarks as a TOSCA-style .vts pair instead: line k of each file is the "
                        "1-based vertex of landmark k on that mesh")
    g.add_argument("--shells", action=argparse.BooleanOptionalAction, default=DEFAULTS.shells,
                   help="after the refinement, align the shapes' smooth shells (a rigid motion and a smooth "
                        "deformation) and map in that space and the spectral one; meshes only (default: on)")
    g.add_argument("--no-extremities", dest="extremities", action="store_false",
                   help="do not try maps started from matched shape extremities (faster; they are "
                        "what holds when the shapes' proportions differ)")
    g.add_argument("--oriented-starts", action="store_true",
                   help="also start maps from the matched tips by an orientation-preserving fit: better "
                        "for people standing (head, hands and feet in one plane cannot tell front from "
                        "back), worse across species (default: off)")
    g.add_argument("--sign-search", action=argparse.BooleanOptionalAction, default=DEFAULTS.sign_search,
                   help="also start the whole-map choice from every sign configuration of the first "
                        "Laplace-Beltrami functions, the best by their smooth-shell alignment (a wider search "
                        f"for the global configuration; default: {'on' if DEFAULTS.sign_search else 'off'})")
    g.add_argument("--check-reverse", action="store_true", default=DEFAULTS.check_reverse,
                   help="also match TARGET to SOURCE and report how far a round trip moves source vertices "
                        "(--json: confidence.cycle_error); a large one means one of the two maps is turned or "
                        "mirrored, and is warned about. Doubles the time (default: off)")
    g.add_argument("--partial", choices=("source", "target"), default=DEFAULTS.partial,
                   help="SOURCE is a part of TARGET (one side of a scan, a cut, large holes), or the reverse: "
                        "the map covers the part only (with 'target', SOURCE vertices outside the matched "
                        "region get -1) and --json reports the matched region of the whole shape "
                        "(default: both are whole)")
    g.add_argument("--fill-holes", action=argparse.BooleanOptionalAction, default=DEFAULTS.fill_holes,
                   help="close each hole of the meshes (a boundary loop) by a fan of triangles before "
                        "matching; the map covers the input's vertices only. Not with --partial or "
                        "--bijective, which keep the boundary (default: on)")
    g.add_argument("--anchor-scale", choices=("embedding", "geodesic"), default=DEFAULTS.anchor_scale,
                   help="scale of the anchor term: the embedding's length scale, or geodesics divided "
                        "by the largest one as in the paper (default: embedding)")
    s = p.add_argument_group("scale")
    s.add_argument("--coarse-vertices", type=int, default=DEFAULTS.coarse_vertices, metavar="N",
                   help="make the global choice on coarse copies of about N vertices (meshes with more are "
                        "decimated) and refine only the chosen map on the full meshes: the choice then costs "
                        "the same at any size. 0 runs every step on the full meshes (slower above a few "
                        f"thousand vertices; default: {DEFAULTS.coarse_vertices})")
    s.add_argument("--mode", choices=MODES, default=DEFAULTS.mode,
                   help="dense: all-pairs geodesics and exact eigenpairs (n x n memory, the reference); "
                        f"scalable: landmark geodesics and the Nystrom extension; auto: dense up to "
                        f"{DEFAULTS.scalable_above} vertices if it fits in --max-memory, else scalable (default: {DEFAULTS.mode})")
    s.add_argument("--samples", type=int, default=DEFAULTS.n_samples, dest="n_samples", metavar="N",
                   help=f"Nystrom samples (landmark vertices) of the scalable mode (default: {DEFAULTS.n_samples})")
    s.add_argument("--scalable-above", type=int, default=DEFAULTS.scalable_above, metavar="N",
                   help=f"--mode auto: the scalable mode when the larger mesh has more than this many vertices "
                        f"(default: {DEFAULTS.scalable_above})")
    s.add_argument("--max-memory", metavar="SIZE", default=DEFAULTS.max_memory,
                   help="memory the dense mode may use, e.g. 4GiB or 500MB; larger inputs are refused "
                        "(default: 80%% of the memory available)")
    o = p.add_argument_group("output")
    o.add_argument("--json", action="store_true",
                   help="print a machine-readable summary (timings, configuration, cost) on stdout "
                        "(then -o may be left out)")
    o.add_argument("--alternative-out", metavar="MAP",
                   help="also write the alternative map (usually the left/right mirror image of MAP)")
    o.add_argument("--report", metavar="REPORT.html",
                   help="also write a self-contained HTML report: linked rotatable 3-D views coloured "
                        "by the correspondence, stage timings, eigenvector configuration")
    o.add_argument("--gt", action="append", metavar="GT",
                   help="ground truth for the report's error curve: 'identity', a file of 0-based "
                        "pairs, or a .vts pair given as --gt SOURCE.vts --gt TARGET.vts")
    p.set_defaults(run=run)


def seed(text: str) -> int:
    """``--seed``: an integer >= 0 (numpy's generators refuse negative seeds)."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected an integer >= 0, got {text!r}") from None
    if value < 0:
        raise argparse.ArgumentTypeError(f"expected an integer >= 0, got {value}")
    return value


def check_output_path(path: str, what: str = "the output") -> None:
    """Fail before hours of work if the output cannot be written (:func:`meshcorr.io.check_outputs`)."""
    from ..io import check_outputs

    check_outputs({what: path})


def progress_for(args, label: str, plan: RunPlan | None = None) -> StderrProgress | None:
    """The progress callback of ``-q`` / default / ``-v``: lines on stderr naming ``label``.

    With ``plan`` (``match``: :data:`~meshcorr.runtime.progress.MATCH_PLAN`), one line for the whole run;
    without, a line per stage. Close it when the work ends (:func:`reporting`).
    """
    if args.quiet:
        return None
    return StderrProgress(sys.stderr, label=label, delay=0.0 if args.verbose else 1.0, plan=plan,
                          verbose=args.verbose)


@contextmanager
def reporting(args, label: str, plan: RunPlan | None = None):
    """:func:`progress_for` for a block; closed as the block ends, by an error or Ctrl-C too (its thread stops)."""
    progress = progress_for(args, label, plan)
    try:
        yield progress
    finally:
        close = getattr(progress, "close", None)
        if close is not None:
            close()


def run(args) -> int:
    from ..io import check_outputs, staged_writes, write_map

    if (args.landmarks_file is not None and args.landmarks_file.strip().isdigit()
            and not os.path.isfile(args.landmarks_file)):
        raise ParameterError(f"--landmarks N was renamed --samples N (the Nystrom sample count of the "
                             f"scalable mode): use --samples {args.landmarks_file.strip()}. --landmarks "
                             "now takes a FILE of corresponding vertex pairs.")
    if args.landmarks_file is not None and args.landmarks_vts:
        raise ParameterError("Give the landmarks once: --landmarks FILE or --landmarks-vts A.vts B.vts.")
    if args.output is None and not args.json:
        raise ParameterError("Give -o MAP for the map (or -o - for stdout), or --json for the summary only.")
    if args.output == "-" and args.json:
        raise ParameterError("-o - and --json both write to stdout; write the map to a file instead.")
    if args.gt and not args.report:
        raise ParameterError("--gt is used by the HTML report only: add --report REPORT.html "
                             "(or score the map with 'meshcorr evaluate').")
    inputs = {"SOURCE": args.source, "TARGET": args.target}
    inputs.update({f"--gt {gt}": gt for gt in args.gt or () if gt != "identity"})
    inputs.update({"--landmarks": args.landmarks_file} if args.landmarks_file else {})
    inputs.update({f"--landmarks-vts {v}": v for v in args.landmarks_vts or ()})
    check_outputs({"-o": args.output, "--alternative-out": args.alternative_out, "--report": args.report},
                  inputs, stdout=("-o",))
    landmarks, origin = _read_landmarks(args)
    report_inputs = _read_truth(args)  # a bad --gt is said before the work, not after it
    if args.verbose:
        print(f"meshcorr: matching {args.source} -> {args.target}", file=sys.stderr)
    with _landmark_lines(landmarks, origin):
        result = _match(args, landmarks)
    if args.alternative_out and result.alternative_map is None:
        raise ParameterError(f"No alternative map to write to {args.alternative_out}: only the spectral "
                             "method with at least two eigenvector configurations has one.")
    summary = result.summary()
    summary.update(source=args.source, target=args.target, output=args.output)
    # All outputs appear together, or none (an error in the report, or Ctrl-C, leaves no map).
    with staged_writes():
        if args.output not in (None, "-"):
            write_map(args.output, result.map)
        if args.alternative_out:
            write_map(args.alternative_out, result.alternative_map)
        if args.report:
            _write_report(args, result.map, summary, *report_inputs)
    if args.output == "-":
        print_map(result.map)
    if args.json:
        json.dump(summary, sys.stdout, indent=2)
        sys.stdout.write("\n")
        sys.stdout.flush()
    if not args.quiet:
        total = sum(result.timings.values())
        where = "stdout" if args.output == "-" else args.output
        if where:
            print(f"meshcorr: wrote {where}: {summary['n_mapped']} source vertices mapped; they land on "
                  f"{summary['n_target_hit']} distinct target vertices ({total:.1f} s)", file=sys.stderr)
        if (result.confidence or {}).get("low") and args.output not in (None, "-"):
            import shlex

            print("meshcorr: to settle the choice, click a few landmarks on the map: meshcorr pick "
                  + " ".join(shlex.quote(str(a)) for a in (args.source, args.target, "--map", args.output))
                  + " -o landmarks.txt", file=sys.stderr)
        closed = result.params.get("holes_closed")
        if closed:
            print(f"meshcorr: closed {closed['source']} hole(s) of SOURCE and {closed['target']} of TARGET "
                  "before matching (--no-fill-holes keeps them open)", file=sys.stderr)
        if summary["partial"] is not None:
            report = summary["partial"]
            print(f"meshcorr: the {report['part']} is a part of the {report['whole']}: the matched region is "
                  f"{report['matched_area_fraction']:.0%} of the {report['whole']}'s area "
                  f"({report['n_matched_vertices']} vertices, listed in --json)", file=sys.stderr)
        for what, path in (("alternative map", args.alternative_out), ("report", args.report)):
            if path:
                print(f"meshcorr: wrote the {what} {path}", file=sys.stderr)
    return 0


def _match(args, landmarks):
    """``meshcorr.match`` with the options of ``meshcorr match`` (:func:`settings_of`)."""
    from .. import match

    # Large PLY/OFF files that would not fit --max-memory: match refuses them from their headers.
    settings = settings_of(args, landmarks)
    label = f"{os.path.basename(args.source)} -> {os.path.basename(args.target)}"
    with reporting(args, label, MATCH_PLAN) as progress:
        return match(args.source, args.target, settings, progress=progress)


def settings_of(args, landmarks) -> Settings:
    """The :class:`~meshcorr.Settings` of parsed ``meshcorr match`` options (dest = field name; ``--seed``)."""
    names = [f.name for f in dataclasses.fields(Settings) if f.name not in ("random_state", "landmarks")]
    return Settings.from_options(**{name: getattr(args, name) for name in names}, random_state=args.seed,
                                 landmarks=landmarks)


def _read_landmarks(args):
    """The ``(L, 2)`` pairs of ``--landmarks`` or ``--landmarks-vts`` (or None), and where they came from.

    The second item, for messages (None without landmarks): the files of the source and target
    columns, each pair's ``(L, 2)`` line numbers in them, and the base the indices are written in
    (1 in a ``.vts``).
    """
    if args.landmarks_file is not None:
        from ..stages.landmarks import read_landmark_lines

        pairs, numbers = read_landmark_lines(args.landmarks_file)
        return pairs, ((args.landmarks_file,) * 2, np.stack([numbers, numbers], axis=1), 0)
    if args.landmarks_vts:
        from ..evaluation.ground_truth import read_vts_lines

        (a, lines_a), (b, lines_b) = (read_vts_lines(path, "landmark") for path in args.landmarks_vts)
        if len(a) != len(b):
            raise ParameterError(f"--landmarks-vts: {args.landmarks_vts[0]} has {len(a)} lines and "
                                 f"{args.landmarks_vts[1]} has {len(b)}; line k of each must be landmark k.")
        return np.stack([a, b], axis=1), (tuple(args.landmarks_vts), np.stack([lines_a, lines_b], axis=1), 1)
    return None, None


@contextmanager
def _landmark_lines(pairs, origin):
    """Turn a :class:`~meshcorr.errors.LandmarkError` into an input error naming the file's line (exit 3)."""
    try:
        yield
    except LandmarkError as error:
        if origin is None:
            raise
        files, lines, base = origin
        row, column = error.row, error.column
        value, side = int(pairs[row, column]) + base, ("source", "target")[column]
        if error.problem == "range":
            reason = (f"{side} vertex {value} is outside the {side} mesh's vertices "
                      f"{base}..{error.limit - 1 + base} ({'1-based, as in a .vts file' if base else '0-based'}).")
        elif error.problem == "repeat":
            reason = (f"source vertex {value} already has another target vertex on line "
                      f"{lines[error.first, 0]}; give each source vertex one target vertex.")
        else:
            reason = (f"{side} vertex {value} lies on a component that was removed (--largest-component); "
                      "choose a vertex on the largest component.")
        raise InputError(f"{files[column]}, line {lines[row, column]}: {reason}") from None


def _read_truth(args):
    """``((source, target), truth)``: the meshes as the report reads them and ``--gt`` checked against
    them, before the work; ``(None, None)`` without ``--gt``."""
    if not args.gt:
        return None, None
    from ..evaluation.ground_truth import load_ground_truth
    from ..io import read_mesh

    meshes = read_mesh(args.source, name=args.source), read_mesh(args.target, name=args.target)
    return meshes, load_ground_truth(args.gt, n_source=len(meshes[0][0]), n_target=len(meshes[1][0]))


def _write_report(args, mapping, summary: dict, meshes=None, truth=None) -> None:
    """The HTML report of ``--report``, with the error curve when ``truth`` (``--gt``, :func:`_read_truth`)
    is given; ``meshes`` as read then, else read here."""
    import numpy as np

    from ..evaluation.metrics import geodesic_errors
    from ..io import read_mesh
    from ..viz.report import write_report

    source, target = meshes or (read_mesh(args.source, name=args.source), read_mesh(args.target, name=args.target))
    errors = None
    if truth is not None:
        predicted = mapping[truth.source]
        errors = np.full(len(truth.source), np.nan)
        mapped = predicted >= 0
        if mapped.any():
            errors[mapped] = geodesic_errors(target, predicted[mapped], truth.target[mapped],
                                             method=args.geodesic)
    write_report(args.report, source, target, mapping, summary, errors=errors,
                 title=f"meshcorr: {args.source} -> {args.target}")
