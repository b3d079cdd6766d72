"""``meshcorr transfer``: carry per-vertex colours or a scalar field through a map."""

from __future__ import annotations

import argparse
import sys

HELP = "carry per-vertex colours or a scalar field from TARGET onto SOURCE; write a coloured PLY"

DESCRIPTION = """\
Give each SOURCE vertex the attribute of the TARGET vertex MAP sends it to
(the pull-back f(map(i))) and write SOURCE with vertex colours.

--attribute:
  colors      TARGET's own vertex colours (a PLY/OBJ with colours)
  parts, xyz  a smooth part colouring / the coordinates of TARGET as colours
  FILE        a per-vertex field of TARGET: .npy or text, one row per vertex;
              3 or 4 columns of 0-255 integers are colours, one column is a
              scalar field, coloured with --cmap
Unmapped SOURCE vertices (-1 in MAP) are grey. --values-out also saves the
transferred values, one row per SOURCE vertex (.npy, else text): a scalar
field (NaN where unmapped), or the colours.
"""


#: The colour map of a scalar field when ``--cmap`` is not given.
CMAP = "viridis"
#: The ``--attribute`` names that give colours, not a scalar field (so no ``--cmap``).
COLOUR_ATTRIBUTES = ("colors", "parts", "xyz")


def add_parser(sub) -> None:
    p = sub.add_parser("transfer", help=HELP, description=DESCRIPTION,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("source", metavar="SOURCE", help="mesh or point cloud whose vertices were mapped")
    p.add_argument("target", metavar="TARGET", help="mesh or point cloud they were mapped onto")
    p.add_argument("map", metavar="MAP", help="the vertex map (.txt one index per line, or .npy)")
    p.add_argument("--attribute", required=True, metavar="ATTR",
                   help="'colors', 'parts', 'xyz' or a per-vertex file of TARGET")
    p.add_argument("-o", "--output", required=True, metavar="OUT.ply",
                   help="SOURCE with the transferred vertex colours (.ply or .obj)")
    p.add_argument("--cmap", choices=("viridis", "coolwarm", "error"), default=None,
                   help=f"colour map of a scalar field (default: {CMAP})")
    p.add_argument("--values-out", metavar="FILE",
                   help="also write the transferred values, one row per SOURCE vertex (.npy, else text)")
    p.set_defaults(run=run)


def _read_attribute(args, vertices, faces):
    """TARGET's values named by --attribute: a name or an attribute FILE that cannot be used is refused
    by :func:`meshcorr.maps.transfer.read_attribute` (a name that is neither an attribute nor a file: exit 2;
    a file that cannot be used: bad input data, exit 3)."""
    from ..maps.transfer import read_attribute

    return read_attribute(args.attribute, args.target, vertices, faces)


def _refuse_cmap(args, why: str) -> None:
    """``--cmap`` colours a scalar field only: with colours it would be ignored."""
    from ..errors import ParameterError

    raise ParameterError(f"--cmap {args.cmap} colours a scalar field, and {why}, not a scalar field: --cmap "
                         "would be ignored. Remove --cmap, or give a FILE of one value per TARGET vertex "
                         "to --attribute.")


def run(args) -> int:
    from ..errors import ParameterError
    from ..io import read_mesh, staged_writes, write_mesh
    from ..maps.transfer import transfer_attribute, write_values
    from ._mapfile import read_checked_map
    from ..io import check_outputs

    if not args.output.lower().endswith((".ply", ".obj")):
        raise ParameterError(f"Cannot write {args.output}: vertex colours need a .ply or .obj file "
                             "(.ply for a point cloud).")
    if args.cmap is not None and args.attribute in COLOUR_ATTRIBUTES:
        _refuse_cmap(args, f"--attribute {args.attribute} gives colours")
    inputs = {"SOURCE": args.source, "TARGET": args.target, "MAP": args.map, "--attribute": args.attribute}
    check_outputs({"-o": args.output, "--values-out": args.values_out}, inputs)
    V1, F1 = read_mesh(args.source, name=args.source)
    V2, F2 = read_mesh(args.target, name=args.target)
    if not len(F1) and not args.output.lower().endswith(".ply"):
        raise ParameterError(f"Cannot write {args.output}: SOURCE is a point cloud; its colours are written "
                             "as a .ply file of points.")
    mapping = read_checked_map(args.map, len(V1), len(V2))
    values = _read_attribute(args, V2, F2)
    if args.cmap is not None and values.ndim == 2:
        _refuse_cmap(args, f"--attribute {args.attribute} holds colours (3 or 4 columns)")
    colors, pulled = transfer_attribute(values, mapping, cmap=args.cmap or CMAP)
    with staged_writes():
        write_mesh(args.output, V1, F1, vertex_colors=colors)
        if args.values_out:
            write_values(args.values_out, pulled)
    if not args.quiet:
        print(f"meshcorr: wrote {args.output} ({int((mapping >= 0).sum())}/{len(V1)} source vertices mapped)",
              file=sys.stderr)
    return 0
