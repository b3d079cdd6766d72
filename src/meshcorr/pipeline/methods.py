"""The registry of correspondence methods: one name per method, one way to run it.

:func:`meshcorr.pipeline.run.match` (the spectral method) and the baselines of
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

import dataclasses
import importlib
import inspect
from typing import Callable

from ..runtime.checks import check_bool, check_choice
from ..errors import ParameterError
from ..core.mesh import MeshLike
from ..runtime.timing import StageProgress

__all__ = ["METHOD_NAMES", "SPATIAL_METHODS", "applicable", "applicable_options", "changed_options",
           "check_options", "method_function", "method_options", "method_parameters", "reject_inapplicable", "run_method"]

#: Method name -> (module, function) of ``f(source, target, **options) -> Correspondence``.
_REGISTRY: dict[str, tuple[str, str]] = {
    "spectral": ("meshcorr.pipeline.run", "match"),
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

#: Methods whose options are the fields of a settings class, not keywords of their function:
#: method name -> (module, class). The spectral method's ``match(source, target, settings, **overrides)``
#: takes every field of :class:`meshcorr.Settings` as a keyword.
_SETTINGS_CLASSES: dict[str, tuple[str, str]] = {"spectral": ("meshcorr.pipeline.settings", "Settings")}


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
    return tuple(p for p in method_parameters(name) if p not in _RUN_OPTIONS)


def method_parameters(name: str) -> dict:
    """Every keyword the function of method ``name`` takes besides the shapes, with its default.

    For the baselines, the keywords of their function; for the spectral
    method, the fields of :class:`meshcorr.Settings` and ``progress`` (its
    function takes them as keywords).
    """
    if check_choice("method", name, METHOD_NAMES) in _SETTINGS_CLASSES:
        module, cls = _SETTINGS_CLASSES[name]
        fields = dataclasses.fields(getattr(importlib.import_module(module), cls))
        return {**{f.name: f.default for f in fields}, "progress": None}
    return {key: p.default for key, p in inspect.signature(method_function(name)).parameters.items()
            if key not in ("source", "target")}


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
    _reject_unknown(name, options, method_options(name))
    if name in SPATIAL_METHODS:
        options["prealign"] = prealign
    _check_switches(name, options)
    return method_function(name)(source, target, random_state=random_state, progress=progress, **options)


def _check_switches(name: str, options: dict) -> None:
    """Options whose default is True or False must be True or False (:func:`meshcorr.runtime.checks.check_bool`).

    The baselines took any value as a switch, so the string ``"false"`` (e.g. from
    ``--set icp:prealign=false``, which is no Python literal) ran as True.
    """
    defaults = method_parameters(name)
    for key, value in options.items():
        if key in defaults and isinstance(defaults[key], bool):
            check_bool(key, value)


def _reject_unknown(name: str, options: dict, allowed) -> None:
    """Raise if ``options`` has a key outside ``allowed``, naming it and the method's own options."""
    unknown = sorted(set(options) - set(allowed))
    if unknown:
        raise ParameterError(
            f"The method {name!r} has no option {unknown[0]!r}. Its options are: {', '.join(method_options(name))}."
        )


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


class _Reached(BaseException):
    """Raised by a :class:`_NoData` stand-in when a call first uses it: the call's option checks passed.

    A BaseException, so that no ``except Exception`` on the way can take it for a failure.
    """


class _NoData:
    """Stands for a method's data (a mesh, points, an embedding, a vertex count) in :func:`check_options`.

    It has a ``shape`` when given ``dims`` (the checks of :func:`meshcorr.stages.icp.tps_icp` read the
    embedding's dimension); any other use of it (an attribute, ``len``, arithmetic, a comparison,
    numpy's conversion) raises :class:`_Reached`.
    """

    def __init__(self, dims: int | None = None) -> None:
        if dims is not None:
            self.shape = (0, dims)

    def __getattr__(self, name):
        raise _Reached(name)

    def _reached(self, *args, **kwargs):
        raise _Reached("data")

    __len__ = __iter__ = __getitem__ = __array__ = __index__ = __int__ = __float__ = __bool__ = _reached
    __lt__ = __le__ = __gt__ = __ge__ = __add__ = __radd__ = __sub__ = __rsub__ = __mul__ = __rmul__ = _reached
    __truediv__ = __rtruediv__ = _reached


