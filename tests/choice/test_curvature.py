"""Smoothed signed mean curvature and its disagreement across a map."""

import numpy as np
import trimesh
import pytest
from scipy.spatial import cKDTree

from meshcorr import datasets as ds
from meshcorr.choice.curvature import curvature_disagreement, signed_mean_curvature, smoothed_curvature
from meshcorr.errors import ParameterError
from meshcorr.core.mesh import Mesh


def nosed_sphere(subdivisions: int = 4):
    """A sphere with a bump (a "nose") at +x and a dent at -x: front and back differ."""
    V, F = ds.sphere(subdivisions=subdivisions)
    r = 1.0 + 0.4 * np.exp(-np.sum((V - [1, 0, 0]) ** 2, axis=1) / 0.05) \
        - 0.3 * np.exp(-np.sum((V - [-1, 0, 0]) ** 2, axis=1) / 0.05)
    return V * r[:, None], F


def test_sphere_curvature_is_the_scale_free_constant():
    V, F = ds.sphere(subdivisions=4)
    for radius in (0.5, 3.0):  # H sqrt(A) = (1 / r) sqrt(4 pi r^2) = 2 sqrt(pi) at any radius
        H, mass = signed_mean_curvature(Mesh(V * radius, F))
        assert np.median(H) == pytest.approx(2 * np.sqrt(np.pi), rel=0.01)
        assert np.all(np.abs(H / (2 * np.sqrt(np.pi)) - 1) < 0.2)
        assert mass.sum() == pytest.approx(4 * np.pi * radius ** 2, rel=0.01)


def test_curvature_is_signed_outwards_whatever_the_winding():
    V, F = nosed_sphere()
    H, _ = signed_mean_curvature(Mesh(V, F[:, ::-1]))  # inward winding is repaired
    direction = V[:, 0] / np.linalg.norm(V, axis=1)
    nose, dent = np.argmax(direction), np.argmin(direction)
    assert H[nose] > 2 * np.sqrt(np.pi) + 1.0  # the bump's tip is more convex than the sphere
    assert H[dent] < 0.0  # the bottom of the dent is concave


def test_descriptor_is_invariant_to_rigid_motion_scale_and_order():
    V, F = nosed_sphere()
    rng = np.random.default_rng(0)
    R, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    perm = rng.permutation(len(V))
    inv = np.argsort(perm)
    src, copy = Mesh(V, F), Mesh((V @ R.T * 2.5 + 1.0)[perm], inv[F])
    some = np.arange(0, len(V), 7)
    np.testing.assert_allclose(smoothed_curvature(src, some, 0.05), smoothed_curvature(copy, inv[some], 0.05),
                               rtol=1e-6)
    assert curvature_disagreement(src, copy, inv, n_sample=len(V)) < 1e-6
    assert curvature_disagreement(src, copy, rng.integers(0, len(V), len(V))) > 0.5


def test_ball_average_agrees_across_resolutions():
    V, F = nosed_sphere()
    fine = Mesh(*trimesh.remesh.subdivide(V, F))  # midpoints appended: original indices kept
    coarse = Mesh(V, F)
    some = np.arange(0, len(V), 5)
    a, b = smoothed_curvature(coarse, some, 0.08), smoothed_curvature(fine, some, 0.08)
    assert np.corrcoef(a, b)[0, 1] > 0.95
    np.testing.assert_allclose(np.median(b / a), 1.0, atol=0.1)


