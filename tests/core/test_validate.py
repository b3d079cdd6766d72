"""Tests for meshcorr.core.validate: every check is triggered by a small hand-made mesh."""

from __future__ import annotations

import numpy as np
import pytest

from meshcorr.errors import MeshError, ParameterError
from meshcorr.core.mesh import Mesh
from meshcorr.core.pointcloud import validate_cloud
from meshcorr.core.validate import validate_mesh

TET_V = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])
TET_F = np.array([[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]])

OCTA_V = np.array(
    [[1.0, 0, 0], [-1.0, 0, 0], [0, 1.0, 0], [0, -1.0, 0], [0, 0, 1.0], [0, 0, -1.0]]
)
OCTA_F = np.array(
    [[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]]
)


def two_tets(shift=(5.0, 0.0, 0.0), second_scale=1.0):
    """Two disjoint tetrahedra: vertices 0-3 and 4-7."""
    v = np.vstack([TET_V, TET_V * second_scale + np.asarray(shift)])
    return v, np.vstack([TET_F, TET_F + 4])


def test_valid_closed_mesh_passes_unchanged():
    v, f, kept = validate_mesh(OCTA_V, OCTA_F)
    np.testing.assert_array_equal(v, OCTA_V)
    np.testing.assert_array_equal(f, OCTA_F)
    np.testing.assert_array_equal(kept, np.arange(6))
    assert v.dtype == np.float64 and f.dtype == np.int64 and kept.dtype == np.int64


def test_valid_open_mesh_with_boundary_passes():
    # a square of two triangles: boundary vertices are still manifold fans
    v = np.array([[0.0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]])
    f = np.array([[0, 1, 2], [0, 2, 3]])
    out_v, out_f, kept = validate_mesh(v, f)
    np.testing.assert_array_equal(out_f, f)
    np.testing.assert_array_equal(kept, np.arange(4))


def test_lists_and_integral_float_faces_are_converted():
    v, f, _ = validate_mesh(TET_V.tolist(), TET_F.astype(np.float64))
    assert f.dtype == np.int64
    np.testing.assert_array_equal(f, TET_F)


def test_result_does_not_alias_input():
    v_in, f_in = OCTA_V.copy(), OCTA_F.copy()
    v, f, _ = validate_mesh(v_in, f_in)
    v[0, 0] = 99.0
    f[0, 0] = 5
    assert v_in[0, 0] == 1.0 and f_in[0, 0] == 0


@pytest.mark.parametrize(
    "vertices, faces, what",
    [
        (np.zeros((0, 3)), TET_F, "no vertices"),
        (TET_V, np.zeros((0, 3), dtype=int), "no faces"),
        (TET_V, [], "no faces"),
    ],
)
def test_empty_mesh(vertices, faces, what):
    with pytest.raises(MeshError, match=f"mesh is empty: it has {what}"):
        validate_mesh(vertices, faces)


def test_vertices_wrong_shape():
    with pytest.raises(MeshError, match=r"vertices must have shape \(n, 3\); got \(4, 2\)"):
        validate_mesh(TET_V[:, :2], TET_F)


def test_quad_faces_rejected():
    quads = np.array([[0, 1, 2, 3]])
    with pytest.raises(MeshError, match="faces must be triangles; triangulate polygons first"):
        validate_mesh(TET_V, quads)


def test_flat_faces_rejected():
    with pytest.raises(MeshError, match=r"faces must have shape \(m, 3\); got \(12,\)"):
        validate_mesh(TET_V, TET_F.ravel())


def test_non_integer_faces_rejected():
    with pytest.raises(MeshError, match="face indices must be integers"):
        validate_mesh(TET_V, TET_F + 0.5)


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_non_finite_coordinates(bad):
    v = OCTA_V.copy()
    v[2, 1] = bad
    v[5, 0] = bad
    with pytest.raises(MeshError, match=r"NaN or inf coordinates in 2 vertices \(vertices 2, 5\)"):
        validate_mesh(v, OCTA_F)


