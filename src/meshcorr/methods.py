"""The registry of correspondence methods: one name per method, one way to run it.

:func:`meshcorr.pipeline.match` (the spectral method) and the baselines of
:mod:`meshcorr.baselines` both read this registry; it imports neither at
import time (each entry names its module and function and is imported on
first use), so the two packages no longer import each other.

========================  =====================================================  ======================
name                      method                                                 reference
========================  =====================================================  ======================
``spectral``              the main pipeline, :func:`meshcorr.match`              Jain & Zhang 2006
``shapiro-brady``         unscaled eigenvectors, greedy signs, nearest match     Shapiro & Brady 1992
``shapiro-brady-scaled``  the same with sqrt(eigenvalue) scaling ("improved")    Jain & Zhang 2006
``tps-rpm``               soft-assign, deterministic annealing, thin-plate spline Chui & Rangarajan 2003
``icp``                   robust (trimmed / Huber) similarity ICP                Besl & McKay 1992
``shape-context``         3D log-polar histograms, chi-square cost, assignment   Belongie et al. 2002
========================  =====================================================  ======================
"""

from __future__ import annotations

import importlib
import inspect
from typing import Callable

from ._params import check_choice
from .errors import ParameterError
from .mesh import MeshLike
from .timing import StageProgress

__all__ = ["METHOD_NAMES", "SPATIAL_METHODS", "applicable", "applicable_options", "changed_options",
           "method_function", "method_options", "reject_inapplicable", "run_method"]

#: Method name -> (module, function) of ``f(source, target, **options) -> Correspondence``.
_REGISTRY: dict[str, tuple[str, str]] = {
    "spectral": ("meshcorr.pipeline", "match"),
    "shapiro-brady": ("meshcorr.baselines.shapiro_brady", "match_shapiro_brady"),
    "shapiro-brady-scaled": ("meshcorr.baselines.shapiro_brady", "match_shapiro_brady_scaled"),
    "tps-rpm": ("meshcorr.baselines.tps_rpm", "match_tps_rpm"),
    "icp": ("meshcorr.baselines.rigid_icp", "match_icp"),
    "shape-context": ("meshcorr.baselines.shape_context", "match_shape_context"),
}

#: The method names, in the order ``--help`` and the docs list them.
METHOD_NAMES: tuple[str, ...] = tuple(_REGISTRY)

#: Methods that work on vertex positions and take the ``prealign`` option.
SPATIAL_METHODS = ("tps-rpm", "icp", "shape-context")

_RUN_OPTIONS = ("source", "target", "prealign", "random_state", "progress", "method")


def method_function(name: str) -> Callable:
    """The function that runs method ``name`` (imported on first use).

    Raises
    ------
    ParameterError
        If ``name`` is not a key of the registry.
    """
    module, function = _REGISTRY[check_choice("method", name, METHOD_NAMES)]
    return getattr(importlib.import_module(module), function)


def method_options(name: str) -> tuple[str, ...]:
    """Keyword options a method takes besides ``prealign``, ``random_state`` and ``progress``.

    Parameters
    ----------
    name : str
        One of :data:`METHOD_NAMES`.
    """
    parameters = inspect.signature(method_function(name)).parameters
    return tuple(p for p in parameters if p not in _RUN_OPTIONS)


def applicable_options(name: str, options: dict) -> dict:
    """The entries of ``options`` that method ``name`` takes (the others are dropped)."""
    allowed = method_options(name)
    return {key: value for key, value in options.items() if key in allowed}


def run_method(name: str, source: MeshLike, target: MeshLike, *, prealign: bool = True,
               random_state: int | None = 0, progress: StageProgress | None = None,
               **options):
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
    return method_function(name)(source, target, random_state=random_state, progress=progress, **options)


#: Options every method takes (how it runs, not what it computes).
_ALWAYS = ("source", "target", "method", "random_state", "progress")


def applicable(name: str) -> tuple[str, ...]:
    """Every keyword of :func:`meshcorr.match` that method ``name`` uses.

    The method's own options (:func:`method_options`), ``prealign`` for the
    spatial methods, and ``random_state`` / ``progress`` for all.
    """
    extra = ("prealign",) if name in SPATIAL_METHODS else ()
    return tuple(method_options(name)) + extra + _ALWAYS


def changed_options(function: Callable, values: dict) -> dict:
    """The entries of ``values`` that differ from ``function``'s keyword defaults.

    Parameters
    ----------
    function : callable
        Its signature supplies the defaults (e.g. :func:`meshcorr.match`).
    values : dict
        Keyword -> value, e.g. a call's arguments; names the signature does
        not have are kept (they cannot be defaults).
    """
    parameters = inspect.signature(function).parameters
    changed = {}
    for key, value in values.items():
        default = parameters[key].default if key in parameters else inspect.Parameter.empty
        same = value is default or (default is not None and value is not None
                                    and type(value) is type(default) and value == default)
        if not same:
            changed[key] = value
    return changed


def reject_inapplicable(name: str, options: dict) -> None:
    """Raise if ``options`` names settings that method ``name`` does not use.

    Parameters
    ----------
    name : str
        One of :data:`METHOD_NAMES`.
    options : dict
        The settings given (e.g. :func:`changed_options` of a call).

    Raises
    ------
    ParameterError
        Naming every such option and the method's own options, e.g.
        "The method 'icp' does not use the options 'k', 'symmetry'; ...".
    """
    unused = sorted(set(options) - set(applicable(name)))
    if unused:
        names = ", ".join(repr(u) for u in unused)
        own = ", ".join(o for o in applicable(name) if o not in _ALWAYS)
        raise ParameterError(f"The method {name!r} does not use the option{'s' if len(unused) > 1 else ''} "
                             f"{names}; remove {'them' if len(unused) > 1 else 'it'} or choose a method that "
                             f"uses {'them' if len(unused) > 1 else 'it'}. The options of {name!r} are: {own}.")
