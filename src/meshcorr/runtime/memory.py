"""Memory budget of the dense pipeline, and the guard that refuses what would not fit.

The dense mode stores ``n x n`` float64 matrices: per mesh, the all-pairs
geodesic matrix (kept for the anchor stage), a transposed copy while it is
symmetrised, then the affinity matrix while the embedding is computed; the
bijective option adds the ``n1 x n2`` cost matrix and the copy the
assignment solver makes. Peak bytes, meshes processed one after the other:

.. math::

    8 \\max\\left(3 n_1^2,\\; n_1^2 + 3 n_2^2,\\;
    n_1^2 + n_2^2 + 2 n_1 n_2 [\\text{bijective}]\\right)

The coarse-to-fine path of large meshes (:mod:`meshcorr.stages.lift`)
holds only arrays linear in the vertex counts; its peak is modelled as a
fixed base plus a cost per vertex of the two meshes,
:math:`B + b (n_1 + n_2)` (:func:`coarse_path_memory`), fitted above the
peaks measured on the Sumner lion pair at 320k and 1.28M vertices
(``benchmarks/RESULTS-scale.md``, issue 33), and a run that would not fit
is refused before the coarse copies are made (:func:`check_coarse_fits`).

It is an upper estimate: at 5000 + 5000 vertices it gives 763 MiB, and the
measured peak resident memory of the whole process was 701 MiB (imports
included; ``benchmarks/RESULTS-scale.md``). The scalable mode
(:mod:`meshcorr.spectral.nystrom`) needs ``O(n m)`` memory except for the bijective
option's ``n1 x n2`` cost matrix.
"""

from __future__ import annotations

import numbers
import os
import re

from ..errors import MemoryLimitError, ParameterError

#: Fraction of the memory available at start-up that the dense mode may use by default.
DEFAULT_FRACTION = 0.8

_UNITS = {"": 1, "b": 1, "k": 1024, "kb": 1000, "kib": 1024, "m": 1024 ** 2, "mb": 1000 ** 2,
          "mib": 1024 ** 2, "g": 1024 ** 3, "gb": 1000 ** 3, "gib": 1024 ** 3, "t": 1024 ** 4,
          "tb": 1000 ** 4, "tib": 1024 ** 4}


def parse_memory(value) -> int:
    """Bytes from an int or a string such as ``"4GiB"``, ``"500MB"``, ``"2G"``.

    ``kB/MB/GB/TB`` are powers of 1000, ``KiB/MiB/GiB/TiB`` and the bare
    letters ``K/M/G/T`` powers of 1024.

    Raises
    ------
    ParameterError
        Not a positive size.
    """
    if isinstance(value, numbers.Real) and not isinstance(value, bool):
        if value == value and value > 0:
            return int(value)
    elif isinstance(value, str):
        found = re.fullmatch(r"\s*([0-9]*\.?[0-9]+)\s*([a-zA-Z]*)\s*", value)
        if found and found.group(2).lower() in _UNITS and float(found.group(1)) > 0:
            return int(float(found.group(1)) * _UNITS[found.group(2).lower()])
    raise ParameterError(
        "The 'max_memory' parameter must be a positive number of bytes or a size such as '4GiB' "
        f"or '500MB'. Got {value!r} instead."
    )


def available_memory() -> int | None:
    """Bytes of memory available now (``MemAvailable`` of /proc/meminfo), or None if unknown."""
    try:
        with open("/proc/meminfo") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    try:
        return int(os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE"))
    except (ValueError, OSError, AttributeError):
        return None


def default_max_memory() -> int | None:
    """``DEFAULT_FRACTION`` of :func:`available_memory` (None: no limit known)."""
    available = available_memory()
    return None if available is None else int(DEFAULT_FRACTION * available)


def dense_memory(n1: int, n2: int, *, bijective: bool = False) -> int:
    """Peak bytes of the dense mode's ``n x n`` matrices (formula in the module docstring)."""
    peak = max(3 * n1 * n1, n1 * n1 + 3 * n2 * n2)
    if bijective:
        peak = max(peak, n1 * n1 + n2 * n2 + 2 * n1 * n2)
    return 8 * peak


#: Fixed part of the coarse-to-fine path's peak (bytes): the interpreter, the libraries, the copies' pipeline.
COARSE_PATH_BASE = 512 * 1024 ** 2
#: Bytes per vertex (of both meshes together) of the coarse-to-fine path's peak: measured 2.56 GiB at
#: 2 x 1.28M vertices and 0.9 GiB at 2 x 320k (about 900 bytes a vertex above the base), with a margin.
COARSE_PATH_PER_VERTEX = 1100


def coarse_path_memory(n1: int, n2: int) -> int:
    """Peak bytes of the coarse-to-fine path for meshes of ``n1`` and ``n2`` vertices (module docstring)."""
    return COARSE_PATH_BASE + COARSE_PATH_PER_VERTEX * (int(n1) + int(n2))


def coarse_path_fits(max_memory: int) -> int:
    """The most vertices each of two equal meshes may have for the coarse-to-fine path to fit ``max_memory``."""
    return max(0, (int(max_memory) - COARSE_PATH_BASE) // (2 * COARSE_PATH_PER_VERTEX))


def check_coarse_fits(n1: int, n2: int, max_memory: int | None) -> None:
    """Raise :class:`MemoryLimitError` if the coarse-to-fine path would exceed ``max_memory`` bytes.

    The message names the need, the allowance and the largest meshes that fit.
    """
    need = coarse_path_memory(n1, n2)
    if max_memory is not None and need > max_memory:
        raise MemoryLimitError(
            f"Matching meshes of {n1} and {n2} vertices needs about {_gib(need)} but may use "
            f"{_gib(max_memory)}: meshes of up to {coarse_path_fits(max_memory)} vertices each fit. "
            "Allow more memory (max_memory, --max-memory) or decimate the meshes first."
        )


def _gib(nbytes: int) -> str:
    return f"{nbytes / 1024 ** 3:.2f} GiB"


def check_dense_fits(n1: int, n2: int, max_memory: int | None, *, bijective: bool = False) -> None:
    """Raise :class:`MemoryLimitError` if the dense mode would exceed ``max_memory`` bytes.

    The message names the matrix sizes and the scalable mode.
    """
    need = dense_memory(n1, n2, bijective=bijective)
    if max_memory is not None and need > max_memory:
        raise MemoryLimitError(
            f"The dense mode needs about {_gib(need)} for its n x n matrices ({n1} x {n1} and "
            f"{n2} x {n2} geodesic and affinity matrices) but may use {_gib(max_memory)}. "
            "Use the scalable mode (mode='scalable', --mode scalable), which never stores an "
            "n x n matrix, or allow more memory (max_memory, --max-memory)."
        )


def check_bijective_fits(n1: int, n2: int, max_memory: int | None) -> None:
    """Raise :class:`MemoryLimitError` if the bijective option's ``n1 x n2`` cost matrix will not fit."""
    need = 16 * n1 * n2
    if max_memory is not None and need > max_memory:
        raise MemoryLimitError(
            f"The bijective option solves a linear assignment on a {n1} x {n2} cost matrix, about "
            f"{_gib(need)}, but may use {_gib(max_memory)}. Drop bijective (--bijective) or allow "
            "more memory (max_memory, --max-memory)."
        )