def test_index_out_of_range():
    f = TET_F.copy()
    f[1, 2] = 4
    with pytest.raises(MeshError, match=r"1 face with vertex indices outside \[0, 3\] \(face 1; index 4\)"):
        validate_mesh(TET_V, f)


def test_negative_index():
    f = TET_F.copy()
    f[0, 0] = -1
    f[3, 1] = -2
    with pytest.raises(MeshError, match=r"2 faces with .*\(faces 0, 3; indices -1, -2\).*0-based"):
        validate_mesh(TET_V, f)


@pytest.mark.parametrize("face", [[1, 1, 2], [0, 1, 1], [1, 2, 1]])  # each pair of corners
def test_repeated_vertex_in_face(face):
    f = np.vstack([TET_F, [face]])
    with pytest.raises(MeshError, match=r"1 degenerate face \(1 with a repeated vertex index, 0 with zero area; face 4\)"):
        validate_mesh(TET_V, f)


def test_zero_area_face():
    # vertex 4 lies on the segment 0-1, so face (0, 1, 4) is collinear
    v = np.vstack([TET_V, [[0.5, 0.0, 0.0]]])
    f = np.vstack([TET_F, [[0, 1, 4]]])
    with pytest.raises(MeshError, match=r"0 with a repeated vertex index, 1 with zero area; face 4\).*Remove degenerate faces"):
        validate_mesh(v, f)


def test_thin_but_valid_face_is_not_degenerate():
    # sliver (1, 0, 4) of area 5e-9, far above 1e-12 * bbox_diagonal**2; the mesh stays closed
    v = np.vstack([TET_V, [[0.5, -1e-8, 0.0]]])
    f = np.array([[0, 2, 1], [0, 4, 3], [4, 1, 3], [1, 2, 3], [0, 3, 2], [1, 0, 4]])
    _, out_f, _ = validate_mesh(v, f)
    np.testing.assert_array_equal(out_f, f)


def test_duplicate_face_is_non_manifold():
    f = np.vstack([TET_F, TET_F[2][::-1]])  # same vertex set, other orientation
    with pytest.raises(MeshError, match=r"non-manifold: 1 duplicate face \(face 4 repeats"):
        validate_mesh(TET_V, f)


def test_non_manifold_edge():
    # three triangles on the edge (0, 1)
    v = np.array([[0.0, 0, 0], [1, 0, 0], [0.5, 1, 0], [0.5, -1, 0], [0.5, 0, 1]])
    f = np.array([[0, 1, 2], [1, 0, 3], [0, 1, 4]])
    with pytest.raises(MeshError, match=r"non-manifold: 1 edge shared by more than 2 faces \(edge \(0, 1\)\).*Repair non Manifold Edges"):
        validate_mesh(v, f)


def test_non_manifold_vertex_two_tets_sharing_a_vertex():
    # second tetrahedron reflected through vertex 0, sharing only that vertex
    v = np.vstack([TET_V, -TET_V[1:]])
    f = np.vstack([TET_F, np.where(TET_F == 0, 0, TET_F + 3)[:, ::-1]])
    with pytest.raises(MeshError, match=r"non-manifold: 1 vertex where separate sheets .*\(vertex 0\).*Repair non Manifold Vertices"):
        validate_mesh(v, f)


def test_non_manifold_vertex_two_cones_touching_at_tip():
    # two open cones (fans of 4 triangles) whose apexes are the same vertex 0
    ring = np.array([[1.0, 0, 1], [0, 1.0, 1], [-1.0, 0, 1], [0, -1.0, 1]])
    v = np.vstack([[[0.0, 0, 0]], ring, ring * [1, 1, -1]])
    upper = [[0, 1 + i, 1 + (i + 1) % 4] for i in range(4)]
    lower = [[0, 5 + (i + 1) % 4, 5 + i] for i in range(4)]
    with pytest.raises(MeshError, match=r"1 vertex where .*\(vertex 0\)"):
        validate_mesh(v, upper + lower)


