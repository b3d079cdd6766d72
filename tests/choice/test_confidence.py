"""The confidence of the whole-map choice (meshcorr.choice.confidence): rivals, margin, suggestions."""

import numpy as np
import pytest

from meshcorr.choice import confidence as conf
from meshcorr.choice.confidence import LOW_MARGIN, RIVAL_DISTANCE, choice_confidence, unsure_message
from meshcorr.choice.selection import MapCandidate

N = 40


def _line_geodesics(i: int) -> np.ndarray:
    """Normalised geodesic distances on a path of N vertices (0 ... 1)."""
    return np.abs(np.arange(N) - i) / (N - 1)


def _candidates():
    identity = np.arange(N)
    near = np.minimum(identity + 1, N - 1)  # a near-copy of the identity: not a rival
    reversed_ = identity[::-1].copy()  # the path turned end to end: another configuration
    return [MapCandidate("spectral", identity), MapCandidate("repaired-spectral", near),
            MapCandidate("extremities-0", reversed_)]


def test_margin_is_the_log_probability_ratio_to_the_best_rival_and_the_probability_sums_the_configuration():
    chosen, near, rival = _candidates()
    energies = {id(chosen): -3.0, id(near): -2.0, id(rival): -1.0}  # minus log-probabilities, up to a constant
    result = choice_confidence([chosen, near, rival], chosen, energies, _line_geodesics, _line_geodesics,
                               np.arange(0, N, 3))
    assert result.rival == "extremities-0"  # the near-copy, though of lower energy, is no rival
    assert result.margin == pytest.approx(2.0)
    # The chosen configuration: the chosen map and its near-copy, against the rival.
    weights = np.exp([3.0, 2.0, 1.0])
    assert result.probability == pytest.approx(weights[:2].sum() / weights.sum())
    assert result.to_dict()["probability"] == pytest.approx(result.probability, abs=1e-4)
    assert not result.low
    # the suggestions: where the two maps disagree most (the path's ends), spread apart
    sources = result.suggestions[:, 0]
    assert {0, N - 1} <= set(sources.tolist())  # 39 is one of the sampled sources 0, 3, ..., 39
    assert np.all(result.suggestions[:, 1] == sources) and np.all(result.suggestions[:, 2] == N - 1 - sources)
    gaps = np.abs(sources[:, None] - sources[None]) / (N - 1)
    assert np.all(gaps[~np.eye(len(sources), dtype=bool)] >= conf.SUGGESTION_SPACING)


def test_a_close_rival_is_low_confidence_and_named_in_the_message():
    chosen, near, rival = _candidates()
    energies = {id(chosen): -3.0, id(near): -2.0, id(rival): -3.0 + LOW_MARGIN / 2}
    result = choice_confidence([chosen, near, rival], chosen, energies, _line_geodesics, _line_geodesics,
                               np.arange(0, N, 3))
    assert result.margin < LOW_MARGIN and result.low
    report = result.to_dict()
    assert report["low"] and report["rival"] == "extremities-0" and report["margin"] == pytest.approx(LOW_MARGIN / 2, abs=1e-4)
    message = unsure_message(report)
    assert "'extremities-0'" in message and "--landmarks" in message
    assert f"probability is {report['probability']:.2f}" in message
    assert "meshcorr pick SOURCE TARGET --map MAP -o LANDMARKS.txt" in message and "result.pick()" in message
    assert str(report["suggested_landmarks"][0]["source"]) in message


def test_without_a_rival_the_margin_is_infinite():
    chosen, near, _ = _candidates()
    energies = {id(chosen): -3.0, id(near): -9.0}
    result = choice_confidence([chosen, near], chosen, energies, _line_geodesics, _line_geodesics, np.arange(N))
    assert result.rival is None and result.margin == np.inf and not result.low and result.probability == 1.0
    assert result.suggestions.shape == (0, 3) and result.to_dict()["margin"] is None


def test_rival_distance_decides_what_counts_as_another_configuration():
    chosen, _, _ = _candidates()
    shifted = MapCandidate("extremities-1", np.minimum(np.arange(N) + int(2 * RIVAL_DISTANCE * (N - 1)), N - 1))
    energies = {id(chosen): -3.0, id(shifted): -3.0}
    result = choice_confidence([chosen, shifted], chosen, energies, _line_geodesics, _line_geodesics, np.arange(N))
    assert result.rival == "extremities-1" and result.margin == pytest.approx(0.0)
