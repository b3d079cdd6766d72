"""The pipeline on coarse copies (Settings.coarse_vertices): the choice on the copies, the map on every vertex."""

import warnings

import numpy as np
import pytest
import trimesh

import meshcorr
from meshcorr.choice import confidence, selection
from meshcorr.cli import main
from meshcorr.errors import ParameterError, UnsureChoiceWarning
from meshcorr.evaluation.metrics import geodesic_errors
from meshcorr.maps.result import Correspondence


@pytest.fixture(scope="module")
def pair(large_creature_rest_and_bent_moved):
    """The creature at rest and bent, moved and re-indexed, 2000 vertices each, and the truth."""
    return large_creature_rest_and_bent_moved[:3]


@pytest.fixture(scope="module")
def results(pair):
    src, tgt, _ = pair
    return meshcorr.match(src, tgt, coarse_vertices=400), meshcorr.match(src, tgt, coarse_vertices=0)


def test_choice_on_copies_maps_as_well_as_on_the_meshes(pair, results):
    src, tgt, truth = pair
    coarse, direct = results
    assert coarse.params["coarse_sizes"] == [401, 401] and "coarse" in coarse.timings
    assert "coarse_sizes" not in direct.params and "coarse" not in direct.timings
    error, reference = (geodesic_errors(tgt, r.map, truth).mean() for r in (coarse, direct))
    assert reference < 0.02 and error < 1.2 * reference


def test_the_chosen_map_is_refined_on_every_vertex(results):
    coarse, _ = results
    # a map lifted from 401 coarse vertices without the fine refinement reaches at most 401 targets
    assert len(np.unique(coarse.map)) > 2.5 * 401
    assert coarse.refine_history  # ZoomOut ran on the full meshes
    assert coarse.source_embedding.shape[0] == 2000 and coarse.aligned_target_embedding.shape[0] == 2000


def test_the_result_reports_the_confidence_in_the_input_numbering(pair, results, monkeypatch):
    coarse, direct = results
    for result in (coarse, direct):  # the creature's candidate maps hold no rival that the rules let compete
        assert result.confidence == {"margin": None, "probability": 1.0, "low": False, "rival": None,
                                     "suggested_landmarks": []}
    monkeypatch.setattr(confidence, "RIVAL_DISTANCE", -1.0)  # now every other map that competes is a rival, even an equal one
    monkeypatch.setattr(selection, "SAME_MAP_DISTANCE", -1.0)  # and near-copies are not merged before the shells
    src, tgt, _ = pair
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UnsureChoiceWarning)  # margins are now small: the next test's subject
        again = meshcorr.match(src, tgt, coarse_vertices=400), meshcorr.match(src, tgt, coarse_vertices=0)
    for result in again:
        report = result.confidence
        assert report["margin"] >= 0.0 and report["low"] == (report["margin"] < confidence.LOW_MARGIN)
        assert f"confidence={round(report['margin'], 2)!r}" in repr(result)
        assert result.summary()["confidence"] == report
        rows = report["suggested_landmarks"]
        assert rows and all(0 <= row[key] < 2000 for row in rows for key in ("source", "chosen", "rival"))
        assert all(result.map[row["source"]] == row["chosen"] for row in rows) or "coarse_sizes" in result.params


def test_confidence_survives_save_and_load(results, tmp_path):
    coarse, _ = results
    coarse.save(tmp_path / "result.npz")
    assert Correspondence.load(tmp_path / "result.npz").confidence == coarse.confidence


def test_an_unsure_choice_warns_naming_the_landmarks_to_give(pair, monkeypatch):
    src, tgt, _ = pair
    monkeypatch.setattr(confidence, "RIVAL_DISTANCE", -1.0)  # every other competing map is a rival, even an equal one
    monkeypatch.setattr(confidence, "LOW_MARGIN", 1e9)  # and every margin is below the threshold
    with pytest.warns(UnsureChoiceWarning, match="landmarks") as caught:
        result = meshcorr.match(src, tgt, coarse_vertices=400)
    assert result.confidence["low"]
    assert caught[0].filename == __file__  # the warning points at the caller's line
    first = result.confidence["suggested_landmarks"][0]
    assert f"source vertices {first['source']}" in str(caught[0].message)
    with warnings.catch_warnings():
        warnings.simplefilter("error", UnsureChoiceWarning)  # a sure choice does not warn
        monkeypatch.setattr(confidence, "LOW_MARGIN", -1e9)
        meshcorr.match(src, tgt, coarse_vertices=400)


def test_the_cli_prints_the_unsure_warning(pair, tmp_path, monkeypatch, capsys):
    src, tgt, _ = pair
    paths = [str(tmp_path / name) for name in ("a.off", "b.off")]
    for mesh, path in zip((src, tgt), paths):
        trimesh.Trimesh(mesh.vertices, mesh.faces, process=False).export(path)
    monkeypatch.setattr(confidence, "RIVAL_DISTANCE", -1.0)
    monkeypatch.setattr(confidence, "LOW_MARGIN", 1e9)
    assert main(["match", *paths, "-o", str(tmp_path / "map.txt"), "--coarse-vertices", "400"]) == 0
    err = capsys.readouterr().err
    assert "meshcorr: warning: The global choice of the map is unsure" in err and "--landmarks FILE" in err


@pytest.mark.parametrize("value", [-1, 10, 299, 2.5, "many"])
def test_coarse_vertices_out_of_range_is_refused(value):
    with pytest.raises(ParameterError, match="coarse_vertices"):
        meshcorr.Settings(coarse_vertices=value)


def test_cli_refuses_too_few_coarse_vertices(tmp_path, capsys, tube_files_with_truth):
    source, target, _ = tube_files_with_truth
    assert main(["match", source, target, "-o", str(tmp_path / "m.txt"), "--coarse-vertices", "10"]) == 2
    err = capsys.readouterr().err
    assert "--coarse-vertices" in err and "at least 300" in err and not (tmp_path / "m.txt").exists()