def test_several_non_manifold_vertices_are_counted():
    # a chain of three triangles touching only at vertices 2 and 4
    v = np.array([[0.0, 0, 0], [0, 1, 0], [1, 0.5, 0], [2, 0, 0], [2, 1, 0], [3, 1.5, 0], [3, 2, 0.5]])
    f = np.array([[0, 2, 1], [2, 3, 4], [4, 5, 6]])
    with pytest.raises(MeshError, match=r"non-manifold: 2 vertices where .*\(vertices 2, 4\)"):
        validate_mesh(v, f)


def test_unreferenced_vertex():
    v = np.vstack([TET_V, [[9.0, 9.0, 9.0]], [[8.0, 8.0, 8.0]]])
    with pytest.raises(MeshError, match=r"2 vertices used by no face \(vertices 4, 5\).*--largest-component.*largest_component=True"):
        validate_mesh(v, TET_F)


def test_several_components_message():
    v, f = two_tets()
    v = np.vstack([v, OCTA_V + [0, 9, 0]])
    f = np.vstack([f, OCTA_F + 8])
    with pytest.raises(
        MeshError,
        match=r"mesh has 3 connected components \(vertex counts, largest first: 6, 4, 4\).*--largest-component \(CLI\) / largest_component=True \(API\)",
    ):
        validate_mesh(v, f)


def test_components_listed_at_most_five():
    v = np.vstack([TET_V + [3.0 * i, 0, 0] for i in range(7)])
    f = np.vstack([TET_F + 4 * i for i in range(7)])
    with pytest.raises(MeshError, match=r"7 connected components \(vertex counts, largest first: 4, 4, 4, 4, 4, \.\.\.\)"):
        validate_mesh(v, f)


def test_largest_component_keeps_right_vertices_and_reindexes():
    # small tet first (vertices 0-3), then the octahedron (4-9), an unused vertex (10), a tet (11-14)
    v = np.vstack([TET_V, OCTA_V + [0, 9, 0], [[7.0, 7.0, 7.0]], TET_V + [5, 0, 0]])
    f = np.vstack([TET_F + 11, OCTA_F + 4, TET_F])
    out_v, out_f, kept = validate_mesh(v, f, largest_component=True)
    np.testing.assert_array_equal(kept, np.arange(4, 10))
    np.testing.assert_array_equal(out_v, v[kept])
    np.testing.assert_array_equal(out_f, OCTA_F)
    # every kept face refers to the same coordinates as the original face did
    np.testing.assert_array_equal(out_v[out_f], v[f[4:12]])


def test_largest_component_drops_unreferenced_vertices():
    v = np.vstack([[[9.0, 9.0, 9.0]], TET_V, [[8.0, 8.0, 8.0]]])
    out_v, out_f, kept = validate_mesh(v, TET_F + 1, largest_component=True)
    np.testing.assert_array_equal(kept, [1, 2, 3, 4])
    np.testing.assert_array_equal(out_v, TET_V)
    np.testing.assert_array_equal(out_f, TET_F)


def test_largest_component_tie_keeps_lowest_index():
    v, f = two_tets()
    _, out_f, kept = validate_mesh(v, f[::-1], largest_component=True)
    np.testing.assert_array_equal(kept, [0, 1, 2, 3])
    np.testing.assert_array_equal(np.sort(out_f, axis=0), np.sort(TET_F, axis=0))


def test_largest_component_on_connected_mesh_is_identity():
    _, f, kept = validate_mesh(OCTA_V, OCTA_F, largest_component=True)
    np.testing.assert_array_equal(kept, np.arange(6))
    np.testing.assert_array_equal(f, OCTA_F)


def test_too_few_vertices_with_reason():
    reason = "the spectral embedding with k=6 needs at least 7 vertices"
    with pytest.raises(MeshError, match=r"mesh has 6 vertices but at least 7 are needed: the spectral embedding "
                                        r"with k=6 needs at least 7 vertices\. Use a finer mesh"):
        validate_mesh(OCTA_V, OCTA_F, min_vertices=7, reason=reason)


