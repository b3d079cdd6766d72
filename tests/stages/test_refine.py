"""ZoomOut refinement: it lowers the error of a noisy map and keeps its orientation."""

import json
import os
import subprocess
import sys
import threading
import time

import numpy as np
import pytest
from scipy.sparse.linalg import LinearOperator
from scipy.spatial import cKDTree

import meshcorr
from meshcorr import datasets as ds
from meshcorr.errors import ParameterError
from meshcorr.core.mesh import Mesh
from meshcorr.core.map_orientation import orientation_score
from meshcorr.spectral.basis import laplace_basis, prefetch_bases
from meshcorr.stages.refine import refine_map, zoomout


@pytest.fixture(scope="module")
def poses():
    """Two poses of one figure (same connectivity: the truth is the identity)."""
    rest, bent = ds.figure(resolution=2, pose="rest"), ds.figure(resolution=2, pose="bent")
    return Mesh(rest.vertices, rest.faces), Mesh(bent.vertices, bent.faces)


def noisy_identity(mesh: Mesh, level: float, seed: int = 0) -> np.ndarray:
    """Each vertex mapped to the vertex nearest to a jittered copy of itself."""
    rng = np.random.default_rng(seed)
    jitter = rng.normal(0.0, level * np.sqrt(mesh.area), mesh.vertices.shape)
    return cKDTree(mesh.vertices).query(mesh.vertices + jitter)[1]


def error(mesh: Mesh, mapping: np.ndarray) -> float:
    return float(np.linalg.norm(mesh.vertices[mapping] - mesh.vertices, axis=1).mean() / np.sqrt(mesh.area))


def test_laplace_basis_is_mass_orthonormal_and_cached(poses):
    import potpourri3d as pp3d

    mesh = poses[0]
    values, phi = laplace_basis(mesh, 12)
    mass = pp3d.vertex_areas(mesh.vertices, mesh.faces)
    mass /= mass.sum()
    np.testing.assert_allclose(phi.T @ (mass[:, None] * phi), np.eye(12), atol=1e-8)
    assert abs(values[0]) < 1e-8 and np.all(np.diff(values) >= -1e-12)
    assert laplace_basis(mesh, 12)[1] is phi and not phi.flags.writeable


def test_refinement_lowers_the_error_of_a_noisy_pose_map(poses):
    rest, bent = poses
    start = noisy_identity(bent, 0.03)
    before = error(bent, start)
    refined, history = refine_map(rest, bent, start, k=30)
    after = error(bent, refined)
    assert after < 0.5 * before, (before, after)
    assert orientation_score(rest, bent, refined) > 0.9
    assert history[0]["k"] == 16 and history[-1]["k"] == 30


def test_refinement_does_not_flip_a_mirrored_map():
    # An exactly symmetric ellipsoid: the reflection z -> -z is an isometry.
    V, F = ds.sphere(subdivisions=3)
    V = V * [2.0, 1.0, 0.7]
    mesh = Mesh(V, F)
    mirror = cKDTree(V).query(V * [1, 1, -1])[1]
    jitter = cKDTree(V).query(V[mirror] + np.random.default_rng(1).normal(0, 0.03, V.shape))[1]
    refined, _ = refine_map(mesh, mesh, jitter, k=20)
    assert orientation_score(mesh, mesh, refined) < 0.2
    assert np.linalg.norm(V[refined] - V[mirror], axis=1).mean() < np.linalg.norm(V[jitter] - V[mirror], axis=1).mean()


def test_bijective_refinement_is_a_permutation(poses):
    rest, bent = poses
    refined, _ = refine_map(rest, bent, noisy_identity(bent, 0.02), k=20, bijective=True)
    np.testing.assert_array_equal(np.sort(refined), np.arange(rest.n_vertices))


def test_pipeline_refinement_improves_a_pose_pair():
    rest, bent = (Mesh(s.vertices, s.faces) for s in (ds.figure(pose="rest"), ds.figure(pose="bent")))
    plain = meshcorr.match(rest, bent, refine=False, reorder="signs")
    refined = meshcorr.match(rest, bent, reorder="signs")
    assert error(bent, refined.map) < error(bent, plain.map)
    assert refined.refine_history and refined.summary()["refine"]["iterations"] == len(refined.refine_history)
    assert "refine" in refined.timings and "refine" not in plain.timings


