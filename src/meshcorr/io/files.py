"""Writing files: atomically, several together, and checking output paths before any work.

Every file is written atomically: to a temporary file in the same directory,
then moved over the target with :func:`os.replace` (:func:`atomic_write`);
:func:`check_outputs` refuses output paths that cannot be written (or are
inputs) before any work, and :func:`staged_writes` moves several outputs into
place only once all are written.
"""

from __future__ import annotations

import errno
import os
import secrets
import stat
from contextlib import contextmanager
from contextvars import ContextVar
from pathlib import Path
from typing import BinaryIO, Callable

from ..errors import DiskFullError, OutputError

__all__ = ["atomic_write", "check_outputs", "staged_writes"]

#: The errno values of a full disk or quota: written as :class:`DiskFullError`.
DISK_FULL = tuple(code for code in (errno.ENOSPC, getattr(errno, "EDQUOT", None)) if code is not None)

#: The (temporary file, target) pairs of the innermost :func:`staged_writes` block, if any.
_STAGED: ContextVar[list | None] = ContextVar("meshcorr_staged_writes", default=None)


def check_outputs(outputs: dict, inputs: dict | None = None, *, stdout: tuple = ()) -> None:
    """Refuse, before any work, output paths that cannot or must not be written.

    Checked for each output: it is not ``"-"`` unless it may go to stdout,
    its path does not end with a path separator (a folder's name), it is not
    the path of an input (compared as real paths, and as the same file where
    both exist), no two outputs share a path, its folder exists and a file
    can be created there (a probe file is made and removed: this catches
    read-only file systems and ``/proc``), and an existing file there is a
    regular file that may be replaced (not read-only, not immutable).
    ``None`` is skipped.

    Parameters
    ----------
    outputs : dict of str -> path
        What each output is (``"-o"``, ``"--report"``, ...) and where it goes.
    inputs : dict of str -> path, optional
        The input files, named the same way.
    stdout : tuple of str
        The outputs that ``"-"`` sends to stdout (e.g. ``("-o",)``); for
        any other, ``"-"`` is refused (it wrote a file named ``-``).

    Raises
    ------
    OutputError
        Naming the option, the path and the fix.
    """
    inputs = {what: Path(path) for what, path in (inputs or {}).items() if path is not None}
    seen: dict[str, str] = {}
    for what, path in outputs.items():
        if path is None or (str(path) == "-" and what in stdout):
            continue
        if str(path) == "-":
            others = f" (only {' and '.join(stdout)} can)" if stdout else ""
            raise OutputError(f"Cannot write {what} to stdout ('-'): it is written to a file only{others}. "
                              "Give a file path (./- for a file named '-').")
        refuse_folder_name(path, what)
        path = Path(path)
        real = os.path.realpath(path)
        for source, input_path in inputs.items():
            if real == os.path.realpath(input_path) or (path.exists() and input_path.exists()
                                                        and os.path.samefile(path, input_path)):
                raise OutputError(f"{what} {path} is the input {source}: writing there would replace it. "
                                  "Give another output path.")
        if real in seen:
            raise OutputError(f"{what} and {seen[real]} are the same file ({path}): one would overwrite the "
                              "other. Give them different paths.")
        seen[real] = what
        folder = path.parent
        if not folder.is_dir():
            raise OutputError(f"Cannot write {what} {path}: the folder {folder} does not exist. Create it first.")
        if path.is_dir():
            raise OutputError(f"Cannot write {what} {path}: it is a folder. Give a file name such as map.txt.")
        if path.exists() and not stat.S_ISREG(path.stat().st_mode):
            raise OutputError(f"Cannot write {what} {path}: it exists and is not a regular file "
                              "(a device or a pipe); give a file path.")
        if path.exists() and not os.access(path, os.W_OK):
            raise OutputError(f"Cannot write {what} {path}: the file exists and cannot be replaced "
                              "(read-only or immutable). Remove it or give another path.")
        probe = sibling(path, "probe")
        try:
            os.close(os.open(probe, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600))
            os.unlink(probe)
        except OSError as exc:
            raise OutputError(f"Cannot write {what} {path}: no file can be created in {folder} "
                              f"({exc.strerror}). Give a path in a writable folder.") from exc


def refuse_folder_name(path, what: str = "the output") -> None:
    """Raise :class:`OutputError` if ``path`` ends with a path separator: it names a folder, not a file.

    ``Path("maps/")`` drops the separator, so ``-o maps/`` wrote a file ``maps`` and ``-o file.txt/``
    replaced ``file.txt``.
    """
    text = os.fspath(path)
    text = text.decode(errors="replace") if isinstance(text, bytes) else text
    if not text.endswith(tuple(sep for sep in (os.sep, os.altsep) if sep)):
        return
    start = f"Cannot write {what} {text}: a path ending with '{text[-1]}' names a folder"
    folder = text.rstrip(os.sep + (os.altsep or "")) or text
    if os.path.isdir(folder):
        raise OutputError(f"{start}. Give a file name in it, e.g. {text}map.txt.")
    if os.path.exists(folder):
        raise OutputError(f"{start}, and {folder} is a file. Give the file path without the trailing '{text[-1]}'.")
    raise OutputError(f"{start}, and there is no folder {folder}. Give a file path without the trailing "
                      f"'{text[-1]}', or create the folder and give a file name in it, e.g. {text}map.txt.")


