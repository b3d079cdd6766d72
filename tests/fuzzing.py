"""The fuzzing harness shared by tests/test_fuzz.py (bounded) and benchmarks/fuzz.py (long runs).

Valid seed files (OFF, OBJ, PLY ASCII and binary, STL ASCII and binary, text
and .npy maps, ground-truth pairs and .vts files) are mutated by hypothesis
strategies: truncation, deleted, inserted or replaced bytes, deleted,
duplicated or swapped lines, and number tokens swapped for hostile ones
(``nan``, ``1e309``, ``-1``, 20-digit integers, ``0x10``, empty). Each
mutated file goes through the reader and through the command line
(``transfer``, ``evaluate``, ``show`` where asked), and the properties are:

* only the project's own errors (:class:`meshcorr.errors.MeshcorrError`)
  escape the readers; the CLI exits 0, 2 or 3, never with a traceback;
* a failed command leaves no output and no temporary file behind;
* no input takes longer than the time bound (hypothesis's deadline).
"""

from __future__ import annotations

import contextlib
import io
import os
import re
import tempfile
import warnings
from pathlib import Path

import numpy as np
import trimesh
from hypothesis import strategies as st

from meshcorr import datasets as ds
from meshcorr.cli import main
from meshcorr.errors import MeshcorrError
from meshcorr.io import read_map, read_mesh
from meshcorr.core.mesh import as_mesh

HOSTILE_NUMBERS = [b"nan", b"inf", b"-inf", b"1e309", b"-1", b"0", b"3.5", b"99999999999999999999", b"0x10",
                   b"", b"-0", b"1e-320", b"+7", b"\xff", b"4294967297", b"-9223372036854775809"]


def _shape():
    vertices, faces = ds.sphere(subdivisions=1)  # 42 vertices: each command runs in milliseconds
    return np.asarray(vertices), np.asarray(faces)


def seed_files() -> dict[str, bytes]:
    """Valid files of every format read by the CLI, keyed by a name with the right extension."""
    V, F = _shape()
    mesh = trimesh.Trimesh(V, F, process=False)
    off = trimesh.exchange.off.export_off(mesh, digits=6).encode()
    files = {
        "mesh.off": off,
        "comment.off": off.replace(b"OFF\n", b"OFF\n# caf\xe9 comment\n", 1),
        "quads.off": b"OFF\n6 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n2 0 0\n2 1 0\n4 0 1 2 3\n4 1 4 5 2\n",
        "mesh.obj": trimesh.exchange.obj.export_obj(mesh, include_normals=False, include_texture=False).encode(),
        "mesh.ply": trimesh.exchange.ply.export_ply(mesh, encoding="ascii"),
        "binary.ply": trimesh.exchange.ply.export_ply(mesh, encoding="binary"),
        "mesh.stl": trimesh.exchange.stl.export_stl_ascii(mesh).encode(),
        "binary.stl": trimesh.exchange.stl.export_stl(mesh),
    }
    n = len(V)
    identity = np.arange(n)
    files["map.txt"] = "".join(f"{i}\n" for i in identity).encode()
    buffer = io.BytesIO()
    np.save(buffer, identity, allow_pickle=False)
    files["map.npy"] = buffer.getvalue()
    files["pairs.txt"] = "".join(f"{i} {i}\n" for i in range(0, n, 3)).encode()
    files["a.vts"] = "".join(f"{i + 1}\n" for i in range(0, n, 2)).encode()
    return files


SEEDS = seed_files()
MESH_SEEDS = [name for name in SEEDS if name.endswith((".off", ".obj", ".ply", ".stl"))]
DATA_SEEDS = [name for name in SEEDS if name not in MESH_SEEDS]


def _lines(data: bytes) -> list[bytes]:
    return data.split(b"\n")


