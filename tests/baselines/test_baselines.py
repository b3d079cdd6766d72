"""The paper's baselines (meshcorr.baselines): known answers on small synthetic pairs."""

import json

import numpy as np
import pytest
import trimesh

import meshcorr
from meshcorr import datasets as ds
from meshcorr.baselines import METHODS, SPATIAL_METHODS, method_options, run_method
from meshcorr.baselines.align import Similarity, align_pair, barycentric_areas, pca_alignment, prealign
from meshcorr.baselines.rigid_icp import initial_rotations, rigid_icp, umeyama
from meshcorr.baselines.sampling import farthest_point_sample
from meshcorr.baselines.shape_context import chi_square_cost, match_histograms
from meshcorr.baselines.tps_rpm import tps_rpm
from meshcorr.cli import main
from meshcorr.errors import ParameterError
from meshcorr.evaluation.metrics import geodesic_errors

# tps-rpm with a faster schedule where only invariances are checked
FAST_RPM = dict(anneal_rate=0.8, inner_iterations=2)


def _rotation(axis, degrees):
    axis = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    K = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    a = np.radians(degrees)
    return np.eye(3) + np.sin(a) * K + (1 - np.cos(a)) * K @ K


@pytest.fixture(scope="module")
def shape():
    return ds.tube(n_along=12, n_around=10)  # 136 vertices, asymmetric bumps


@pytest.fixture(scope="module")
def moved(shape):
    """A randomly rotated, translated, scaled (x2.5) and re-indexed copy, and its truth."""
    copy, truth = ds.rigid_copy(shape, scale=2.5, random_state=7)
    return copy, truth


@pytest.fixture(scope="module")
def bent(shape):
    """A mildly bent (0.35 rad), randomly moved, re-indexed copy and the true map onto it."""
    target = ds.tube(n_along=12, n_around=10, bend=0.35)
    copy, truth = ds.rigid_copy(target, scale=0.7, random_state=3)
    return copy, truth[ds.ground_truth(shape, target)]


def _vf(s):
    return (s.vertices, s.faces)


# ---------------------------------------------------------------- registry and API


def test_registry_names_and_spatial_methods():
    assert list(METHODS) == ["spectral", "shapiro-brady", "shapiro-brady-scaled", "tps-rpm", "icp",
                             "shape-context"]
    assert set(SPATIAL_METHODS) == {"tps-rpm", "icp", "shape-context"}
    assert "trim" in method_options("icp") and "prealign" not in method_options("icp")
    assert "k" in method_options("shapiro-brady") and "method" not in method_options("spectral")


def test_match_dispatches_to_the_baseline(shape, moved):
    copy, truth = moved
    result = meshcorr.match(_vf(shape), _vf(copy), method="icp")
    assert result.method == "icp"
    np.testing.assert_array_equal(result.map, truth)
    assert result.params["prealign"] is True and set(result.timings) >= {"load", "prealign", "icp", "matching"}
    assert result.summary()["method"] == "icp"


def test_match_rejects_options_the_baseline_does_not_use(shape):
    # issue 14: match(a, b, method="icp", k=9, symmetry="mirror") ran without a word.
    with pytest.raises(ParameterError, match="'icp' does not use the options 'k', 'reorder'.*trim"):
        meshcorr.match(_vf(shape), _vf(shape), method="icp", k=5, reorder="greedy")
    with pytest.raises(ParameterError, match="'spectral' does not use the option 'prealign'"):
        meshcorr.match(_vf(shape), _vf(shape), prealign=False)


def test_run_method_spectral_is_the_pipeline(shape, moved):
    copy, truth = moved
    result = run_method("spectral", _vf(shape), _vf(copy), reorder="greedy")
    assert result.method == "spectral"
    np.testing.assert_array_equal(result.map, truth)


def test_unknown_method_raises(shape):
    with pytest.raises(ParameterError, match="'method' parameter must be one of"):
        run_method("procrustes", _vf(shape), _vf(shape))
    with pytest.raises(ParameterError, match="'method' parameter must be one of"):
        meshcorr.match(_vf(shape), _vf(shape), method="procrustes")


