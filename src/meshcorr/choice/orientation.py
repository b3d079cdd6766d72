"""Surface orientation and the orientation score of a map, at home in :mod:`meshcorr.core.orientation`.

The module moved to the core layer (issue 30): the smooth shells of
:mod:`meshcorr.stages.shells` use it, and the stages sit below the choice of
a whole map. These names answer the imports of the pipeline until they name
:mod:`meshcorr.core.orientation`.
"""

from __future__ import annotations

from ..core.orientation import (CAPPED_VOLUME_MIN, Orientation, consistent_vertices, mesh_orientation,
                                orient_outward, orientation_score, orientation_scores, oriented_normals,
                                regional_orientation, vertex_normals)

__all__ = ["CAPPED_VOLUME_MIN", "Orientation", "consistent_vertices", "mesh_orientation", "orient_outward",
           "orientation_score", "orientation_scores", "oriented_normals", "regional_orientation", "vertex_normals"]