#: Options a method checks only once its data is loaded, where it passes them on: per method,
#: (module, function, {option: that function's keyword}, its data as stand-ins given the options).
#: Each of these functions checks its options before it first uses its data.
_LATER_CHECKS: dict[str, tuple] = {
    "spectral": (
        # Step 5's thin-plate-spline ICP (its n_control needs the embedding's k - 1 dimensions).
        ("meshcorr.stages.icp", "tps_icp", {"icp_iterations": "max_iter", "n_control": "n_control", "anneal": "anneal"},
         lambda o: {"X": _NoData(o["k"] - 1), "Y": _NoData(o["k"] - 1)}),
        ("meshcorr.spectral.modes", "select_mode", {"mode": "mode", "scalable_above": "scalable_above"},
         lambda o: {"n1": _NoData(), "n2": _NoData(), "max_memory": None}),
    ),
    "tps-rpm": (
        ("meshcorr.baselines.tps_rpm", "tps_rpm",
         {key: key for key in ("lambda_init", "affine_init", "anneal_rate", "inner_iterations")},
         lambda o: {"V": _NoData(3), "X": _NoData(3)}),
    ),
    "icp": (
        ("meshcorr.baselines.rigid_icp", "rigid_icp",
         {key: key for key in ("trim", "huber", "with_scale", "n_rotations", "max_iter")},
         lambda o: {"P": _NoData(3), "Q": _NoData(3)}),
    ),
}


def _checks_of(function: Callable, **arguments) -> None:
    """Call ``function`` on stand-in data until it first uses the data (its checks are done by then)."""
    try:
        function(**arguments)
    except _Reached:
        pass


def check_options(name: str, **options) -> None:
    """Raise the :class:`ParameterError` that method ``name`` would raise for ``options``, before any work.

    The method's own checks decide: its function (:func:`method_function`, e.g.
    :func:`meshcorr.match` for ``"spectral"``) is called with stand-ins for the
    source and target that stop it when it first loads them, and the options it
    checks only later, where it passes them on (e.g. ``icp_iterations`` in
    :func:`meshcorr.stages.icp.tps_icp`), are checked by the functions that take
    them, on stand-in data. Nothing is loaded or computed: use it to refuse a
    bad setting before a long run (``meshcorr bench --set``, :func:`meshcorr.collection.batch.batch`)
    instead of failing every pair.

    Parameters
    ----------
    name : str
        One of :data:`METHOD_NAMES`.
    **options
        Keywords of the method's function other than ``source`` and
        ``target`` (its own options, and ``random_state``, ``progress`` and
        ``prealign`` where it takes them).

    Raises
    ------
    ParameterError
        An unknown method or option, or a value the method refuses (the
        method's message, e.g. "The 'k' parameter must be an int >= 2. Got -3
        instead."). Checks that need the meshes (``landmarks``, ``n_anchors``
        against the vertex count) are left to the run.
    """
    function = method_function(name)
    defaults = method_parameters(name)
    _reject_unknown(name, options, list(defaults))
    _check_switches(name, options)
    call = dict(options, source=_NoData(), target=_NoData())
    if call.get("progress") is True:  # it passes the checks as False does, without drawing a bar
        call["progress"] = False
    _checks_of(function, **call)
    given = {key: default for key, default in defaults.items() if default is not inspect.Parameter.empty}
    given.update(options)
    for module, later, keywords, data in _LATER_CHECKS.get(name, ()):
        _checks_of(getattr(importlib.import_module(module), later), **data(given),
                   **{keyword: given[option] for option, keyword in keywords.items()})