def test_above_field_max_the_balls_sum_over_a_sample_and_agree(monkeypatch):
    # Large meshes average over a seeded uniform sample of FIELD_MAX vertices (each with its area): the
    # cost of a ball stops growing with the vertex count, the averages stay those of every vertex.
    from meshcorr.choice import curvature

    V, F = nosed_sphere(subdivisions=5)  # 10242 vertices, a smooth field
    some = np.arange(0, len(V), 17)
    full = smoothed_curvature(Mesh(V, F), some, 0.08)
    monkeypatch.setattr(curvature, "FIELD_MAX", len(V) // 4)  # ~50 sampled vertices a ball
    mesh = Mesh(V, F)
    sampled = smoothed_curvature(mesh, some, 0.08)
    assert len(mesh.store[("curvature_field",)][1]) == len(V) // 4  # the balls' vertices
    assert not np.array_equal(sampled, full)
    assert np.corrcoef(full, sampled)[0, 1] > 0.95
    assert np.median(np.abs(sampled - full)) < 0.02 * np.std(full)
    np.testing.assert_array_equal(smoothed_curvature(Mesh(V, F), some, 0.08), sampled)  # seeded


def test_a_half_turn_that_puts_the_nose_behind_disagrees():
    V, F = nosed_sphere()
    mesh = Mesh(V, F)
    half_turn = cKDTree(V).query(V * [-1, -1, 1])[1]  # 180 degrees about z: front <-> back
    mirror = cKDTree(V).query(V * [1, 1, -1])[1]  # a reflection keeping the nose in front
    identity = np.arange(len(V))
    assert curvature_disagreement(mesh, mesh, half_turn) > 10 * curvature_disagreement(mesh, mesh, mirror)
    assert curvature_disagreement(mesh, mesh, mirror) < 0.05
    assert curvature_disagreement(mesh, mesh, identity) == 0.0


def test_bad_maps_are_refused():
    V, F = nosed_sphere()
    mesh = Mesh(V, F)
    with pytest.raises(ParameterError, match="one target vertex"):
        curvature_disagreement(mesh, mesh, np.arange(len(V) - 1))
    with pytest.raises(ParameterError, match="one target vertex"):
        curvature_disagreement(mesh, mesh, np.full(len(V), len(V)))


def test_a_boundary_does_not_bend_the_curvature_next_to_it():
    # A sphere with its top cut off: the one-sided Laplacian on the rim is not a curvature.
    from meshcorr.evaluation import cuts as cuts
    from meshcorr.choice.curvature import _on_boundary
    from meshcorr.core.mesh import as_mesh

    ball = as_mesh(ds.sphere(subdivisions=4))
    part, _ = cuts.cut_by_plane(ball, keep=0.8, normal=[0, 0, 1])
    rim = np.flatnonzero(_on_boundary(part))
    assert len(rim) > 50
    interior = smoothed_curvature(part, np.flatnonzero(part.vertices[:, 2] < -0.5), 0.045)
    np.testing.assert_allclose(smoothed_curvature(part, rim, 0.045), np.median(interior), rtol=0.02)


def test_mapped_curvature_is_smoothed_curvature_bit_for_bit_from_a_cached_table(monkeypatch):
    from meshcorr.choice import curvature as curvature
    from meshcorr.choice.curvature import mapped_curvature, smoothed_curvature

    shape = ds.creature(resolution=1)
    mesh = Mesh(shape.vertices, shape.faces)
    vertices = np.random.default_rng(0).integers(0, mesh.n_vertices, size=300)
    for signed in (True, False):
        np.testing.assert_array_equal(mapped_curvature(mesh, vertices, 0.045, signed=signed),
                                      smoothed_curvature(mesh, vertices, 0.045, signed=signed))
    table = mesh.store[("curvature_table", 0.045)]
    assert table.shape == (mesh.n_vertices,) and not table.flags.writeable
    assert ("curvature_table", 0.045, "unsigned") in mesh.store
    # Above the size limit: no table, the same values.
    other = Mesh(shape.vertices, shape.faces)
    monkeypatch.setattr(curvature, "CURVATURE_TABLE_MAX", 10)
    np.testing.assert_array_equal(mapped_curvature(other, vertices, 0.045), smoothed_curvature(other, vertices, 0.045))
    assert not any(key[0] == "curvature_table" for key in other.store)
