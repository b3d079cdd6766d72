"""``meshcorr embed``: the affinity eigenvectors and the spectral embedding of one mesh (PNG)."""

from __future__ import annotations

import argparse
import sys

from ..core.geodesics import GEODESIC_METHODS
from .match import reporting, seed
from .show import add_camera_arguments, check_png

HELP = "draw a mesh's affinity eigenvectors and its 3-D spectral embedding as a PNG"

DESCRIPTION = """\
Draw MESH coloured by part, its 3-D spectral embedding (vertices moved to
the eigenvectors u2, u3, u4 of the Gaussian geodesic affinity matrix, scaled
by sqrt(eigenvalue); Jain & Zhang 2006, Figure 2) and the first eigenvectors
as colour plots (blue negative, red positive) with their eigenvalues
(Figure 6). Needs matplotlib (pip install meshcorr[plot]); no display or GPU.
The dense affinity matrix is n x n: decimate meshes beyond a few thousand
vertices first (a mesh whose matrices would not fit in --max-memory is refused).
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
    p.add_argument("--largest-component", action="store_true",
                   help="draw the largest connected piece of MESH (default: a mesh of several pieces, "
                        "or with vertices used by no face, is refused)")
    p.add_argument("--max-memory", metavar="SIZE", default=None,
                   help="memory the n x n matrices may use, e.g. 4GiB (default: 80%% of the memory "
                        "available at start-up)")
    add_camera_arguments(p)
    p.set_defaults(run=run)


def _size(nbytes: int) -> str:
    return f"{nbytes / 1024 ** 3:.2f} GiB" if nbytes >= 1024 ** 3 else f"{nbytes / 1024 ** 2:.1f} MiB"


def check_memory(name: str, n_vertices: int, max_memory) -> None:
    """Refuse, before the work, a mesh whose n x n geodesic and affinity matrices would not fit.

    (Such a mesh ran for minutes and then ended as 'out of memory', or was killed.)
    """
    from ..errors import MemoryLimitError
    from ..runtime.memory import default_max_memory, dense_memory, parse_memory

    limit = default_max_memory() if max_memory is None else parse_memory(max_memory)
    need = dense_memory(n_vertices, 0)
    if limit is not None and need > limit:
        raise MemoryLimitError(
            f"embed needs about {_size(need)} for the {n_vertices} x {n_vertices} geodesic and "
            f"affinity matrices of {name} but may use {_size(limit)}. Decimate the mesh to a few "
            "thousand vertices (e.g. MeshLab: Filters > Remeshing > Quadric Edge Collapse Decimation), "
            "or allow more memory (--max-memory).")


def run(args) -> int:
    from ..runtime.checks import check_int
    from ..core.mesh import as_mesh
    from ..viz.plots import require_matplotlib
    from ..viz.figures import spectrum_figure
    from ..io import check_outputs

    check_png(args.output)
    check_outputs({"-o": args.output}, {"MESH": args.mesh})
    check_int("n_eigenvectors", args.n_eigenvectors, minimum=1, maximum=30)
    if args.max_memory is not None:
        from ..runtime.memory import parse_memory

        parse_memory(args.max_memory)
    require_matplotlib()
    k = max(args.n_eigenvectors, 8)  # the picture lists the first 8 eigenvalues
    mesh = as_mesh(args.mesh, name=args.mesh, largest_component=args.largest_component, min_vertices=k + 2,
                   reason=f"embed computes the first {k} eigenvectors of the affinity matrix")
    if mesh.n_vertices < mesh.n_original and not args.quiet:
        print(f"meshcorr: drawing the largest piece of {args.mesh}: {mesh.n_vertices} of its "
              f"{mesh.n_original} vertices", file=sys.stderr)
    check_memory(args.mesh, mesh.n_vertices, args.max_memory)
    if mesh.n_vertices > 2000 and not args.quiet:
        print(f"meshcorr: {args.mesh}: computing the {mesh.n_vertices} x {mesh.n_vertices} geodesic and "
              "affinity matrices and their eigenvectors...", file=sys.stderr)
    vertices, faces = mesh.vertices, mesh.faces
    with reporting(args, args.mesh) as progress:
        values = spectrum_figure(vertices, faces, args.output, n_eigenvectors=args.n_eigenvectors,
                                 geodesic=args.geodesic, scale=args.scale, random_state=args.seed,
                                 elev=args.elev, azim=args.azim, up=args.up, dpi=args.dpi, progress=progress)
    listed = ", ".join(f"{v:.4g}" for v in values[:args.n_eigenvectors])
    if not args.quiet:
        print(f"meshcorr: wrote {args.output}; eigenvalues: {listed}", file=sys.stderr)
    return 0
