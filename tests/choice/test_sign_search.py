"""The sign search (meshcorr.choice.sign_search): right configurations among its starts, distinct, in the choice."""

import numpy as np
import pytest

import meshcorr
from meshcorr.choice import sign_search
from meshcorr.choice.sign_search import N_KEPT, sign_search_starts
from meshcorr.core.map_orientation import orientation_score
from meshcorr.evaluation.metrics import geodesic_errors


@pytest.fixture(autouse=True)
def fewer_signs(monkeypatch):
    """16 configurations instead of 64: the creature's right one is among them, and the tests stay fast."""
    monkeypatch.setattr(sign_search, "N_SIGNS", 4)


@pytest.fixture(scope="module")
def pair(creature_rest_and_bent_moved):
    return creature_rest_and_bent_moved[:3]


def test_the_best_configuration_is_the_right_map(pair):
    src, tgt, truth = pair
    starts = sign_search_starts(src, tgt, reliable=True)
    assert 1 <= len(starts) <= N_KEPT and starts[0][0] == "signs-0"
    name, mapping, extra = starts[0]
    assert mapping.shape == (src.n_vertices,) and extra["search_alignment"] >= 0
    assert geodesic_errors(tgt, mapping, truth).mean() < 0.03  # the bent copy, moved and re-indexed
    assert all(orientation_score(src, tgt, m) >= 0.5 for _, m, _ in starts)  # mirror images left out


def test_kept_maps_are_distinct(pair, monkeypatch):
    src, tgt, _ = pair
    monkeypatch.setattr(sign_search, "N_KEPT", 4)
    starts = sign_search_starts(src, tgt, reliable=True)
    for i in range(len(starts)):
        for j in range(i):
            assert np.mean(starts[i][1] == starts[j][1]) < 0.9


def test_the_whole_map_choice_takes_its_starts_only_when_asked(pair):
    src, tgt, _ = pair
    origins = [{c["origin"] for c in meshcorr.match(src, tgt, sign_search=flag).map_candidates} for flag in (True, False)]
    assert "signs-0" in origins[0] and not any(o.startswith("signs") for o in origins[1])
