"""``meshcorr show``: a picture of a vertex map by colour transfer (PNG, headless)."""

from __future__ import annotations

import argparse
import sys

import numpy as np

from ..geodesics import GEODESIC_METHODS

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
    p.add_argument("--geodesic", choices=GEODESIC_METHODS, default="heat",
                   help="geodesic solver for --error (default: heat)")
    add_camera_arguments(p)
    p.set_defaults(run=run)


def add_camera_arguments(p) -> None:
    """The picture options shared by ``show`` and ``embed``: camera and resolution."""
    p.add_argument("--elev", type=float, default=30.0, help="camera elevation, degrees (default 30)")
    p.add_argument("--azim", type=float, default=-60.0, help="camera azimuth, degrees (default -60)")
    p.add_argument("--up", choices=("x", "y", "z"), default="z",
                   help="world axis drawn pointing up (default: z)")
    p.add_argument("--dpi", type=int, default=100, help="resolution (default 100)")


def dense_truth(spec, n_source: int, n_target: int) -> np.ndarray:
    """A ground truth as a dense map: ``truth[i]`` = true target of source ``i``, -1 if none."""
    from ..ground_truth import load_ground_truth

    pairs = load_ground_truth(spec, n_source=n_source, n_target=n_target)
    truth = np.full(n_source, -1, dtype=np.int64)
    truth[pairs.source] = pairs.target
    return truth


def run(args) -> int:
    from ..errors import ParameterError
    from ..io import read_mesh
    from ._mapfile import read_checked_map
    from ..plots import require_matplotlib
    from ..viz.figures import correspondence_figure
    from ..io import check_outputs

    check_outputs({"-o": args.output}, {"SOURCE": args.source, "TARGET": args.target, "MAP": args.map})
    require_matplotlib()
    if args.error and not args.gt:
        raise ParameterError("--error colours SOURCE by its error against the ground truth: give --gt GT.")
    source = read_mesh(args.source, name=args.source)
    target = read_mesh(args.target, name=args.target)
    mapping = read_checked_map(args.map, len(source[0]), len(target[0]))
    truth = dense_truth(args.gt, len(source[0]), len(target[0])) if args.gt else None
    info = correspondence_figure(source, target, mapping, args.output, truth=truth,
                                 error=args.error, coloring=args.coloring, geodesic=args.geodesic,
                                 elev=args.elev, azim=args.azim, up=args.up, dpi=args.dpi,
                                 map_name=args.map)
    line = f"wrote {args.output}"
    if info:
        line += f" (geodesic error / sqrt(area): mean {info['mean_error']:.4f})"
    if not args.quiet:
        print(f"meshcorr: {line}", file=sys.stderr)
    return 0