def sibling(path: Path, kind: str) -> Path:
    """A new hidden name beside ``path`` for a temporary file: ``.NAME.<12 hex>.<kind>``.

    ``NAME`` is ``path``'s name, cut so that the whole name fits the
    folder's limit (255 bytes on most file systems): a valid output name of
    250 characters must not fail because of its temporary file's suffix.
    """
    try:
        limit = os.pathconf(path.parent, "PC_NAME_MAX")
    except (OSError, ValueError, AttributeError):
        limit = 255
    tail = f".{secrets.token_hex(6)}.{kind}"
    room = max(1, limit - 1 - len(tail.encode()))
    name = path.name.encode()[:room].decode(errors="ignore")
    return path.parent / f".{name}{tail}"


@contextmanager
def staged_writes():
    """Let the writes inside the block appear together at its end, or not at all.

    Inside the block :func:`atomic_write` (and so :func:`write_map`,
    :func:`write_mesh` and the report writer) writes each file to its
    temporary file only. When the block ends normally the temporary files
    are moved over their targets, in the order written; when it raises
    (including KeyboardInterrupt) they are removed and no target changes.
    """
    staged: list = []
    token = _STAGED.set(staged)
    try:
        yield
    except BaseException:
        _STAGED.reset(token)
        for temp, _ in staged:
            temp.unlink(missing_ok=True)
        raise
    _STAGED.reset(token)
    try:
        for index, (temp, path) in enumerate(staged):
            _replace(temp, path)
    except BaseException:
        for temp, _ in staged[index:]:
            temp.unlink(missing_ok=True)
        raise


def disk_full_message(path, exc: OSError, *, removed: bool = True) -> str:
    """The words of a full disk (``exc.errno`` in :data:`DISK_FULL`) while writing ``path``.

    ``removed``: the partial file was removed (:func:`atomic_write`); False for a stream such as stdout.
    """
    what = "the disk quota is exceeded" if exc.errno != errno.ENOSPC else "the disk is full"
    left = "nothing was left of it" if removed else "what was written of it is incomplete"
    return (f"Cannot write {path}: {what} ({exc.strerror or os.strerror(exc.errno)}); {left}. "
            "Free some space (or write to another disk) and run again.")


def _replace(temp: Path, path: Path) -> None:
    try:
        os.replace(temp, path)
    except OSError as exc:
        temp.unlink(missing_ok=True)
        raise OutputError(f"Cannot write {path}: {exc.strerror}.") from exc


def atomic_write(path, writer: Callable[[BinaryIO], object]) -> None:
    """Write a file atomically: all of it appears at ``path``, or nothing changes.

    ``writer`` writes into a temporary file in the same directory, opened in
    binary mode; the temporary file then replaces ``path`` with
    :func:`os.replace` (inside :func:`staged_writes`: when that block ends).
    If ``writer`` raises, the temporary file is removed and ``path`` is left
    as it was.

    Parameters
    ----------
    path : str or os.PathLike
        The file to create or replace.
    writer : callable
        Called as ``writer(file)`` with a binary file object.

    Raises
    ------
    OutputError
        If ``path`` ends with a path separator, the directory of ``path``
        does not exist or the file cannot be created there (a
        :class:`ParameterError`).
    DiskFullError
        If the disk or the quota is full (``ENOSPC``, ``EDQUOT``): an
        :class:`OutputError` naming ``path``; nothing is left of the file.
    """
    refuse_folder_name(path)
    path = Path(path)
    directory = path.parent
    if not directory.is_dir():
        raise OutputError(f"Cannot write {path}: directory {directory} does not exist.")
    temp = sibling(path, "tmp")
    try:
        # os.open applies the umask, so the final file gets ordinary permissions.
        fd = os.open(temp, os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_BINARY", 0), 0o666)
    except OSError as exc:
        raise OutputError(f"Cannot write {path}: no file can be created in {directory} ({exc.strerror}).") from exc
    try:
        with os.fdopen(fd, "wb") as file:
            writer(file)
            file.flush()
            os.fsync(file.fileno())
    except OSError as exc:
        temp.unlink(missing_ok=True)
        if exc.errno in DISK_FULL:
            raise DiskFullError(disk_full_message(path, exc)) from exc
        raise
    except BaseException:
        temp.unlink(missing_ok=True)
        raise
    staged = _STAGED.get()
    if staged is not None:
        staged.append((temp, path))
    else:
        _replace(temp, path)