@st.composite
def mutation(draw, data: bytes) -> bytes:
    """One random change of ``data``."""
    kind = draw(st.sampled_from(["truncate", "delete", "insert", "replace", "drop_line", "dup_line",
                                 "swap_lines", "number", "header"]))
    n = len(data)
    if kind == "truncate":
        return data[:draw(st.integers(0, max(n - 1, 0)))]
    if kind in ("delete", "insert", "replace"):
        at = draw(st.integers(0, n))
        if kind == "delete":
            return data[:at] + data[at + draw(st.integers(1, 64)):]
        chunk = draw(st.binary(min_size=1, max_size=16))
        return data[:at] + chunk + data[at + (len(chunk) if kind == "replace" else 0):]
    lines = _lines(data)
    if kind in ("drop_line", "dup_line", "swap_lines") and len(lines) > 1:
        i = draw(st.integers(0, len(lines) - 1))
        if kind == "drop_line":
            del lines[i]
        elif kind == "dup_line":
            lines.insert(i, lines[i])
        else:
            j = draw(st.integers(0, len(lines) - 1))
            lines[i], lines[j] = lines[j], lines[i]
        return b"\n".join(lines)
    numbers = list(re.finditer(rb"-?\d+(\.\d+)?(e-?\d+)?", data[:4096] if kind == "header" else data))
    if not numbers:
        return data
    match = numbers[draw(st.integers(0, len(numbers) - 1))]
    token = draw(st.sampled_from(HOSTILE_NUMBERS))
    return data[:match.start()] + token + data[match.end():]


@st.composite
def mutated(draw, names: list[str]) -> tuple[str, bytes]:
    """A seed file with one to four mutations: (name, content)."""
    name = draw(st.sampled_from(names))
    data = SEEDS[name]
    for _ in range(draw(st.integers(1, 4))):
        data = draw(mutation(data))
    return name, data


def check_mesh_reader(name: str, data: bytes) -> None:
    """read_mesh and as_mesh on a mutated file: arrays of the right kind, or a MeshcorrError."""
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / name
        path.write_bytes(data)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            try:
                vertices, faces = read_mesh(path)
            except MeshcorrError:
                return
            assert vertices.dtype == np.float64 and vertices.ndim == 2 and vertices.shape[1] == 3
            assert faces.dtype == np.int64 and faces.ndim == 2 and faces.shape[1] == 3
            try:
                mesh = as_mesh(path)
            except MeshcorrError:
                return
            assert mesh.n_vertices >= 3 and np.isfinite(np.asarray(mesh.vertices)).all()


def check_map_reader(name: str, data: bytes) -> None:
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / name
        path.write_bytes(data)
        try:
            mapping = read_map(path)
        except MeshcorrError:
            return
        assert mapping.dtype == np.int64 and mapping.ndim == 1


def run_cli(args: list[str]) -> tuple[int, str]:
    """``main(args)`` with stdout and stderr captured."""
    err, out = io.StringIO(), io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(out), warnings.catch_warnings():
        code = main(args)
    return code, err.getvalue()


def check_cli(name: str, data: bytes, command: str) -> None:
    """A command on the mutated file (as a mesh, map or ground truth): a clean exit, no stray output."""
    with tempfile.TemporaryDirectory() as folder:
        folder = Path(folder)
        good_mesh, good_map = folder / "good.off", folder / "good.txt"
        good_mesh.write_bytes(SEEDS["mesh.off"])
        good_map.write_bytes(SEEDS["map.txt"])
        bad = folder / ("bad" + Path(name).suffix)
        bad.write_bytes(data)
        is_mesh = name in MESH_SEEDS
        source = bad if is_mesh else good_mesh
        mapping = bad if name.startswith("map") else good_map
        truth = str(bad) if name in ("pairs.txt",) else "identity"
        out = folder / ("out.png" if command == "show" else "out.ply")
        if command == "transfer":
            args = ["transfer", str(source), str(good_mesh), str(mapping), "--attribute", "xyz", "-o", str(out)]
        elif command == "evaluate":
            args = ["evaluate", str(source), str(good_mesh), str(mapping), "--gt", truth, "--json"]
            if name.endswith(".vts"):
                args = ["evaluate", str(good_mesh), str(good_mesh), str(good_map), "--gt", str(bad), "--gt",
                        str(bad), "--json"]
        else:
            args = ["show", str(source), str(good_mesh), str(mapping), "-o", str(out), "--dpi", "20"]
        before = {good_mesh.name, good_map.name, bad.name}
        code, err = run_cli(args)
        assert "Traceback" not in err and "internal error" not in err, (args, err)
        assert code in (0, 2, 3), (code, err)
        left = set(os.listdir(folder)) - before
        if code != 0:
            assert not left, f"a failed {command} left {left}"
        else:
            assert left <= {out.name}, left
