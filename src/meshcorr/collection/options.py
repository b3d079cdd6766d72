"""The options of a batch: split into per-shape settings and match options, checked, and made into keys.

:func:`split_options` checks every option as :func:`meshcorr.match` would,
before any work; :func:`task_key` names what a map is made from (its mesh
files' path and content, :func:`file_digest`, and the settings), so that a
rerun into the same folder knows which maps still hold: a mesh changed in
place keeps its size and modification time only if it is made to, its
SHA-256 never.
"""

from __future__ import annotations

import hashlib
import json
import os
from pathlib import Path

from ..core.holes import fills
from ..errors import ParameterError
from ..pipeline.settings import SHAPE_SETTINGS, shape_settings

__all__ = ["cache_root", "file_digest", "jsonable", "split_options", "task_key"]


def split_options(options: dict) -> tuple[dict, dict]:
    """The per-shape settings and the other match options, every value checked before any work.

    Returns
    -------
    settings : dict
        The settings of a prepared shape (:data:`meshcorr.pipeline.settings.SHAPE_SETTINGS`,
        defaults filled in, ``fill_holes`` resolved for ``partial`` and ``bijective``).
    options : dict
        The other options of :func:`meshcorr.match`, as given.

    Raises
    ------
    ParameterError
        A method other than the spectral one, user landmarks, an option
        :func:`meshcorr.match` does not take, or a value it refuses.
    """
    from ..pipeline.methods import check_options, method_parameters

    given = dict(options)
    if "method" in given and given["method"] != "spectral":
        raise ParameterError("meshcorr batch runs the spectral method only (prepared shapes); "
                             f"got method={given['method']!r}.")
    if given.get("landmarks") is not None:
        raise ParameterError("User landmarks belong to one pair: meshcorr batch does not take them (match "
                             "such pairs one by one with meshcorr.match(..., landmarks=...)).")
    shape = {key: given.pop(key, default) for key, default in SHAPE_SETTINGS.items()}
    settings = shape_settings(**shape)
    settings["fill_holes"] = fills(settings["fill_holes"], partial=given.get("partial"),
                                   bijective=given.get("bijective", False))
    taken = list(method_parameters("spectral"))
    unknown = sorted(set(given) - set(taken))
    if unknown:
        raise ParameterError(f"Unknown option of meshcorr.batch: {unknown[0]!r} is no option of meshcorr.match "
                             f"(its options are: {', '.join(taken)}).")
    # Every value as match would check it, those it checks only once the meshes are loaded
    # (e.g. icp_iterations) included, so that no pair fails for a bad option.
    check_options("spectral", **given, **settings)
    return settings, given


def jsonable(options: dict) -> dict:
    """``options`` sorted by key, each value that JSON cannot hold as its ``repr``: for ``run.json`` and the keys."""
    return {key: (value if isinstance(value, (int, float, str, bool, type(None))) else repr(value))
            for key, value in sorted(options.items())}


def file_digest(path: str) -> str | None:
    """SHA-256 (hex) of a file's bytes (as ``meshcorr bench`` records its meshes), or None if it cannot be read."""
    try:
        with open(path, "rb") as file:
            return hashlib.file_digest(file, "sha256").hexdigest()
    except OSError:
        return None


def task_key(text: str, *parts, digests: dict | None = None) -> str:
    """A deterministic key: each file's path and content (each path in ``text``) and the settings.

    ``digests`` (path -> :func:`file_digest`), kept by the caller, saves reading a file twice.
    """
    digests = {} if digests is None else digests
    files = []
    for path in text.split(chr(0)):
        if path not in digests:
            digests[path] = file_digest(path)
        files.append([os.path.abspath(path), digests[path]] if digests[path] is not None else [path])
    payload = json.dumps([files, [jsonable(p) if isinstance(p, dict) else p for p in parts]], sort_keys=True)
    return hashlib.sha256(payload.encode()).hexdigest()[:24]


def cache_root(cache) -> Path:
    """The folder of the on-disk cache ``cache`` (a ShapeCache, a path, or True for the default one)."""
    from ..shapes.cache import as_cache

    return as_cache(cache).root
