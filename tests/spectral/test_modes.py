"""meshcorr.spectral.modes: which of the dense and the scalable mode a pair of meshes gets."""

import pytest

from meshcorr.errors import MemoryLimitError, ParameterError
from meshcorr.runtime.memory import dense_memory
from meshcorr.spectral.modes import SCALABLE_ABOVE, select_mode


def test_auto_by_vertex_count():
    assert select_mode("auto", 500, SCALABLE_ABOVE, max_memory=None, scalable_above=SCALABLE_ABOVE) == "dense"
    assert select_mode("auto", 500, SCALABLE_ABOVE + 1, max_memory=None,
                       scalable_above=SCALABLE_ABOVE) == "scalable"


def test_auto_by_memory():
    need = dense_memory(1000, 1000)
    assert select_mode("auto", 1000, 1000, max_memory=need, scalable_above=2000) == "dense"
    assert select_mode("auto", 1000, 1000, max_memory=need - 1, scalable_above=2000) == "scalable"


def test_forced_modes():
    assert select_mode("scalable", 10, 10, max_memory=None, scalable_above=2000) == "scalable"
    assert select_mode("dense", 5000, 5000, max_memory=None, scalable_above=2000) == "dense"
    with pytest.raises(MemoryLimitError, match="mode='scalable'"):
        select_mode("dense", 1000, 1000, max_memory=1000, scalable_above=2000)
    with pytest.raises(MemoryLimitError, match="cost matrix"):
        select_mode("scalable", 1000, 1000, max_memory=1000, scalable_above=2000, bijective=True)


def test_unknown_mode_refused():
    with pytest.raises(ParameterError, match="The 'mode' parameter must be one of 'auto', 'dense', 'scalable'"):
        select_mode("fast", 10, 10, max_memory=None, scalable_above=2000)
