"""meshcorr.io.meshes: mesh reading keeps vertex order, errors and warnings; writing meshes."""

from __future__ import annotations

import logging
import os
import warnings

from pathlib import Path

import numpy as np
import pytest
import trimesh

from meshcorr import io as mio
import meshcorr.io.meshes  # noqa: F401 (mio.meshes: the module whose trimesh parses)
from meshcorr.errors import MeshError, MeshWarning, ParameterError
from meshcorr.io import read_mesh, write_mesh

OCTA_V = np.array(
    [[1.0, 0, 0], [-1.0, 0, 0], [0, 1.0, 0], [0, -1.0, 0], [0, 0, 1.0], [0, 0, -1.0]]
)
OCTA_F = np.array(
    [[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]]
)

# two unit squares side by side, as two quads
QUAD_OFF = """OFF
# two quads
6 2 0
0 0 0
1 0 0
1 1 0
0 1 0
2 0 0
2 1 0
4 0 1 2 3
4 1 4 5 2
"""
QUAD_OBJ = """v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
v 2 0 0
v 2 1 0
f 1 2 3 4
f 2 5 6 3
"""
QUAD_PLY = """ply
format ascii 1.0
element vertex 6
property float x
property float y
property float z
element face 2
property list uchar int vertex_indices
end_header
0 0 0
1 0 0
1 1 0
0 1 0
2 0 0
2 1 0
4 0 1 2 3
4 1 4 5 2
"""

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


def shuffled_octahedron(seed=0):
    """An octahedron with vertices in a random order and coordinates exact in float32 and text."""
    rng = np.random.default_rng(seed)
    perm = rng.permutation(6)
    vertices = OCTA_V[perm] * 1.5 + np.array([0.125, -2.25, 3.5])
    inverse = np.argsort(perm)
    return vertices, inverse[OCTA_F]


def export(tmp_path, vertices, faces, ext):
    path = tmp_path / f"mesh.{ext}"
    trimesh.Trimesh(vertices, faces, process=False).export(path)
    return path


@pytest.mark.parametrize("ext", ["off", "obj", "ply"])
def test_round_trip_keeps_vertex_order(tmp_path, ext):
    vertices, faces = shuffled_octahedron()
    path = export(tmp_path, vertices, faces, ext)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        v, f = read_mesh(path)
    assert v.dtype == np.float64 and f.dtype == np.int64
    np.testing.assert_array_equal(v, vertices)
    np.testing.assert_array_equal(f, faces)


def test_textured_obj_keeps_vertex_order(tmp_path):
    # texture seams (several vt per v) would make trimesh split and reorder vertices
    vertices, faces = shuffled_octahedron(seed=1)
    lines = [f"v {x} {y} {z}" for x, y, z in vertices]
    lines += [f"vt {u} {u}" for u in (0.0, 0.25, 0.5, 0.75)]
    for k, face in enumerate(faces):
        lines.append("f " + " ".join(f"{i + 1}/{(k + j) % 4 + 1}" for j, i in enumerate(face)))
    path = tmp_path / "textured.obj"
    path.write_text("\n".join(lines) + "\n")
    v, f = read_mesh(path)
    np.testing.assert_array_equal(v, vertices)
    np.testing.assert_array_equal(f, faces)


def test_textured_obj_trailing_unused_vertex_warns(tmp_path):
    lines = [f"v {x} {y} {z}" for x, y, z in OCTA_V] + ["v 9 9 9", "vt 0 0", "vt 1 1"]
    lines += ["f " + " ".join(f"{i + 1}/{(i % 2) + 1}" for i in face) for face in OCTA_F]
    path = tmp_path / "trailing.obj"
    path.write_text("\n".join(lines) + "\n")
    with pytest.warns(MeshWarning, match="1 trailing vertices used by no face were dropped"):
        v, f = read_mesh(path)
    np.testing.assert_array_equal(v, OCTA_V)
    np.testing.assert_array_equal(f, OCTA_F)


def test_stl_merges_duplicate_vertices(tmp_path):
    path = export(tmp_path, OCTA_V, OCTA_F, "stl")
    v, f = read_mesh(path)
    assert v.shape == (6, 3)
    assert f.shape == (8, 3)
    # the same triangles, as sets of corner coordinates
    def triangles(vv, ff):
        return sorted(tuple(sorted(map(tuple, vv[face].round(6)))) for face in ff)
    assert triangles(v, f) == triangles(OCTA_V, OCTA_F)