def test_unknown_option_raises_and_names_the_valid_ones(shape):
    with pytest.raises(ParameterError, match="'icp' has no option 'k'.*trim"):
        run_method("icp", _vf(shape), _vf(shape), k=6)


# Each row: method, a bad option, the message it must give.
BAD_OPTIONS = [
    ("icp", dict(trim=0.0), "'trim' parameter must be a number > 0.0"),
    ("icp", dict(trim=1.5), "'trim' parameter must be a number <= 1.0"),
    ("icp", dict(huber=0.0), "'huber' parameter must be a number > 0.0"),
    ("icp", dict(n_rotations=0), "'n_rotations' parameter must be an int >= 1"),
    ("icp", dict(max_iter=-1), "'max_iter' parameter must be an int >= 0"),
    ("tps-rpm", dict(n_points=5), "'n_points' parameter must be an int >= 10"),
    ("tps-rpm", dict(lambda_init=0.0), "'lambda_init' parameter must be a number > 0.0"),
    ("tps-rpm", dict(affine_init=-1.0), "'affine_init' parameter must be a number >= 0.0"),
    ("tps-rpm", dict(anneal_rate=1.0), "'anneal_rate' parameter must be a number <= 0.999"),
    ("tps-rpm", dict(inner_iterations=0), "'inner_iterations' parameter must be an int >= 1"),
    ("shape-context", dict(n_points=2), "'n_points' parameter must be an int >= 10"),
    ("shape-context", dict(n_radial=0), "'n_radial' parameter must be an int >= 1"),
    ("shape-context", dict(n_azimuth=0), "'n_azimuth' parameter must be an int >= 1"),
    ("shape-context", dict(n_elevation=0), "'n_elevation' parameter must be an int >= 1"),
    ("shape-context", dict(r_inner=0.0), "'r_inner' parameter must be a number > 0.0"),
    ("shape-context", dict(r_inner=0.5, r_outer=0.5), "'r_outer' parameter must be a number > 0.5"),
    ("shape-context", dict(assignment="greedy"), "'assignment' parameter must be one of"),
    ("shapiro-brady", dict(k=1), "'k' parameter must be an int >= 2"),
    ("shapiro-brady-scaled", dict(geodesic="euclid"), "'geodesic' parameter must be one of"),
]


@pytest.mark.parametrize("method, options, message", BAD_OPTIONS)
def test_bad_options_raise(shape, method, options, message):
    with pytest.raises(ParameterError, match=message):
        run_method(method, _vf(shape), _vf(shape), **options)


@pytest.mark.parametrize("options, message", [
    (dict(t_init_factor=0.0), "'t_init_factor' parameter must be a number > 0.0"),
    (dict(t_final=0.0), "'t_final' parameter must be a number > 0.0"),
    (dict(sinkhorn_iterations=0), "'sinkhorn_iterations' parameter must be an int >= 1"),
])
def test_bad_tps_rpm_schedule_raises(options, message):
    points = np.random.default_rng(0).standard_normal((20, 3))
    with pytest.raises(ParameterError, match=message):
        tps_rpm(points, points, **options)


def test_bijective_needs_equal_counts(shape):
    other = ds.tube(n_along=14, n_around=10)
    with pytest.raises(ParameterError, match="same number of vertices"):
        run_method("icp", _vf(shape), _vf(other), bijective=True)


# ---------------------------------------------------------------- pre-alignment


def test_prealign_normalises_pose_and_scale(shape):
    w = barycentric_areas(shape.vertices, shape.faces)
    np.testing.assert_allclose(w.sum(), trimesh.Trimesh(shape.vertices, shape.faces, process=False).area,
                               rtol=1e-12)
    P = prealign(shape.vertices, w)
    wn = w / w.sum()
    np.testing.assert_allclose(wn @ P, 0.0, atol=1e-12)
    assert wn @ np.sum(P**2, axis=1) == pytest.approx(1.0, rel=1e-12)
    cov = (P * wn[:, None]).T @ P
    np.testing.assert_allclose(cov - np.diag(np.diag(cov)), 0.0, atol=1e-12)
    assert np.all(np.diff(np.diag(cov)) <= 0)
    assert np.linalg.det(pca_alignment(shape.vertices, w).rotation) == pytest.approx(1.0, abs=1e-12)


