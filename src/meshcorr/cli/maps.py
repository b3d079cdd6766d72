"""``meshcorr texture`` and ``meshcorr fmap``: the outputs made from a vertex map.

Both commands read SOURCE, TARGET and MAP like ``meshcorr transfer``.
"""

from __future__ import annotations

import argparse

TEXTURE_HELP = "carry TARGET's UV atlas and texture onto SOURCE through a precise map; write an OBJ"
FMAP_HELP = "export the map's functional map in Laplace-Beltrami bases (.npz), or import one as a map"

TEXTURE_DESCRIPTION = """\
TARGET is an OBJ with texture coordinates and a texture image (named by its
.mtl). Each SOURCE vertex is sent to a point on a TARGET triangle (the precise
map of MAP, computed in the Laplace-Beltrami bases of size -k) and takes the
UV coordinate interpolated there. Writes OUT.obj, OUT.mtl and OUT_texture.png
(the same image); inputs are never replaced.
"""

FMAP_DESCRIPTION = """\
Export: C = Phi_S^T M_S Phi_T[MAP], the (k, k) matrix taking the coefficients
of a TARGET function to those of its pull-back on SOURCE, written with both
bases, eigenvalues and masses (each mesh scaled to unit area) to OUT.npz.
In pyFM's naming MAP is p2p_21 and C is FM_12 with mesh 1 = TARGET and mesh
2 = SOURCE. --to-map FMAP.npz reads such a file and writes the vertex map
instead (the nearest TARGET row of Phi_S C for each SOURCE vertex).
"""


#: The source argument both commands share: (flags, options); each has its own TARGET help.
_SOURCE = (("source",), dict(metavar="SOURCE", help="mesh whose vertices were mapped"))


def add_parser(sub) -> None:
    commands = {
        "texture": (TEXTURE_HELP, TEXTURE_DESCRIPTION, run_texture,
                    [(("target",), dict(metavar="TARGET", help="mesh they were mapped onto: an OBJ with UVs")),
                     (("map",), dict(metavar="MAP", help="the vertex map (.txt or .npy)")),
                     (("-o", "--output"), dict(required=True, metavar="OUT.obj", help="SOURCE with the carried UVs")),
                     (("-k",), dict(type=int, default=40, help="basis size of the precise map (40)"))]),
        "fmap": (FMAP_HELP, FMAP_DESCRIPTION, run_fmap,
                 [(("target",), dict(metavar="TARGET", help="mesh they were mapped onto")),
                  (("map",), dict(metavar="MAP", nargs="?", help="the vertex map to export")),
                  (("-o", "--output"), dict(required=True, metavar="OUT", help="the functional map (.npz), "
                                            "or with --to-map the vertex map (.txt/.npy)")),
                  (("-k",), dict(type=int, default=30, help="basis size (30)")),
                  (("--to-map",), dict(metavar="FMAP.npz", help="import this functional map as a vertex map")),
                  (("--seed",), dict(type=int, default=0, help="seed of the eigensolvers (0)"))]),
    }
    for name, (help_text, description, run, arguments) in commands.items():
        parser = sub.add_parser(name, help=help_text, description=description,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
        for flags, options in (_SOURCE, *arguments):
            parser.add_argument(*flags, **options)
        parser.set_defaults(run=run)


def _inputs(args, target_mesh=None):
    from ..mesh import as_mesh
    from ._mapfile import read_checked_map

    source = as_mesh(args.source, name=args.source)
    target = as_mesh(target_mesh if target_mesh is not None else args.target, name=args.target)
    mapping = None
    if args.map is not None:
        mapping = read_checked_map(args.map, source.n_vertices, target.n_vertices)
    return source, target, mapping


def _check_outputs(args, outputs: dict) -> None:
    from ..io import check_outputs

    check_outputs(outputs, {"SOURCE": args.source, "TARGET": args.target, "MAP": args.map,
                            "--to-map": getattr(args, "to_map", None)})


def run_texture(args) -> int:
    from pathlib import Path

    from ..precise import precise_map
    from ..texture import read_textured_obj, transfer_uv, write_textured_obj

    obj = Path(args.output)
    _check_outputs(args, {"-o": obj, "its .mtl": obj.with_suffix(".mtl"),
                          "its texture": obj.with_name(obj.stem + "_texture.png")})
    textured = read_textured_obj(args.target)
    source, target, mapping = _inputs(args, (textured.vertices, textured.faces))
    uv = transfer_uv(precise_map(source, target, mapping, k=args.k), textured)
    write_textured_obj(args.output, source.vertices, source.faces, uv, textured.image,
                       inputs=(args.source, args.target, args.map))
    return 0


def run_fmap(args) -> int:
    from ..errors import InputError, ParameterError
    from ..fmap import FunctionalMap, functional_map
    from ..io import write_map

    _check_outputs(args, {"-o": args.output})
    if (args.map is None) == (args.to_map is None):
        raise ParameterError("Give either MAP (to export its functional map) or --to-map FMAP.npz (to import one).")
    source, target, mapping = _inputs(args)
    if args.to_map:
        fmap = FunctionalMap.load(args.to_map)
        if fmap.source_basis.shape[0] != source.n_vertices or fmap.target_basis.shape[0] != target.n_vertices:
            raise InputError(f"{args.to_map} was written for meshes of {fmap.source_basis.shape[0]} and "
                                 f"{fmap.target_basis.shape[0]} vertices, not these ({source.n_vertices}, "
                                 f"{target.n_vertices}).")
        write_map(args.output, fmap.point_map())
        return 0
    if not args.output.endswith(".npz"):
        raise ParameterError(f"Cannot write {args.output}: a functional map is written as .npz.")
    functional_map(source, target, mapping, args.k, random_state=args.seed).save(args.output)
    return 0
