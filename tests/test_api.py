"""The staged API (Matcher, Settings) and the result object (issue 14, items 1-2 and 7)."""

import dataclasses
import inspect
import json
import subprocess
import sys

import numpy as np
import pytest

import meshcorr
from meshcorr.pipeline.settings import REFINE_K
from meshcorr import Correspondence, Matcher, Settings
from meshcorr import datasets as ds
from meshcorr.errors import InputError, ParameterError
from meshcorr.progress import TqdmProgress, as_progress


@pytest.fixture(scope="module")
def shape():
    return ds.tube(n_along=26, n_around=12)


@pytest.fixture(scope="module")
def copy_and_truth(shape):
    return ds.rigid_copy(shape, scale=2.0, random_state=3)


@pytest.fixture(scope="module")
def result(shape, copy_and_truth):
    return Matcher(refine=False).fit(shape, copy_and_truth[0])


# ---------------------------------------------------------------- settings


def test_match_takes_settings_or_keywords_and_settings_hold_every_default():
    parameters = inspect.signature(meshcorr.match).parameters
    assert list(parameters)[:3] == ["source", "target", "settings"] and "k" not in parameters
    assert Settings().k == 6 and Settings().refine_k == REFINE_K
    with pytest.raises(ParameterError, match="Unknown setting 'n_landmarks'.*now 'n_samples'"):
        meshcorr.match(None, None, n_landmarks=40)
    with pytest.raises(ParameterError, match="'k' parameter must be an int <= 10"):
        meshcorr.match(None, None, Settings(), k=12)


def test_options_the_method_does_not_use_raise_naming_them():
    with pytest.raises(ParameterError, match="'icp' does not use the options 'k', 'n_anchors', 'symmetry'"):
        Settings(method="icp", k=9, symmetry="mirror", n_anchors=7)
    with pytest.raises(ParameterError, match="'spectral' does not use the option 'prealign'"):
        Matcher(prealign=False).get_params()
    assert Settings(method="icp", prealign=False, bijective=True).changed() == {
        "method": "icp", "prealign": False, "bijective": True}


def test_unknown_setting_and_bad_method_and_landmarks_raise():
    with pytest.raises(ParameterError, match="Unknown setting 'n_landmarks'.*now 'n_samples'"):
        Settings.from_options(n_landmarks=40)
    with pytest.raises(ParameterError, match="'method' parameter must be one of"):
        Settings(method="procrustes")
    with pytest.raises(ParameterError, match="'landmarks' parameter must be"):
        Settings(landmarks=[1, 2, 3])


def test_settings_values_are_checked_when_fit_runs(shape):
    with pytest.raises(ParameterError, match="'k' parameter must be an int <= 10"):
        Matcher(k=12).fit(shape, shape)


def test_matcher_get_set_params_and_repr():
    matcher = Matcher(k=5)
    assert matcher.get_params()["k"] == 5 and matcher.get_params()["method"] == "spectral"
    matcher.set_params(refine=False)
    assert repr(matcher) == "Matcher(k=5, refine=False)"
    assert Matcher(Settings(k=4), k=3).get_params()["k"] == 3


def test_a_matcher_with_bad_settings_still_prints_and_fit_names_the_problem():
    matcher = Matcher(n_landmarks=50)  # stored as given, validated by fit (scikit-learn's convention)
    assert repr(matcher) == "Matcher(n_landmarks=50)"
    with pytest.raises(ParameterError, match="'n_landmarks' is now 'n_samples'"):
        matcher.fit(ds.sphere(subdivisions=1), ds.sphere(subdivisions=1))


def test_matcher_gives_match_s_map(result, shape, copy_and_truth):
    copy, truth = copy_and_truth
    np.testing.assert_array_equal(result.map, truth)
    direct = meshcorr.match(shape, copy, refine=False)
    np.testing.assert_array_equal(direct.map, result.map)


def test_progress_true_draws_a_bar_and_bad_progress_raises(shape, copy_and_truth, capsys):
    bar = TqdmProgress(file=sys.stderr)
    meshcorr.match(shape, copy_and_truth[0], refine=False, icp_iterations=0, progress=bar)
    bar.close()
    assert {"load", "geodesics", "reorder"} <= set(bar.stages)
    assert "meshcorr: " in capsys.readouterr().err
    with pytest.raises(ParameterError, match="'progress' parameter must be True"):
        as_progress("yes")


# ---------------------------------------------------------------- the result


def test_repr_is_compact_and_html_is_a_table(result, shape):
    text = repr(result)
    assert len(text) < 300 and text.startswith("Correspondence(method='spectral'")
    assert f"n_source={shape.n_vertices}" in text and "version=" in text
    page = result._repr_html_()
    assert page.startswith("<table>") and "target vertices reached" in page and len(page) < 3000