@pytest.mark.parametrize("name, text", [("quad.off", QUAD_OFF), ("quad.obj", QUAD_OBJ)])
def test_quads_warn_with_exact_count(tmp_path, name, text):
    path = tmp_path / name
    path.write_text(text)
    with pytest.warns(MeshWarning, match="2 polygonal faces with more than 3 sides were triangulated"):
        v, f = read_mesh(path)
    assert f.shape == (4, 3)
    np.testing.assert_array_equal(v[:, :2], [[0, 0], [1, 0], [1, 1], [0, 1], [2, 0], [2, 1]])


def test_quads_warn_with_one_line_off_header(tmp_path):
    path = tmp_path / "quad.off"
    path.write_text(QUAD_OFF.replace("OFF\n# two quads\n6 2 0\n", "OFF 6 2 0\n"))
    with pytest.warns(MeshWarning, match="^quad.off: 2 polygonal faces"):
        read_mesh(path, name="quad.off")


def test_quads_in_ply_warn(tmp_path):
    path = tmp_path / "quad.ply"
    path.write_text(QUAD_PLY)
    with pytest.warns(MeshWarning, match=r"polygonal faces .* \(2 faces in the file became 4 triangles\)"):
        read_mesh(path)


def test_mixed_triangles_and_pentagon_obj_counts_polygons(tmp_path):
    text = QUAD_OBJ.replace("f 1 2 3 4\nf 2 5 6 3\n", "f 1 2 3\nf 1 3 4\nf 2 5 6 3\n")
    path = tmp_path / "mixed.obj"
    path.write_text(text)
    with pytest.warns(MeshWarning, match=r"^mixed.obj: 1 polygonal faces"):
        read_mesh(path, name="mixed.obj")


def test_missing_file(tmp_path):
    with pytest.raises(MeshError, match="No such file: .*nothere.off"):
        read_mesh(tmp_path / "nothere.off")


def test_directory_is_not_a_file(tmp_path):
    with pytest.raises(MeshError, match="Not a file"):
        read_mesh(tmp_path)


@pytest.mark.parametrize("name", ["mesh.pts", "mesh"])
def test_unsupported_extension(tmp_path, name):
    path = tmp_path / name
    path.write_text("0 0 0\n")
    with pytest.raises(MeshError, match=r"Unsupported mesh format .*supported: \.off, \.obj, \.ply, \.stl, \.xyz, \.npy"):
        read_mesh(path)


TETRA_OFF = "OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n"


@pytest.mark.parametrize(
    "content, message",
    [
        ("OFF\n3 1 0\n0 0 0\n1 zz 0\n0 1 0\n3 0 1 2\n", r"line 4: vertex 1: expected three numbers, got '1 zz 0'"),
        ("OFF\n5 2 0\n0 0 0\n1 0 0\n", r"line 4: the file ends after 2 of the 5 vertices its header declares"),
        # issue 16: faces missing at the end, a face cut in the middle, a missing vertex line
        (TETRA_OFF.rsplit("3 1 2 3", 1)[0], r"line 9: the file ends after 3 of the 4 faces .* truncated"),
        (TETRA_OFF[:-3], r"line 10: face 3 declares 3 vertices but lists 2 \(a truncated line\?\)"),
        (TETRA_OFF.replace("0 0 1\n", ""), r"line 9: the file ends after 3 of the 4 faces"),
        (TETRA_OFF.replace("3 1 2 3", "3 1 2 4"), r"line 10: face 3 refers to vertex 4, outside the 4 vertices"),
        (TETRA_OFF + "3 0 1 2\n", r"line 11: data after the 4 vertices and 4 faces the header declares"),
        (TETRA_OFF.replace("4 4 0", "4 four 0"), r"line 2: expected the counts 'n_vertices n_faces n_edges'"),
        (TETRA_OFF.replace("0 0 1\n", "0 0\n"), r"line 6: vertex 3 has 2 coordinates, not 3"),
        (TETRA_OFF.replace("0 0 1\n", "0 0 nan\n"), r"vertex 3 has a non-finite coordinate"),
        (TETRA_OFF.replace("3 1 2 3", "2 1 2"), r"line 10: face 3 has 2 vertices; a face needs at least 3"),
        (TETRA_OFF.replace("OFF", "OFF BINARY"), r"line 1: binary OFF is not supported"),
        (TETRA_OFF.replace("OFF", "4OFF"), r"line 1: the 4OFF variant is not supported"),
        ("PLY\n" + TETRA_OFF[4:], r"line 1: expected the OFF keyword, got 'PLY'"),
        ("# only a comment\n", r"holds only comments, no OFF header"),
    ],
)
def test_off_refusals_name_the_line(tmp_path, content, message):
    path = tmp_path / "bad.off"
    path.write_text(content)
    with pytest.raises(MeshError, match=message):
        read_mesh(path, name="m.off")


