"""The scalable mode: landmarks, Nyström spectrum, memory guard, mode selection, large-n matching."""

import numpy as np
import pytest
from scipy.linalg import orthogonal_procrustes
from scipy.spatial import cKDTree

import meshcorr
from meshcorr.stages import anchors as anchors_module
from meshcorr import datasets as ds
from meshcorr.stages.anchors import proximity_matching, select_anchors
from meshcorr.cli import main
from meshcorr.spectral.embedding import gaussian_affinity, spectral_embedding
from meshcorr.errors import MemoryLimitError, ParameterError
from meshcorr.core.geodesics import geodesic_solver
from meshcorr.stages.icp import tps_icp
from meshcorr.core.sampling import farthest_point_sampling
from meshcorr.runtime.memory import dense_memory, parse_memory
from meshcorr.core.mesh import Mesh
from meshcorr.spectral.modes import select_mode
from meshcorr.spectral.nystrom import landmark_spectrum, nystrom_eigenpairs
from meshcorr.stages.reorder import _configured_queries, _to_target_frame
from meshcorr.spectral.spectrum import dense_spectrum
from meshcorr.runtime.timing import StageTimer


@pytest.fixture(scope="module")
def sphere():
    V, F = ds.sphere(subdivisions=2)  # 162 vertices on the unit sphere
    return Mesh(V, F, name="sphere")


@pytest.fixture(scope="module")
def creature():
    return Mesh(*_arrays(ds.creature(resolution=2)), name="creature")  # 1000 vertices


def _arrays(shape):
    return shape.vertices, shape.faces


def _sphere_rows(mesh):
    """Exact great-circle distances on the unit sphere."""
    V = mesh.vertices / np.linalg.norm(mesh.vertices, axis=1, keepdims=True)
    return lambda i: np.arccos(np.clip(V @ V[i], -1.0, 1.0))


# --- farthest-point sampling -------------------------------------------------

def test_farthest_point_sampling_spreads_points_and_is_deterministic(sphere):
    rows = _sphere_rows(sphere)
    lm = farthest_point_sampling(rows, sphere.n_vertices, 40, random_state=3)
    assert len(set(lm.indices.tolist())) == 40
    assert np.all(np.diff(lm.radii) <= 1e-12)  # covering radius never grows
    # Every vertex is within the covering radius of a landmark.
    np.testing.assert_allclose(lm.distances.min(axis=0).max(), lm.radii[-1], rtol=1e-12)
    # The second landmark is the antipode of the first: the diameter is pi.
    assert lm.diameter == pytest.approx(np.pi, rel=0.02)
    # 40 well-spread points cover the sphere far better than the diameter.
    assert lm.radii[-1] < 0.25 * np.pi
    again = farthest_point_sampling(rows, sphere.n_vertices, 40, random_state=3)
    np.testing.assert_array_equal(lm.indices, again.indices)
    other = farthest_point_sampling(rows, sphere.n_vertices, 40, random_state=4)
    assert other.indices[0] != lm.indices[0]


def test_farthest_point_sampling_rejects_bad_counts(sphere):
    rows = _sphere_rows(sphere)
    with pytest.raises(ParameterError, match="'n_landmarks' parameter must be an int <= 162"):
        farthest_point_sampling(rows, sphere.n_vertices, 163)
    with pytest.raises(ParameterError, match="'n_landmarks' parameter must be an int >= 1"):
        farthest_point_sampling(rows, sphere.n_vertices, 0)
    with pytest.raises(ParameterError, match="'start' parameter must be an int <= 161"):
        farthest_point_sampling(rows, sphere.n_vertices, 5, start=162)


# --- Nyström ----------------------------------------------------------------

def test_nystrom_with_every_vertex_as_landmark_is_exact(sphere):
    rows = _sphere_rows(sphere)
    n = sphere.n_vertices
    D = np.stack([rows(i) for i in range(n)])
    A = gaussian_affinity(D, np.pi)
    exact = np.linalg.eigvalsh(A)[::-1][:6]
    values, vectors = nystrom_eigenpairs(np.arange(n), D, np.pi, 6, rcond=1e-10)
    np.testing.assert_allclose(values, exact, rtol=1e-8)
    np.testing.assert_allclose(vectors.T @ vectors, np.eye(6), atol=1e-8)
    # Eigenvectors: A v = lambda v.
    np.testing.assert_allclose(A @ vectors[:, 0], values[0] * vectors[:, 0], atol=1e-6 * values[0])


