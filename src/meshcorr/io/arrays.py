"""NumPy files: one array (``.npy``) and archives of named arrays (``.npz``), never pickles.

NumPy reads an ``.npz`` given as ``.npy`` as an archive object and says of
any other file that it holds pickled data, to be loaded with
``allow_pickle``: advice to run untrusted code. :func:`file_kind` tells what
a file holds from its first bytes, so that the messages say it instead.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..errors import InputError
from .files import atomic_write

__all__ = ["file_kind", "load_npy", "read_npz", "write_npz"]

def file_kind(path) -> str | None:
    """What a file holds, told from its first bytes, for messages: ``"npy"`` (a NumPy ``.npy`` array),
    ``"zip"`` (a zip archive, as an ``.npz`` is), ``"text"``, ``"empty"``; None for any other.
    ``OSError`` if it cannot be read."""
    with open(path, "rb") as file:
        head = file.read(4096)
    if not head:
        return "empty"
    if head.startswith(b"\x93NUMPY"):
        return "npy"
    if head.startswith((b"PK\x03\x04", b"PK\x05\x06")):
        return "zip"
    if b"\0" not in head:
        try:
            head.decode("utf-8")
        except UnicodeDecodeError as exc:
            if exc.start < len(head) - 3:  # not a character cut at the end of the head
                return None
        return "text"
    return None


def load_npy(path) -> np.ndarray:
    """The array of a ``.npy`` file (no pickles); ``ValueError`` with the reason in words if it is none.

    NumPy read an ``.npz`` as an archive object and said of any other file that it holds pickled
    data, to be loaded with ``allow_pickle``: advice to run untrusted code.
    """
    try:
        kind = file_kind(path)
    except OSError as exc:
        raise ValueError(f"it cannot be read: {exc.strerror or exc}") from exc
    if kind != "npy":
        raise ValueError({"zip": "it is a zip archive such as an .npz, not a .npy array",
                          "text": "it is a text file, not a .npy array", "empty": "the file is empty"}.get(
                              kind, "it is not a .npy file: it lacks the NumPy header"))
    try:
        return np.load(path, allow_pickle=False)
    except Exception as exc:  # numpy raises several types on a damaged .npy array
        if "pickle" in str(exc):
            raise ValueError("it holds an array of Python objects, which meshcorr does not load") from exc
        raise ValueError(str(exc).rstrip(".")) from exc


def read_npz(path, what: str) -> dict[str, np.ndarray]:
    """Every array of an ``.npz`` file (no pickles), or an :class:`InputError` naming ``what`` was expected.

    Parameters
    ----------
    path : str or os.PathLike
    what : str
        What the file should hold, for messages (e.g. "a saved meshcorr result").
    """
    import zipfile

    if not Path(path).exists():
        raise InputError(f"{path}: no such file.")
    if not Path(path).is_file():
        raise InputError(f"{path} is not {what}: it is a folder, not a file.")
    try:
        kind = file_kind(path)
    except OSError as exc:
        raise InputError(f"{path} cannot be read: {exc.strerror or exc}.") from exc
    if kind != "zip":  # np.load read a .npy as one array and any other file as a pickle
        found = {"npy": "a .npy array (one array, as numpy.save writes)", "text": "a text file",
                 "empty": "an empty file"}.get(kind)
        raise InputError(f"{path} is not {what}: it is {found + ', not' if found else 'not'} an .npz "
                         f"archive. Give {what}: an .npz archive of named arrays (numpy.savez).")
    try:
        with zipfile.ZipFile(path) as archive:
            odd = [name for name in archive.namelist() if not name.endswith(".npy")]
        if odd:
            raise InputError(f"{path} is not {what}: it is a zip archive, not an .npz archive (its member "
                             f"{odd[0]!r} is no .npy array). Give {what}: an .npz archive of named arrays "
                             "(numpy.savez).")
        with np.load(path, allow_pickle=False) as data:
            return {name: np.asarray(data[name]) for name in data.files}
    except InputError:
        raise
    except (OSError, ValueError, EOFError, zipfile.BadZipFile) as exc:
        if "pickle" in str(exc):
            reason = "an array in it holds Python objects, which meshcorr does not load"
        else:
            reason = str(exc).rstrip(".")
        raise InputError(f"{path} is not {what} (.npz): {reason}.") from exc


def write_npz(path, arrays: dict) -> None:
    """Write named arrays to one compressed ``.npz`` file, atomically (read back by :func:`read_npz`)."""
    atomic_write(path, lambda file: np.savez_compressed(file, **arrays))