def test_off_with_latin1_comment_and_pentagon_reads(tmp_path):
    """issue 16: a Latin-1 comment needed charset_normalizer; a 5-gon gave a numpy TypeError."""
    path = tmp_path / "pent.off"
    path.write_bytes(b"OFF\n# caf\xe9 cr\xe8me\n5 1 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n0 0.5 1\n5 0 1 2 3 4\n")
    with pytest.warns(MeshWarning, match=r"1 polygonal faces .* \(1 faces in the file became 3 triangles\)"):
        vertices, faces = read_mesh(path)
    assert vertices.shape == (5, 3)
    np.testing.assert_array_equal(faces, [[0, 1, 2], [0, 2, 3], [0, 3, 4]])


def test_off_non_ascii_outside_a_comment_is_refused(tmp_path):
    path = tmp_path / "bin.off"
    path.write_bytes(TETRA_OFF.encode().replace(b"0 0 1\n", b"0 0 \xff\n"))
    with pytest.raises(MeshError, match=r"line 6: holds non-ASCII bytes outside a comment"):
        read_mesh(path)


def test_obj_with_latin1_comment_reads(tmp_path):
    path = tmp_path / "a.obj"
    path.write_bytes(b"# caf\xe9\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n")
    vertices, faces = read_mesh(path)
    assert vertices.shape == (4, 3) and faces.shape == (4, 3)


@pytest.mark.parametrize("text, message", [
    # Found by the fuzzer: 'show' drew a NaN vertex and failed inside matplotlib.
    ("v nan 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n",
     r"bad.obj: vertex 0 has a non-finite coordinate"),
    ("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2\n", r"bad.obj, line 6: a face lists 2 vertices"),
])
def test_obj_refusals(tmp_path, text, message):
    path = tmp_path / "bad.obj"
    path.write_text(text)
    with pytest.raises(MeshError, match=message):
        read_mesh(path)


@pytest.mark.parametrize("name, message", [
    ("garbage.off", r"line 1: holds non-ASCII bytes outside a comment"),
    ("garbage.obj", r"holds NUL bytes, so it is not a OBJ text file"),
    ("garbage.stl", r"neither a binary STL .* nor an ASCII STL"),
    ("garbage.ply", r"not a PLY file"),
])
def test_binary_garbage_is_refused_as_such(tmp_path, name, message):
    """issue 16: binary garbage gave "No module named 'charset_normalizer'"."""
    path = tmp_path / name
    path.write_bytes(bytes(np.random.default_rng(1).integers(128, 256, 300, dtype=np.uint8)) + b"\x00")
    with pytest.raises(MeshError, match=message):
        read_mesh(path)


def test_ply_with_fewer_faces_than_declared_is_refused(tmp_path):
    text = ("ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
            "element face 4\nproperty list uchar int vertex_indices\nend_header\n"
            "0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n")
    path = tmp_path / "short.ply"
    path.write_text(text)
    with pytest.raises(MeshError, match=r"short.ply"):
        read_mesh(path)


