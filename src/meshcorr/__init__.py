"""meshcorr: dense vertex correspondence between 3D triangle meshes in the spectral domain.

The main entry point is :func:`match`; see :mod:`meshcorr.pipeline` for the
method (Jain & Zhang, SMI 2006).
"""

from .errors import MeshError, MeshWarning, MeshcorrError, ParameterError
from .mesh import Mesh, as_mesh
from .pipeline import match
from .result import Correspondence

__version__ = "0.1.0"

__all__ = ["match", "Correspondence", "Mesh", "as_mesh", "MeshError", "MeshWarning",
           "MeshcorrError", "ParameterError", "__version__"]
