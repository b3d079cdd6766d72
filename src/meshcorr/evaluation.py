"""Evaluation of vertex maps against ground truth.

The field's protocol (Kim, Lipman & Funkhouser, "Blended intrinsic maps",
SIGGRAPH 2011; the Princeton benchmark): the error of a predicted match is
the geodesic distance on the target between the predicted and the true
vertex, divided by the square root of the target's surface area.
"""

from __future__ import annotations

import numpy as np

from .geodesics import geodesic_solver
from .mesh import Mesh, MeshLike, as_mesh


def geodesic_errors(target: MeshLike, predicted: np.ndarray, truth: np.ndarray, *,
                    method: str = "heat", normalize: bool = True) -> np.ndarray:
    """Geodesic distance between predicted and true target vertices.

    Parameters
    ----------
    target : mesh-like
        The mesh the map points into.
    predicted : (p,) int
        Predicted target vertex of each evaluated point.
    truth : (p,) int
        True target vertex of each evaluated point.
    method : str
        Geodesic solver (see :mod:`meshcorr.geodesics`).
    normalize : bool
        Divide by sqrt(surface area of the target).

    Returns
    -------
    errors : (p,) float
        One distance per point; each distinct true vertex costs one
        single-source solve.
    """
    mesh = target if isinstance(target, Mesh) else as_mesh(target, name="target")
    predicted = np.asarray(predicted, dtype=np.int64)
    truth = np.asarray(truth, dtype=np.int64)
    solver = geodesic_solver(mesh.vertices, mesh.faces, method)
    sources, inverse = np.unique(truth, return_inverse=True)
    errors = np.empty(len(truth))
    for block in range(0, len(sources), 256):
        rows = solver.distances(sources[block:block + 256])
        sel = (inverse >= block) & (inverse < block + 256)
        errors[sel] = rows[inverse[sel] - block, predicted[sel]]
    if normalize:
        errors /= np.sqrt(mesh.area)
    return errors
