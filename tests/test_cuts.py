"""Partial shapes and holes (meshcorr.cuts): kept area, index maps, boundaries, refusals."""

import numpy as np
import pytest
import trimesh

from meshcorr import cuts, datasets
from meshcorr.errors import ParameterError
from meshcorr.mesh import as_mesh


@pytest.fixture(scope="module")
def ball():
    return as_mesh(datasets.sphere(subdivisions=4), name="ball")


def _boundary_loops(mesh) -> int:
    shape = trimesh.Trimesh(mesh.vertices, mesh.faces, process=False)
    return 0 if shape.is_watertight else len(shape.outline().entities)


@pytest.mark.parametrize("keep", [0.6, 0.75, 0.9])
def test_plane_cut_keeps_the_asked_area_on_one_side(ball, keep):
    normal = np.array([0.0, 0.0, 1.0])
    part, kept = cuts.cut_by_plane(ball, keep=keep, normal=normal)
    np.testing.assert_allclose(part.vertices, ball.vertices[kept])
    assert part.area / ball.area == pytest.approx(keep, abs=0.02)
    # One side only: nothing kept lies above the lowest removed vertex.
    removed = np.setdiff1d(np.arange(ball.n_vertices), kept)
    assert part.vertices[:, 2].max() <= ball.vertices[removed, 2].min() + 0.1
    assert _boundary_loops(part) == 1


def test_ball_removal_keeps_one_connected_piece_of_about_the_asked_area(ball):
    part, kept = cuts.remove_balls(ball, keep=0.7, n_balls=3, random_state=1)
    np.testing.assert_allclose(part.vertices, ball.vertices[kept])
    assert 0.6 <= part.area / ball.area <= 0.72
    assert len(np.unique(kept)) == len(kept)


def test_holes_are_the_asked_number_of_boundary_loops(ball):
    holed, kept = cuts.punch_holes(ball, n_holes=6, hole_area=0.01, random_state=3)
    assert _boundary_loops(holed) == 6
    assert holed.area / ball.area == pytest.approx(1 - 6 * 0.01, abs=0.03)
    np.testing.assert_allclose(holed.vertices, ball.vertices[kept])


def test_same_seed_same_part(ball):
    a = cuts.remove_balls(ball, keep=0.8, random_state=5)[1]
    b = cuts.remove_balls(ball, keep=0.8, random_state=5)[1]
    c = cuts.remove_balls(ball, keep=0.8, random_state=6)[1]
    np.testing.assert_array_equal(a, b)
    assert not np.array_equal(a, c)


@pytest.mark.parametrize("call, message", [
    (lambda m: cuts.cut_by_plane(m, keep=1.0), "strictly between 0 and 1"),
    (lambda m: cuts.cut_by_plane(m, keep=0), "strictly between 0 and 1"),
    (lambda m: cuts.remove_balls(m, keep="half"), "strictly between 0 and 1"),
    (lambda m: cuts.cut_by_plane(m, normal=[0, 0, 0]), "non-zero 3-vector"),
    (lambda m: cuts.cut_by_plane(m, normal=[1, 0]), "non-zero 3-vector"),
    (lambda m: cuts.remove_balls(m, n_balls=0), "n_balls"),
    (lambda m: cuts.punch_holes(m, n_holes=0), "n_holes"),
    (lambda m: cuts.punch_holes(m, hole_area=0.5), r"\(0, 0.1\]"),
    (lambda m: cuts.submesh(m, np.zeros(len(m.faces), bool)), "Nothing of ball is left"),
])
def test_bad_parameters_are_refused_by_name(ball, call, message):
    with pytest.raises(ParameterError, match=message):
        call(ball)


def test_a_pinch_left_by_a_cut_is_taken_apart():
    # A 3 x 3 grid of squares; keep two squares and a third one that touches the pair at a corner only.
    xs, ys = np.meshgrid(np.arange(4.0), np.arange(4.0), indexing="ij")
    vertices = np.column_stack([xs.ravel(), ys.ravel(), np.zeros(16)])
    index = lambda i, j: 4 * i + j  # noqa: E731
    faces = np.array([f for i in range(3) for j in range(3)
                      for f in ([index(i, j), index(i + 1, j), index(i + 1, j + 1)],
                                [index(i, j), index(i + 1, j + 1), index(i, j + 1)])])
    grid = as_mesh((vertices, faces), name="grid")
    square = lambda i, j: [2 * (3 * i + j), 2 * (3 * i + j) + 1]  # noqa: E731
    keep = np.zeros(len(faces), dtype=bool)
    keep[square(0, 0) + square(0, 1) + square(1, 2)] = True  # (1, 2) touches (0, 1) at vertex (1, 2)
    part, kept = cuts.submesh(grid, keep)  # validate_mesh refuses a pinch: this must not raise
    np.testing.assert_array_equal(np.sort(kept), [index(0, 0), index(0, 1), index(0, 2), index(1, 0),
                                                  index(1, 1), index(1, 2)])
    assert len(part.faces) == 4
