"""meshcorr: dense vertex correspondence between 3D triangle meshes in the spectral domain.

The main entry point is :func:`match`; see :mod:`meshcorr.pipeline` for the
method (Jain & Zhang, SMI 2006).
"""

from ._interrupt import deferred_interrupt

# A Ctrl-C during the imports is delivered once they end: some third-party
# imports catch BaseException (measured: 1 of 40 interrupts 0.5 s into
# 'meshcorr match' was lost, and the run went on to write its map).
with deferred_interrupt():
    from .errors import MeshError, MeshWarning, MeshcorrError, ParameterError
    from .mesh import Mesh, as_mesh
    from .pipeline import match
    from .result import Correspondence

__version__ = "0.1.0"

__all__ = ["match", "Correspondence", "Mesh", "as_mesh", "MeshError", "MeshWarning",
           "MeshcorrError", "ParameterError", "__version__"]
