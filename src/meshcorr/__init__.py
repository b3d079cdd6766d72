"""meshcorr: dense vertex correspondence between 3D triangle meshes in the spectral domain.

The one-call entry point is :func:`match`; :class:`Matcher` is the staged
form (settings first, ``fit`` later) with its :class:`Settings`. See
:mod:`meshcorr.pipeline` for the method (Jain & Zhang, SMI 2006) and
``docs/method.md`` for its choices.
"""

from ._version import __version__
from .errors import MeshError, MeshWarning, MeshcorrError, ParameterError
from .mesh import Mesh, as_mesh
from .pipeline import match
from .prepared import PreparedShape, prepare
from .result import Correspondence
from .settings import Settings
from .matcher import Matcher
from . import datasets, evaluation, fmap, precise, progress, transfer, viz  # noqa: E402 - public submodules

__all__ = ["match", "Matcher", "Settings", "prepare", "PreparedShape", "batch", "Correspondence", "Mesh",
           "as_mesh", "MeshError", "MeshWarning", "MeshcorrError", "ParameterError", "datasets", "evaluation",
           "fmap", "precise", "progress", "transfer", "viz", "__version__"]


def __getattr__(name: str):
    # meshcorr.batch (meshcorr.collection.batch) is imported on first use: it pulls in the
    # benchmark and evaluation modules, and Dask only when it runs.
    if name == "batch":
        from .collection import batch

        return batch
    raise AttributeError(f"module 'meshcorr' has no attribute {name!r}")
