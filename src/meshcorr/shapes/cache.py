"""An on-disk cache of prepared shapes, keyed by mesh content and settings.

One file per prepared shape (:meth:`meshcorr.shapes.prepared.PreparedShape.save`),
named by the SHA-256 of the validated mesh (:func:`meshcorr.shapes.prepared.mesh_digest`),
the per-shape settings, the resolved mode, the file format and the meshcorr
version: a changed mesh, option or version gives another name, never a
stale hit. A file is written to a temporary name and renamed into place
(:func:`meshcorr.io.atomic_write`), so several processes may prepare the
same shape at once: each rename replaces a complete file with an equal one,
and readers only ever see complete files. A file that cannot be read (cut
short, or a member that is no array), or whose header disagrees with its
name, is prepared again and replaced. A shape that cannot be stored (a
read-only or full folder) is used all the same, with a :class:`CacheWarning`;
:meth:`ShapeCache.check_writable` tells before any work whether the folder
takes files.

The folder is ``$MESHCORR_CACHE`` if set, else ``$XDG_CACHE_HOME/meshcorr``,
else ``~/.cache/meshcorr``.
"""

from __future__ import annotations

import hashlib
import json
import os
import re
import tempfile
import warnings
from pathlib import Path

from ..errors import OutputError, ParameterError, PreparedShapeError
from ..core.mesh import Mesh
from .prepared import FORMAT_VERSION, PreparedShape, meshcorr_version, mesh_digest, prepare_mesh

SUFFIX = ".npz"
#: A cache file's name (the key: 64 hex digits), and a writer's temporary file of one
#: (:func:`meshcorr.io.atomic_write`: ".NAME.RANDOM.tmp"). Only such files are listed or removed:
#: a user's own files in the folder are left alone.
_CACHE_FILE = re.compile(r"[0-9a-f]{64}" + re.escape(SUFFIX))
_TEMPORARY_FILE = re.compile(r"\.[0-9a-f]{64}" + re.escape(SUFFIX) + r"\.[0-9a-f]+\.tmp")


class CacheWarning(UserWarning):
    """The cache folder cannot be written: shapes are prepared, and not kept."""


def default_cache_dir() -> Path:
    """``$MESHCORR_CACHE``, ``$XDG_CACHE_HOME/meshcorr`` or ``~/.cache/meshcorr``."""
    if os.environ.get("MESHCORR_CACHE"):
        return Path(os.environ["MESHCORR_CACHE"])
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base) / "meshcorr"


class ShapeCache:
    """Prepared shapes on disk (module docstring).

    Parameters
    ----------
    root : str or PathLike, optional
        The cache folder (default: :func:`default_cache_dir`); created on the first write.
    """

    def __init__(self, root=None) -> None:
        self.root = Path(default_cache_dir() if root is None else root)
        if self.root.exists() and not self.root.is_dir():
            raise ParameterError(f"The cache folder {self.root} is a file: give a folder (or remove the file).")

    def key(self, mesh: Mesh, settings: dict, mode: str) -> str:
        """SHA-256 (hex) of the mesh content, the settings, the mode and the versions."""
        text = json.dumps(dict(settings, mode=mode, format=FORMAT_VERSION, meshcorr=meshcorr_version(),
                               mesh=mesh_digest(mesh)), sort_keys=True)
        return hashlib.sha256(text.encode()).hexdigest()

    def path(self, key: str) -> Path:
        return self.root / f"{key}{SUFFIX}"

    def get(self, mesh: Mesh, settings: dict, mode: str) -> PreparedShape | None:
        """The cached shape, or None if there is none or it cannot be used (it is then prepared again)."""
        path = self.path(self.key(mesh, settings, mode))
        if not path.is_file():
            return None
        try:
            return PreparedShape.load(path, mesh=mesh, settings=dict(settings, mode=mode))
        except PreparedShapeError:
            return None

    def prepare(self, mesh: Mesh, settings: dict, mode: str) -> PreparedShape:
        """The cached shape, or :func:`meshcorr.shapes.prepared.prepare_mesh` stored under its key."""
        shape = self.get(mesh, settings, mode)
        if shape is None:
            shape = prepare_mesh(mesh, settings, mode)
            try:
                self.root.mkdir(parents=True, exist_ok=True)
                shape.save(self.path(self.key(mesh, settings, mode)))
            except (OutputError, OSError) as exc:  # the cache saves time: a shape it cannot keep is still good
                warnings.warn(f"The prepared shape {mesh.name!r} could not be stored in the cache {self.root} "
                              f"({_reason(exc)}); it is used without being kept.", CacheWarning, stacklevel=2)
        return shape

    def check_writable(self) -> None:
        """Refuse, before any work, a cache folder that cannot be created or take a file (read-only, full).

        Raises
        ------
        OutputError
            Naming the folder and why.
        """
        try:
            self.root.mkdir(parents=True, exist_ok=True)
            fd, probe = tempfile.mkstemp(dir=self.root, prefix=".probe.", suffix=".tmp")
            try:
                os.write(fd, b"x")  # a full disk may still create an empty file
            finally:
                os.close(fd)
                os.unlink(probe)
        except OSError as exc:
            raise OutputError(f"The cache folder {self.root} cannot be written ({_reason(exc)}).") from None

    def files(self) -> list[Path]:
        """The cache files (complete ones; temporary files of writers under way are not listed, nor a
        folder or anything else that is no regular file, whatever its name)."""
        if not self.root.is_dir():
            return []
        return sorted(p for p in self.root.iterdir() if _CACHE_FILE.fullmatch(p.name) and p.is_file())

    def info(self) -> dict:
        """``{"path": str, "files": int, "bytes": int}``."""
        files = self.files()
        return {"path": str(self.root), "files": len(files), "bytes": sum(_size(p) for p in files)}

    def clear(self) -> dict:
        """Remove every cache file and stale temporary file (files named as meshcorr names them, nothing
        else: a folder of such a name is left alone); returns what :meth:`info` said before."""
        before = self.info()
        if self.root.is_dir():
            for path in self.root.iterdir():
                if (_CACHE_FILE.fullmatch(path.name) or _TEMPORARY_FILE.fullmatch(path.name)) and path.is_file():
                    path.unlink(missing_ok=True)
        return before

    def __repr__(self) -> str:
        return f"ShapeCache({str(self.root)!r})"


def as_cache(cache) -> ShapeCache:
    """A :class:`ShapeCache` from a ShapeCache, a folder path or True (the default folder)."""
    if isinstance(cache, ShapeCache):
        return cache
    if cache is True:
        return ShapeCache()
    if isinstance(cache, (str, os.PathLike)):
        return ShapeCache(cache)
    raise ParameterError(f"The 'cache' parameter must be a ShapeCache, a folder path or True. Got {cache!r} instead.")


def _reason(exc: BaseException) -> str:
    return getattr(exc, "strerror", None) or str(exc)


def _size(path: Path) -> int:
    try:
        return path.stat().st_size
    except FileNotFoundError:  # removed by a concurrent clear
        return 0