def test_nystrom_errors():
    D = np.zeros((3, 10))
    with pytest.raises(ParameterError, match="sigma must be a positive number"):
        nystrom_eigenpairs(np.arange(3), D, 0.0, 2)
    with pytest.raises(ParameterError, match="'k' parameter must be an int <= 3"):
        nystrom_eigenpairs(np.arange(3), D, 1.0, 4)
    # Three identical landmarks: rank 1.
    with pytest.raises(ParameterError, match="numerical rank 1 < k=2.*more samples"):
        nystrom_eigenpairs(np.array([0, 0, 0]), D, 1.0, 2)


def test_scalable_embedding_agrees_with_the_dense_one(creature):
    dense = dense_spectrum(creature, k=6, geodesic="heat", scale=True, random_state=0, timer=StageTimer())
    approx = landmark_spectrum(creature, k=6, geodesic="heat", scale=True, n_samples=64,
                               random_state=0, timer=StageTimer())
    # sigma from the landmark rows (the dense one comes from the symmetrised matrix).
    assert approx.max_geodesic == pytest.approx(dense.max_geodesic, rel=0.01)
    np.testing.assert_allclose(approx.eigenvalues, dense.eigenvalues, rtol=0.03)
    # Up to sign and rotation within near-degenerate eigenspaces: Procrustes.
    R, _ = orthogonal_procrustes(approx.embedding, dense.embedding)
    residual = np.linalg.norm(approx.embedding @ R - dense.embedding) / np.linalg.norm(dense.embedding)
    assert residual < 0.03
    # The creature's eigenvalues are well apart, so R is close to a signed identity.
    np.testing.assert_allclose(np.abs(R), np.eye(5), atol=0.05)
    # geodesics_from: a single-source solve, normalised, zero at the source.
    row = approx.geodesics_from(17)
    assert row[17] == 0.0 and 0.3 < row.max() <= 1.01
    np.testing.assert_allclose(row, dense.geodesics_from(17), atol=0.03)


# --- the pipeline in both modes ----------------------------------------------

@pytest.fixture(scope="module")
def small_pair():
    shape = ds.creature(resolution=1)  # 500 vertices
    return _arrays(shape), _arrays(shape)


@pytest.fixture(scope="module")
def pose_pair():
    rest, bent = ds.creature(resolution=2), ds.creature(resolution=2, pose="bent")
    return _arrays(rest), _arrays(bent), rest


def test_scalable_and_dense_maps_agree_on_a_pose_pair(pose_pair):
    source, target, rest = pose_pair
    options = dict(refine=False, random_state=0)
    dense = meshcorr.match(source, target, mode="dense", **options)
    scalable = meshcorr.match(source, target, mode="scalable", n_samples=48, **options)
    assert dense.params["mode"] == "dense" and scalable.params["mode"] == "scalable"
    # Same vertices and faces in both poses: the truth is the identity.
    truth = np.arange(rest.n_vertices)
    mesh = Mesh(*target)
    solver = geodesic_solver(mesh.vertices, mesh.faces, "heat")
    scale = np.sqrt(mesh.area)
    rows = solver.distances(truth)
    dense_error = rows[truth, dense.map].mean() / scale
    scalable_error = rows[truth, scalable.map].mean() / scale
    between = rows[dense.map, scalable.map].mean() / scale
    assert dense_error < 0.02
    assert scalable_error < 0.02
    assert between < 0.02
    assert np.mean(dense.map == scalable.map) > 0.5


FAST = dict(icp_iterations=0, n_anchors=0, refine=False, reorder="none")