def test_too_few_vertices_checked_after_component_selection():
    v, f = two_tets()
    with pytest.raises(MeshError, match=r"has 4 vertices but at least 5 are needed\. "):
        validate_mesh(v, f, largest_component=True, min_vertices=5)


def test_name_appears_in_message():
    with pytest.raises(MeshError, match=r"^cat0\.off: 1 face with vertex indices"):
        validate_mesh(TET_V, np.vstack([TET_F[:3], [[0, 3, 7]]]), name="cat0.off")


@pytest.mark.parametrize("bad", [0, -3, 2.5, True, "3"])
def test_bad_min_vertices(bad):
    with pytest.raises(ParameterError, match="The 'min_vertices' parameter of validate_mesh must be an int >= 1"):
        validate_mesh(OCTA_V, OCTA_F, min_vertices=bad)


def test_check_order_shape_before_finiteness():
    v = np.full((4, 2), np.nan)
    with pytest.raises(MeshError, match="vertices must have shape"):
        validate_mesh(v, TET_F)


def test_check_order_degenerate_before_non_manifold():
    # duplicate of a degenerate face: degenerate is reported first
    f = np.vstack([TET_F, [[0, 1, 1]], [[0, 1, 1]]])
    with pytest.raises(MeshError, match="degenerate"):
        validate_mesh(TET_V, f)


def test_check_order_non_manifold_before_components():
    v, f = two_tets()
    f = np.vstack([f, f[:1]])
    with pytest.raises(MeshError, match="duplicate face"):
        validate_mesh(v, f, largest_component=True)


def test_long_index_lists_are_cut_after_five():
    v = np.vstack([TET_V, np.arange(21.0).reshape(7, 3) + 10])
    with pytest.raises(MeshError, match=r"7 vertices used by no face \(vertices 4, 5, 6, 7, 8, \.\.\.\)"):
        validate_mesh(v, TET_F)


def _repeated_rows_reference(rows) -> np.ndarray:
    """Rows equal to an earlier row, by a dictionary of tuples (no numpy keys, no np.unique)."""
    seen: set = set()
    repeated = []
    for row in map(tuple, rows.tolist()):
        repeated.append(row in seen)
        seen.add(row)
    return np.array(repeated)


