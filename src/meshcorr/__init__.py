"""meshcorr: dense vertex correspondence between 3D triangle meshes in the spectral domain.

The main entry point is :func:`match`; see :mod:`meshcorr.pipeline` for the
method (Jain & Zhang, SMI 2006).
"""

from .errors import MeshError, MeshWarning, MeshcorrError, ParameterError
from .mesh import Mesh, as_mesh
from .pipeline import match
from .prepared import PreparedShape, prepare
from .result import Correspondence

__version__ = "0.1.0"

__all__ = ["match", "prepare", "PreparedShape", "batch", "Correspondence", "Mesh", "as_mesh", "MeshError",
           "MeshWarning", "MeshcorrError", "ParameterError", "__version__"]


def __getattr__(name: str):
    # meshcorr.batch (meshcorr.collection.batch) is imported on first use: it pulls in the
    # benchmark and evaluation modules, and Dask only when it runs.
    if name == "batch":
        from .collection import batch

        return batch
    raise AttributeError(f"module 'meshcorr' has no attribute {name!r}")