def test_auto_mode_switches_to_scalable_above_the_threshold(small_pair):
    source, target = small_pair
    small = meshcorr.match(source, target, **FAST)
    assert small.params["mode"] == "dense"
    large = meshcorr.match(source, target, scalable_above=499, **FAST)
    assert large.params["mode"] == "scalable"


def test_memory_guard_refuses_the_dense_mode_and_names_the_scalable_one(small_pair):
    source, target = small_pair
    with pytest.raises(MemoryLimitError, match=r"500 x 500.*--mode scalable"):
        meshcorr.match(source, target, mode="dense", max_memory="1MiB")
    # "auto" falls back to the scalable mode instead of failing.
    res = meshcorr.match(source, target, max_memory="1MiB", **FAST)
    assert res.params["mode"] == "scalable"


def test_select_mode_and_the_memory_estimate():
    assert dense_memory(1000, 1000) == 8 * 4 * 10 ** 6
    assert dense_memory(100, 100, bijective=True) == dense_memory(100, 100)
    assert dense_memory(10, 1000, bijective=True) == 8 * (100 + 3 * 10 ** 6)
    assert select_mode("auto", 10, 20, max_memory=None, scalable_above=15) == "scalable"
    assert select_mode("auto", 10, 15, max_memory=None, scalable_above=15) == "dense"
    assert select_mode("scalable", 10, 15, max_memory=1, scalable_above=15) == "scalable"
    with pytest.raises(MemoryLimitError, match=r"bijective option.*5000 x 5000"):
        select_mode("scalable", 5000, 5000, max_memory=10 ** 6, scalable_above=15, bijective=True)


@pytest.mark.parametrize("text, expected", [
    ("4GiB", 4 * 1024 ** 3), ("500MB", 500 * 1000 ** 2), ("2G", 2 * 1024 ** 3), ("1.5 KiB", 1536),
    ("123", 123), (2048, 2048), (1e9, 10 ** 9),
])
def test_parse_memory(text, expected):
    assert parse_memory(text) == expected


@pytest.mark.parametrize("kwargs, message", [
    ({"mode": "fast"}, "'mode' parameter must be one of 'auto', 'dense', 'scalable'"),
    ({"n_samples": 6}, "'n_samples' parameter must be an int >= 7"),
    ({"n_samples": 10.5}, "'n_samples' parameter must be an int"),
    ({"max_memory": "lots"}, "'max_memory' parameter must be a positive number of bytes"),
    ({"max_memory": "4XB"}, "'max_memory' parameter must be"),
    ({"max_memory": -1}, "'max_memory' parameter must be"),
    ({"max_memory": True}, "'max_memory' parameter must be"),
    ({"scalable_above": -1, "mode": "auto"}, "'scalable_above' parameter must be an int >= 0"),
])
def test_bad_scalable_options_are_rejected(small_pair, kwargs, message):
    source, target = small_pair
    with pytest.raises(ParameterError, match=message):
        meshcorr.match(source, target, **kwargs)


# --- large-n matching stages on small inputs ---------------------------------

def _cloud(seed, n1=400, n2=300, h=3):
    rng = np.random.default_rng(seed)
    X, Y = rng.normal(size=(n1, 5)), rng.normal(size=(n2, 5))
    return X, Y, rng.uniform(size=(n1, h)), rng.uniform(size=(n2, h))


def test_candidate_matching_without_anchors_is_the_exact_argmin(monkeypatch):
    X, Y, F1, F2 = _cloud(1, h=0)
    exact_map, exact_cost = proximity_matching(X, Y, F1, F2)
    monkeypatch.setattr(anchors_module, "EXACT_PAIRS", 0)
    fast_map, fast_cost = proximity_matching(X, Y, F1, F2)
    np.testing.assert_array_equal(fast_map, exact_map)
    np.testing.assert_allclose(fast_cost, exact_cost, rtol=1e-12)


