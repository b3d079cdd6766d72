"""meshcorr: dense vertex correspondence between 3D triangle meshes in the spectral domain.

The one-call entry point is :func:`match`; :class:`Matcher` is the staged
form (settings first, ``fit`` later) with its :class:`Settings`. See
:mod:`meshcorr.pipeline.run` for the method (Jain & Zhang, SMI 2006) and
``docs/method.md`` for its choices.

The public names are imported on first use (PEP 562): ``import meshcorr``
itself loads no numerical library, so the command line can take Ctrl-C
cleanly while numpy, scipy and the pipeline load, and ``meshcorr.batch``
pulls in Dask only when it runs.
"""

from importlib import import_module

from ._moved import PUBLIC_MODULES, install as _install_old_paths, moved_attribute as _moved_attribute
from ._version import __version__
from .errors import (InputError, LandmarkError, MeshError, MeshWarning, MeshcorrError, ParameterError,
                     PartialityError, PartialShapeWarning, PreparedShapeError, UnsureChoiceWarning,
                     LandmarkWarning)

#: Public name -> (module, attribute); attribute None for a public submodule.
_LAZY = {
    "match": ("pipeline.run", "match"),
    "Matcher": ("pipeline.matcher", "Matcher"),
    "Settings": ("pipeline.settings", "Settings"),
    "prepare": ("pipeline.prepare", "prepare"),
    "PreparedShape": ("shapes.prepared", "PreparedShape"),
    "batch": ("collection.batch", "batch"),
    "Correspondence": ("maps.result", "Correspondence"),
    "Mesh": ("core.mesh", "Mesh"),
    "as_mesh": ("core.mesh", "as_mesh"),
    **{name: (path, None) for name, path in PUBLIC_MODULES.items()},
}

__all__ = ["match", "Matcher", "Settings", "prepare", "PreparedShape", "batch", "Correspondence", "Mesh",
           "as_mesh", "MeshError", "MeshWarning", "MeshcorrError", "ParameterError", "InputError", "LandmarkError",
           "PartialityError", "PartialShapeWarning", "PreparedShapeError", "UnsureChoiceWarning", "LandmarkWarning",
           "datasets", "evaluation",
           "fmap", "precise", "progress", "transfer", "viz", "__version__"]


def __getattr__(name: str):
    if name not in _LAZY:
        moved = _moved_attribute(name)  # a module of the flat layout (meshcorr._moved)
        if moved is not None:
            return moved
        raise AttributeError(f"module 'meshcorr' has no attribute {name!r}")
    module, attribute = _LAZY[name]
    value = import_module(f".{module}", __name__)
    if attribute is not None:
        value = getattr(value, attribute)
    globals()[name] = value  # later lookups skip this function
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))


_install_old_paths()
