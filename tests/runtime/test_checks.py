"""meshcorr.runtime.checks: every parameter check accepts what it should and refuses the rest in one message shape."""

import numpy as np
import pytest

from meshcorr.errors import ParameterError
from meshcorr.runtime.checks import check_bool, check_choice, check_float, check_int, check_seed


def test_check_int_accepts_integers_of_any_kind_and_returns_int():
    assert check_int("k", 6) == 6
    value = check_int("k", np.int64(7), minimum=2, maximum=10)
    assert value == 7 and type(value) is int


@pytest.mark.parametrize("value", [True, 2.0, "3", None])
def test_check_int_refuses_non_integers_and_bools(value):
    with pytest.raises(ParameterError, match=r"^The 'k' parameter must be an int\. Got .* instead\.$"):
        check_int("k", value)


def test_check_int_bounds_are_inclusive_and_named():
    assert check_int("k", 2, minimum=2, maximum=2) == 2
    with pytest.raises(ParameterError, match=r"^The 'k' parameter must be an int >= 2\. Got 1 instead\.$"):
        check_int("k", 1, minimum=2)
    with pytest.raises(ParameterError, match=r"must be an int <= 10\. Got 11 instead\.$"):
        check_int("k", 11, maximum=10)


def test_check_float_bounds_inclusive_and_exclusive():
    assert check_float("anneal", 0, minimum=0) == 0.0
    assert type(check_float("anneal", np.float32(0.5))) is float
    with pytest.raises(ParameterError, match=r"must be a number > 0\b"):
        check_float("anneal", 0, minimum=0, exclusive=True)
    with pytest.raises(ParameterError, match=r"must be a number >= 1\b"):
        check_float("alpha", 0.5, minimum=1)
    with pytest.raises(ParameterError, match=r"must be a number <= 1\b"):
        check_float("anneal", 1.5, maximum=1)


@pytest.mark.parametrize("value", [float("nan"), float("inf"), True, "0.5"])
def test_check_float_refuses_non_finite_and_non_numbers(value):
    with pytest.raises(ParameterError, match="must be a finite real number"):
        check_float("anneal", value)


def test_check_bool_takes_python_and_numpy_bools_only():
    assert check_bool("refine", np.bool_(True)) is True
    assert check_bool("refine", False) is False
    for value in (1, 0, "yes", None):
        with pytest.raises(ParameterError, match=r"^The 'refine' parameter must be True or False\."):
            check_bool("refine", value)


def test_check_seed_none_or_non_negative_int():
    assert check_seed(None) is None
    assert check_seed(0) == 0
    with pytest.raises(ParameterError, match="'random_state' parameter must be an int >= 0"):
        check_seed(-1)


def test_check_choice_lists_the_choices():
    assert check_choice("mode", "dense", ("auto", "dense")) == "dense"
    with pytest.raises(ParameterError, match=r"^The 'mode' parameter must be one of 'auto', 'dense'\. "
                                             r"Got 'fast' instead\.$"):
        check_choice("mode", "fast", ("auto", "dense"))
