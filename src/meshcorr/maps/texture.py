"""Texture transfer: carry a target's UV coordinates and texture image to the source.

A textured mesh gives each corner of each triangle a point of the texture
image, :math:`(u, v) \\in [0, 1]^2` (per corner, because a UV atlas cuts the
surface along seams). A precise map (:mod:`meshcorr.maps.precise`) sends source
vertex i to the point :math:`\\sum_k w_{ik} v_{f_i, k}` of target triangle
:math:`f_i`; the same weights on that triangle's corner UVs give the source
vertex its texture coordinate,

.. math::

    uv_i = \\sum_{k=1}^{3} w_{ik} \\, uv_{f_i, k},

so the source, written with these UVs and the target's image, shows the
target's texture carried through the map. A source triangle whose corners
land on both sides of a target seam interpolates across the atlas (a
smear along the seam's image); seamless textures (or a map from a
UV-less mesh onto a textured one) have none.

OBJ files are read with trimesh (which splits vertices along UV seams; they
are merged back by position here, so that the mesh is one surface) and
written by :func:`write_textured_obj`: the ``.obj``, its ``.mtl`` and the
texture ``.png`` side by side, each atomically.
"""

from __future__ import annotations

import io as _io
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import MeshError, OutputError, ParameterError
from .precise import PreciseMap

__all__ = ["TexturedMesh", "read_textured_obj", "transfer_uv", "write_textured_obj"]


@dataclass(frozen=True)
class TexturedMesh:
    """A triangle mesh with a UV atlas and its texture image.

    Attributes
    ----------
    vertices : (n, 3) float
    faces : (m, 3) int
    corner_uv : (m, 3, 2) float
        UV coordinates of each triangle's corners.
    image : PIL.Image.Image
        The texture.
    path : str
        The file it came from ("" if built in memory).
    """

    vertices: np.ndarray
    faces: np.ndarray
    corner_uv: np.ndarray
    image: object
    path: str = ""

    def vertex_uv(self) -> np.ndarray:
        """``(n, 2)`` float: one UV per vertex (the last corner's, where seams give several)."""
        uv = np.zeros((len(self.vertices), 2))
        uv[self.faces.reshape(-1)] = self.corner_uv.reshape(-1, 2)
        return uv


def read_textured_obj(path: str | os.PathLike) -> TexturedMesh:
    """Read an OBJ file with texture coordinates and a texture image (via its ``.mtl``).

    Vertices split along UV seams are merged back by position (first
    occurrence first: a seamless file keeps its vertex order).

    Raises
    ------
    MeshError
        If the file cannot be read, has no UV coordinates or no texture image.
    """
    import trimesh

    try:
        loaded = trimesh.load(os.fspath(path), process=False, force="mesh")
    except Exception as exc:  # trimesh raises many types for broken files
        raise MeshError(f"{path}: cannot be read as a mesh ({exc}).") from exc
    visual = loaded.visual
    uv = getattr(visual, "uv", None)
    image = getattr(getattr(visual, "material", None), "image", None)
    if uv is None or len(uv) != len(loaded.vertices):
        raise MeshError(f"{path} has no texture coordinates (no 'vt' lines). Give an OBJ with a UV atlas.")
    if image is None or getattr(image, "format", None) is None:  # trimesh fills in a blank image
        raise MeshError(f"{path} names no texture image (map_Kd in its .mtl), or the image is missing; "
                        "keep the .mtl and the image next to the .obj.")
    V, F = np.asarray(loaded.vertices, dtype=np.float64), np.asarray(loaded.faces, dtype=np.int64)
    _, first, inverse = np.unique(V, axis=0, return_index=True, return_inverse=True)
    order = np.argsort(first)  # unique rows in order of first occurrence
    new_index = np.empty(len(order), dtype=np.int64)
    new_index[order] = np.arange(len(order))
    merged = new_index[inverse.reshape(-1)]
    return TexturedMesh(vertices=V[first[order]], faces=merged[F], corner_uv=np.asarray(uv, float)[F],
                        image=image, path=os.fspath(path))