def test_version_is_recorded_and_cost_is_none_after_refinement(result, shape, copy_and_truth):
    assert result.params["meshcorr_version"] == meshcorr.__version__ == result.summary()["meshcorr_version"]
    spectral = meshcorr.match(shape, copy_and_truth[0], refine=False, extremities=False)
    assert np.isfinite(spectral.cost).all()  # the proximity matching's cost, when its map is the result
    refined = meshcorr.match(shape, copy_and_truth[0], icp_iterations=0)
    assert refined.cost is None and refined.summary()["mean_cost"] is None


def test_save_and_load_round_trip(result, tmp_path):
    path = tmp_path / "result.npz"
    result.save(path)
    loaded = Correspondence.load(path)
    np.testing.assert_array_equal(loaded.map, result.map)
    np.testing.assert_allclose(loaded.source_embedding, result.source_embedding)
    assert loaded.configuration == result.configuration and loaded.alternatives == result.alternatives
    np.testing.assert_array_equal(loaded.target.faces, result.target.faces)
    assert json.dumps(loaded.summary()) == json.dumps(result.summary())


def test_load_rejects_other_files(tmp_path):
    with pytest.raises(ParameterError, match="no such file"):
        Correspondence.load(tmp_path / "none.npz")
    np.savez(tmp_path / "other.npz", x=np.zeros(3))
    with pytest.raises(ParameterError, match="not a saved meshcorr result"):
        Correspondence.load(tmp_path / "other.npz")
    (tmp_path / "text.npz").write_text("hello")
    with pytest.raises(ParameterError, match="not a saved meshcorr result"):
        Correspondence.load(tmp_path / "text.npz")
    # A map with metadata that is not a result's (was a raw KeyError / JSONDecodeError).
    for text in ('{"x": 1}', "{damaged"):
        np.savez(tmp_path / "bad.npz", map=np.arange(3), json=np.frombuffer(text.encode(), dtype=np.uint8))
        with pytest.raises(InputError, match="not a saved meshcorr result .damaged or from another program"):
            Correspondence.load(tmp_path / "bad.npz")


def test_evaluate_transfer_inverse_compose(result, copy_and_truth, shape):
    _, truth = copy_and_truth
    report = result.evaluate(truth)
    assert report["mean_error"] == pytest.approx(0.0, abs=1e-12)
    assert report["coverage"] == pytest.approx(1.0) and report["bijectivity"] == pytest.approx(1.0)
    values = np.arange(shape.n_vertices) * 2.0
    np.testing.assert_array_equal(result.transfer(values), values[truth])
    inverse = result.inverse()
    np.testing.assert_array_equal(inverse.map, np.argsort(truth))
    np.testing.assert_array_equal(result.compose(inverse).map, np.arange(shape.n_vertices))
    with pytest.raises(ParameterError, match="one value per target vertex"):
        result.transfer(values[:-1])
    with pytest.raises(ParameterError, match="Cannot compose"):
        result.compose(Correspondence(map=np.zeros(3, dtype=np.int64)))


def test_methods_needing_meshes_say_how_to_get_them():
    bare = Correspondence(map=np.arange(4))
    for call in (bare.inverse, bare.show, bare.precise_map, lambda: bare.evaluate(np.arange(4))):
        with pytest.raises(ParameterError, match="needs the meshes"):
            call()
    square = meshcorr.as_mesh(([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0.0]], [[0, 1, 2], [0, 2, 3]]))
    bare.attach_meshes(square, square)
    np.testing.assert_array_equal(bare.inverse().map, np.arange(4))


def test_baseline_results_keep_their_meshes_too(shape, copy_and_truth):
    icp = meshcorr.match(shape, copy_and_truth[0], method="icp")
    assert icp.target is not None and icp.evaluate(copy_and_truth[1])["mean_error"] < 1e-9


# ---------------------------------------------------------------- the house


def test_pipeline_and_baselines_no_longer_import_each_other():
    code = ("import sys, meshcorr.pipeline.run; "
            "assert 'meshcorr.baselines' not in sys.modules, 'pipeline imported the baselines'")
    subprocess.run([sys.executable, "-c", code], check=True)
    import meshcorr.baselines as baselines
    from meshcorr.pipeline import methods as methods

    assert baselines.run_method is methods.run_method and baselines.METHODS == methods.METHOD_NAMES


def test_import_meshcorr_exposes_the_submodules():
    for name in ("evaluation", "transfer", "viz", "fmap", "precise", "datasets", "progress"):
        assert hasattr(meshcorr, name), name
    assert callable(meshcorr.viz.show) and callable(meshcorr.progress.StderrProgress)