def test_prealign_is_invariant_to_similarity_and_order(shape, moved):
    copy, truth = moved
    P = prealign(shape.vertices, barycentric_areas(shape.vertices, shape.faces))
    Q = prealign(copy.vertices, barycentric_areas(copy.vertices, copy.faces))
    np.testing.assert_allclose(Q[truth], P, atol=1e-9)


def test_align_pair_fixes_a_wrong_axis_sign(shape):
    """Mirror-free half-turn of the target frame: align_pair undoes it by Chamfer distance."""
    P, Q = align_pair(shape.vertices, shape.vertices @ np.diag([-1.0, -1.0, 1.0]))
    np.testing.assert_allclose(Q, P, atol=1e-9)


def test_similarity_inverse_and_composition():
    S = Similarity(2.0, _rotation([1, 2, 3], 40), np.array([0.5, -1.0, 2.0]))
    T = Similarity(0.5, _rotation([0, 0, 1], -70), np.array([1.0, 0.0, 0.0]))
    X = np.random.default_rng(1).standard_normal((10, 3))
    np.testing.assert_allclose(S.inverse().apply(S.apply(X)), X, atol=1e-12)
    np.testing.assert_allclose(S.then(T).apply(X), T.apply(S.apply(X)), atol=1e-12)


def test_farthest_point_sample_spreads_and_is_seeded():
    line = np.linspace(0.0, 10.0, 101)[:, None]
    sample = farthest_point_sample(line, 4, random_state=4)
    start = sample[0]
    assert sample[1] == (0 if start > 50 else 100)  # the end farthest from the seeded start
    gaps = np.diff(np.sort(line[sample, 0]))
    assert len(set(sample.tolist())) == 4 and gaps.min() >= 10.0 / 4  # 2-approximation of even spread
    np.testing.assert_array_equal(sample, farthest_point_sample(line, 4, random_state=4))
    np.testing.assert_array_equal(farthest_point_sample(line, 500), np.arange(101))


# ---------------------------------------------------------------- rigid ICP


def test_umeyama_recovers_a_similarity():
    P = np.random.default_rng(2).standard_normal((30, 3))
    R, t = _rotation([1, -1, 2], 110), np.array([3.0, -2.0, 1.0])
    fit = umeyama(P, 1.7 * P @ R.T + t)
    assert fit.scale == pytest.approx(1.7, rel=1e-12)
    np.testing.assert_allclose(fit.rotation, R, atol=1e-12)
    np.testing.assert_allclose(fit.translation, t, atol=1e-12)
    assert umeyama(P, 1.7 * P @ R.T + t, with_scale=False).scale == 1.0


def test_rigid_icp_recovers_rotation_translation_scale_exactly(shape):
    """No pre-alignment: ICP from superposed centroids undoes a 25 degree turn, a shift and x1.5."""
    R, t, s = _rotation([0.3, 1.0, 0.2], 25), np.array([2.0, -1.0, 0.5]), 1.5
    order = np.random.default_rng(3).permutation(shape.n_vertices)
    Q = (s * shape.vertices @ R.T + t)[order]
    truth = np.argsort(order)
    for options in (dict(), dict(trim=1.0, huber=1.0)):
        icp = rigid_icp(shape.vertices, Q, **options)
        np.testing.assert_array_equal(icp.matches, truth)
        assert icp.transform.scale == pytest.approx(s, rel=1e-9)
        np.testing.assert_allclose(icp.transform.rotation, R, atol=1e-9)
        np.testing.assert_allclose(icp.transform.translation, t, atol=1e-9)
        assert icp.converged and icp.cost == pytest.approx(0.0, abs=1e-9)


def test_rigid_icp_tries_initial_rotations(shape):
    """Upside down (a half-turn): only the starts that include half-turns recover it."""
    Q = shape.vertices @ _rotation([1, 0, 0], 180).T
    assert len(initial_rotations(6, random_state=0)) == 6
    one = rigid_icp(shape.vertices, Q, n_rotations=1)
    four = rigid_icp(shape.vertices, Q, n_rotations=4)
    assert four.start == 1 and four.cost == pytest.approx(0.0, abs=1e-9) and one.cost > 0.01
    np.testing.assert_array_equal(four.matches, np.arange(shape.n_vertices))


