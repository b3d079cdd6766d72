"""The methods Jain & Zhang (2006) compare against, behind one registry.

The registry of all methods, their names and references is
:mod:`meshcorr.pipeline.methods`, which the spectral pipeline uses too.

The three *spatial* methods (``tps-rpm``, ``icp``, ``shape-context``) work on
vertex positions, so they depend on the inputs' poses; with ``prealign=True``
(the default) both meshes are first centred, scaled and rotated to their
principal axes (:mod:`meshcorr.baselines.align`), as the paper hand-aligned
them. Each method's module documents its maths and its reference.
"""

from __future__ import annotations

from ..pipeline.methods import METHOD_NAMES, SPATIAL_METHODS, applicable_options, method_function, method_options, run_method
from .align import align_pair, pca_alignment, prealign
from .rigid_icp import match_icp, rigid_icp, umeyama
from .shape_context import match_shape_context
from .shapiro_brady import match_shapiro_brady, match_shapiro_brady_scaled
from .tps_rpm import match_tps_rpm, tps_rpm

#: Method names of :mod:`meshcorr.pipeline.methods`, the registry (kept here for old imports).
METHODS = METHOD_NAMES

__all__ = ["METHODS", "SPATIAL_METHODS", "run_method", "method_function", "method_options",
           "applicable_options", "align_pair", "pca_alignment", "prealign", "rigid_icp", "umeyama",
           "tps_rpm", "match_icp", "match_shape_context", "match_shapiro_brady",
           "match_shapiro_brady_scaled", "match_tps_rpm"]
