"""Partial shapes and holes (meshcorr.evaluation.cuts): kept area, index maps, boundaries, refusals."""

import numpy as np
import pytest
import trimesh

from meshcorr import datasets

from meshcorr.evaluation import cuts as cuts
from meshcorr.errors import ParameterError
from meshcorr.core.mesh import as_mesh
from meshcorr.core.validate import pinched_vertices


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


@pytest.mark.parametrize("seed", [0, 2, 6])
def test_balls_that_sever_a_piece_still_leave_the_asked_area(seed):
    # On the creature these balls cut off a limb or the tail: keeping the faces of the asked area and
    # then the largest piece left 0.59-0.61 of it; the radius now shrinks until the piece holds 0.7.
    creature = as_mesh(datasets.creature(resolution=1), name="creature")
    part, _ = cuts.remove_balls(creature, keep=0.7, n_balls=3, random_state=seed)
    assert part.area / creature.area == pytest.approx(0.7, abs=0.01)


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


def test_a_cut_that_would_pinch_a_vertex_drops_the_faces_around_it(ball):
    # Remove two opposite faces of one vertex's fan: the rest of the fan is two sheets touching at the vertex.
    vertex = 0
    fan = np.flatnonzero((ball.faces == vertex).any(axis=1))
    # The fan's faces are not in cyclic order; find two that share no edge.
    first = ball.faces[fan[0]]
    opposite = [f for f in fan[1:] if len(np.intersect1d(ball.faces[f], first)) == 1][0]
    keep = np.ones(len(ball.faces), dtype=bool)
    keep[[fan[0], opposite]] = False
    assert list(pinched_vertices(ball.faces[keep], ball.n_vertices)) == [vertex]
    part, kept = cuts.submesh(ball, keep)
    assert vertex not in kept
    assert len(pinched_vertices(part.faces, part.n_vertices)) == 0
    assert part.n_vertices == ball.n_vertices - 1