def test_refine_errors(poses):
    rest, bent = poses
    identity = np.arange(rest.n_vertices)
    with pytest.raises(ParameterError, match="one target vertex"):
        refine_map(rest, bent, identity[:-1])
    with pytest.raises(ParameterError, match="one target vertex"):
        refine_map(rest, bent, identity + 1)
    with pytest.raises(ParameterError, match="'refine_k' parameter must be an int >= 2"):
        refine_map(rest, bent, identity, k=1)
    phi = np.ones((10, 4))
    with pytest.raises(ParameterError, match="same size"):
        zoomout(phi, np.ones((10, 5)), np.arange(10))
    with pytest.raises(ParameterError, match="equal vertex counts"):
        zoomout(phi, np.ones((12, 4)), np.arange(10), k_start=2, bijective=True)
    with pytest.raises(ParameterError, match="refine_step"):
        zoomout(phi, phi, np.arange(10), k_start=2, step=0)
    with pytest.raises(ParameterError, match="refine_k_start"):
        zoomout(phi, phi, np.arange(10), k_start=5)


def test_laplace_basis_matches_a_dense_generalised_eigh_up_to_sign(poses):
    import potpourri3d as pp3d
    import scipy.linalg

    mesh = poses[1]
    values, phi = laplace_basis(mesh, 10)
    L = pp3d.cotan_laplacian(mesh.vertices, mesh.faces).toarray()
    mass = pp3d.vertex_areas(mesh.vertices, mesh.faces)
    ref_values, ref = scipy.linalg.eigh(L, np.diag(mass / mass.sum()), subset_by_index=[0, 9])
    np.testing.assert_allclose(values[1:], ref_values[1:], rtol=1e-8)
    signs = np.sign(np.sum(phi * ref, axis=0))
    np.testing.assert_allclose(phi[:, 1:], (ref * signs)[:, 1:], atol=1e-6)


def test_pruned_search_equals_brute_force(poses):
    from meshcorr.spectral.nearest import _nearest_rows_pruned, nearest_rows as _nearest_rows

    rest, bent = poses
    _, phi1 = laplace_basis(rest, 20)
    _, phi2 = laplace_basis(bent, 20)
    queries = phi1 + np.random.default_rng(0).normal(0.0, 0.05, phi1.shape)
    for n_cells in (1, 40, 400):
        np.testing.assert_array_equal(_nearest_rows_pruned(queries, phi2, n_cells=n_cells),
                                      _nearest_rows(queries, phi2))
    cloud = np.random.default_rng(1).normal(size=(2000, 8))  # no manifold: little pruning, still exact
    np.testing.assert_array_equal(_nearest_rows_pruned(cloud[:300] + 0.1, cloud, n_cells=50),
                                  _nearest_rows(cloud[:300] + 0.1, cloud))


def test_zoomout_prunes_above_the_threshold_with_the_same_map(poses, monkeypatch):
    import meshcorr.spectral.nearest as nearest_module

    rest, bent = poses
    start = noisy_identity(bent, 0.03)
    brute, _ = refine_map(rest, bent, start, k=20)
    monkeypatch.setattr(nearest_module, "PRUNE_ABOVE", 10)
    pruned, _ = refine_map(rest, bent, start, k=20)
    np.testing.assert_array_equal(pruned, brute)


def assert_blas_restored(script: str) -> None:
    """Run ``script`` (printing BLAS thread counts before and after) in a fresh interpreter with 2 BLAS threads."""
    env = dict(os.environ, OPENBLAS_NUM_THREADS="2", OMP_NUM_THREADS="2")
    out = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                         env=env, timeout=120, check=True).stdout
    counts = json.loads(out)
    if max(counts["before"]) < 2:
        pytest.skip("BLAS runs one thread here: nothing to restore")
    assert counts["after"] == counts["before"]


_OVERLAPPING_REFINE = """
import json, threading, time
from threadpoolctl import threadpool_info
import meshcorr.stages.refine as refine
import meshcorr.spectral.basis as basis
from meshcorr import datasets as ds
from meshcorr.core.mesh import Mesh

real_eigsh, lock, barrier, entered = basis.eigsh, threading.Lock(), threading.Barrier(2), []

def overlapping_eigsh(*args, **kwargs):
    with lock:
        entered.append(threading.get_ident())
    barrier.wait(timeout=10)
    if entered.index(threading.get_ident()) == 1:
        time.sleep(0.1)
    return real_eigsh(*args, **kwargs)

def counts():
    return sorted(i["num_threads"] for i in threadpool_info() if i["user_api"] == "blas")

basis.eigsh = overlapping_eigsh
shape = ds.figure(resolution=1)
source, target = Mesh(shape.vertices, shape.faces), Mesh(shape.vertices, shape.faces)
before = counts()
refine.refine_map(source, target, list(range(source.n_vertices)), k=12)
print(json.dumps({"before": before, "after": counts()}))
"""


