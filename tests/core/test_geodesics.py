"""Geodesic solvers against the great-circle formula and against each other."""

import numpy as np
import pytest
import trimesh

from meshcorr.errors import ParameterError
from meshcorr.core.geodesics import geodesic_solver, pairwise_geodesics


@pytest.fixture(scope="module")
def sphere():
    mesh = trimesh.creation.icosphere(subdivisions=4, radius=2.0)  # 2562 vertices
    return np.asarray(mesh.vertices), np.asarray(mesh.faces)


def great_circle(vertices, sources, radius=2.0):
    unit = vertices / np.linalg.norm(vertices, axis=1, keepdims=True)
    return radius * np.arccos(np.clip(unit[sources] @ unit.T, -1.0, 1.0))


@pytest.mark.parametrize("method, tolerance", [("heat", 0.02), ("fmm", 0.02)])
def test_sphere_matches_great_circle(sphere, method, tolerance):
    V, F = sphere
    sources = np.array([0, 100, 1000, 2000])
    D = geodesic_solver(V, F, method).distances(sources)
    exact = great_circle(V, sources)
    far = exact > 0.5  # heat and fast marching err most next to the source
    rel = np.abs(D[far] - exact[far]) / exact[far]
    assert rel.mean() < tolerance
    np.testing.assert_allclose(D[np.arange(4), sources], 0.0, atol=1e-12)


def test_exact_solver_is_exact(sphere):
    pytest.importorskip("pygeodesic")
    V, F = sphere
    D = geodesic_solver(V, F, "exact").distances(np.array([5]))
    exact = great_circle(V, [5])
    # The polyhedral geodesic of an inscribed icosphere is a little shorter.
    rel = np.abs(D - exact)[exact > 0.5] / exact[exact > 0.5]
    assert rel.mean() < 0.005


def test_dijkstra_overestimates(sphere):
    V, F = sphere
    D = geodesic_solver(V, F, "dijkstra").distances(np.array([7]))
    exact = great_circle(V, [7])
    assert np.all(D >= exact * 0.999 - 1e-9)
    assert (D / np.maximum(exact, 1e-12))[exact > 0.5].mean() > 1.02


def test_heat_and_fast_marching_agree(sphere):
    V, F = sphere
    sources = np.arange(0, 2562, 250)
    heat = geodesic_solver(V, F, "heat").distances(sources)
    fmm = geodesic_solver(V, F, "fmm").distances(sources)
    far = heat > 0.5
    assert np.mean(np.abs(heat[far] - fmm[far]) / fmm[far]) < 0.03


def test_pairwise_is_symmetric_with_zero_diagonal():
    mesh = trimesh.creation.icosphere(subdivisions=2)
    D = pairwise_geodesics(mesh.vertices, mesh.faces, "heat")
    np.testing.assert_array_equal(D, D.T)
    np.testing.assert_array_equal(np.diag(D), 0.0)
    assert D.min() >= 0.0


def test_progress_is_reported():
    mesh = trimesh.creation.icosphere(subdivisions=1)
    calls = []
    pairwise_geodesics(mesh.vertices, mesh.faces, "heat", progress=lambda d, t: calls.append((d, t)))
    assert calls[-1] == (len(mesh.vertices), len(mesh.vertices))


def test_unknown_solver_is_rejected():
    mesh = trimesh.creation.icosphere(subdivisions=1)
    with pytest.raises(ParameterError, match="'geodesic' parameter must be one of heat, fmm"):
        geodesic_solver(mesh.vertices, mesh.faces, "magic")
