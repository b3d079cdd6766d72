"""Synthetic shapes with known ground-truth correspondence.

Every generator here builds a closed, genus-0, consistently and outwardly
oriented triangle mesh from a fixed two-dimensional *chart*, so that tests and
benchmarks need no downloaded data:

- :func:`creature` -- a compact "starfish": a round body with five limbs of
  clearly different lengths and thicknesses, each bending at hinges. Its
  spectral embedding is well conditioned (distinct top eigenvalues, no
  intrinsic symmetry), so it is the shape for end-to-end tests of the
  spectral pipeline; the bundled example pair is made from it;
- :func:`tube` -- a capsule with asymmetric bumps, optionally bent into a
  circular arc;
- :func:`figure` -- a tube-shaped creature: a capsule with a head, a neck, a
  tapering tail and limb-like protrusions, articulated at three hinges. Thin
  and nearly round in cross-section, it has three nearly equal eigenvalues in
  the spectral embedding (they mix between poses), so it suits tests of
  meshes and ground truth rather than of matching;
- :func:`sphere` -- an icosphere, for checking geodesic solvers against the
  great-circle formula;
- :func:`rigid_copy` -- a rotated, translated, scaled and re-indexed copy
  with its ground truth;
- :func:`ground_truth` -- the correspondence between two shapes of one family
  (different poses and/or resolutions);
- :func:`save_example_pair` -- writes the bundled example pair.

The charts
----------
A shape's ``chart`` attribute says how its ``params`` are read.

``"capsule"`` (:func:`tube`, :func:`figure`): each vertex carries chart
coordinates ``params[i] = (t, theta)``. ``t`` is the arc length along a
meridian of the *reference capsule* (the straight, unbumped capsule of radius
``r`` around a centre line of length ``L``): ``t`` runs from ``-pi r / 2``
(pole at the start) through ``[0, L]`` (the cylinder, where ``t`` equals the
arc length ``s`` along the centre line) to ``L + pi r / 2`` (pole at the
end). ``theta`` in ``[0, 2 pi)`` is the angle around the centre line,
measured from the normal of a parallel-transported (twist-free) frame, so it
is the same material direction in every pose.

``"creature"`` (:func:`creature`): each vertex comes from a unit vector
``u``, stored as ``params[i] = (polar angle, azimuth)`` about the z axis. A
fixed conformal map sends ``u`` to the creature's rest pose (body sphere
scaled; each limb's cap of the sphere stretched along the limb), and the
poses bend the limbs.

Bumps, radius profiles and poses are functions of the chart only, so every
pose and every resolution of a family samples one surface, and poses of one
resolution share vertices, faces and ``params`` exactly (their ground truth
is the identity).

The package holds one module per family, on the shared pieces:
:mod:`~meshcorr.evaluation.datasets.shape` (:class:`SyntheticShape` and the
parameter checks), :mod:`~meshcorr.evaluation.datasets.capsule` (the capsule
chart of the tube and the figure), :mod:`~meshcorr.evaluation.datasets.tubes`,
:mod:`~meshcorr.evaluation.datasets.figures`,
:mod:`~meshcorr.evaluation.datasets.creatures`,
:mod:`~meshcorr.evaluation.datasets.spheres`,
:mod:`~meshcorr.evaluation.datasets.truth` (ground truths, rigid copies) and
:mod:`~meshcorr.evaluation.datasets.example` (the bundled pair); the public
names are all here (``meshcorr.datasets.<name>``).
"""

from __future__ import annotations

from .creatures import creature
from .example import save_example_pair
from .figures import figure
from .shape import SyntheticShape
from .spheres import sphere
from .truth import ground_truth, rigid_copy
from .tubes import tube

__all__ = [
    "SyntheticShape",
    "creature",
    "figure",
    "ground_truth",
    "rigid_copy",
    "save_example_pair",
    "sphere",
    "tube",
]