def test_refinement_restores_the_blas_thread_count():
    """Both eigenproblems run in threads under a process-wide BLAS limit: the count must come back.

    In a fresh interpreter (threadpoolctl lets only the first thread that
    limits OpenBLAS change it while that thread lives), with the eigensolver
    made to overlap in the two threads and the thread that entered second
    to leave last: limits set only inside each thread left BLAS at one
    thread for the rest of the process.
    """
    assert_blas_restored(_OVERLAPPING_REFINE)


def test_prefetched_bases_are_the_ones_computed_directly(poses):
    """The worker thread caches exactly what laplace_basis computes in the caller's thread."""
    fresh = [Mesh(m.vertices, m.faces) for m in poses]
    with prefetch_bases(*fresh, 12, random_state=3) as prefetch:
        pass  # leaving the block waits for the worker
    assert prefetch.seconds is not None and prefetch.seconds > 0
    for mesh, cached in zip(poses, fresh):
        direct = laplace_basis(Mesh(mesh.vertices, mesh.faces), 12, random_state=3)
        prefetched = cached.store[("laplace_basis", 12, 3)]
        np.testing.assert_array_equal(prefetched[0], direct[0])
        np.testing.assert_array_equal(prefetched[1], direct[1])


def test_prefetch_reraises_the_worker_error_and_cancels_the_worker_after_an_error(poses, monkeypatch):
    import meshcorr.spectral.basis as refine

    def failing(mesh, k, random_state, cancel):
        raise ParameterError("basis failed")

    with monkeypatch.context() as patch:
        patch.setattr(refine, "_laplace_basis", failing)
        with pytest.raises(ParameterError, match="basis failed"):
            with prefetch_bases(*poses, 12):
                pass

    # An error in the block cancels the worker at its next solve: no wait for the whole eigensolve
    # (~50 solves). The worker's third solve holds until the cancel is requested, then goes on.
    solves = []
    holder, ready, reached = [], threading.Event(), threading.Event()

    def counting_eigsh(*args, OPinv, **kwargs):
        def held_solve(x):
            solves.append(1)
            if len(solves) == 3:
                reached.set()
                assert ready.wait(60.0) and holder[0]._cancel.wait(60.0)  # deadlock guards
            return OPinv.matvec(x)

        return real_eigsh(*args, OPinv=LinearOperator(OPinv.shape, matvec=held_solve, dtype=float), **kwargs)

    real_eigsh = refine.eigsh
    monkeypatch.setattr(refine, "eigsh", counting_eigsh)
    fresh = [Mesh(m.vertices, m.faces) for m in poses]
    with pytest.raises(RuntimeError, match="stage failed"):
        with prefetch_bases(*fresh, 12) as prefetch:
            holder.append(prefetch)
            ready.set()
            assert reached.wait(60.0)
            raise RuntimeError("stage failed")
    assert prefetch._done.is_set()  # leaving the block waited for the worker
    assert len(solves) == 3  # the solve after the cancel request stopped it
    assert not any(key[0] == "laplace_basis" for mesh in fresh for key in mesh.store)


def test_match_reports_the_background_basis_time(poses):
    result = meshcorr.match(*poses, refine_k=12)
    assert result.background_timings["refine_bases"] > 0
    assert "refine_bases" not in result.timings  # the stages' sum stays the end-to-end time
    assert result.summary()["background_timings"] == {"refine_bases": round(result.background_timings["refine_bases"], 4)}
    assert meshcorr.match(*poses, refine=False).background_timings == {}


_MATCH_BLAS = """
import json
from threadpoolctl import threadpool_info
import meshcorr
from meshcorr import datasets as ds

def counts():
    return sorted(i["num_threads"] for i in threadpool_info() if i["user_api"] == "blas")

shape = ds.figure(resolution=1)
before = counts()
meshcorr.match((shape.vertices, shape.faces), (shape.vertices, shape.faces), refine_k=12)
print(json.dumps({"before": before, "after": counts()}))
"""