@pytest.mark.parametrize("n_values", [50, 1_000, 3_000_000])
def test_repeated_rows_match_a_reference(n_values):
    """The int64-key duplicate test (and its fallback for huge meshes) against a set of tuples."""
    from meshcorr.core.validate import _repeated_rows

    rng = np.random.default_rng(0)
    rows = np.sort(rng.integers(0, 8, size=(400, 3)), axis=1) * (n_values // 8)
    expected = _repeated_rows_reference(rows)
    assert expected.sum() > 10
    np.testing.assert_array_equal(_repeated_rows(rows, n_values), expected)


def test_repeated_rows_of_a_huge_mesh_do_not_collide():
    """At 3 million vertices a * n**2 + b * n + c overflows int64: two different rows share a key."""
    from meshcorr.core.validate import _repeated_rows

    n = 3_000_000
    # (a, b, c) with a * n**2 + b * n + c == 2**64, whose int64 key wraps to 0, the key of (0, 0, 0).
    a, rest = divmod(2**64, n * n)
    b, c = divmod(rest, n)
    rows = np.array([[0, 0, 0], [a, b, c], [a, b, c], [1, 2, 3]], dtype=np.int64)
    assert max(a, b, c) < n
    with np.errstate(over="ignore"):
        wrapped = (rows[:, 0] * np.int64(n) + rows[:, 1]) * np.int64(n) + rows[:, 2]
    assert wrapped[0] == wrapped[1]  # the collision the fallback must avoid
    np.testing.assert_array_equal(_repeated_rows(rows, n), [False, False, True, False])
    np.testing.assert_array_equal(_repeated_rows_reference(rows), [False, False, True, False])


@pytest.mark.parametrize("vertices, faces, message", [
    ([[0.0, 0, 0], [1.0, 0], [0, 1.0, 0], [0, 0, 1.0]], TET_F.tolist(),
     r"vertices must have shape \(n, 3\); got rows of different lengths \(row 1 has 2 entries\)"),
    ([[0.0, 0, 0], 1.0, [0, 1.0, 0], [0, 0, 1.0]], TET_F.tolist(),
     r"vertices must have shape \(n, 3\); got rows of different lengths \(row 1 is not a sequence\)"),
    (TET_V.tolist(), [[0, 2, 1], [0, 1, 3, 2], [1, 2, 3], [0, 3, 2]],
     r"faces must have shape \(m, 3\); got rows of different lengths \(row 1 has 4 entries\)\. "
     "faces must be triangles"),
])
def test_ragged_lists_raise_a_mesh_error(vertices, faces, message):
    with pytest.raises(MeshError, match=message):
        validate_mesh(vertices, faces)


def test_ragged_vertex_list_through_match_raises_a_mesh_error():
    import meshcorr

    ragged = [[0.0, 0, 0], [1.0, 0], [0, 1.0, 0], [0, 0, 1.0]]
    with pytest.raises(MeshError, match=r"^source: vertices must have shape \(n, 3\); got rows"):
        meshcorr.match((ragged, TET_F.tolist()), (TET_V, TET_F))


@pytest.mark.parametrize("vertices", [
    np.array([["0", "0", "0"], ["1", "0", "0"], ["0", "1", "0"], ["0", "0", "1"]]),
    TET_V.astype(np.complex128),
    np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, None]], dtype=object),
])
def test_coordinates_that_are_not_real_numbers(vertices):
    with pytest.raises(MeshError, match=f"vertex coordinates must be real numbers; got dtype {vertices.dtype}"):
        validate_mesh(vertices, TET_F)


def test_shape_store_computes_each_key_once_and_keeps_it():
    from meshcorr.core.store import ShapeStore

    store, calls = ShapeStore(), []
    assert store.get(("double", 2), lambda: calls.append(1) or 4) == 4
    assert store.get(("double", 2), lambda: calls.append(1) or -1) == 4  # kept, not recomputed
    assert calls == [1] and ("double", 2) in store and ("double", 3) not in store
    store.put(("double", 3), 6)
    assert store[("double", 3)] == 6 and len(store) == 2 and sorted(store) == [("double", 2), ("double", 3)]



@pytest.mark.parametrize("vertices, problem", [
    (OCTA_V * 1e200, "coordinates as large as 1e+200"),
    (OCTA_V + 1e60, "coordinates as large as 1e+60"),  # small, but far from the origin
    (OCTA_V * 1e-200, "a bounding box only 2e-200 across"),
])
def test_coordinates_beyond_the_numerics_are_refused_with_the_fix(vertices, problem):
    # Near 1e200 potpourri3d failed on inf (an internal error); near 1e-200 every face looked degenerate.
    for check in (lambda: validate_mesh(vertices, OCTA_F), lambda: validate_cloud(vertices),
                  lambda: Mesh(vertices, OCTA_F)):
        with pytest.raises(MeshError) as error:
            check()
        message = str(error.value)
        assert problem in message and "divide them by the bounding box" in message
        assert "degenerate" not in message


def test_coordinates_within_the_numerics_pass_and_the_checks_see_the_faces_only():
    for scale in (1e-40, 1e40):
        np.testing.assert_array_equal(validate_mesh(OCTA_V * scale, OCTA_F)[0], OCTA_V * scale)
    far = np.vstack([OCTA_V, [1e200, 0.0, 0.0]])  # an unreferenced vertex: dropped, not a scale problem
    assert len(validate_mesh(far, OCTA_F, largest_component=True)[0]) == 6
