"""``Settings``: checks of options that other options make certain to be ignored (issue 31, item 10)."""

import numpy as np
import pytest

from meshcorr import Settings
from meshcorr.errors import ParameterError
from meshcorr.pipeline.settings import MAX_REFINE_K


@pytest.mark.parametrize("options, names", [
    (dict(mode="dense", n_samples=30), ("n_samples (--samples)", "mode='dense' (--mode dense)")),
    (dict(mode="scalable", max_memory="1GiB"), ("max_memory (--max-memory)", "mode='scalable'")),
    (dict(refine=False, refine_k=20), ("refine_k (--refine-k)", "refine=False (--no-refine)")),
    (dict(refine=np.False_, refine_k=20), ("refine_k (--refine-k)", "refine=False (--no-refine)")),
    (dict(icp_iterations=0, n_control=50), ("n_control (--control-points)", "icp_iterations=0")),
    (dict(icp_iterations=0, anneal=0.7), ("anneal (--anneal)", "icp_iterations=0")),
])
def test_an_option_that_another_makes_ignored_is_refused_naming_both(options, names):
    with pytest.raises(ParameterError) as error:
        Settings(**options)
    message = str(error.value)
    for name in names:
        assert name in message
    assert "ignored" in message and "Remove" in message


@pytest.mark.parametrize("options", [
    dict(mode="auto", n_samples=30, max_memory="1GiB"),  # auto may resolve to either mode
    dict(mode="scalable", n_samples=30),
    dict(mode="dense", max_memory="1GiB"),
    dict(mode="scalable", max_memory="1GiB", bijective=True),  # bounds the one-to-one map's cost matrix
    dict(refine=False), dict(refine_k=20), dict(icp_iterations=0), dict(icp_iterations=3, n_control=50),
])
def test_options_that_are_used_are_kept(options):
    settings = Settings(**options)
    assert all(getattr(settings, name) == value for name, value in options.items())


def test_refine_k_is_bounded():
    # 100000 was lowered to n - 1 in silence and took 131 s on a 500-vertex mesh (issue 31, item 17).
    assert Settings(refine_k=MAX_REFINE_K).refine_k == MAX_REFINE_K
    with pytest.raises(ParameterError, match=r"refine_k=100000 \(--refine-k\) is more than .* at most 200"):
        Settings(refine_k=100000)


def test_messages_name_the_command_line_flags_too():
    # They named n_anchors and anchor_weight where the command line says --anchors and --alpha (item 19).
    with pytest.raises(ParameterError, match=r"'n_anchors' parameter \(--anchors\) must be an int >= 0"):
        Settings(n_anchors=-1)
    with pytest.raises(ParameterError, match=r"'anchor_weight' parameter \(--alpha\) must be a number >= 0"):
        Settings(anchor_weight=-1.0)
