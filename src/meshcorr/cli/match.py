"""``meshcorr match``: compute a vertex map and write it."""

from __future__ import annotations

import argparse
import json
import os
import sys

from ..baselines import METHODS, SPATIAL_METHODS
from ..errors import ParameterError
from ..geodesics import GEODESIC_METHODS
from ..modes import MODES, N_SAMPLES, SCALABLE_ABOVE
from ..reorder import REORDER_MODES
from ._progress import StageProgress

HELP = "compute the vertex map from SOURCE to TARGET"

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
--bijective, --largest-component, --seed and --no-prealign. Options that do
not apply to the chosen method are ignored.

Meshes: OFF, OBJ, PLY or STL triangle meshes (vertex order is kept as in the
file). Output: line i of MAP holds the 0-based index of the TARGET vertex
matched to SOURCE vertex i (-1 if that vertex was not mapped, see
--largest-component); a .npy extension writes a NumPy int64 array instead.
"""


def add_parser(sub) -> None:
    p = sub.add_parser("match", help=HELP, description=DESCRIPTION,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("source", metavar="SOURCE", help="mesh whose vertices are mapped")
    p.add_argument("target", metavar="TARGET", help="mesh they are mapped onto")
    p.add_argument("-o", "--output", metavar="MAP", required=True,
                   help="where to write the map (.txt: one index per line; .npy: NumPy array)")
    g = p.add_argument_group("method")
    g.add_argument("--method", choices=tuple(METHODS), default="spectral",
                   help="the spectral method or one of the paper's baselines (default: spectral; "
                        "see above for the options each uses)")
    g.add_argument("--no-prealign", dest="prealign", action="store_false",
                   help=f"do not centre, scale and rotate the inputs to their principal axes "
                        f"before a spatial method ({', '.join(SPATIAL_METHODS)})")
    g.add_argument("-k", type=int, default=6,
                   help="eigenpairs computed; the embedding has k-1 dimensions (default: 6, the paper's)")
    g.add_argument("--geodesic", choices=GEODESIC_METHODS, default="heat",
                   help="geodesic solver: heat method, fast marching, exact MMP (needs "
                        "meshcorr[exact]) or edge Dijkstra (default: heat)")
    g.add_argument("--reorder", choices=REORDER_MODES, default="exhaustive",
                   help="eigenvector reordering and sign correction (default: exhaustive)")
    g.add_argument("--no-eigenvalue-scaling", dest="scale_eigenvalues", action="store_false",
                   help="use plain eigenvectors instead of scaling them by sqrt(eigenvalue)")
    g.add_argument("--icp-iterations", type=int, default=10,
                   help="most thin-plate-spline ICP iterations; 0 skips the alignment (default: 10)")
    g.add_argument("--anchors", type=int, default=3, dest="n_anchors",
                   help="anchor pairs h for proximity-aided matching; 0 disables it (default: 3)")
    g.add_argument("--alpha", type=float, default=1.0, dest="anchor_weight",
                   help="weight of each anchor's geodesic term (default: 1)")
    g.add_argument("--bijective", action="store_true",
                   help="one-to-one map by linear assignment (needs equal vertex counts)")
    g.add_argument("--largest-component", action="store_true",
                   help="map only the largest connected component of each mesh instead of "
                        "failing on meshes with several components")
    g.add_argument("--seed", type=int, default=0, help="random seed (default: 0)")
    g.add_argument("--symmetry", choices=("auto", "cost", "mirror"), default="auto",
                   help="choice among near-tied eigenvector configurations: auto keeps the "
                        "orientation-preserving map whose curvature agrees best (resolves the left/right "
                        "mirror and front/back half turns), cost the cheapest "
                        "configuration (the paper), mirror the other one (default: auto)")
    g.add_argument("--refine", action=argparse.BooleanOptionalAction, default=True,
                   help="refine the map by ZoomOut spectral upsampling (default: on)")
    g.add_argument("--anchor-scale", choices=("embedding", "geodesic"), default="embedding",
                   help="scale of the anchor term: the embedding's length scale, or geodesics divided "
                        "by the largest one as in the paper (default: embedding)")
    s = p.add_argument_group("scale")
    s.add_argument("--mode", choices=MODES, default="auto",
                   help="dense: all-pairs geodesics and exact eigenpairs (n x n memory, the reference); "
                        f"scalable: landmark geodesics and the Nystrom extension; auto: dense up to "
                        f"{SCALABLE_ABOVE} vertices if it fits in --max-memory, else scalable (default: auto)")
    s.add_argument("--samples", type=int, default=N_SAMPLES, dest="n_samples", metavar="N",
                   help=f"Nystrom samples (landmark vertices) of the scalable mode (default: {N_SAMPLES})")
    s.add_argument("--landmarks", metavar="FILE", dest="landmarks_file", help=argparse.SUPPRESS)
    s.add_argument("--max-memory", metavar="SIZE", default=None,
                   help="memory the dense mode may use, e.g. 4GiB or 500MB; larger inputs are refused "
                        "(default: 80%% of the memory available)")
    o = p.add_argument_group("output")
    o.add_argument("--json", action="store_true",
                   help="print a machine-readable summary (timings, configuration, cost) on stdout")
    o.add_argument("--alternative-out", metavar="MAP",
                   help="also write the alternative map (usually the left/right mirror image of MAP)")
    o.add_argument("-q", "--quiet", action="store_true", help="no progress on stderr")
    o.add_argument("--report", metavar="REPORT.html",
                   help="also write a self-contained HTML report: linked rotatable 3-D views coloured "
                        "by the correspondence, stage timings, eigenvector configuration")
    o.add_argument("--gt", nargs="+", metavar="GT",
                   help="ground truth for the report's error curve ('identity', SOURCE.vts "
                        "TARGET.vts, or a file of 0-based pairs)")
    p.set_defaults(run=run)


def check_output_path(path: str) -> None:
    """Fail before hours of work if the output cannot be written."""
    folder = os.path.dirname(os.path.abspath(path)) or "."
    if not os.path.isdir(folder):
        raise ParameterError(f"Cannot write {path}: the folder {folder} does not exist. Create it first.")
    if not os.access(folder, os.W_OK):
        raise ParameterError(f"Cannot write {path}: no permission to write in {folder}.")
    if os.path.isdir(path):
        raise ParameterError(f"Cannot write {path}: it is a folder. Give a file name such as map.txt.")


def run(args) -> int:
    from .. import match
    from ..io import write_map

    if args.landmarks_file is not None:
        if args.landmarks_file.strip().isdigit():
            raise ParameterError(f"--landmarks N was renamed --samples N (the Nystrom sample count of the "
                                 f"scalable mode): use --samples {args.landmarks_file.strip()}.")
        raise ParameterError("--landmarks FILE (user landmark pairs) is not supported yet; for the Nystrom "
                             "sample count use --samples N.")
    check_output_path(args.output)
    if args.alternative_out:
        check_output_path(args.alternative_out)
    if args.report:
        check_output_path(args.report)
    elif args.gt:
        raise ParameterError("--gt is used by the HTML report only: add --report REPORT.html "
                             "(or score the map with 'meshcorr evaluate').")
    progress = None if args.quiet else StageProgress(sys.stderr)
    result = match(args.source, args.target, symmetry=args.symmetry, refine=args.refine,
                   anchor_scale=args.anchor_scale, k=args.k, geodesic=args.geodesic,
                   scale_eigenvalues=args.scale_eigenvalues, reorder=args.reorder,
                   icp_iterations=args.icp_iterations, n_anchors=args.n_anchors,
                   anchor_weight=args.anchor_weight, bijective=args.bijective,
                   largest_component=args.largest_component, random_state=args.seed,
                   progress=progress, method=args.method, prealign=args.prealign, mode=args.mode,
                   n_samples=args.n_samples, max_memory=args.max_memory)
    write_map(args.output, result.map)
    if args.alternative_out:
        if result.alternative_map is None:
            raise ParameterError(f"No alternative map to write to {args.alternative_out}: only the spectral "
                                 "method with at least two eigenvector configurations has one.")
        write_map(args.alternative_out, result.alternative_map)
    summary = result.summary()
    summary.update(source=args.source, target=args.target, output=args.output)
    if args.report:
        _write_report(args, result.map, summary)
    if args.json:
        json.dump(summary, sys.stdout, indent=2)
        sys.stdout.write("\n")
    elif not args.quiet:
        total = sum(result.timings.values())
        print(f"meshcorr: wrote {args.output}: {summary['n_mapped']} source vertices mapped onto "
              f"{summary['n_target_hit']} target vertices in {total:.1f} s", file=sys.stderr)
    return 0


def _write_report(args, mapping, summary: dict) -> None:
    """The HTML report of ``--report``, with the error curve when ``--gt`` is given."""
    import numpy as np

    from ..evaluation import geodesic_errors
    from ..ground_truth import load_ground_truth
    from ..io import read_mesh
    from ..viz.report import write_report

    source = read_mesh(args.source, name=args.source)
    target = read_mesh(args.target, name=args.target)
    errors = None
    if args.gt:
        truth = load_ground_truth(args.gt, n_source=len(source[0]), n_target=len(target[0]))
        predicted = mapping[truth.source]
        errors = np.full(len(truth.source), np.nan)
        mapped = predicted >= 0
        if mapped.any():
            errors[mapped] = geodesic_errors(target, predicted[mapped], truth.target[mapped],
                                             method=args.geodesic)
    write_report(args.report, source, target, mapping, summary, errors=errors,
                 title=f"meshcorr: {args.source} -> {args.target}")
