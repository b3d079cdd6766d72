"""meshcorr.io.off: the strict OFF reader on small hand-written files."""

import numpy as np
import pytest

from meshcorr.errors import MeshError
from meshcorr.io.off import parse_off

TETRA = b"""OFF
# a tetrahedron
4 4 6
0 0 0
1 0 0
0 1 0
0 0 1   # a trailing comment
3 0 2 1
3 0 1 3
3 0 3 2
3 1 2 3
"""


def test_tetrahedron_read_as_written():
    vertices, faces, n_polygons, n_records = parse_off(TETRA, "tetra.off")
    np.testing.assert_array_equal(vertices, [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
    np.testing.assert_array_equal(faces, [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    assert vertices.dtype == np.float64 and faces.dtype == np.int64
    assert (n_polygons, n_records) == (0, 4)


def test_counts_on_the_keyword_line_and_extra_vertex_values_are_read():
    data = b"COFF 3 1 0\n0 0 0 255 0 0 255\n1 0 0 0 255 0 255\n0 1 0 0 0 255 255\n3 0 1 2 10 20 30\n"
    vertices, faces, _, _ = parse_off(data, "c.off")
    np.testing.assert_array_equal(vertices[:, 0], [0, 1, 0])
    np.testing.assert_array_equal(faces, [[0, 1, 2]])


def test_polygons_become_fans():
    data = b"OFF\n5 1 0\n0 0 0\n1 0 0\n2 1 0\n1 2 0\n0 1 0\n5 0 1 2 3 4\n"
    _, faces, n_polygons, n_records = parse_off(data, "pentagon.off")
    np.testing.assert_array_equal(faces, [[0, 1, 2], [0, 2, 3], [0, 3, 4]])
    assert (n_polygons, n_records) == (1, 1)


@pytest.mark.parametrize("data, message", [
    (b"# nothing\n", r"^empty\.off: holds only comments, no OFF header"),
    (b"PLY\n3 1 0\n", r"^bad\.off, line 1: expected the OFF keyword, got 'PLY'"),
    (b"OFF BINARY\n", r"binary OFF is not supported"),
    (b"4OFF\n", r"the 4OFF variant is not supported"),
    (b"OFF\nthree 1 0\n", r"line 2: expected the counts 'n_vertices n_faces n_edges'"),
    (b"OFF\n3 1 0\n0 0 0\n1 0 0\n", r"line 4: the file ends after 2 of the 3 vertices its header declares: "
                                    r"it is truncated"),
    (b"OFF\n3 1 0\n0 0 0\n1 0\n0 1 0\n3 0 1 2\n", r"line 4: vertex 1 has 2 coordinates, not 3"),
    (b"OFF\n3 1 0\n0 0 0\n1 0 nan\n0 1 0\n3 0 1 2\n", r"vertex 1 has a non-finite coordinate"),
    (b"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n2 0 1\n", r"line 6: face 0 has 2 vertices; a face needs at least 3"),
    (b"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1\n", r"face 0 declares 3 vertices but lists 2"),
    (b"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n", r"face 0 refers to vertex 3, outside the 3 vertices"),
    (b"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 0 1 2\n", r"line 7: data after the 3 vertices and 1 faces"),
    (b"OFF\n1000 1 0\n0 0 0\n", r"the header declares 1000 vertices and 1 faces, but the file has only"),
    (b"OFF\n3 1 0\n0 0 0\n1 \xe9 0\n0 1 0\n3 0 1 2\n", r"line 4: holds non-ASCII bytes outside a comment"),
])
def test_refusals_name_the_file_and_the_line(data, message):
    label = "empty.off" if data.startswith(b"#") else "bad.off"
    with pytest.raises(MeshError, match=message):
        parse_off(data, label)


def test_non_ascii_comment_is_accepted():
    data = b"OFF # caf\xe9\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2 # \xff\n"
    assert parse_off(data, "c.off")[1].shape == (1, 3)
