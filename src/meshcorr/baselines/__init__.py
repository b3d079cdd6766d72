"""The methods Jain & Zhang (2006) compare against, behind one registry.

========================  ==========================================================  ============================
name                      method                                                      reference
========================  ==========================================================  ============================
``spectral``              the main pipeline, :func:`meshcorr.match`                   Jain & Zhang 2006
``shapiro-brady``         unscaled eigenvectors, greedy signs, nearest match          Shapiro & Brady 1992
``shapiro-brady-scaled``  the same with sqrt(eigenvalue) scaling ("improved")         Jain & Zhang 2006
``tps-rpm``               soft-assign, deterministic annealing, thin-plate spline     Chui & Rangarajan 2003
``icp``                   robust (trimmed / Huber) similarity ICP                     Besl & McKay 1992
``shape-context``         3D log-polar histograms, chi-square cost, assignment        Belongie et al. 2002
========================  ==========================================================  ============================

The three *spatial* methods (``tps-rpm``, ``icp``, ``shape-context``) work on
vertex positions, so they depend on the inputs' poses; with ``prealign=True``
(the default) both meshes are first centred, scaled and rotated to their
principal axes (:mod:`meshcorr.baselines.align`), as the paper hand-aligned
them. Each method's module documents its maths and its reference.
"""

from __future__ import annotations

import inspect
from typing import Callable

from .._params import check_choice
from ..errors import ParameterError
from ..mesh import MeshLike
from ..pipeline import match as _spectral
from ..result import Correspondence
from ..timing import StageProgress
from .align import align_pair, pca_alignment, prealign
from .rigid_icp import match_icp, rigid_icp, umeyama
from .shape_context import match_shape_context
from .shapiro_brady import match_shapiro_brady, match_shapiro_brady_scaled
from .tps_rpm import match_tps_rpm, tps_rpm

#: Method name -> function ``f(source, target, **options) -> Correspondence``.
METHODS: dict[str, Callable[..., Correspondence]] = {
    "spectral": _spectral,
    "shapiro-brady": match_shapiro_brady,
    "shapiro-brady-scaled": match_shapiro_brady_scaled,
    "tps-rpm": match_tps_rpm,
    "icp": match_icp,
    "shape-context": match_shape_context,
}

#: Methods that work on vertex positions and take the ``prealign`` option.
SPATIAL_METHODS = ("tps-rpm", "icp", "shape-context")

_RUN_OPTIONS = ("source", "target", "prealign", "random_state", "progress", "method")

__all__ = ["METHODS", "SPATIAL_METHODS", "run_method", "method_options", "applicable_options",
           "align_pair", "pca_alignment", "prealign", "rigid_icp", "umeyama", "tps_rpm"]


def method_options(name: str) -> tuple[str, ...]:
    """Keyword options a method takes besides ``prealign``, ``random_state`` and ``progress``.

    Parameters
    ----------
    name : str
        A key of :data:`METHODS`.
    """
    check_choice("method", name, tuple(METHODS))
    parameters = inspect.signature(METHODS[name]).parameters
    return tuple(p for p in parameters if p not in _RUN_OPTIONS)


def applicable_options(name: str, options: dict) -> dict:
    """The entries of ``options`` that method ``name`` takes (the others are dropped)."""
    allowed = method_options(name)
    return {key: value for key, value in options.items() if key in allowed}


def run_method(name: str, source: MeshLike, target: MeshLike, *, prealign: bool = True,
               random_state: int | None = 0, progress: StageProgress | None = None,
               **options) -> Correspondence:
    """Vertex map from ``source`` to ``target`` by the named method.

    Parameters
    ----------
    name : {"spectral", "shapiro-brady", "shapiro-brady-scaled", "tps-rpm", "icp", "shape-context"}
        The method (see the module docstring).
    source, target : path, trimesh.Trimesh, Mesh or (vertices, faces)
    prealign : bool
        Pre-align the inputs (spatial methods only; ignored by the others).
    random_state : int or None
        Seed for everything random.
    progress : callable, optional
        ``progress(stage, done, total)``.
    **options
        The method's own options (see :func:`method_options` and the
        method's function, e.g. :func:`~meshcorr.baselines.rigid_icp.match_icp`).

    Returns
    -------
    result : Correspondence
        ``result.method == name``; ``result.map[i]`` is the target vertex of
        source vertex i.

    Raises
    ------
    ParameterError
        Unknown method, or an option the method does not take.
    """
    allowed = method_options(name)
    unknown = sorted(set(options) - set(allowed))
    if unknown:
        raise ParameterError(
            f"The method {name!r} has no option {unknown[0]!r}. Its options are: {', '.join(allowed)}."
        )
    if name in SPATIAL_METHODS:
        options["prealign"] = prealign
    return METHODS[name](source, target, random_state=random_state, progress=progress, **options)