def test_landmarks_pass_through_the_settings(shape, copy_and_truth):
    pairs = [(0, int(copy_and_truth[1][0]))]
    assert Settings(landmarks=pairs).as_dict()["landmarks"] == [list(pairs[0])]
    result = Matcher(landmarks=pairs, refine=False).fit(shape, copy_and_truth[0])
    assert result.map[0] == copy_and_truth[1][0]


def test_progress_true_without_tqdm_says_how_to_install_it(monkeypatch):
    monkeypatch.setitem(sys.modules, "tqdm.auto", None)  # import fails
    with pytest.raises(ParameterError, match=r"pip install meshcorr\[notebook\]"):
        as_progress(True)


def test_largest_component_results_keep_the_input_numbering():
    shape = ds.figure()
    copy, truth = ds.rigid_copy(shape, random_state=1)
    tet_v = np.array([[10, 10, 10], [11, 10, 10], [10, 11, 10], [10, 10, 11.0]])
    tet_f = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])

    def with_tetrahedron(s):
        return np.vstack([s.vertices, tet_v]), np.vstack([s.faces, tet_f + s.n_vertices])

    n = shape.n_vertices
    result = Matcher(largest_component=True, refine=False).fit(with_tetrahedron(shape), with_tetrahedron(copy))
    np.testing.assert_array_equal(result.map, np.r_[truth, [-1] * 4])
    precise = result.precise_map()
    np.testing.assert_array_equal(precise.vertex_map(), np.r_[truth, [-1] * 4])
    np.testing.assert_array_equal(result.inverse().map, np.r_[np.argsort(truth), [-1] * 4])
    with pytest.raises(ParameterError, match="needs the whole target mesh"):
        result.evaluate(np.r_[truth, [0] * 4])
    assert len(result.show().data[0].x) == n


def test_inverse_of_an_empty_map_raises(shape):
    empty = Correspondence(map=np.full(shape.n_vertices, -1), source=meshcorr.as_mesh(shape),
                           target=meshcorr.as_mesh(shape))
    with pytest.raises(ParameterError, match="no inverse"):
        empty.inverse()


def test_settings_replace_validates_again():
    assert Settings(k=5).replace(refine=False).changed() == {"k": 5, "refine": False}
    with pytest.raises(ParameterError, match="'icp' does not use the option 'k'"):
        Settings(k=5).replace(method="icp")


def test_precise_transfer_of_colours_keeps_their_type(result, copy_and_truth):
    _, truth = copy_and_truth
    colours = np.random.default_rng(0).integers(0, 256, size=(len(truth), 3)).astype(np.uint8)
    carried = result.transfer(colours, precise=True)
    assert carried.dtype == np.uint8
    np.testing.assert_array_equal(carried, colours[truth])  # exact map: weights one-hot


def test_matcher_takes_prepared_shapes(shape, copy_and_truth, result):
    prepared = [meshcorr.prepare(s, refine=False) for s in (shape, copy_and_truth[0])]
    again = Matcher(refine=False).fit(*prepared)
    np.testing.assert_array_equal(again.map, result.map)
    assert again.target is not None and again.evaluate(copy_and_truth[1])["mean_error"] < 1e-9


@pytest.mark.parametrize("options, message", [
    ({"random_state": -1}, "'random_state' parameter must be an int >= 0. Got -1"),
    ({"random_state": 1.5, "method": "icp"}, "'random_state' parameter must be an int. Got 1.5"),
    ({"anchor_weight": float("inf")}, r"'anchor_weight' parameter \(--alpha\) must be a finite real number"),
    ({"shells": "no"}, "'shells' parameter must be True or False. Got 'no'"),
    ({"bijective": "yes"}, "'bijective' parameter must be True or False"),
    ({"extremities": None}, "'extremities' parameter must be True or False"),
])
def test_bad_options_are_refused_by_name(shape, options, message):
    # Each used to run: a raw numpy error for the negative seed, a collapsed map for an infinite
    # weight, any truthy value for a switch.
    with pytest.raises(ParameterError, match=message):
        meshcorr.match(shape, shape, **options)


def test_the_summary_is_json_with_a_numpy_seed(shape):
    result = meshcorr.match(shape, shape, random_state=np.int64(3), refine=False)
    assert json.loads(json.dumps(result.summary()))["params"]["random_state"] == 3