def test_match_restores_the_blas_thread_count():
    """match() limits BLAS to one thread while the bases compute in the background, then restores it."""
    assert_blas_restored(_MATCH_BLAS)


_INTERRUPTED_WAIT = """
import signal, time
from scipy.sparse.linalg import LinearOperator
import meshcorr.spectral.basis as refine
from meshcorr import datasets as ds
from meshcorr.core.mesh import Mesh

real_eigsh = refine.eigsh

def slow_eigsh(*args, OPinv, **kwargs):
    def solve(x):
        time.sleep(0.02)
        return OPinv.matvec(x)
    return real_eigsh(*args, OPinv=LinearOperator(OPinv.shape, matvec=solve, dtype=float), **kwargs)

def interrupt(*_):
    raise KeyboardInterrupt

refine.eigsh = slow_eigsh
shape = ds.figure(resolution=2)
meshes = [Mesh(shape.vertices, shape.faces) for _ in range(2)]
signal.signal(signal.SIGALRM, interrupt)
signal.setitimer(signal.ITIMER_REAL, 0.3)
try:
    with refine.prefetch_bases(*meshes, 12) as prefetch:
        prefetch.wait()
except KeyboardInterrupt:
    print("interrupted", prefetch._done.is_set())
"""


def test_ctrl_c_while_waiting_for_the_bases_cancels_the_worker_and_exits_cleanly():
    """Ctrl-C in the wait stops the worker before the interpreter exits (an interrupted
    Thread.join could mark it stopped while it ran, and the exit then crashed under it)."""
    out = subprocess.run([sys.executable, "-c", _INTERRUPTED_WAIT], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "interrupted True"
    assert out.stderr == ""


def test_single_precision_screen_gives_the_double_precision_answer(poses, monkeypatch):
    import meshcorr.spectral.nearest as refine_module
    from meshcorr.spectral.nearest import _nearest_rows_double, _single_precision_bound, nearest_rows as _nearest_rows

    screened = []
    original = refine_module._single_precision_bound
    monkeypatch.setattr(refine_module, "SCREEN_ABOVE", 1000)  # these small sets take the screened path
    monkeypatch.setattr(refine_module, "_single_precision_bound", lambda *a: screened.append(1) or original(*a))

    rest, bent = poses
    _, phi1 = laplace_basis(rest, 20)
    _, phi2 = laplace_basis(bent, 20)
    queries = phi1 + np.random.default_rng(0).normal(0.0, 0.05, phi1.shape)
    np.testing.assert_array_equal(_nearest_rows(queries, phi2), _nearest_rows_double(queries, phi2))
    assert screened
    # Near-ties the single precision cannot resolve: duplicated points and queries halfway between two
    # points, off by far less than float32's roundoff. Which copy of a duplicate double precision picks
    # depends on the BLAS kernel (OpenBLAS's AVX-512 kernels round some columns differently); the screen
    # must pick the same one.
    rng = np.random.default_rng(1)
    points = rng.normal(size=(1500, 30))
    points = np.vstack([points, points[:200]])
    halfway = 0.5 * (points[:700] + points[700:1400])
    queries = np.vstack([points[:500] + 1e-3, halfway + 1e-12 * rng.normal(size=halfway.shape)])
    expected = _nearest_rows_double(queries, points)
    assert np.array_equal(points[expected[:500]], points[:500])  # a copy of the point each query sits by
    np.testing.assert_array_equal(_nearest_rows(queries, points), expected)
    # The bound holds the float32 error with room: at most half of it on these points.
    augmented_q = np.hstack([queries, np.ones((len(queries), 1))])
    augmented_p = np.vstack([-2.0 * points.T, (points ** 2).sum(axis=1)[None, :]])
    error = np.abs(augmented_q.astype(np.float32) @ augmented_p.astype(np.float32) - augmented_q @ augmented_p)
    assert (error.max(axis=1) <= 0.5 * _single_precision_bound(augmented_q, augmented_p)).all()
    # Non-finite input: the double-precision search answers (NaN rows are never nearest).
    bad = queries[:50].copy()
    bad[0, 0] = np.nan
    np.testing.assert_array_equal(_nearest_rows(bad, points), _nearest_rows_double(bad, points))
