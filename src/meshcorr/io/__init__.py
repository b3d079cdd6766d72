"""Read and write meshes, point clouds and vertex maps.

Meshes are read without processing, so vertex ``i`` of the file is vertex
``i`` of the arrays (correspondences are reported by vertex index): OFF by
:mod:`meshcorr.io.off`, which checks every record against the header, the other
formats by trimesh after the checks of :func:`read_mesh`. A file without
faces is a point cloud (faces ``(0, 3)``), and so are the point formats
``.xyz`` (text, ``x y z`` per line) and ``.npy`` (an ``(n, 3)`` array). Every file is
written atomically: to a temporary file in the same directory, then moved
over the target with :func:`os.replace`; :func:`check_outputs` refuses
output paths that cannot be written (or are inputs) before any work, and
:func:`staged_writes` moves several outputs into place only once all are
written.
"""

from __future__ import annotations

import io
import os
import re
import secrets
import stat
import warnings
from contextlib import contextmanager
from contextvars import ContextVar
from pathlib import Path
from typing import BinaryIO, Callable

import numpy as np

from meshcorr.runtime.interrupt import deferred_interrupt

with deferred_interrupt():  # trimesh's guards around its optional imports catch BaseException
    import trimesh
from meshcorr.errors import InputError, MeshError, MeshWarning, OutputError, ParameterError
from meshcorr.io.off import parse_off
from meshcorr.runtime.checks import MapMessages, check_vertex_map

__all__ = ["SUPPORTED_FORMATS", "atomic_write", "check_outputs", "read_map", "read_mesh", "staged_writes",
           "write_map", "write_mesh"]

#: File extensions read_mesh and write_mesh understand, and their format names.
SUPPORTED_FORMATS = {".off": "OFF", ".obj": "OBJ", ".ply": "PLY", ".stl": "STL"}
_SUPPORTED_LIST = ", ".join(SUPPORTED_FORMATS)
#: Point-cloud formats read_mesh reads as well (clouds are also read from the mesh formats without faces).
POINT_FORMATS = {".xyz": "XYZ", ".npy": "NPY"}
_READ_LIST = ", ".join({**SUPPORTED_FORMATS, **POINT_FORMATS})
_NO_FACES = np.zeros((0, 3), dtype=np.int64)


def _int_or_none(text) -> int | None:
    try:
        return int(text)
    except (TypeError, ValueError):
        return None


def _declared_counts(data: bytes, fmt: str) -> tuple[int | None, int | None]:
    """(vertex records, face records) a file declares, read cheaply as text; None if unknown."""
    if fmt == "OBJ":
        return (
            len(re.findall(rb"^v[ \t]", data, flags=re.MULTILINE)),
            len(re.findall(rb"^f[ \t]", data, flags=re.MULTILINE)),
        )
    if fmt == "PLY":
        end = data.find(b"end_header")
        if end < 0:
            return None, None
        header = data[:end].decode("ascii", errors="replace")
        n_v = re.search(r"^element\s+vertex\s+(\d+)", header, flags=re.MULTILINE)
        n_f = re.search(r"^element\s+face\s+(\d+)", header, flags=re.MULTILINE)
        return (int(n_v.group(1)) if n_v else None), (int(n_f.group(1)) if n_f else None)
    return None, None


def _count_polygons(data: bytes, fmt: str, n_vertices: int | None) -> int | None:
    """Exact number of faces with more than 3 sides, where cheap to find (OBJ)."""
    if fmt == "OBJ":
        return sum(
            1 for rec in re.findall(rb"^f[ \t]+([^\n]*)", data, flags=re.MULTILINE)
            if len(rec.split(b"#", 1)[0].split()) > 3
        )
    return None


