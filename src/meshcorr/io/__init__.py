"""Read and write meshes, point clouds, vertex maps and arrays: one module per family of files.

- :mod:`meshcorr.io.meshes`: mesh and point-cloud files (OFF, OBJ, PLY, STL;
  XYZ, NPY), read without processing so that vertex ``i`` of the file is
  vertex ``i`` of the arrays (OFF by :mod:`meshcorr.io.off`);
- :mod:`meshcorr.io.maps`: vertex maps (``.npy`` or one integer per line);
- :mod:`meshcorr.io.indices`: plain-text index files (ground truths, landmarks);
- :mod:`meshcorr.io.arrays`: ``.npy`` and ``.npz`` files, never pickles;
- :mod:`meshcorr.io.files`: atomic writes (a temporary file in the same
  directory moved over the target with :func:`os.replace`), writes staged to
  appear together (:func:`staged_writes`), output paths checked before any
  work (:func:`check_outputs`).

Every public name is also ``meshcorr.io.<name>``. The mesh formats need
trimesh, whose import takes a while: :mod:`meshcorr.io.meshes` is imported on
the first use of one of its names here, so that the other families (read by
the pipeline's landmark and ground-truth files) do not import it.
"""

from __future__ import annotations

from .arrays import file_kind, load_npy, read_npz, write_npz
from .files import atomic_write, check_outputs, staged_writes
from .indices import index_fields, read_index_lines
from .maps import map_text, read_map, write_map

__all__ = ["POINT_FORMATS", "SUPPORTED_FORMATS", "atomic_write", "check_outputs", "file_kind", "index_fields",
           "load_npy", "map_text", "quiet_trimesh", "read_index_lines", "read_map", "read_mesh", "read_npz",
           "staged_writes", "write_map", "write_mesh", "write_npz"]

#: The names of :mod:`meshcorr.io.meshes`, imported on first use (module docstring).
_MESH_NAMES = ("POINT_FORMATS", "SUPPORTED_FORMATS", "quiet_trimesh", "read_mesh", "write_mesh")


def __getattr__(name: str):
    """``meshcorr.io.read_mesh`` and the other names of :mod:`meshcorr.io.meshes`, imported on first use."""
    if name in _MESH_NAMES:
        from . import meshes

        value = getattr(meshes, name)
        globals()[name] = value
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_MESH_NAMES))