def test_icp_method_maps_a_moved_copy_to_the_permutation(shape, moved):
    copy, truth = moved
    result = run_method("icp", _vf(shape), _vf(copy))
    np.testing.assert_array_equal(result.map, truth)
    np.testing.assert_allclose(result.cost, 0.0, atol=1e-9)
    assert result.icp_converged and result.icp_history[0]["cost"] == pytest.approx(0.0, abs=1e-9)


# ---------------------------------------------------------------- spectral baselines


def test_shapiro_brady_variants_map_a_reindexed_copy_to_the_permutation(shape, moved):
    copy, truth = moved
    plain = run_method("shapiro-brady", _vf(shape), _vf(copy))
    scaled = run_method("shapiro-brady-scaled", _vf(shape), _vf(copy))
    np.testing.assert_array_equal(scaled.map, truth)
    np.testing.assert_array_equal(plain.map, scaled.map)
    assert plain.method == "shapiro-brady" and scaled.method == "shapiro-brady-scaled"
    assert plain.params["reorder"] == "signs-greedy" and plain.configuration.perm == (0, 1, 2, 3, 4)
    assert plain.params["scale_eigenvalues"] is False and scaled.params["scale_eigenvalues"] is True
    # the two differ only by the eigenvalue scaling of the embedding
    np.testing.assert_allclose(plain.eigenvalues["source"], scaled.eigenvalues["source"], rtol=1e-10)
    root = np.sqrt(plain.eigenvalues["source"][1:])
    np.testing.assert_allclose(np.abs(plain.source_embedding * root), np.abs(scaled.source_embedding),
                               atol=1e-8)
    assert plain.anchors is None and plain.aligned_target_embedding is None


# ---------------------------------------------------------------- non-rigid spatial baselines


def test_tps_rpm_follows_a_mild_bend(shape, bent):
    copy, truth = bent
    result = run_method("tps-rpm", _vf(shape), _vf(copy))
    errors = geodesic_errors(_vf(copy), result.map, truth)
    assert np.mean(result.map == truth) >= 0.9
    assert errors.mean() <= 0.005 and errors.max() <= 0.1
    assert set(result.timings) >= {"prealign", "sample", "tps-rpm", "matching"}


def test_tps_rpm_subsamples_and_interpolates(shape, moved):
    copy, truth = moved
    result = run_method("tps-rpm", _vf(shape), _vf(copy), n_points=60, **FAST_RPM)
    errors = geodesic_errors(_vf(copy), result.map, truth)
    # 60 of 136 vertices on each side, different samples: about one edge length (0.095) of error
    assert errors.mean() <= 0.15 and np.mean(errors <= 0.2) >= 0.8


def test_shape_context_follows_a_mild_bend(shape, bent, moved):
    copy, truth = bent
    result = run_method("shape-context", _vf(shape), _vf(copy))
    errors = geodesic_errors(_vf(copy), result.map, truth)
    assert np.mean(result.map == truth) >= 0.9
    assert errors.mean() <= 0.01
    # The bend changes the descriptors a little (chi-square cost, measured mean 0.094); a
    # moved copy keeps them exactly: every cost is 0 and the map is the permutation.
    assert 0.02 < result.cost.mean() < 0.2
    copy, truth = moved
    rigid = run_method("shape-context", _vf(shape), _vf(copy))
    np.testing.assert_array_equal(rigid.map, truth)
    np.testing.assert_allclose(rigid.cost, 0.0, atol=1e-12)


def test_shape_context_subsamples_and_interpolates(shape, moved):
    copy, truth = moved
    result = run_method("shape-context", _vf(shape), _vf(copy), n_points=60, assignment="argmin")
    errors = geodesic_errors(_vf(copy), result.map, truth)
    # 60 of 136 vertices on each side: under one edge length (0.095) of error on average
    assert errors.mean() <= 0.1 and np.mean(errors <= 0.2) >= 0.8


