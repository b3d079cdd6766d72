"""Carry per-vertex data through a vertex map (pull-back).

A map ``p2p[i] = j`` sends source vertex ``i`` to target vertex ``j``. Any
per-vertex field ``f`` on the target then defines a field on the source,

.. math::

    (f \\circ p2p)(i) = f(p2p(i)),

the *pull-back* of ``f`` through the map. This is how the paper shows its
results (Jain & Zhang 2006, Figures 7-8: the target is coloured by part and
each colour is carried to the source), and how users transfer labels,
textures-as-colours or scalar fields between shapes.
"""

from __future__ import annotations

import numpy as np

from ..errors import InputError, ParameterError
from ..runtime.checks import check_vertex_map as check_map  # the one check of a vertex map, named as before

__all__ = ["check_map", "pull_back", "read_attribute", "transfer_attribute", "write_values"]

#: What an attribute file holds, for the messages that refuse one.
_NUMBERS = "give one number (a scalar field) or 3-4 colour channels (0-255) per target vertex."


def pull_back(values, mapping, *, fill=np.nan) -> np.ndarray:
    """Carry per-vertex target values to the source through a map.

    Parameters
    ----------
    values : (n_target,) or (n_target, c) array
        One value (or row of values, e.g. RGB) per target vertex.
    mapping : (n_source,) int
        Target vertex of each source vertex; -1 where unmapped. Assumed
        checked (see :func:`check_map`).
    fill : scalar or (c,) array
        Value given to unmapped source vertices.

    Returns
    -------
    pulled : (n_source,) or (n_source, c) array
        ``pulled[i] = values[mapping[i]]``, ``fill`` where ``mapping[i] == -1``;
        the dtype of ``values`` (promoted if ``fill`` does not fit it).
    """
    values = np.asarray(values)
    mapping = np.asarray(mapping, dtype=np.int64)
    mapped = mapping >= 0
    pulled = values[np.where(mapped, mapping, 0)]
    if not mapped.all():
        fill = np.asarray(fill)
        pulled = pulled.astype(np.result_type(pulled, fill), copy=False)
        pulled[~mapped] = fill
    return pulled


def read_attribute(spec: str, target_path, vertices, faces) -> np.ndarray:
    """Per-vertex values of the target named by ``spec``.

    Parameters
    ----------
    spec : str
        ``"colors"`` (the target file's own vertex colours), ``"parts"`` or
        ``"xyz"`` (see :func:`meshcorr.maps.colors.mesh_coloring`), or a
        ``.npy``/text file with one row per target vertex.
    target_path : str or path-like
        The target mesh file (read again for its colours).
    vertices : (n, 3) float
    faces : (m, 3) int

    Returns
    -------
    values : (n,) float, or (n, 3) uint8 colours

    Raises
    ------
    ParameterError
        If ``spec`` is neither an attribute name nor an existing file, or
        the target has no colours.
    InputError
        If the file cannot be read, is not a table of numbers, or does not
        have one row per target vertex (bad input data: the CLI's exit 3).
    """
    n = len(vertices)
    if spec in ("parts", "xyz"):
        from .colors import mesh_coloring

        return mesh_coloring(spec, vertices, faces)
    if spec == "colors":
        import trimesh

        colors = None
        try:  # a mesh, or a cloud of points (a PLY of vertices only loads as trimesh.PointCloud)
            loaded = trimesh.load(target_path, process=False, force="mesh" if len(faces) else None)
        except (NotImplementedError, ValueError, OSError):  # .npy / .xyz: points only, no colours
            loaded = None
        if isinstance(loaded, trimesh.PointCloud):
            colors = loaded.colors if len(loaded.colors) else None
        elif loaded is not None and getattr(loaded.visual, "kind", None) == "vertex":
            colors = loaded.visual.vertex_colors
        if colors is None or len(colors) != n:
            raise ParameterError(
                f"{target_path} has no per-vertex colours. Use a PLY/OBJ with vertex colours, "
                "or --attribute parts|xyz|FILE."
            )
        return np.asarray(colors)[:, :3].astype(np.uint8)
    try:
        values = np.load(spec) if str(spec).endswith(".npy") else np.loadtxt(spec, ndmin=1)
    except FileNotFoundError as exc:
        raise ParameterError(
            f"--attribute {spec}: not a known attribute and no such file; give 'colors', 'parts', "
            "'xyz' or a file with one row per target vertex (.npy or text)."
        ) from exc
    except OSError as exc:  # a folder, no permission, ...
        raise InputError(f"--attribute {spec}: cannot be read ({exc.strerror or exc}).") from exc
    except (TypeError, ValueError) as exc:  # text that is not numbers, a .npy of strings or objects
        raise InputError(f"--attribute {spec}: not a table of numbers ({exc}); {_NUMBERS}") from exc
    values = np.asarray(values)
    if not (np.issubdtype(values.dtype, np.number) or values.dtype == bool):  # e.g. a .npy of strings
        raise InputError(f"--attribute {spec}: not a table of numbers (it holds {values.dtype} values); {_NUMBERS}")
    if values.ndim == 2 and values.shape[1] == 1:
        values = values[:, 0]
    if len(values) != n or values.ndim > 2 or (values.ndim == 2 and values.shape[1] not in (3, 4)):
        raise InputError(
            f"--attribute {spec} has shape {values.shape}; expected one row per target vertex "
            f"({n}) holding one number (a scalar field) or 3-4 colour channels (0-255)."
        )
    if values.ndim == 2:
        if np.any(values < 0) or np.any(values > 255):
            raise InputError(f"--attribute {spec}: colour channels must lie in 0..255.")
        return np.round(values[:, :3]).astype(np.uint8)
    return values.astype(np.float64)


def transfer_attribute(values, mapping, *, cmap: str = "viridis") -> tuple[np.ndarray, np.ndarray]:
    """Pull target values back to the source and colour them.

    Parameters
    ----------
    values : (n_target,) float or (n_target, 3) uint8
        A scalar field or RGB colours.
    mapping : (n_source,) int
        Checked map (see :func:`check_map`).
    cmap : str
        Colour map of a scalar field (see :func:`meshcorr.maps.colors.scalar_colors`),
        spanning the target field's range so that both meshes share one scale.

    Returns
    -------
    colors : (n_source, 3) uint8
        Grey where unmapped.
    pulled : (n_source,) float or (n_source, 3) uint8
        The pulled-back values (NaN / grey where unmapped).
    """
    from .colors import UNMAPPED_COLOR, scalar_colors

    values = np.asarray(values)
    if values.ndim == 2:
        pulled = pull_back(values, mapping, fill=UNMAPPED_COLOR)
        return pulled, pulled
    pulled = pull_back(values.astype(np.float64), mapping, fill=np.nan)
    finite = values[np.isfinite(values)]
    lo, hi = (float(finite.min()), float(finite.max())) if finite.size else (0.0, 1.0)
    return scalar_colors(pulled, cmap, vmin=lo, vmax=hi), pulled


def write_values(path, values) -> None:
    """Write per-vertex values atomically: ``.npy``, else text with one row per vertex."""
    import io as _io

    from ..io import atomic_write

    def writer(file):
        if str(path).endswith(".npy"):
            np.save(file, values)
        else:
            buffer = _io.StringIO()
            np.savetxt(buffer, values, fmt="%d" if values.dtype.kind in "iu" else "%.9g")
            file.write(buffer.getvalue().encode())

    atomic_write(path, writer)
