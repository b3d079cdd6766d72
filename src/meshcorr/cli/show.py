"""``meshcorr show``: a picture of a vertex map by colour transfer (PNG, headless)."""

from __future__ import annotations

import argparse
import sys

import numpy as np

from ..core.geodesics import GEODESIC_METHODS

HELP = "draw a vertex map as a PNG: the target coloured by part, the source through the map"

DESCRIPTION = """\
Draw SOURCE and TARGET side by side with the same camera. TARGET is coloured
smoothly by part (or by xyz); each SOURCE vertex takes the colour of the
TARGET vertex MAP sends it to (grey: unmapped), so a good map gives both
meshes the same parts in the same colours (Jain & Zhang 2006, Figures 7-8).
--gt adds a second row with SOURCE coloured through the ground truth;
--error (with --gt) colours SOURCE by each vertex's geodesic error instead.
Needs matplotlib (pip install meshcorr[plot]); no display or GPU.
"""


#: The geodesic solver of the errors against ``--gt`` when ``--geodesic`` is not given.
GEODESIC = "heat"


def add_parser(sub) -> None:
    p = sub.add_parser("show", help=HELP, description=DESCRIPTION,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("source", metavar="SOURCE", help="mesh or point cloud whose vertices were mapped")
    p.add_argument("target", metavar="TARGET", help="mesh or point cloud they were mapped onto")
    p.add_argument("map", metavar="MAP", help="the vertex map (.txt one index per line, or .npy)")
    p.add_argument("-o", "--output", required=True, metavar="FILE.png", help="the picture to write")
    p.add_argument("--gt", action="append", metavar="GT",
                   help="ground truth ('identity', a file of 0-based pairs, or --gt SOURCE.vts "
                        "--gt TARGET.vts): adds a row coloured through it")
    p.add_argument("--error", action="store_true",
                   help="colour SOURCE by geodesic error (needs --gt)")
    p.add_argument("--coloring", choices=("parts", "xyz"), default="parts",
                   help="colouring of TARGET (default: parts)")
    p.add_argument("--geodesic", choices=GEODESIC_METHODS, default=None,
                   help=f"geodesic solver of the errors against --gt (default: {GEODESIC})")
    add_camera_arguments(p)
    p.set_defaults(run=run)


def add_camera_arguments(p) -> None:
    """The picture options shared by ``show`` and ``embed``: camera and resolution."""
    p.add_argument("--elev", type=float, default=30.0, help="camera elevation, degrees (default 30)")
    p.add_argument("--azim", type=float, default=-60.0, help="camera azimuth, degrees (default -60)")
    p.add_argument("--up", choices=("x", "y", "z"), default="z",
                   help="world axis drawn pointing up (default: z)")
    p.add_argument("--dpi", type=dpi, default=100,
                   help=f"resolution, dots per inch, {MIN_DPI}..{MAX_DPI} (default 100)")


#: The ``--dpi`` range: below it a picture is a few pixels wide, above it tens of thousands.
MIN_DPI, MAX_DPI = 10, 1000


def dpi(text: str) -> int:
    """``--dpi``: an integer in ``[MIN_DPI, MAX_DPI]`` (0 or less failed inside matplotlib, and a huge
    value ran out of memory with a message about n x n matrices)."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected an integer, got {text!r}") from None
    if not MIN_DPI <= value <= MAX_DPI:
        raise argparse.ArgumentTypeError(f"expected dots per inch from {MIN_DPI} to {MAX_DPI}, got {value}")
    return value


def check_png(path: str, what: str = "-o") -> None:
    """Refuse a picture path that does not end in .png: the picture is always a PNG (a .jpg or .pdf
    name got PNG bytes, and '-' a file named '-')."""
    from ..errors import ParameterError

    if not str(path).lower().endswith(".png"):
        raise ParameterError(f"Cannot write {what} {path}: the picture is a PNG; give a file name ending "
                             "in .png.")


def truth_inputs(specs, flag: str = "--gt") -> dict:
    """The ground-truth files of ``--gt`` / ``--sym`` as named inputs, so that no output replaces them."""
    return {f"{flag} {spec}": spec for spec in specs or () if spec != "identity"}


def one_surface(path, what: str, why: str, name: str | None = None):
    """The mesh at ``path`` as a validated Mesh; several pieces are refused with ``why`` (what needs one
    surface) instead of validation's advice to pass --largest-component, which the command does not take.

    ``what`` names the argument ("TARGET"); ``path`` may also be a ``(vertices, faces)`` pair, then
    ``name`` is its file.
    """
    from ..errors import MeshError
    from ..core.mesh import as_mesh

    name = name or str(path)
    try:
        return as_mesh(path, name=name)
    except MeshError as error:
        try:
            whole = as_mesh(path, name=name, largest_component=True)
        except MeshError:
            raise error from None
        raise MeshError(f"{what} {name} is not one connected surface: its largest piece holds "
                        f"{whole.n_vertices} of its {whole.n_original} vertices (the others are other "
                        f"pieces or vertices used by no face). {why}") from None


def dense_truth(spec, n_source: int, n_target: int) -> np.ndarray:
    """A ground truth as a dense map: ``truth[i]`` = true target of source ``i``, -1 if none."""
    from ..evaluation.ground_truth import load_ground_truth

    pairs = load_ground_truth(spec, n_source=n_source, n_target=n_target)
    truth = np.full(n_source, -1, dtype=np.int64)
    truth[pairs.source] = pairs.target
    return truth


def run(args) -> int:
    from ..errors import ParameterError
    from ..io import read_mesh
    from ._mapfile import read_checked_map
    from ..viz.plots import require_matplotlib
    from ..viz.figures import correspondence_figure
    from ..io import check_outputs
    from .match import reporting

    check_png(args.output)
    check_outputs({"-o": args.output}, {"SOURCE": args.source, "TARGET": args.target, "MAP": args.map,
                                        **truth_inputs(args.gt)})
    require_matplotlib()
    if args.error and not args.gt:
        raise ParameterError("--error colours SOURCE by its error against the ground truth: give --gt GT.")
    if args.geodesic is not None and not args.gt:
        raise ParameterError(f"--geodesic {args.geodesic} chooses the solver of the errors against the ground "
                             "truth, and without --gt there are none: it would be ignored. Remove --geodesic, "
                             "or give --gt GT.")
    source = read_mesh(args.source, name=args.source)
    if args.gt:  # the errors against the truth are geodesic distances on TARGET
        mesh = one_surface(args.target, "TARGET", "The geodesic errors of --gt need one connected "
                           "surface: draw the map without --gt, or remove the other pieces first.")
        target = (mesh.vertices, mesh.faces)
    else:
        target = read_mesh(args.target, name=args.target)
    mapping = read_checked_map(args.map, len(source[0]), len(target[0]))
    truth = dense_truth(args.gt, len(source[0]), len(target[0])) if args.gt else None
    # The geodesic errors against --gt take minutes on large meshes: say how far they are (as evaluate).
    with reporting(args, f"{args.map} on {args.target}") as progress:
        info = correspondence_figure(source, target, mapping, args.output, truth=truth,
                                     error=args.error, coloring=args.coloring, geodesic=args.geodesic or GEODESIC,
                                     elev=args.elev, azim=args.azim, up=args.up, dpi=args.dpi,
                                     map_name=args.map, progress=progress)
    line = f"wrote {args.output}"
    if info:
        line += f" (geodesic error / sqrt(area): mean {info['mean_error']:.4f})"
    if not args.quiet:
        print(f"meshcorr: {line}", file=sys.stderr)
    return 0
