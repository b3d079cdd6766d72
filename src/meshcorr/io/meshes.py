"""Mesh and point-cloud files: OFF, OBJ, PLY, STL, and the point formats XYZ and NPY.

Meshes are read without processing, so vertex ``i`` of the file is vertex
``i`` of the arrays (correspondences are reported by vertex index): OFF by
:mod:`meshcorr.io.off`, which checks every record against the header, the other
formats by trimesh after the checks of :func:`read_mesh`. A file without
faces is a point cloud (faces ``(0, 3)``), and so are the point formats
``.xyz`` (text, ``x y z`` per line) and ``.npy`` (an ``(n, 3)`` array).
Meshes are written atomically (:func:`meshcorr.io.files.atomic_write`).
"""

from __future__ import annotations

import io
import re
import warnings
from contextlib import contextmanager
from pathlib import Path

import numpy as np

from ..runtime.interrupt import deferred_interrupt

from ..errors import MeshError, MeshWarning, ParameterError
from .arrays import load_npy
from .files import atomic_write
from .off import parse_off

__all__ = ["POINT_FORMATS", "SUPPORTED_FORMATS", "declared_vertex_count", "quiet_trimesh", "read_mesh", "write_mesh"]

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
        header = _ply_header(data)
        if header is None:
            return None, None
        n_v = re.search(r"^element\s+vertex\s+(\d+)", header, flags=re.MULTILINE)
        n_f = re.search(r"^element\s+face\s+(\d+)", header, flags=re.MULTILINE)
        return (int(n_v.group(1)) if n_v else None), (int(n_f.group(1)) if n_f else None)
    return None, None


def declared_vertex_count(path) -> int | None:
    """The vertex count a PLY or OFF file declares in its header, read from its first 64 KiB; None otherwise.

    For checks made before a file is read (the memory a run will need): the
    count is the file's, before any vertex is dropped (unused vertices, the
    largest connected component). None for other formats, a file that cannot
    be opened, or a header that does not say.
    """
    fmt = {**SUPPORTED_FORMATS, **POINT_FORMATS}.get(Path(path).suffix.lower())
    if fmt not in ("PLY", "OFF"):
        return None
    try:
        with open(path, "rb") as file:
            head = file.read(1 << 16)
    except OSError:
        return None
    if fmt == "PLY":
        return _declared_counts(head, "PLY")[0]
    lines = [line.split(b"#")[0].split() for line in head.splitlines()[:64]]
    tokens = [token for line in lines for token in line][:4]  # "OFF" (or "COFF", ...) and the counts
    if len(tokens) >= 2 and tokens[0].endswith(b"OFF"):
        count = _int_or_none(tokens[1].decode("ascii", errors="replace"))
        return count if count is not None and count >= 0 else None
    return None


def _ply_header(data: bytes) -> str | None:
    """The header of a PLY file (up to ``end_header``) as text, or None without one."""
    end = data.find(b"end_header")
    return None if end < 0 else data[:end].decode("ascii", errors="replace")


def _check_ascii_ply_records(data: bytes, label: str) -> None:
    """Refuse an ASCII PLY whose data lines outnumber the records its header declares.

    Every record of an ASCII PLY body is one line, and the header declares
    how many each element has. trimesh reads the declared number and ignores
    the rest, so a header that undercounts the faces would silently drop
    them (the holes this leaves are then closed as if they were the mesh's
    own). A binary PLY or an OFF refuses the same case.
    """
    header = _ply_header(data)
    if header is None or not re.search(r"^format\s+ascii\b", header, flags=re.MULTILINE):
        return
    declared = sum(int(n) for n in re.findall(r"^element\s+\S+\s+(\d+)", header, flags=re.MULTILINE))
    body = data[data.find(b"\n", data.find(b"end_header")) + 1:]
    lines_at_most = body.count(b"\n") + (not body.endswith(b"\n"))
    if lines_at_most <= declared:  # the common case, without splitting a large file into lines
        return
    n_lines = sum(1 for line in body.splitlines() if line.strip())
    if n_lines > declared:
        raise MeshError(f"{label}: the header declares {declared} records (vertices, faces and other elements) "
                        f"but the file has {n_lines} lines of data: the extra {n_lines - declared} would be "
                        "ignored. Correct the counts in the header ('element face N') or re-export the mesh.")


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
        points = load_npy(path)
    except ValueError as exc:
        raise MeshError(f"{label}: could not be read as a .npy array ({exc}). Save the points with "
                        "numpy.save(path, points).") from exc
    if points.ndim != 2 or points.shape[1] != 3 or not np.issubdtype(points.dtype, np.number) \
            or np.iscomplexobj(points):
        raise MeshError(f"{label}: a point cloud in .npy must be an (n, 3) array of real numbers; got shape "
                        f"{points.shape} and dtype {points.dtype}. Save the x, y, z columns only.")
    return np.array(points, dtype=np.float64)


def _trimesh():
    """The trimesh module, imported on first use.

    Importing it takes about 0.2 s, a tenth of a 5000-vertex match, and the
    commonest files (OFF) and arrays never need it. Its guards around its
    optional imports catch BaseException, so Ctrl-C is deferred meanwhile.
    """
    with deferred_interrupt():
        import trimesh
    return trimesh


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
    vertices, faces, data = _parse_with_trimesh(data, label, fmt)
    if fmt == "STL":
        return vertices, faces

    if fmt == "PLY":
        _check_ascii_ply_records(data, label)
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


def _parse_with_trimesh(data: bytes, label: str, fmt: str) -> tuple[np.ndarray, np.ndarray, bytes]:
    """``(n, 3)`` float64 vertices, ``(m, 3)`` int64 faces (``(0, 3)``: a cloud) and the bytes parsed, of an OBJ, PLY or STL file.

    The file's bytes are checked for their format first (:func:`_check_obj`,
    :func:`_check_binary_formats`), then parsed by trimesh with ``process=False``
    (OBJ: ``maintain_order=True``; text that is not UTF-8 is read as Latin-1); STL's unshared
    vertices are merged. Raises
    :class:`MeshError` for a file that trimesh cannot parse, several
    geometries, no vertices, or coordinates that are not finite.
    """
    if fmt == "OBJ":
        data = _text(data, label, fmt)
        _check_obj(data, label)
    else:
        data = _check_binary_formats(data, label, fmt)
    options = {"maintain_order": True, "skip_materials": True} if fmt == "OBJ" else {}
    trimesh = _trimesh()
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
    return vertices, faces, data


def _warn_polygons(label: str, what: str, n_file_faces: int, n_triangles: int) -> None:
    warnings.warn(
        MeshWarning(
            f"{label}: {what} with more than 3 sides were triangulated "
            f"({n_file_faces} faces in the file became {n_triangles} triangles). "
            "Triangulate the mesh yourself to control how."
        ),
        stacklevel=3,
    )


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
    trimesh = _trimesh()
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
