"""The map the other way round as a check (meshcorr.choice.reverse_check, Settings.check_reverse)."""

import json

import numpy as np
import pytest

import meshcorr
from meshcorr.choice import reverse_check
from meshcorr.choice.reverse_check import CYCLE_LIMIT, cycle_error
from meshcorr.cli import main
from meshcorr.errors import UnsureChoiceWarning


def test_a_round_trip_through_the_truth_stays_and_a_scrambled_one_does_not(creature_rest_and_bent_moved):
    rest, _, truth, back = creature_rest_and_bent_moved
    assert cycle_error(rest, truth, back) < 0.1 * CYCLE_LIMIT  # the two truths are nearest vertices of each other
    scrambled = np.random.default_rng(1).permutation(len(back))
    assert cycle_error(rest, truth, scrambled) > CYCLE_LIMIT  # a random round trip: about the mean distance
    unmapped = truth.copy()
    unmapped[:] = -1  # nothing makes the round trip
    assert np.isnan(cycle_error(rest, unmapped, back))


def test_match_reports_the_cycle_error_and_warns_above_the_limit(creature_rest_and_bent_moved, monkeypatch):
    rest, bent, _, _ = creature_rest_and_bent_moved
    result = meshcorr.match(rest, bent, check_reverse=True)
    assert 0.0 <= result.confidence["cycle_error"] < CYCLE_LIMIT and not result.confidence["low"]
    assert "reverse" in result.timings and "cycle_error" not in (meshcorr.match(rest, bent).confidence or {})
    monkeypatch.setattr("meshcorr.pipeline.run.CYCLE_LIMIT", -1.0)  # every round trip is now too long
    with pytest.warns(UnsureChoiceWarning, match="the map back from the target disagrees"):
        unsure = meshcorr.match(rest, bent, check_reverse=True)
    assert unsure.confidence["low"]


def test_the_cli_prints_the_cycle_error(tmp_path, capsys):
    code = main(["match", "examples/creature_rest.off", "examples/creature_bent.off", "--check-reverse", "--json"])
    assert code == 0
    report = json.loads(capsys.readouterr().out)["confidence"]
    assert report["cycle_error"] < reverse_check.CYCLE_LIMIT
