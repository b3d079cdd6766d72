"""Eigenvector reordering and sign correction recover a known configuration."""

import numpy as np
import pytest

from meshcorr.errors import ParameterError
from meshcorr.stages.reorder import configuration_cost, rank_configurations


@pytest.fixture(scope="module")
def embeddings():
    rng = np.random.default_rng(0)
    # An anisotropic point cloud: each axis has its own spread, like a
    # spectral embedding with decaying eigenvalues.
    X = rng.normal(size=(600, 5)) * np.array([1.0, 0.7, 0.5, 0.35, 0.25])
    perm = np.array([2, 0, 4, 1, 3])
    signs = np.array([-1, 1, -1, -1, 1])
    # Target column perm[c] holds source column c times signs[c]; rows shuffled.
    Y = np.empty_like(X)
    Y[:, perm] = X * signs
    rows = rng.permutation(len(X))
    return X, Y[rows], perm, signs


@pytest.mark.parametrize("mode", ["exhaustive", "greedy"])
def test_recovers_known_permutation_and_signs(embeddings, mode):
    X, Y, perm, signs = embeddings
    best = rank_configurations(X, Y, mode, random_state=0)[0]
    assert best.perm == tuple(perm)
    assert best.signs == tuple(signs)
    assert best.cost == pytest.approx(0.0, abs=1e-12)
    # Applying it gives back the source point set exactly.
    configured = best.apply(Y)
    assert np.allclose(np.sort(configured, axis=0), np.sort(X, axis=0), atol=1e-12)


def test_ranked_list_is_ascending_after_the_choice(embeddings):
    X, Y, _, _ = embeddings
    ranked = rank_configurations(X, Y, "exhaustive")
    costs = [c.cost for c in ranked]
    assert costs == sorted(costs)
    assert len({(c.perm, c.signs) for c in ranked}) == len(ranked)
    # Pre-scoring on samples keeps 16 candidates (n_rescore), re-scored exactly.
    assert len(ranked) == 16
    assert ranked[1].cost == pytest.approx(configuration_cost(X, Y, ranked[1].perm, ranked[1].signs))


def test_sign_modes_keep_eigenvalue_order(embeddings):
    X, _, _, _ = embeddings
    Y = X * np.array([1, -1, 1, -1, -1])
    for mode in ("signs", "signs-greedy"):
        best = rank_configurations(X, Y, mode)[0]
        assert best.perm == (0, 1, 2, 3, 4)
        assert best.signs == (1, -1, 1, -1, -1)
    assert rank_configurations(X, Y, "none")[0].signs == (1, 1, 1, 1, 1)


def test_same_seed_same_ranking(embeddings):
    X, Y, _, _ = embeddings
    a = rank_configurations(X, Y + 0.01, "exhaustive", random_state=4)
    b = rank_configurations(X, Y + 0.01, "exhaustive", random_state=4)
    assert a == b


def test_unknown_mode_is_rejected(embeddings):
    X, Y, _, _ = embeddings
    with pytest.raises(ParameterError, match="'reorder' parameter must be one of"):
        rank_configurations(X, Y, "random")


def test_brute_force_prescore_equals_kdtree_costs():
    """The coarse passes' brute-force costs equal one KD-tree query per configuration (issue 5)."""
    import itertools

    from scipy.spatial import cKDTree

    from meshcorr.stages.reorder import _all_signs, _brute_costs

    rng = np.random.default_rng(3)
    Xs = rng.normal(size=(40, 5)) * np.array([1.0, 0.7, 0.5, 0.35, 0.25])
    targets = rng.normal(size=(90, 5)) * np.array([1.0, 0.7, 0.5, 0.35, 0.25])
    configs = [(p, s) for p in itertools.permutations(range(5)) for s in _all_signs(5)]
    tree = cKDTree(targets)
    expected = np.array([configuration_cost(Xs, targets, p, s, tree) for p, s in configs])
    got = _brute_costs(Xs, targets, configs)
    np.testing.assert_allclose(got, expected, rtol=0, atol=1e-12)
    # A source point equal to a target point has cost 0, not a tiny negative under the root.
    assert _brute_costs(targets[:3], targets, [(tuple(range(5)), (1,) * 5)])[0] == pytest.approx(0.0, abs=1e-7)


def test_marginal_proxy_is_zero_for_the_true_configuration_and_higher_for_any_other_permutation(embeddings):
    """The pre-screen's proxy (sum of 1-d Wasserstein distances) vanishes only where every coordinate's
    distribution matches; the quantile levels are symmetric, so flipped coordinates are scored exactly."""
    import itertools

    from meshcorr.stages.reorder import _all_signs, _marginal_costs

    X, Y, perm, signs = embeddings
    configs = [(p, s) for p in itertools.permutations(range(5)) for s in _all_signs(5)]
    proxy = _marginal_costs(X, Y, configs)
    truth = configs.index((tuple(perm), tuple(signs)))
    assert proxy[truth] == pytest.approx(0.0, abs=1e-9)
    # Every configuration that moves a coordinate to another eigenvector costs clearly more.
    moved = [i for i, (p, _) in enumerate(configs) if p != tuple(perm)]
    assert proxy[moved].min() > 0.05
    # One entry by hand: 1-d W1 between equal-size samples is the mean gap of the sorted values.
    p, s = configs[7]
    by_hand = sum(np.abs(np.sort(X[:, c]) - np.sort(s[c] * Y[:, p[c]])).mean() for c in range(5))
    assert proxy[7] == pytest.approx(by_hand, rel=0.05)


def test_exhaustive_screen_equals_the_best_of_the_full_list(embeddings):
    """The screen finds the 768 configurations of lowest proxy without listing all d! 2^d of them."""
    import itertools

    from meshcorr.stages.reorder import _MARGINAL_KEEP, _all_signs, _exhaustive_configurations, _marginal_costs

    X, Y, _, _ = embeddings
    full = [(p, s) for p in itertools.permutations(range(5)) for s in _all_signs(5)]
    proxy = _marginal_costs(X, Y, full)
    screened = _exhaustive_configurations(X, Y)
    assert len(screened) == _MARGINAL_KEEP
    assert set(screened) == {full[i] for i in np.argsort(proxy, kind="stable")[:_MARGINAL_KEEP]}
    costs = _marginal_costs(X, Y, screened)
    assert np.all(np.diff(costs) >= 0)
    # Small inputs keep the full list (scored exactly by brute force).
    assert len(_exhaustive_configurations(X[:40], Y[:40])) == len(full)


def test_exhaustive_mode_at_k10_recovers_a_known_configuration():
    """d = 9 has 185 million configurations: listing them would exhaust memory; the screen does not."""
    rng = np.random.default_rng(1)
    X = rng.normal(size=(800, 9)) * np.linspace(1.0, 0.2, 9)
    perm = rng.permutation(9)
    signs = rng.choice([-1, 1], size=9)
    Y = np.empty_like(X)
    Y[:, perm] = X * signs
    best = rank_configurations(X, Y[rng.permutation(len(X))], "exhaustive")[0]
    assert best.perm == tuple(perm) and best.signs == tuple(signs)
    assert best.cost == pytest.approx(0.0, abs=1e-12)


def test_embeddings_of_different_dimensions_are_refused():
    X, Y = np.zeros((10, 3)), np.zeros((10, 4))
    with pytest.raises(ValueError, match="Embeddings have different dimensions: 3 and 4"):
        rank_configurations(X, Y)
