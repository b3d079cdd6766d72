"""A left/right symmetric "person" on a sphere, shared by the tests of the whole-map choice
(meshcorr.choice.selection, extremities) and of the oriented start (meshcorr.choice.oriented_start)."""

import numpy as np

from meshcorr import datasets
from meshcorr.core.geodesics import geodesic_solver

#: The tips: direction from the centre and bump height; head, two arms, two legs, a nose in front.
TIPS = {"head": ((0, 0, 1), 0.9), "nose": ((0, 1, 0.2), 0.35), "arm_l": ((1, 0, 0.3), 0.8),
        "arm_r": ((-1, 0, 0.3), 0.8), "leg_l": ((0.45, 0, -1), 1.1), "leg_r": ((-0.45, 0, -1), 1.1)}


def person_vertices(subdivisions: int = 3):
    """The person: ``(vertices, faces)``, a unit icosphere with a Gaussian bump of each tip's height.

    The radius at unit direction ``u`` is ``1 + sum_tips height * exp(-(1 - u . d) / 0.03)``.
    """
    vertices, faces = datasets.sphere(subdivisions=subdivisions)
    u = vertices / np.linalg.norm(vertices, axis=1, keepdims=True)
    radius = np.ones(len(u))
    for direction, height in TIPS.values():
        d = np.asarray(direction, float) / np.linalg.norm(direction)
        radius += height * np.exp(-(1 - u @ d) / 0.03)
    return u * radius[:, None], np.asarray(faces)


def scaled_geodesics(mesh):
    """``row(i)``: the heat-method geodesic distances from vertex ``i``, shape ``(n,)``, divided by 5
    (the length unit the tests pass); each row is solved once."""
    solver = geodesic_solver(mesh.vertices, mesh.faces, "heat")
    rows = {}

    def row(i):
        if i not in rows:
            rows[i] = solver.distances([int(i)])[0]
        return rows[i] / 5.0
    return row


def tip_vertex(mesh, name):
    """The vertex furthest along the direction of tip ``name``."""
    d = np.asarray(TIPS[name][0], float)
    return int(np.argmax(mesh.vertices @ (d / np.linalg.norm(d))))
