"""Dense or scalable: which spectrum builder the pipeline uses.

``"dense"``
    All-pairs geodesics and the exact top-k eigenpairs of the ``n x n``
    affinity (:func:`meshcorr.spectral.spectrum.dense_spectrum`): the paper's method
    and the reference. ``O(n^2)`` memory; refused with
    :class:`~meshcorr.errors.MemoryLimitError` when it would not fit in
    ``max_memory`` (:mod:`meshcorr.runtime.memory`).
``"scalable"``
    ``m`` sampled (landmark) geodesic rows and the Nyström extension
    (:func:`meshcorr.spectral.nystrom.landmark_spectrum`): ``O(n m)`` memory, never an
    ``n x n`` matrix.
``"auto"``
    Dense up to ``scalable_above`` vertices on the larger mesh if it fits in
    ``max_memory``, scalable otherwise.
"""

from __future__ import annotations

from ..runtime.checks import check_choice, check_int
from ..runtime.memory import check_bijective_fits, check_dense_fits, default_max_memory, dense_memory, parse_memory
from ..core.mesh import Mesh
from .nystrom import landmark_spectrum
from .spectrum import Spectrum, dense_spectrum
from ..runtime.timing import StageTimer

MODES = ("auto", "dense", "scalable")

#: "auto" switches to the scalable mode above this many vertices (on the larger mesh):
#: dense all-pairs heat geodesics take ~2 s per mesh there on 2 cores, the scalable mode ~0.1 s.
SCALABLE_ABOVE = 2000

#: Nyström samples (landmark vertices) of the scalable mode: on TOSCA cat0 (5k) the embedding agrees with the dense one to
#: ~1.5 % (Procrustes residual) from 50 landmarks on, more do not improve it; on the Sumner cat
#: subdivided to 29k and 115k vertices, 48 landmarks agree with 160 to 1.2-1.6 %, 32 to 2.5 %.
#: Mean TOSCA error over 8 pairs: 0.087 with 48 or 64 landmarks.
N_SAMPLES = 48


def resolve_memory(max_memory) -> int | None:
    """Bytes allowed: ``max_memory`` parsed, or the default (a fraction of the available memory)."""
    return default_max_memory() if max_memory is None else parse_memory(max_memory)


def select_mode(mode: str, n1: int, n2: int, *, max_memory: int | None, scalable_above: int,
                bijective: bool = False) -> str:
    """``"dense"`` or ``"scalable"`` for meshes of ``n1`` and ``n2`` vertices.

    Raises
    ------
    MemoryLimitError
        ``mode="dense"`` whose ``n x n`` matrices exceed ``max_memory`` bytes,
        or a bijective map whose cost matrix does.
    ParameterError
        Unknown ``mode``.
    """
    check_choice("mode", mode, MODES)
    scalable_above = check_int("scalable_above", scalable_above, minimum=0)
    if mode == "auto":
        fits = max_memory is None or dense_memory(n1, n2, bijective=bijective) <= max_memory
        mode = "dense" if max(n1, n2) <= scalable_above and fits else "scalable"
    if mode == "dense":
        check_dense_fits(n1, n2, max_memory, bijective=bijective)
    elif bijective:
        check_bijective_fits(n1, n2, max_memory)
    return mode


def build_spectrum(mesh: Mesh, mode: str, *, k: int, geodesic: str, scale: bool, n_samples: int,
                   random_state: int | None, timer: StageTimer) -> Spectrum:
    """The :class:`~meshcorr.spectral.spectrum.Spectrum` of ``mesh`` in ``mode`` ("dense" or "scalable")."""
    if mode == "dense":
        return dense_spectrum(mesh, k=k, geodesic=geodesic, scale=scale, random_state=random_state,
                              timer=timer)
    return landmark_spectrum(mesh, k=k, geodesic=geodesic, scale=scale, n_samples=n_samples,
                             random_state=random_state, timer=timer)
