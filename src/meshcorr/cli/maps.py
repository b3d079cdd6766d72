"""``meshcorr texture`` and ``meshcorr fmap``: the outputs made from a vertex map.

Both commands read SOURCE, TARGET and MAP like ``meshcorr transfer``.
"""

from __future__ import annotations

import argparse
import sys

from ._mapfile import print_map
from .match import seed

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
instead (the nearest TARGET row of Phi_S C for each SOURCE vertex; -o - writes
it to stdout).
"""


#: ``meshcorr fmap``'s basis size and eigensolver seed when -k / --seed are not given.
FMAP_K, FMAP_SEED = 30, 0

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
                  (("-k",), dict(type=int, default=None, help=f"basis size ({FMAP_K}; not with --to-map)")),
                  (("--to-map",), dict(metavar="FMAP.npz", help="import this functional map as a vertex map")),
                  (("--seed",), dict(type=seed, default=None,
                                     help=f"seed of the eigensolvers, an integer >= 0 ({FMAP_SEED}; "
                                          "not with --to-map)"))]),
    }
    for name, (help_text, description, run, arguments) in commands.items():
        parser = sub.add_parser(name, help=help_text, description=description,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
        for flags, options in (_SOURCE, *arguments):
            parser.add_argument(*flags, **options)
        parser.set_defaults(run=run)


def _inputs(args, target_mesh=None):
    from ..errors import InputError
    from ._mapfile import read_checked_map
    from .show import one_surface

    why = (f"'meshcorr {args.command}' needs one Laplace-Beltrami basis per mesh, so one connected surface: "
           "remove the other pieces first (e.g. MeshLab: Filters > Cleaning and Repairing > Remove Isolated "
           "pieces) and map again.")
    source = one_surface(args.source, "SOURCE", why)
    target = one_surface(target_mesh if target_mesh is not None else args.target, "TARGET", why,
                         name=args.target)
    mapping = None
    if args.map is not None:
        mapping = read_checked_map(args.map, source.n_vertices, target.n_vertices)
        if not (mapping >= 0).any():  # its functional map was all zeros, its UVs all (0, 0)
            raise InputError(f"{args.map} maps no SOURCE vertex (every entry is -1): there is nothing to "
                             "carry. Check that it is the map you meant.")
    return source, target, mapping


def _status(args, text: str) -> None:
    if not args.quiet:
        print(f"meshcorr: {text}", file=sys.stderr)


def _texture_files(obj) -> dict:
    """The files an OBJ's texture comes from: its .mtl files (``mtllib``) and their images (``map_*``).

    They are inputs too: ``-o NAME.obj`` writes NAME.mtl and NAME_texture.png, which replaced TARGET's
    own material file when the names met (e.g. -o material.obj next to trimesh's material.mtl).
    """
    from pathlib import Path

    obj = Path(obj)
    files = {}
    try:
        lines = obj.read_text(encoding="latin-1").splitlines()
    except OSError:
        return files
    for line in lines:
        if line.startswith("mtllib"):
            for name in line.split()[1:]:
                mtl = obj.parent / name
                files[f"TARGET's material {mtl}"] = mtl
                try:
                    material = mtl.read_text(encoding="latin-1").splitlines()
                except OSError:
                    continue
                for entry in material:
                    fields = entry.split()
                    if fields and fields[0].lower().startswith(("map_", "bump", "disp", "decal")) and len(fields) > 1:
                        image = mtl.parent / fields[-1]
                        files[f"TARGET's texture {image}"] = image
    return files


def _load_fmap(path, source, target):
    """The functional map in ``path``, its vertex map for these meshes; a file that cannot be used is bad
    input data (exit 3). (A .npy, or arrays of text, were internal errors; NaN values a usage error.)"""
    import os
    import zipfile

    from ..errors import InputError, ParameterError
    from ..spectral.fmap import FunctionalMap

    if os.path.isfile(path) and not zipfile.is_zipfile(path):  # np.load read a .npy as one array, and
        # any other file as a pickle, whose message suggested loading it unsafely
        raise InputError(f"{path} is not a functional map file: it is no .npz archive. Give the .npz "
                         "that 'meshcorr fmap SOURCE TARGET MAP -o OUT.npz' writes.")
    fmap = FunctionalMap.load(path)
    if fmap.source_basis.shape[0] != source.n_vertices or fmap.target_basis.shape[0] != target.n_vertices:
        raise InputError(f"{path} was written for meshes of {fmap.source_basis.shape[0]} and "
                         f"{fmap.target_basis.shape[0]} vertices, not these ({source.n_vertices}, "
                         f"{target.n_vertices}).")
    try:
        return fmap.point_map()
    except (ParameterError, TypeError, ValueError) as error:
        raise InputError(f"{path}: {error}".rstrip(".") + ". Write it again with 'meshcorr fmap'.") from None


def _check_outputs(args, outputs: dict) -> None:
    from ..io import check_outputs

    check_outputs(outputs, {"SOURCE": args.source, "TARGET": args.target, "MAP": args.map,
                            "--to-map": getattr(args, "to_map", None)}, stdout=("-o",))


def run_texture(args) -> int:
    from pathlib import Path

    from ..maps.precise import precise_map
    from ..maps.texture import read_textured_obj, transfer_uv, write_textured_obj

    from ..io import check_outputs, staged_writes

    obj = Path(args.output)
    inputs = {"SOURCE": args.source, "TARGET": args.target, "MAP": args.map, **_texture_files(args.target)}
    check_outputs({"-o": obj, "its .mtl": obj.with_suffix(".mtl"),
                   "its texture": obj.with_name(obj.stem + "_texture.png")}, inputs)
    textured = read_textured_obj(args.target)
    source, target, mapping = _inputs(args, (textured.vertices, textured.faces))
    if source.is_cloud:  # it wrote an OBJ of points with UVs: no surface shows a texture
        from ..errors import InputError

        raise InputError(f"SOURCE {args.source} is a point cloud: a texture needs a surface. Mesh it first "
                         "('meshcorr transfer' carries per-vertex colours onto a cloud).")
    uv = transfer_uv(precise_map(source, target, mapping, k=args.k), textured)
    with staged_writes():  # the .obj, .mtl and image appear together, or none of them
        obj, mtl, png = write_textured_obj(args.output, source.vertices, source.faces, uv, textured.image,
                                           inputs=tuple(inputs.values()))
    _status(args, f"wrote {obj}, {mtl.name} and {png.name} ({int((mapping >= 0).sum())}/{len(mapping)} "
                  "source vertices mapped)")
    return 0


def run_fmap(args) -> int:
    from ..errors import ParameterError
    from ..spectral.fmap import functional_map
    from ..io import write_map

    _check_outputs(args, {"-o": args.output})
    if (args.map is None) == (args.to_map is None):
        raise ParameterError("Give either MAP (to export its functional map) or --to-map FMAP.npz (to import one).")
    if args.to_map is not None:
        given = [f"{flag} {value}" for flag, value in (("-k", args.k), ("--seed", args.seed)) if value is not None]
        if given:
            raise ParameterError(f"{' and '.join(given)} shape{'s' if len(given) == 1 else ''} an exported "
                                 f"functional map; --to-map {args.to_map} imports one, whose basis and seed are in "
                                 f"the file: {'it' if len(given) == 1 else 'they'} would be ignored. Remove "
                                 f"{' and '.join(g.split()[0] for g in given)}, or export a map (MAP) instead.")
    if args.map is not None and not args.output.lower().endswith(".npz"):  # before the work, not after
        raise ParameterError(f"Cannot write {args.output}: a functional map is written as .npz.")
    source, target, mapping = _inputs(args)
    if args.to_map:
        mapping = _load_fmap(args.to_map, source, target)
        if args.output == "-":  # stdout, as 'meshcorr match -o -' (it wrote a file named '-')
            print_map(mapping)
        else:
            write_map(args.output, mapping)
            _status(args, f"wrote {args.output}: the vertex map of {args.to_map}")
        return 0
    k = FMAP_K if args.k is None else args.k
    functional_map(source, target, mapping, k, random_state=FMAP_SEED if args.seed is None else args.seed
                   ).save(args.output)
    _status(args, f"wrote {args.output}: the {k} x {k} functional map of {args.map}")
    return 0