def test_wrong_values_for_the_result_s_methods_are_refused_by_name(shape):
    from meshcorr.evaluation import metrics as evaluation
    from meshcorr.evaluation.ground_truth import GroundTruth

    result = meshcorr.match(shape, shape, refine=False)
    n = shape.n_vertices
    truth = GroundTruth(np.arange(10), np.arange(10), "ten")
    cases = [
        # Each was a raw numpy error or a silent wrong answer (a NaN tolerance counted every point right).
        (lambda: result.evaluate(np.arange(5)), r"truth must be a GroundTruth or a dense true map.*got shape \(5,\)"),
        (lambda: result.evaluate(np.full(n, 1.5)), "dtype float64"),
        (lambda: result.evaluate(None), "truth must be a GroundTruth"),
        (lambda: result.transfer(3.0), "transfer needs numbers, one value"),
        (lambda: result.transfer(np.array(["a"] * n), precise=True), "transfer needs numbers"),
        (lambda: result.precise_map().interpolate(np.arange(5)), f"at least {n}"),
        (lambda: evaluation.feature_point_accuracy(shape, result.map, truth, tolerance=float("nan")),
         "'tolerance' parameter must be a finite real number"),
        (lambda: evaluation.evaluate_map(shape, result.map, truth, thresholds=[np.nan]),
         "'threshold' parameter must be a finite real number"),
        (lambda: evaluation.geodesic_errors(shape, np.array([0, -1]), np.array([0, 1])),
         r"predicted\[1\] is -1, outside the target's vertices"),
        (lambda: evaluation.geodesic_errors(shape, np.array([0, 1, 2]), np.array([0, 1])), "same points"),
    ]
    for call, message in cases:
        with pytest.raises(ParameterError, match=message):
            call()
    assert result.evaluate(np.arange(n))["mean_error"] == pytest.approx(0.0, abs=1e-12)


def test_a_functional_map_and_a_matcher_refuse_wrong_inputs_by_name(shape):
    from meshcorr import fmap

    basis = np.random.default_rng(0).normal(size=(20, 4))
    with pytest.raises(ParameterError, match="C holds NaN"):  # was an all-zero map
        fmap.point_map(np.full((4, 4), np.nan), basis, basis)
    result = meshcorr.match(shape, shape, refine=False)
    functional = result.functional_map(k=6)
    with pytest.raises(ParameterError, match="one value .or row. per target vertex"):
        functional.transfer(np.zeros(5))
    with pytest.raises(ParameterError, match="settings must be a meshcorr.Settings"):
        Matcher(settings={"k": 6})


def test_a_mesh_made_directly_is_checked():
    from meshcorr.errors import MeshError
    from meshcorr.core.mesh import Mesh

    shape = ds.creature(resolution=1)
    V, F = np.asarray(shape.vertices), np.asarray(shape.faces)
    nan = V.copy()
    nan[3] = np.nan
    for make, message in [(lambda: Mesh(V[:, :2], F), r"vertices must be \(n, 3\)"),
                          (lambda: Mesh(nan, F), "NaN or infinite"),
                          (lambda: Mesh(V, F + len(V)), f"a face names vertex [0-9]+, outside 0..{len(V) - 1}"),
                          (lambda: Mesh(V, F + 0.5), "integer vertex indices")]:
        with pytest.raises(MeshError, match=message):  # were raw numpy / scipy / geometry-central errors
            make()
    two = Mesh(np.vstack([V, V + 10]), np.vstack([F, F + len(V)]))
    with pytest.raises(MeshError, match="2 connected components"):  # was matched whole
        meshcorr.match(two, shape)
    piece = meshcorr.as_mesh(two, largest_component=True)
    assert piece.n_vertices == len(V) and piece.n_original == 2 * len(V)
    assert meshcorr.as_mesh(piece) is piece  # a connected mesh is passed through, its caches kept


def test_a_synthetic_shape_prints_in_one_short_line():
    text = repr(ds.creature(resolution=1))
    assert text == "SyntheticShape(name='creature-r1-rest', n_vertices=500, n_faces=996, chart='creature')"


def test_the_laplace_beltrami_basis_names_its_own_k():
    from meshcorr import fmap

    with pytest.raises(ParameterError, match="The 'k' parameter must be an int >= 2. Got 0"):
        fmap.laplace_beltrami(meshcorr.as_mesh(ds.creature(resolution=1)), 0)


def test_params_say_whether_the_shells_ran(shape):
    points = np.asarray(ds.creature(resolution=1).vertices)
    assert meshcorr.match(points, points).params["shells"] is False  # a cloud keeps the ZoomOut map
    assert meshcorr.match(shape, shape, bijective=True).params["shells"] is False
    assert meshcorr.match(shape, shape).params["shells"] is True


def test_more_anchors_than_vertices_are_refused(shape):
    with pytest.raises(ParameterError, match=f"n_anchors={shape.n_vertices + 1} .* smaller shape's"):
        meshcorr.match(shape, shape, n_anchors=shape.n_vertices + 1)  # ran, with repeated anchor vertices


def test_a_saved_result_keeps_its_meshes_names(shape, tmp_path):
    named = meshcorr.as_mesh(shape, name="tube.off")
    result = meshcorr.match(named, named, refine=False)
    result.save(tmp_path / "r.npz")
    loaded = Correspondence.load(tmp_path / "r.npz")
    assert (loaded.source.name, loaded.target.name) == ("tube.off", "tube.off")  # were "source" and "target"
