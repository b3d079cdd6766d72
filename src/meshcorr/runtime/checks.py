"""Parameter validation with one message shape.

"The 'k' parameter must be an int >= 2. Got 1 instead."
"""

from __future__ import annotations

import math
import numbers
from typing import Sequence

import numpy as np

from ..errors import ParameterError


def check_int(name: str, value, *, minimum: int | None = None, maximum: int | None = None) -> int:
    """Return ``value`` as an int or raise :class:`ParameterError`."""
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise ParameterError(f"The {name!r} parameter must be an int. Got {value!r} instead.")
    value = int(value)
    if minimum is not None and value < minimum:
        raise ParameterError(f"The {name!r} parameter must be an int >= {minimum}. Got {value} instead.")
    if maximum is not None and value > maximum:
        raise ParameterError(f"The {name!r} parameter must be an int <= {maximum}. Got {value} instead.")
    return value


def check_float(name: str, value, *, minimum: float | None = None, exclusive: bool = False,
                maximum: float | None = None) -> float:
    """Return ``value`` as a float or raise :class:`ParameterError`."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real) or not math.isfinite(value):
        raise ParameterError(f"The {name!r} parameter must be a finite real number. Got {value!r} instead.")
    value = float(value)
    if minimum is not None and (value <= minimum if exclusive else value < minimum):
        op = ">" if exclusive else ">="
        raise ParameterError(f"The {name!r} parameter must be a number {op} {minimum}. Got {value} instead.")
    if maximum is not None and value > maximum:
        raise ParameterError(f"The {name!r} parameter must be a number <= {maximum}. Got {value} instead.")
    return value


def check_bool(name: str, value) -> bool:
    """Return ``value`` as a bool if it is True or False (numpy's too), or raise :class:`ParameterError`."""
    if not isinstance(value, (bool, np.bool_)):
        raise ParameterError(f"The {name!r} parameter must be True or False. Got {value!r} instead.")
    return bool(value)


def check_seed(value) -> int | None:
    """The ``random_state``: None or an int >= 0 (numpy's seeds), or raise :class:`ParameterError`."""
    return None if value is None else check_int("random_state", value, minimum=0)


def check_choice(name: str, value, choices: Sequence[str]) -> str:
    """Return ``value`` if it is one of ``choices`` or raise :class:`ParameterError`."""
    if value not in choices:
        options = ", ".join(repr(c) for c in choices)
        raise ParameterError(f"The {name!r} parameter must be one of {options}. Got {value!r} instead.")
    return value
