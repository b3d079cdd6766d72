"""``meshcorr embed``: the affinity eigenvectors and the spectral embedding of one mesh (PNG)."""

from __future__ import annotations

import argparse
import sys

from ..geodesics import GEODESIC_METHODS
from .match import seed
from .show import add_camera_arguments

HELP = "draw a mesh's affinity eigenvectors and its 3-D spectral embedding as a PNG"

DESCRIPTION = """\
Draw MESH coloured by part, its 3-D spectral embedding (vertices moved to
the eigenvectors u2, u3, u4 of the Gaussian geodesic affinity matrix, scaled
by sqrt(eigenvalue); Jain & Zhang 2006, Figure 2) and the first eigenvectors
as colour plots (blue negative, red positive) with their eigenvalues
(Figure 6). Needs matplotlib (pip install meshcorr[plot]); no display or GPU.
The dense affinity matrix is n x n: decimate meshes beyond a few thousand
vertices first.
"""


def add_parser(sub) -> None:
    p = sub.add_parser("embed", help=HELP, description=DESCRIPTION,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("mesh", metavar="MESH", help="the mesh (.off, .obj, .ply, .stl)")
    p.add_argument("-o", "--output", required=True, metavar="FILE.png", help="the picture to write")
    p.add_argument("-n", "--n-eigenvectors", type=int, default=6,
                   help="eigenvectors drawn (default 6, at most 30)")
    p.add_argument("--geodesic", choices=GEODESIC_METHODS, default="heat",
                   help="geodesic solver (default: heat)")
    p.add_argument("--no-scale", dest="scale", action="store_false",
                   help="draw the embedding without scaling by sqrt(eigenvalue)")
    p.add_argument("--seed", type=seed, default=0, help="random state of the eigensolver (default 0)")
    add_camera_arguments(p)
    p.set_defaults(run=run)


def run(args) -> int:
    from ..io import read_mesh
    from ..plots import require_matplotlib
    from ..viz.figures import spectrum_figure
    from ..io import check_outputs

    check_outputs({"-o": args.output}, {"MESH": args.mesh})
    require_matplotlib()
    vertices, faces = read_mesh(args.mesh, name=args.mesh)
    values = spectrum_figure(vertices, faces, args.output, n_eigenvectors=args.n_eigenvectors,
                             geodesic=args.geodesic, scale=args.scale, random_state=args.seed,
                             elev=args.elev, azim=args.azim, up=args.up, dpi=args.dpi)
    listed = ", ".join(f"{v:.4g}" for v in values[:args.n_eigenvectors])
    if not args.quiet:
        print(f"meshcorr: wrote {args.output}; eigenvalues: {listed}", file=sys.stderr)
    return 0