def transfer_uv(precise: PreciseMap, textured_target: TexturedMesh) -> np.ndarray:
    """Texture coordinates of the source vertices (module docstring).

    Parameters
    ----------
    precise : PreciseMap
        Source vertices on target triangles (e.g. ``result.precise_map()``),
        the target being ``textured_target``'s mesh.
    textured_target : TexturedMesh

    Returns
    -------
    uv : (n_source, 2) float
        NaN rows where the source vertex is unmapped.

    Raises
    ------
    ParameterError
        If the precise map's triangles are not those of ``textured_target``.
    """
    faces = np.asarray(textured_target.faces)
    if precise.target_faces.shape != faces.shape or not np.array_equal(precise.target_faces, faces):
        raise ParameterError("The precise map points into other triangles than the textured mesh's: "
                             "match onto the TexturedMesh itself (its vertices and faces) and try again.")
    uv = textured_target.corner_uv[np.maximum(precise.faces, 0)]  # (n, 3, 2)
    out = np.einsum("nk,nkc->nc", precise.weights, uv)
    out[precise.faces < 0] = np.nan
    return out


def write_textured_obj(path: str | os.PathLike, vertices, faces, uv, image, *,
                       inputs: tuple = ()) -> tuple[Path, Path, Path]:
    """Write a mesh with per-vertex UVs and its texture: ``NAME.obj``, ``NAME.mtl``, ``NAME.png``.

    Parameters
    ----------
    path : str or path-like
        The ``.obj`` file; the material and image go next to it.
    vertices : (n, 3) float
    faces : (m, 3) int
    uv : (n, 2) float
        Texture coordinates of each vertex (NaN rows are written as 0, 0).
    image : PIL.Image.Image
        The texture.
    inputs : tuple of paths
        Files that must not be overwritten (e.g. the textured input).

    Returns
    -------
    paths : (Path, Path, Path)
        The ``.obj``, ``.mtl`` and ``.png`` written.

    Raises
    ------
    OutputError
        If a file to write is one of ``inputs``.
    ParameterError
        If the folder does not exist, the name does not end in ``.obj`` or ``uv`` has the wrong shape.
    """
    from ..io import atomic_write

    obj = Path(path)
    if obj.suffix.lower() != ".obj":
        raise ParameterError(f"{obj}: a textured mesh is written as .obj; give a file name ending in .obj.")
    mtl, png = obj.with_suffix(".mtl"), obj.with_name(obj.stem + "_texture.png")
    protected = {Path(p).resolve() for p in inputs if p}
    for out in (obj, mtl, png):
        if out.resolve() in protected:
            raise OutputError(f"{out} is an input file; choose another output name (inputs are never replaced).")
    vertices, faces = np.asarray(vertices, dtype=np.float64), np.asarray(faces, dtype=np.int64)
    uv = np.nan_to_num(np.asarray(uv, dtype=np.float64), nan=0.0)
    if uv.shape != (len(vertices), 2):
        raise ParameterError(f"uv must have one row per vertex, ({len(vertices)}, 2); got {uv.shape}.")
    text = _io.StringIO()
    text.write(f"mtllib {mtl.name}\nusemtl texture\n")
    np.savetxt(text, vertices, fmt="v %.9g %.9g %.9g")
    np.savetxt(text, uv, fmt="vt %.9g %.9g")
    np.savetxt(text, np.repeat(faces + 1, 2, axis=1), fmt="f %d/%d %d/%d %d/%d")
    material = f"newmtl texture\nKa 1 1 1\nKd 1 1 1\nmap_Kd {png.name}\n"
    image_bytes = _io.BytesIO()
    image.save(image_bytes, format="PNG")
    atomic_write(png, lambda file: file.write(image_bytes.getvalue()))
    atomic_write(mtl, lambda file: file.write(material.encode()))
    atomic_write(obj, lambda file: file.write(text.getvalue().encode()))
    return obj, mtl, png
