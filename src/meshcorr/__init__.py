"""meshcorr: dense vertex correspondence between 3D triangle meshes in the spectral domain.

The one-call entry point is :func:`match`; :class:`Matcher` is the staged
form (settings first, ``fit`` later) with its :class:`Settings`. See
:mod:`meshcorr.pipeline` for the method (Jain & Zhang, SMI 2006) and
``docs/method.md`` for its choices.

The public names are imported on first use (PEP 562): ``import meshcorr``
itself loads no numerical library, so the command line can take Ctrl-C
cleanly while numpy, scipy and the pipeline load, and ``meshcorr.batch``
pulls in Dask only when it runs.
"""

from importlib import import_module

from ._version import __version__
from .errors import (InputError, LandmarkError, MeshError, MeshWarning, MeshcorrError, ParameterError,
                     PartialityError, PartialShapeWarning, PreparedShapeError)

#: Public name -> (module, attribute); attribute None for a public submodule.
_LAZY = {
    "match": ("pipeline", "match"),
    "Matcher": ("matcher", "Matcher"),
    "Settings": ("settings", "Settings"),
    "prepare": ("prepared", "prepare"),
    "PreparedShape": ("prepared", "PreparedShape"),
    "batch": ("collection", "batch"),
    "Correspondence": ("result", "Correspondence"),
    "Mesh": ("mesh", "Mesh"),
    "as_mesh": ("mesh", "as_mesh"),
    **{name: (name, None) for name in ("datasets", "evaluation", "fmap", "precise", "progress", "transfer",
                                       "viz")},
}

__all__ = ["match", "Matcher", "Settings", "prepare", "PreparedShape", "batch", "Correspondence", "Mesh",
           "as_mesh", "MeshError", "MeshWarning", "MeshcorrError", "ParameterError", "InputError", "LandmarkError",
           "PartialityError", "PartialShapeWarning", "PreparedShapeError", "datasets", "evaluation",
           "fmap", "precise", "progress", "transfer", "viz", "__version__"]


def __getattr__(name: str):
    if name not in _LAZY:
        raise AttributeError(f"module 'meshcorr' has no attribute {name!r}")
    module, attribute = _LAZY[name]
    value = import_module(f".{module}", __name__)
    if attribute is not None:
        value = getattr(value, attribute)
    globals()[name] = value  # later lookups skip this function
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
