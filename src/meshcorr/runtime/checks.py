"""Parameter validation with one message shape, and the one check of a vertex map.

"The 'k' parameter must be an int >= 2. Got 1 instead."

A vertex map ``mapping`` ``(n_source,)`` int sends source vertex ``i`` to
target vertex ``mapping[i]`` in ``[0, n_target)``, or -1 where it is unmapped;
:func:`check_vertex_map` checks one for every layer that takes one (refinement,
functional maps, map files, evaluation, transfer), each in its own words
(:class:`MapMessages`).
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass
from typing import Sequence

import numpy as np

from ..errors import ParameterError


def _named(name: str, flag: str | None) -> str:
    """How a message names a parameter: ``'n_control'``, with its command-line flag when it has another name."""
    return f"{name!r} parameter ({flag})" if flag else f"{name!r} parameter"


def check_int(name: str, value, *, minimum: int | None = None, maximum: int | None = None,
              flag: str | None = None) -> int:
    """Return ``value`` as an int or raise :class:`ParameterError` (naming ``flag`` too, when given)."""
    what = _named(name, flag)
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise ParameterError(f"The {what} must be an int. Got {value!r} instead.")
    value = int(value)
    if minimum is not None and value < minimum:
        raise ParameterError(f"The {what} must be an int >= {minimum}. Got {value} instead.")
    if maximum is not None and value > maximum:
        raise ParameterError(f"The {what} must be an int <= {maximum}. Got {value} instead.")
    return value


def check_float(name: str, value, *, minimum: float | None = None, exclusive: bool = False,
                maximum: float | None = None, flag: str | None = None) -> float:
    """Return ``value`` as a float or raise :class:`ParameterError` (naming ``flag`` too, when given)."""
    what = _named(name, flag)
    if isinstance(value, bool) or not isinstance(value, numbers.Real) or not math.isfinite(value):
        raise ParameterError(f"The {what} must be a finite real number. Got {value!r} instead.")
    value = float(value)
    if minimum is not None and (value <= minimum if exclusive else value < minimum):
        op = ">" if exclusive else ">="
        raise ParameterError(f"The {what} must be a number {op} {minimum}. Got {value} instead.")
    if maximum is not None and value > maximum:
        raise ParameterError(f"The {what} must be a number <= {maximum}. Got {value} instead.")
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


@dataclass(frozen=True)
class MapMessages:
    """How :func:`check_vertex_map` words its refusals: :meth:`str.format` templates.

    The templates may use ``{name}`` (how the map is called), ``{shape}`` and
    ``{dtype}`` (of the array), ``{length}``, ``{n_source}``, ``{n_target}``,
    ``{last}`` (``n_target - 1``), ``{entry}`` and ``{value}`` (the first
    entry out of range).

    Attributes
    ----------
    not_integer : str or None
        A map that is not a 1-D integer array; None: no such check (any array
        of whole numbers is taken as it is, not converted).
    wrong_length : str
        A map whose shape is not ``(n_source,)``.
    out_of_range : str
        An entry outside ``[lowest, n_target)``.
    unmapped : bool
        True: -1 marks an unmapped vertex (``lowest = -1``); False: ``lowest = 0``.
    """

    not_integer: str | None
    wrong_length: str
    out_of_range: str
    unmapped: bool = True


#: The words of a map handed to transfer, plots and functional maps (:mod:`meshcorr.maps.transfer`).
MAP_MESSAGES = MapMessages(
    not_integer="{name} must be a 1-D array of integer vertex indices. "
                "Got shape {shape} and dtype {dtype} instead.",
    wrong_length="{name} has {length} entries but the source mesh has {n_source} vertices: "
                 "a map needs one target index per source vertex. Check the order of SOURCE and "
                 "TARGET (the map goes from SOURCE to TARGET) and that the map belongs to these meshes.",
    out_of_range="{name} entry {entry} is {value}, outside the target's vertex range "
                 "0..{last} (-1 marks an unmapped vertex). Check that the map belongs to "
                 "these meshes and that SOURCE and TARGET are not swapped.")


def check_vertex_map(mapping, n_source: int | None = None, n_target: int | None = None, *,
                     name: str = "map", messages: MapMessages = MAP_MESSAGES) -> np.ndarray:
    """``(n_source,)`` int64: ``mapping`` checked to be a vertex map from ``n_source`` to ``n_target`` vertices.

    Parameters
    ----------
    mapping : (n_source,) int
        ``mapping[i]`` is the target vertex of source vertex ``i`` (-1: unmapped,
        where ``messages.unmapped``).
    n_source, n_target : int, optional
        Vertex counts of the two meshes; None skips the check of the length,
        or of the range.
    name : str
        How messages call the map (e.g. its file name).
    messages : MapMessages
        The words of the refusals.

    Returns
    -------
    mapping : (n_source,) int64
        As given where ``messages.not_integer`` is None.

    Raises
    ------
    ParameterError
        In the order: not a 1-D integer array, a length other than
        ``n_source``, an entry outside ``[lowest, n_target)``.
    """
    mapping = np.asarray(mapping)
    words = dict(name=name, shape=mapping.shape, dtype=mapping.dtype, length=mapping.size,
                 n_source=n_source, n_target=n_target, last=None if n_target is None else n_target - 1)
    if messages.not_integer is not None and (mapping.ndim != 1 or not np.issubdtype(mapping.dtype, np.integer)):
        raise ParameterError(messages.not_integer.format(**words))
    if n_source is not None and mapping.shape != (n_source,):
        raise ParameterError(messages.wrong_length.format(**words))
    if n_target is not None:
        bad = (mapping < (-1 if messages.unmapped else 0)) | (mapping >= n_target)
        if bad.any():
            first = int(np.flatnonzero(bad)[0])
            raise ParameterError(messages.out_of_range.format(**words, entry=first, value=int(mapping[first])))
    return mapping if messages.not_integer is None else mapping.astype(np.int64, copy=False)