def test_chi_square_cost_known_values():
    H = np.array([[0.5, 0.5, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0]])
    C = chi_square_cost(H, H)
    np.testing.assert_allclose(C, [[0.0, 1.0], [1.0, 0.0]], atol=1e-15)
    G = np.array([[0.25, 0.75, 0.0, 0.0]])
    expected = 0.5 * (0.25**2 / 0.75 + 0.25**2 / 1.25)
    assert chi_square_cost(H[:1], G)[0, 0] == pytest.approx(expected, rel=1e-12)
    # rows left over by the assignment take their cheapest column
    np.testing.assert_array_equal(match_histograms(np.array([[0.0, 1.0], [0.1, 2.0], [5.0, 0.3]])), [0, 0, 1])


# ---------------------------------------------------------------- invariance and bookkeeping


@pytest.mark.parametrize("method, options", [("icp", {}), ("tps-rpm", FAST_RPM), ("shape-context", {})])
def test_prealignment_makes_spatial_methods_rotation_invariant(shape, bent, method, options):
    copy, _ = bent
    turned = (copy.vertices @ _rotation([2, -1, 1], 137).T * 3.0 + 5.0, copy.faces)
    first = run_method(method, _vf(shape), _vf(copy), **options)
    second = run_method(method, _vf(shape), turned, **options)
    np.testing.assert_array_equal(first.map, second.map)


def test_without_prealignment_a_turn_breaks_icp(shape):
    turned = (shape.vertices @ _rotation([1, 0, 0], 180).T, shape.faces)
    result = run_method("icp", _vf(shape), turned, prealign=False)
    assert np.mean(result.map == np.arange(shape.n_vertices)) < 0.5
    assert result.params["prealign"] is False and "prealign" not in result.timings


def test_largest_component_leaves_dropped_vertices_unmapped(shape):
    far = shape.vertices[:20].mean(axis=0) + 100.0
    extra = trimesh.creation.icosahedron()
    V = np.vstack([shape.vertices, extra.vertices + far])
    F = np.vstack([shape.faces, extra.faces + shape.n_vertices])
    result = run_method("icp", (V, F), _vf(shape), largest_component=True)
    np.testing.assert_array_equal(result.map[:shape.n_vertices], np.arange(shape.n_vertices))
    assert np.all(result.map[shape.n_vertices:] == -1) and np.all(np.isnan(result.cost[shape.n_vertices:]))


# ---------------------------------------------------------------- command line


def test_cli_method_icp_end_to_end(shape, moved, tmp_path, capsys):
    copy, truth = moved
    src, tgt, out = tmp_path / "a.off", tmp_path / "b.ply", tmp_path / "map.txt"
    trimesh.Trimesh(shape.vertices, shape.faces, process=False).export(src)
    trimesh.Trimesh(copy.vertices, copy.faces, process=False).export(tgt)
    assert main(["match", str(src), str(tgt), "-o", str(out), "--method", "icp", "--json", "-q"]) == 0
    np.testing.assert_array_equal(np.loadtxt(out, dtype=np.int64), truth)
    summary = json.loads(capsys.readouterr().out)
    assert summary["method"] == "icp" and summary["params"]["prealign"] is True
    assert main(["match", str(src), str(tgt), "-o", str(out), "--method", "icp", "--no-prealign", "-q",
                 "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["params"]["prealign"] is False


def test_cli_rejects_an_unknown_method(tmp_path, capsys):
    with pytest.raises(SystemExit) as exc:
        main(["match", "a.off", "b.off", "-o", str(tmp_path / "m.txt"), "--method", "nope"])
    assert exc.value.code == 2 and "invalid choice: 'nope'" in capsys.readouterr().err


def test_cli_help_lists_the_methods(capsys):
    with pytest.raises(SystemExit):
        main(["match", "--help"])
    text = capsys.readouterr().out
    for word in ("--method", "--no-prealign", "shape-context", "tps-rpm", "Rangarajan", "is\nrefused (exit 2)"):
        assert word in text


def test_cli_refuses_an_option_the_method_does_not_use(shape, tmp_path, capsys):
    src = tmp_path / "a.off"
    trimesh.Trimesh(shape.vertices, shape.faces, process=False).export(src)
    code = main(["match", str(src), str(src), "-o", str(tmp_path / "m.txt"), "--method", "icp", "-k", "9", "-q"])
    assert code == 2 and "'icp' does not use the option 'k'" in capsys.readouterr().err
    assert not (tmp_path / "m.txt").exists()