def test_candidate_matching_with_anchors_is_close_to_the_dense_argmin(monkeypatch):
    X, Y, F1, F2 = _cloud(1, h=3)
    exact_map, exact_cost = proximity_matching(X, Y, F1, F2)
    monkeypatch.setattr(anchors_module, "EXACT_PAIRS", 0)
    fast_map, fast_cost = proximity_matching(X, Y, F1, F2)
    np.testing.assert_allclose(fast_cost, np.linalg.norm(X - Y[fast_map], axis=1)
                               + np.abs(F1 - F2[fast_map]).sum(axis=1), rtol=1e-12)
    assert np.all(fast_cost >= exact_cost - 1e-12)
    # Measured on these random clouds: 98 % identical rows, costs 0.09 % higher on average.
    assert np.mean(fast_map == exact_map) > 0.95
    assert np.mean(fast_cost / exact_cost) < 1.01


def test_candidate_anchors_start_with_the_exact_closest_pair(monkeypatch):
    X, Y, _, _ = _cloud(2)
    gx = lambda i: np.linalg.norm(X - X[i], axis=1) / 10  # noqa: E731
    gy = lambda j: np.linalg.norm(Y - Y[j], axis=1) / 10  # noqa: E731
    exact = select_anchors(X, Y, gx, gy, 3)
    monkeypatch.setattr(anchors_module, "EXACT_PAIRS", 0)
    approx = select_anchors(X, Y, gx, gy, 3)
    np.testing.assert_array_equal(approx[0], exact[0])
    assert len(set(approx[:, 0].tolist())) == 3 and len(set(approx[:, 1].tolist())) == 3


def test_configured_queries_equal_one_configuration_at_a_time():
    X = np.random.default_rng(3).normal(size=(7, 4))
    configs = [((2, 0, 3, 1), (1, -1, -1, 1)), ((0, 1, 2, 3), (-1, 1, 1, -1))]
    expected = np.concatenate([_to_target_frame(X, p, s) for p, s in configs])
    np.testing.assert_array_equal(_configured_queries(X, configs), expected)


def test_icp_on_subsets_warps_every_point():
    g = np.linspace(-2.0, 2.0, 30)
    xx, yy = np.meshgrid(g, g)
    X = np.c_[xx.ravel(), yy.ravel(), 0.3 * np.sin(xx.ravel())]  # a curved sheet, 900 points
    Y = X @ np.diag([1.1, 0.9, 1.0]) + 0.05
    full = tps_icp(X, Y, n_control=100, max_points=1000, random_state=0)
    subset = tps_icp(X, Y, n_control=100, max_points=300, random_state=0)
    assert subset.warped.shape == Y.shape and subset.matches.shape == (900,)
    np.testing.assert_allclose(subset.warped, subset.spline(Y))
    # The warp found on 300-point subsets aligns the whole clouds about as well
    # (measured: mean nearest-neighbour residual 0.044 on all points, 0.057 on subsets).
    d_start = cKDTree(Y).query(X)[0].mean()
    d_full = np.linalg.norm(X - full.warped[full.matches], axis=1).mean()
    d_subset = np.linalg.norm(X - subset.warped[subset.matches], axis=1).mean()
    assert d_subset < 1.5 * d_full and d_subset < 0.75 * d_start
    with pytest.raises(ParameterError, match="'max_points' parameter must be an int >= 1"):
        tps_icp(X, Y, n_control=100, max_points=0)


# --- CLI ----------------------------------------------------------------------

def test_cli_scalable_mode_and_memory_guard(tmp_path, capsys):
    shape = ds.creature(resolution=1)
    src, out = tmp_path / "a.off", tmp_path / "map.txt"
    import trimesh

    trimesh.Trimesh(shape.vertices, shape.faces, process=False).export(src)
    code = main(["match", str(src), str(src), "-o", str(out), "--mode", "scalable", "--samples", "32",
                 "--no-refine", "-q"])
    assert code == 0
    assert np.mean(np.loadtxt(out, dtype=int) == np.arange(shape.n_vertices)) > 0.95
    code = main(["match", str(src), str(src), "-o", str(out), "--mode", "dense", "--max-memory", "1KB", "-q"])
    err = capsys.readouterr().err
    assert code == 2
    assert err.startswith("meshcorr: error: The dense mode needs about") and "--mode scalable" in err
    assert len(err.strip().splitlines()) == 1
