"""Map files of the commands: read and checked (one that does not fit the meshes is bad input data,
exit 3), or written to stdout for ``-o -``."""

from __future__ import annotations

import sys

import numpy as np

from ..errors import InputError, ParameterError


def read_checked_map(path: str, n_source: int, n_target: int) -> np.ndarray:
    """``(n_source,)`` int64: the map in ``path``, checked against the meshes' vertex counts.

    Raises
    ------
    InputError
        Unreadable, or not one entry in ``[-1, n_target)`` per source vertex
        (:func:`meshcorr.maps.transfer.check_map`, whose :class:`ParameterError`
        is about an argument; here the file is the data at fault).
    """
    from ..io import read_map
    from ..maps.transfer import check_map

    mapping = read_map(path, name="MAP")
    try:
        return check_map(mapping, n_source, n_target, name=path)
    except ParameterError as error:
        raise InputError(str(error)) from None


def print_map(mapping) -> None:
    """``-o -``: the map on stdout, as the text of a map file (:func:`meshcorr.io.map_text`)."""
    from ..io import map_text

    sys.stdout.write(map_text(mapping))
    sys.stdout.flush()