@pytest.mark.parametrize("name, content, n_points", [
    ("none.off", "OFF\n4 0 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n", 4),
    ("none.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n", 3),
    ("none.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                 "property float z\nend_header\n0 0 0\n1 0 0\n0 1 0\n", 3),
])
def test_a_file_without_faces_is_a_point_cloud(tmp_path, name, content, n_points):
    """A zero-face mesh file is read as a point cloud, faces (0, 3) (issue 15; refused before it)."""
    path = tmp_path / name
    path.write_text(content)
    vertices, faces = read_mesh(path)
    assert vertices.shape == (n_points, 3) and faces.shape == (0, 3)
    np.testing.assert_array_equal(vertices[1], [1.0, 0.0, 0.0])


def test_an_empty_scene_is_refused(tmp_path):
    path = tmp_path / "empty-scene.obj"
    path.write_text("# nothing but comments\no empty\n")
    with pytest.raises(MeshError, match="contains no vertices"):
        read_mesh(path)


def test_a_ply_of_points_declaring_faces_it_lacks_is_refused(tmp_path):
    path = tmp_path / "cut.ply"
    path.write_text("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                    "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
                    "0 0 0\n1 0 0\n0 1 0\n")
    with pytest.raises(MeshError, match="declares 1 faces but 0 were read"):
        read_mesh(path)


@pytest.mark.parametrize("extra", [1, 20])
def test_an_ascii_ply_with_more_face_lines_than_its_header_declares_is_refused(tmp_path, extra):
    # trimesh reads the declared count and drops the rest: 20 faces lost, their holes closed, exit 0 (issue 31)
    mesh = trimesh.load(EXAMPLES / "creature_rest.off", process=False)
    text = trimesh.exchange.ply.export_ply(mesh, encoding="ascii").decode()
    n = len(mesh.faces)
    path = tmp_path / "undercounted.ply"
    path.write_text(text.replace(f"element face {n}\n", f"element face {n - extra}\n"))
    with pytest.raises(MeshError, match=rf"{len(mesh.vertices) + n - extra} records .* {len(mesh.vertices) + n} "
                                        rf"lines of data: the extra {extra} would be ignored"):
        read_mesh(path)
    path.write_text(text + "\n\n")  # trailing blank lines are no records
    assert read_mesh(path)[1].shape == (n, 3)


def test_truncated_binary_ply(tmp_path):
    path = export(tmp_path, OCTA_V, OCTA_F, "ply")
    path.write_bytes(path.read_bytes()[:-20])
    with pytest.raises(MeshError, match="could not be parsed as PLY"):
        read_mesh(path)


@pytest.mark.parametrize("name", ["empty.off", "empty.obj", "empty.ply", "empty.stl"])
def test_empty_file(tmp_path, name):
    path = tmp_path / name
    path.write_text("  \n")
    with pytest.raises(MeshError, match="File is empty"):
        read_mesh(path)


def test_xyz_text_of_points(tmp_path):
    """x y z a line, commas or spaces, extra columns and # comments ignored; a short line is refused."""
    path = tmp_path / "points.xyz"
    path.write_text("# scan\n0 0 0 9 9 9\n1,0,0\n\n0 1 0.5  # a comment\n")
    vertices, faces = read_mesh(path)
    np.testing.assert_array_equal(vertices, [[0, 0, 0], [1, 0, 0], [0, 1, 0.5]])
    assert faces.shape == (0, 3)
    path.write_text("0 0 0\n1 x 0\n")
    with pytest.raises(MeshError, match="points.xyz, line 2: expected 'x y z'.*Repair the line"):
        read_mesh(path)
    path.write_text("x y z\n0 0 0\n")  # a header line, not commented out
    with pytest.raises(MeshError, match="points.xyz, line 1: expected 'x y z'.*Start a header line with '#'"):
        read_mesh(path)
    path.write_text("# only a comment\n")
    with pytest.raises(MeshError, match="holds no points"):
        read_mesh(path)


def test_npy_of_points(tmp_path):
    path = tmp_path / "points.npy"
    np.save(path, np.eye(3))
    vertices, faces = read_mesh(path)
    np.testing.assert_array_equal(vertices, np.eye(3))
    assert faces.shape == (0, 3)
    np.save(path, np.arange(8))
    with pytest.raises(MeshError, match="an \\(n, 3\\) array of real numbers; got shape \\(8,\\)"):
        read_mesh(path)
    path.write_bytes(b"not numpy")
    with pytest.raises(MeshError, match="could not be read as a .npy array"):
        read_mesh(path)


def test_several_geometries(tmp_path):
    text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nusemtl a\nf 1 3 2\nf 1 2 4\nusemtl b\nf 2 3 4\nf 1 4 3\n"
    path = tmp_path / "two.obj"
    path.write_text(text)
    with pytest.raises(MeshError, match="holds 2 separate geometries"):
        read_mesh(path)


def test_vertex_count_mismatch_is_an_error(tmp_path, monkeypatch):
    path = export(tmp_path, OCTA_V, OCTA_F, "ply")  # PLY: plain OFF files never reach trimesh.load
    # No real file was found that trimesh reads with another vertex count (OFF no longer reaches it).
    merged = trimesh.Scene(trimesh.Trimesh(OCTA_V[:5], OCTA_F, process=False))
    monkeypatch.setattr(trimesh, "load", lambda *args, **kwargs: merged)
    with pytest.raises(MeshError, match="declares 6 vertices but 5 were read"):
        read_mesh(path)


def test_name_is_used_in_messages(tmp_path):
    path = tmp_path / "bad.off"
    path.write_text("OFF\n3 1 0\nx y z\n")
    with pytest.raises(MeshError, match=r"^source mesh \S*bad.off, line 3: vertex 0: expected three numbers"):
        read_mesh(path, name="source mesh")


@pytest.mark.parametrize("ext", ["off", "obj", "ply", "stl"])
def test_write_mesh_round_trip(tmp_path, ext):
    vertices, faces = shuffled_octahedron(seed=2)
    path = tmp_path / f"out.{ext}"
    write_mesh(path, vertices, faces)
    v, f = read_mesh(path)
    if ext == "stl":
        assert v.shape == (6, 3) and f.shape == (8, 3)
    else:
        np.testing.assert_array_equal(v, vertices)
        np.testing.assert_array_equal(f, faces)
    assert os.listdir(tmp_path) == [f"out.{ext}"]


def test_write_mesh_ply_keeps_colors(tmp_path):
    colors = np.array([[255, 0, 0, 255], [0, 255, 0, 255], [0, 0, 255, 255]] * 2, dtype=np.uint8)
    path = tmp_path / "colored.ply"
    write_mesh(path, OCTA_V, OCTA_F, vertex_colors=colors)
    loaded = trimesh.load(path, process=False)
    np.testing.assert_array_equal(loaded.visual.vertex_colors, colors)
    np.testing.assert_array_equal(loaded.vertices, OCTA_V)


def test_write_mesh_unsupported_extension(tmp_path):
    with pytest.raises(ParameterError, match=r"unsupported extension '\.glb'"):
        write_mesh(tmp_path / "m.glb", OCTA_V, OCTA_F)


@pytest.mark.parametrize("text", [
    "OFF\n4 2 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1.5e-1\n3 0 1 2\n3 0 2 3\n",  # the fast reader's case
    "OFF\n# comment\n4 2 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1.5e-1\n3 0 1 2\n3 0 2 3\n",  # trimesh's
    "COFF\n4 2 0\n0 0 0 1 1 1 1\n1 0 0 1 1 1 1\n0 1 0 1 1 1 1\n0 0 1.5e-1 1 1 1 1\n3 0 1 2\n3 0 2 3\n",
])
def test_plain_off_fast_reader_agrees_with_trimesh(tmp_path, text):
    """The hand-written reader of plain OFF files gives what trimesh gives (issue 5)."""
    import trimesh

    path = tmp_path / "m.off"
    path.write_text(text)
    vertices, faces = read_mesh(path)
    reference = trimesh.load(path, process=False, force="mesh")
    np.testing.assert_array_equal(vertices, np.asarray(reference.vertices, dtype=np.float64))
    np.testing.assert_array_equal(faces, np.asarray(reference.faces, dtype=np.int64))
    assert vertices.dtype == np.float64 and faces.dtype == np.int64 and faces.shape == (2, 3)


def test_a_damaged_stl_is_one_error_without_trimesh_log_lines(tmp_path, caplog):
    # trimesh logs a traceback for each parser that fails; read_mesh's MeshError says what is wrong.
    path = tmp_path / "normals.stl"
    path.write_text("solid t\nfacet normal 0 0 x\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\n"
                    "endloop\nendfacet\nendsolid t\n")
    with caplog.at_level("DEBUG"):
        read_mesh(path)
    assert not [r for r in caplog.records if r.name.startswith("trimesh")]
    assert logging.getLogger("trimesh").level == logging.NOTSET  # restored


def test_declared_vertex_count_reads_only_the_header(tmp_path):
    from meshcorr.io.meshes import declared_vertex_count

    (tmp_path / "a.ply").write_bytes(b"ply\nformat ascii 1.0\nelement vertex 12\nproperty float x\nend_header\n")
    (tmp_path / "b.off").write_text("OFF\n# a comment\n7 3 0\n")
    (tmp_path / "c.off").write_text("# first a comment\nOFF 9 1 0\n")
    (tmp_path / "d.obj").write_text("v 0 0 0\n")
    (tmp_path / "e.ply").write_bytes(b"ply\nformat ascii 1.0\n")  # no end of header
    assert declared_vertex_count(tmp_path / "a.ply") == 12
    assert declared_vertex_count(tmp_path / "b.off") == 7
    assert declared_vertex_count(tmp_path / "c.off") == 9
    assert declared_vertex_count(tmp_path / "d.obj") is None  # an OBJ declares nothing
    assert declared_vertex_count(tmp_path / "e.ply") is None
    assert declared_vertex_count(tmp_path / "missing.ply") is None
