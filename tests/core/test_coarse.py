"""Coarse copies (meshcorr.core.coarse): size, validity, parents and children, the lift of a map."""

import numpy as np
import pytest

from meshcorr import datasets as ds
from meshcorr.core.coarse import COARSE_ABOVE, coarse_copy, needs_copy
from meshcorr.core.mesh import as_mesh


@pytest.fixture(scope="module")
def creature():
    shape = ds.creature(resolution=3)  # 2000 vertices
    return as_mesh((shape.vertices, shape.faces), name="creature")


def test_copy_has_about_the_vertices_asked_and_is_a_valid_closed_mesh(creature):
    copy = coarse_copy(creature, 400)
    assert abs(copy.mesh.n_vertices - 400) <= 0.05 * 400
    assert copy.mesh.name == "creature" and copy.fine is creature and not copy.is_identity
    assert not copy.mesh.is_cloud
    # closed like the fine mesh: every edge in exactly two faces (Euler characteristic of a sphere)
    n_edges = len(np.unique(np.sort(copy.mesh.faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1), axis=0))
    assert copy.mesh.n_vertices - n_edges + len(copy.mesh.faces) == 2


def test_parents_and_children_link_nearby_vertices(creature):
    copy = coarse_copy(creature, 400)
    assert copy.parent.shape == (copy.mesh.n_vertices,) and copy.child.shape == (creature.n_vertices,)
    spacing = np.sqrt(creature.area / copy.mesh.n_vertices)  # the copy's vertex spacing
    born = np.linalg.norm(creature.vertices[copy.parent] - copy.mesh.vertices, axis=1)
    assert born.max() < 2.5 * spacing  # a merged vertex stays near the vertex it was born from
    nearest = np.linalg.norm(creature.vertices - copy.mesh.vertices[copy.child], axis=1)
    assert nearest.max() < 2.5 * spacing
    # the child is the nearest coarse vertex
    all_distances = np.linalg.norm(creature.vertices[:, None] - copy.mesh.vertices[None], axis=2)
    np.testing.assert_allclose(nearest, all_distances.min(axis=1), atol=1e-12)


def test_lift_of_the_identity_keeps_each_vertex_near_itself(creature):
    copy = coarse_copy(creature, 400)
    lifted = copy.lift_map(np.arange(copy.mesh.n_vertices), copy)
    assert lifted.shape == (creature.n_vertices,)
    np.testing.assert_array_equal(lifted, copy.parent[copy.child])
    moved = np.linalg.norm(creature.vertices[lifted] - creature.vertices, axis=1)
    assert moved.mean() < 2.0 * np.sqrt(creature.area / copy.mesh.n_vertices)


def test_a_small_mesh_is_its_own_copy_and_a_cloud_has_none(creature):
    assert COARSE_ABOVE * 500 >= 2000 and not needs_copy(2000, 500)
    copy = coarse_copy(creature, 500)
    assert copy.is_identity and copy.mesh is creature
    np.testing.assert_array_equal(copy.lift_map(np.arange(2000), copy), np.arange(2000))
    assert needs_copy(2000, 400) and not needs_copy(10**6, 0)  # 0: never
    cloud = as_mesh(creature.vertices)
    assert coarse_copy(cloud, 400) is None


def test_copies_made_in_child_processes_are_those_made_here(creature):
    from meshcorr.core.coarse import coarse_copies

    here = coarse_copies([creature, creature], 400, processes=False)
    apart = coarse_copies([creature, creature], 400, processes=True)
    for a, b in zip(here, apart):
        np.testing.assert_array_equal(a.mesh.vertices, b.mesh.vertices)
        np.testing.assert_array_equal(a.mesh.faces, b.mesh.faces)
        np.testing.assert_array_equal(a.parent, b.parent)
        np.testing.assert_array_equal(a.child, b.child)
    small, cloud = coarse_copies([creature, as_mesh(creature.vertices)], 600, processes=True)
    assert small.is_identity and cloud.is_identity  # 2000 <= 4 x 600: their own copies
    assert coarse_copies([as_mesh(creature.vertices)], 400, processes=True) == [None]  # a cloud has none


def test_a_child_process_that_dies_gives_no_copy(creature, monkeypatch):
    import os

    from meshcorr.core import coarse

    monkeypatch.setattr(coarse, "_decimate", lambda *args: os._exit(1))  # the forked child inherits it
    assert coarse.coarse_copies([creature], 400, processes=True) == [None]