def _read_plain_off(data: bytes) -> tuple[np.ndarray, np.ndarray] | None:
    """Vertices and faces of the commonest OFF file, or None to let trimesh read it.

    Handles only ``OFF`` with no comments, colours or polygons: the header
    ``OFF``, the counts, then exactly ``3 n`` coordinates and ``n_f`` records
    ``3 i j k``. Hand-written for speed: trimesh's OFF reader takes ~80 ms for a
    5000-vertex file, this ~10 ms; anything else falls back to trimesh.
    """
    if b"#" in data:
        return None
    tokens = data.split()
    if len(tokens) < 4 or tokens[0] != b"OFF":
        return None
    n_v, n_f = _int_or_none(tokens[1]), _int_or_none(tokens[2])
    if not n_v or not n_f or len(tokens) != 4 + 3 * n_v + 4 * n_f:
        return None
    try:
        vertices = np.array(tokens[4:4 + 3 * n_v], dtype=np.float64).reshape(n_v, 3)
        records = np.array(tokens[4 + 3 * n_v:], dtype=np.int64).reshape(n_f, 4)
    except (ValueError, OverflowError):  # the strict reader says where
        return None
    faces = np.ascontiguousarray(records[:, 1:])
    if (records[:, 0] != 3).any() or not np.isfinite(vertices).all() or faces.min() < 0 or faces.max() >= n_v:
        return None  # the strict reader says where the problem is
    return vertices, faces


def _text(data: bytes, label: str, fmt: str) -> bytes:
    """A text format's bytes as UTF-8: Latin-1 (any byte) where they are not UTF-8 already.

    trimesh would guess the encoding of non-UTF-8 text with charset_normalizer,
    an optional dependency; numbers and keywords are ASCII in any case.
    """
    if b"\x00" in data:
        raise MeshError(f"{label}: holds NUL bytes, so it is not a {fmt} text file (a binary file "
                        "with the wrong extension?). Check the file and its extension.")
    try:
        data.decode("utf-8")
        return data
    except UnicodeDecodeError:
        return data.decode("latin-1").encode("utf-8")


def _check_obj(data: bytes, label: str) -> None:
    """Every ``f`` record of an OBJ file lists at least three vertices (else: truncated)."""
    for match in re.finditer(rb"^f([ \t][^\r\n]*)?$", data, flags=re.MULTILINE):
        refs = (match.group(1) or b"").split(b"#", 1)[0].split()
        if len(refs) < 3:
            line = data.count(b"\n", 0, match.start()) + 1
            raise MeshError(f"{label}, line {line}: a face lists {len(refs)} vertices; a face needs at "
                            "least 3 (is the file truncated?). Re-export the mesh or repair the line.")


def _check_binary_formats(data: bytes, label: str, fmt: str) -> bytes:
    """The data trimesh gets for PLY and STL, refused early where it is neither binary nor text of the format."""
    if fmt == "PLY":
        if not data.startswith(b"ply") or b"end_header" not in data[:65536]:
            raise MeshError(f"{label}: not a PLY file (it does not start with 'ply' and a header ending in "
                            "'end_header'). Check the file and its extension.")
        return data
    # STL: binary if the size matches the triangle count of the 84-byte header, else ASCII text.
    if len(data) >= 84 and len(data) == 84 + 50 * int.from_bytes(data[80:84], "little"):
        return data
    if not data.lstrip()[:5].lower() == b"solid":
        raise MeshError(f"{label}: neither a binary STL (its size does not match the triangle count in its "
                        "header: truncated?) nor an ASCII STL (starting with 'solid'). "
                        "Re-export the mesh.")
    return _text(data, label, fmt)


def _read_xyz(data: bytes, label: str) -> np.ndarray:
    """The points of an XYZ text file: ``x y z`` per line, further columns ignored, ``#`` comments.

    Raises
    ------
    MeshError
        Naming the first line with fewer than three numbers (or a value that is no number).
    """
    text = _text(data, label, "XYZ").decode("utf-8")
    rows = []
    for number, line in enumerate(text.splitlines(), start=1):
        fields = line.split("#", 1)[0].replace(",", " ").split()
        if not fields:
            continue
        try:
            if len(fields) < 3:
                raise ValueError
            rows.append((float(fields[0]), float(fields[1]), float(fields[2])))
        except ValueError:
            hint = ("Start a header line with '#' (a comment)" if not rows and any(c.isalpha() for c in line)
                    else "Repair the line or re-export the points")
            raise MeshError(f"{label}, line {number}: expected 'x y z' (three numbers, further columns "
                            f"ignored), got {line.strip()[:60]!r}. {hint}.") from None
    if not rows:
        raise MeshError(f"{label}: the file holds no points (only comments or blank lines).")
    return np.array(rows, dtype=np.float64)


def _read_npy(path: Path, label: str) -> np.ndarray:
    """The points of an ``.npy`` file holding one ``(n, 3)`` array of real numbers."""
    try:
        points = _load_npy(path)
    except ValueError as exc:
        raise MeshError(f"{label}: could not be read as a .npy array ({exc}). Save the points with "
                        "numpy.save(path, points).") from exc
    if points.ndim != 2 or points.shape[1] != 3 or not np.issubdtype(points.dtype, np.number) \
            or np.iscomplexobj(points):
        raise MeshError(f"{label}: a point cloud in .npy must be an (n, 3) array of real numbers; got shape "
                        f"{points.shape} and dtype {points.dtype}. Save the x, y, z columns only.")
    return np.array(points, dtype=np.float64)


@contextmanager
def quiet_trimesh():
    """Hide trimesh's log lines while it parses: on a damaged file it logs the traceback of each parser
    it tries in turn, and the :class:`MeshError` raised here says what was wrong (library code does
    not print). The level of the ``trimesh`` logger is restored afterwards."""
    import logging

    logger = logging.getLogger("trimesh")
    level = logger.level
    logger.setLevel(logging.CRITICAL)
    try:
        yield
    finally:
        logger.setLevel(level)


def read_mesh(path, *, name: str | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Read a triangle mesh or a point cloud, keeping vertex order.

    Meshes: OFF, OBJ, PLY or STL. Point clouds: any of those without faces
    (a PLY of points, an OBJ of ``v`` lines, an OFF with 0 faces), ``.xyz``
    text (one point ``x y z`` a line, separated by spaces, tabs or commas;
    further columns such as normals or colours are ignored; blank lines and
    ``#`` comments are skipped) or ``.npy`` (one ``(n, 3)`` array).

    Vertices are neither merged nor reordered (OFF by :func:`meshcorr.io.off.parse_off`;
    the other formats by trimesh with ``process=False``, for OBJ also
    ``maintain_order=True`` so texture coordinates do not split vertices),
    so vertex ``i`` of the file is row ``i`` of ``vertices``. The exception
    is STL, which stores three unshared vertices per triangle: there
    duplicate vertices are merged, as an STL file has no vertex order.

    The input rules (README, "Reading meshes: input rules"): the header
    counts of OFF and PLY are checked against the data and each face's
    arity against its indices (OFF: every record; OBJ: faces of fewer than
    three vertices); text may be in any ASCII-compatible encoding (bytes
    that are not UTF-8 are read as Latin-1, in comments say); polygons are
    triangulated with a :class:`MeshWarning`. Everything else that does not
    fit is refused with the file, the line where it applies and the fix.

    Parameters
    ----------
    path : str or os.PathLike
        The mesh file; its extension selects the format.
    name : str, optional
        How messages refer to the mesh (followed by the path unless it holds
        the file name); defaults to the path.

    Returns
    -------
    vertices : (n, 3) float64
        Vertex coordinates in file order.
    faces : (m, 3) int64
        Triangles as 0-based vertex indices (not validated; see
        :func:`meshcorr.core.validate.validate_mesh`); ``(0, 3)`` for a point
        cloud (see :func:`meshcorr.core.pointcloud.validate_cloud`).

    Raises
    ------
    MeshError
        If the file is missing, empty, of an unsupported format, truncated,
        cannot be parsed, holds several separate geometries or no vertices.

    Warns
    -----
    MeshWarning
        If faces with more than 3 sides were triangulated, or if trailing
        vertices used by no face were dropped from a textured OBJ.
    """
    path = Path(path)
    # Messages name the file even where the caller's name is a role ("source").
    label = name if name and path.name in name else f"{name} {path}" if name else str(path)
    if not path.is_file():
        which = f" ({name})" if name and name != str(path) else ""
        raise MeshError(f"No such file: {path}{which}. Check the path." if not path.exists()
                        else f"Not a file: {path}{which}; give a mesh file.")
    fmt = {**SUPPORTED_FORMATS, **POINT_FORMATS}.get(path.suffix.lower())
    if fmt is None:
        raise MeshError(
            f"Unsupported mesh format '{path.suffix or '(no extension)'}' for {path}; "
            f"supported: {_READ_LIST}. Convert the file first (e.g. in MeshLab)."
        )
    if fmt == "NPY":
        return _read_npy(path, label), _NO_FACES.copy()
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise MeshError(f"{label}: cannot be read ({exc.strerror}). Check its permissions.") from exc
    if not data or data.isspace():
        raise MeshError(f"File is empty: {path}. Check that it was written completely.")
    if fmt == "XYZ":
        return _read_xyz(data, label), _NO_FACES.copy()
    if fmt == "OFF":
        plain = _read_plain_off(data)
        if plain is not None:
            return plain
        vertices, faces, n_polygons, n_records = parse_off(data, label)
        if not len(vertices):
            raise MeshError(f"{label}: the file contains no vertices. Check that it was written completely.")
        if not len(faces):  # a point cloud
            return vertices, _NO_FACES.copy()
        if n_polygons:
            _warn_polygons(label, f"{n_polygons} polygonal faces", n_records, len(faces))
        return vertices, faces
    if fmt == "OBJ":
        data = _text(data, label, fmt)
        _check_obj(data, label)
    else:
        data = _check_binary_formats(data, label, fmt)
    options = {"maintain_order": True, "skip_materials": True} if fmt == "OBJ" else {}
    try:
        # trimesh's parsers catch BaseException in places (fast path, then a fallback): a
        # Ctrl-C there would be swallowed, so it is delivered once the parse ends.
        with deferred_interrupt(), quiet_trimesh():
            scene = trimesh.load(io.BytesIO(data), file_type=fmt.lower(), process=False, force="scene",
                                 **options)
    except Exception as exc:  # trimesh raises many types on corrupt input
        raise MeshError(
            f"{label}: the file could not be parsed as {fmt} ({type(exc).__name__}: {exc}). "
            f"Check that it is a valid {fmt} file, e.g. by opening it in MeshLab."
        ) from exc
    geometries = list(scene.geometry.values())
    if len(geometries) > 1:
        raise MeshError(
            f"{label} holds {len(geometries)} separate geometries (objects or materials); "
            "meshcorr needs a single mesh. Merge them into one object first."
        )
    if not geometries or not isinstance(geometries[0], (trimesh.Trimesh, trimesh.PointCloud)) \
            or not len(geometries[0].vertices):
        raise MeshError(
            f"{label}: the file contains no vertices (it is empty, or not a valid {fmt} file). "
            "meshcorr needs a triangle mesh or a point cloud."
        )
    mesh = geometries[0]
    cloud = isinstance(mesh, trimesh.PointCloud) or not len(mesh.faces)  # a point cloud: no faces
    if fmt == "STL":
        mesh.merge_vertices()
    vertices = np.array(mesh.vertices, dtype=np.float64)
    faces = _NO_FACES.copy() if cloud else np.array(mesh.faces, dtype=np.int64)
    if vertices.ndim != 2 or vertices.shape[1] != 3 or faces.ndim != 2 or faces.shape[1] != 3:
        raise MeshError(f"{label}: the file could not be parsed as a 3-D triangle mesh (vertices of shape "
                        f"{vertices.shape}, faces of shape {faces.shape}; a vertex line with two coordinates?). "
                        f"Check that it is a valid {fmt} file, e.g. by opening it in MeshLab.")
    if not np.isfinite(vertices).all():
        row = int(np.flatnonzero(~np.isfinite(vertices).all(axis=1))[0])
        raise MeshError(f"{label}: vertex {row} has a non-finite coordinate (nan or inf). "
                        "Repair or re-export the mesh.")
    if fmt == "STL":
        return vertices, faces

    n_vertex_records, n_face_records = _declared_counts(data, fmt)
    if n_face_records is not None and len(faces) > n_face_records:
        n_polygons = _count_polygons(data, fmt, n_vertex_records)
        _warn_polygons(label, f"{n_polygons} polygonal faces" if n_polygons else "polygonal faces",
                       n_face_records, len(faces))
    if n_face_records is not None and fmt == "PLY" and len(faces) < n_face_records:
        raise MeshError(f"{label}: the header declares {n_face_records} faces but {len(faces)} were read: "
                        "the file is truncated or malformed. Re-export the mesh.")
    if n_vertex_records is not None and len(vertices) != n_vertex_records:
        if fmt == "OBJ" and len(vertices) < n_vertex_records:
            warnings.warn(
                MeshWarning(
                    f"{label}: {n_vertex_records - len(vertices)} trailing vertices used by "
                    "no face were dropped while reading; the other vertex indices are unchanged."
                ),
                stacklevel=2,
            )
        else:
            raise MeshError(
                f"{label}: the file declares {n_vertex_records} vertices but "
                f"{len(vertices)} were read, so vertex order could not be preserved. "
                "Re-save the file (e.g. in MeshLab) without texture seams or extra data."
            )
    return vertices, faces


def _warn_polygons(label: str, what: str, n_file_faces: int, n_triangles: int) -> None:
    warnings.warn(
        MeshWarning(
            f"{label}: {what} with more than 3 sides were triangulated "
            f"({n_file_faces} faces in the file became {n_triangles} triangles). "
            "Triangulate the mesh yourself to control how."
        ),
        stacklevel=3,
    )


#: The (temporary file, target) pairs of the innermost :func:`staged_writes` block, if any.
_STAGED: ContextVar[list | None] = ContextVar("meshcorr_staged_writes", default=None)


def check_outputs(outputs: dict, inputs: dict | None = None) -> None:
    """Refuse, before any work, output paths that cannot or must not be written.

    Checked for each output: it is not the path of an input (compared as
    real paths, and as the same file where both exist), no two outputs share
    a path, its folder exists and a file can be created there (a probe file
    is made and removed: this catches read-only file systems and ``/proc``),
    and an existing file there is a regular file that may be replaced (not
    read-only, not immutable). ``"-"`` (stdout) and ``None`` are skipped.

    Parameters
    ----------
    outputs : dict of str -> path
        What each output is (``"-o"``, ``"--report"``, ...) and where it goes.
    inputs : dict of str -> path, optional
        The input files, named the same way.

    Raises
    ------
    OutputError
        Naming the option, the path and the fix.
    """
    inputs = {what: Path(path) for what, path in (inputs or {}).items() if path is not None}
    seen: dict[str, str] = {}
    for what, path in outputs.items():
        if path is None or str(path) == "-":
            continue
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
        probe = folder / f".{path.name}.{secrets.token_hex(6)}.probe"
        try:
            os.close(os.open(probe, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600))
            os.unlink(probe)
        except OSError as exc:
            raise OutputError(f"Cannot write {what} {path}: no file can be created in {folder} "
                              f"({exc.strerror}). Give a path in a writable folder.") from exc


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
        If the directory of ``path`` does not exist or the file cannot be
        created there (a :class:`ParameterError`).
    """
    path = Path(path)
    directory = path.parent
    if not directory.is_dir():
        raise OutputError(f"Cannot write {path}: directory {directory} does not exist.")
    temp = directory / f".{path.name}.{secrets.token_hex(6)}.tmp"
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
    except BaseException:
        temp.unlink(missing_ok=True)
        raise
    staged = _STAGED.get()
    if staged is not None:
        staged.append((temp, path))
    else:
        _replace(temp, path)


#: The words of a map that :func:`write_map` refuses (:func:`meshcorr.runtime.checks.check_vertex_map`).
_WRITTEN_MAP = MapMessages(
    not_integer="The 'mapping' parameter of write_map must be a 1-D integer array. "
                "Got shape {shape} and dtype {dtype} instead.",
    wrong_length="", out_of_range="")  # write_map checks no vertex counts


def write_map(path, mapping) -> None:
    """Write a vertex map atomically: ``.npy`` with :func:`numpy.save`, else one integer per line.

    Parameters
    ----------
    path : str or os.PathLike
        Target file. ``.npy`` gives a NumPy file; any other extension
        (``.txt``, ``.map``, none) gives text with one integer per line.
    mapping : (n,) int
        The map, e.g. ``p2p_21[i]`` = vertex of mesh 1 matched to vertex ``i`` of mesh 2.
    """
    mapping = check_vertex_map(mapping, messages=_WRITTEN_MAP)
    if Path(path).suffix.lower() == ".npy":
        atomic_write(path, lambda file: np.save(file, mapping, allow_pickle=False))
    else:
        text = map_text(mapping)
        atomic_write(path, lambda file: file.write(text.encode("ascii")))


def map_text(mapping) -> str:
    """A vertex map as the text :func:`write_map` writes: one integer per line."""
    return "".join(f"{value}\n" for value in np.asarray(mapping).tolist())


def read_map(path, *, name: str | None = None) -> np.ndarray:
    """Read a vertex map written by :func:`write_map` (``.npy`` or one integer per line).

    Parameters
    ----------
    path : str or os.PathLike
        The map file. Blank lines in text files are ignored.
    name : str, optional
        What the file is, for messages (e.g. ``"MAP"``).

    Returns
    -------
    mapping : (n,) int64

    Raises
    ------
    InputError
        If the file is missing or does not hold a 1-D array of integers
        (a :class:`ParameterError`).
    """
    path = Path(path)
    if not path.is_file():
        which = f" ({name})" if name else ""
        raise InputError(f"No such file: {path}{which}. Check the path." if not path.exists()
                         else f"Not a file: {path}{which}; give a map file.")
    if path.suffix.lower() == ".npy":
        try:
            mapping = _load_npy(path)
        except ValueError as exc:
            raise InputError(f"{path}: could not be read as a .npy array ({exc}).") from exc
        if mapping.ndim != 1 or not np.issubdtype(mapping.dtype, np.integer):
            raise InputError(
                f"{path}: a map must be a 1-D integer array; got shape {mapping.shape} "
                f"and dtype {mapping.dtype}."
            )
        return mapping.astype(np.int64)
    try:
        lines = path.read_text(encoding="ascii").splitlines()
    except UnicodeDecodeError as exc:
        raise InputError(f"{path}: not a text file (byte {exc.start} is not ASCII); a map file is text with "
                         "one integer per line, or a .npy array.") from exc
    numbered = [(i + 1, line.strip()) for i, line in enumerate(lines) if line.strip()]
    for number, line in numbered:
        if not re.fullmatch(r"[+-]?\d{1,18}", line):
            raise InputError(
                f"{path}, line {number}: expected one integer per line (at most 18 digits), got {line[:40]!r}."
            )
    return np.array([int(line) for _, line in numbered], dtype=np.int64)


def write_mesh(path, vertices, faces, vertex_colors=None) -> None:
    """Write a triangle mesh atomically in the format given by the extension.

    Vertex order is kept. PLY (and OBJ) keep ``vertex_colors``; OFF and STL drop them.

    Parameters
    ----------
    path : str or os.PathLike
        Target file ending in .off, .obj, .ply or .stl (.ply for a point cloud).
    vertices : (n, 3) float
    faces : (m, 3) int
        ``m = 0``: a point cloud, written as a PLY of points.
    vertex_colors : (n, 3) or (n, 4) uint8, optional
        RGB(A) color per vertex.
    """
    fmt = SUPPORTED_FORMATS.get(Path(path).suffix.lower())
    if fmt is None:
        raise ParameterError(
            f"Cannot write {path}: unsupported extension '{Path(path).suffix}'; "
            f"use one of {_SUPPORTED_LIST}."
        )
    if np.asarray(faces).size == 0:  # a point cloud: a PLY of points (with colours)
        if fmt != "PLY":
            raise ParameterError(f"Cannot write {path}: a point cloud (no faces) is written as .ply.")
        cloud = trimesh.PointCloud(np.asarray(vertices, dtype=np.float64), colors=vertex_colors)
        payload = cloud.export(file_type="ply")
        atomic_write(path, lambda file: file.write(payload))
        return
    mesh = trimesh.Trimesh(
        vertices=np.asarray(vertices, dtype=np.float64),
        faces=np.asarray(faces, dtype=np.int64),
        vertex_colors=vertex_colors,
        process=False,
    )
    data = mesh.export(file_type=fmt.lower())
    payload = data if isinstance(data, bytes) else data.encode("utf-8")
    atomic_write(path, lambda file: file.write(payload))


def _file_kind(path) -> str | None:
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


def _load_npy(path) -> np.ndarray:
    """The array of a ``.npy`` file (no pickles); ``ValueError`` with the reason in words if it is none.

    NumPy read an ``.npz`` as an archive object and said of any other file that it holds pickled
    data, to be loaded with ``allow_pickle``: advice to run untrusted code.
    """
    try:
        kind = _file_kind(path)
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
        kind = _file_kind(path)
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
