"""Smoothed signed mean curvature: a descriptor that tells front from back.

On a thin, left/right-symmetric shape (a person), a map that turns the body
half a turn about its long axis (front to back and left to right) preserves
orientation, and it is almost an isometry: geodesic distances on a thin
body barely see front from back. Orientation and metric distortion cannot
reject it (:mod:`meshcorr.choice.symmetry`); curvature can: a nose, a knee cap or
the toes are convex where the back of the head, the back of the knee or
the heel are flatter or concave.

The signed mean curvature :math:`H` comes from the mean-curvature normal,
:math:`\\Delta x = -2 H n` for the Laplace-Beltrami operator applied to
the coordinate functions (Meyer, Desbrun, Schroeder & Barr, "Discrete
differential-geometry operators for triangulated 2-manifolds", 2003):

.. math::

    H_i = \\tfrac{1}{2} \\langle (M^{-1} L X)_i, n_i \\rangle \\sqrt{A}

with the cotangent Laplacian :math:`L` (positive semi-definite), the lumped
mass :math:`M`, the outward vertex normals :math:`n` and the total area
:math:`A` (the factor makes :math:`H` scale-invariant): positive on convex
parts. It is invariant to rigid motions and uniform scaling and changes
under bending only near the joints. Clipped to its 1st-99th percentiles
(badly shaped triangles give spikes), it is averaged over Euclidean balls
of radius :math:`r \\sqrt{A}`, weighted by vertex area (the curvature
integrated over the ball divided by the ball's area: the same on a coarse
and a finely subdivided mesh), at a few radii, and standardised by its mean
and standard deviation over an area-weighted vertex sample (on an open mesh
the boundary vertices, where the Laplacian of the coordinates is one-sided
and no curvature, get no weight), so that two
meshes of different resolution and size compare. Evaluating it only at a
sample of source vertices and their images keeps the cost independent of
the mesh size (balls hold more vertices on finer meshes; a sparse
diffusion solve instead took ~40 s per mesh at 115k vertices).
"""

from __future__ import annotations

import itertools

import numpy as np
from scipy.spatial import cKDTree

from ..runtime.checks import check_int
from ..core.boundary import mesh_boundary
from ..errors import ParameterError
from ..core.mesh import Mesh
from ..core.laplacian import laplacian
from ..core.orientation import oriented_normals

#: Ball radii, as fractions of sqrt(area), over which the curvature is averaged.
CURVATURE_RADII = (0.045,)


def signed_mean_curvature(mesh: Mesh) -> tuple[np.ndarray, np.ndarray]:
    """Scale-free signed mean curvature per vertex, and the lumped vertex areas.

    Parameters
    ----------
    mesh : Mesh
        Its winding is repaired and turned outwards internally
        (:func:`meshcorr.core.orientation.mesh_orientation`). A point cloud uses
        its estimated outward normals and its cloud Laplacian
        (:func:`meshcorr.core.orientation.oriented_normals`,
        :func:`meshcorr.core.laplacian.laplacian`): the same formula, with
        :math:`L` and :math:`M` of the cloud.

    Returns
    -------
    curvature : (n,) float
        :math:`H_i \\sqrt{A}` (module docstring): :math:`2 \\sqrt{\\pi}` on a
        sphere, positive where the surface is convex.
    mass : (n,) float
        Lumped (barycentric) vertex areas.
    """
    V = np.asarray(mesh.vertices, dtype=float)
    normals, mass = oriented_normals(mesh)
    L = laplacian(mesh)[0]
    safe = np.where(mass > 0, mass, mass[mass > 0].min() if (mass > 0).any() else 1.0)
    H = 0.5 * np.einsum("ij,ij->i", (L @ V) / safe[:, None], normals) * np.sqrt(mass.sum())
    return H, mass


#: Meshes of more vertices average the curvature over balls of a seeded uniform sample of this many
#: vertices (each weighted by its area: the same ratio of integrals, estimated), so that a ball's cost
#: stops growing with the vertex count (a 1.28M-vertex mesh: ~8000 vertices a ball, ~1 s a candidate).
FIELD_MAX = 200_000


def _curvature_field(mesh: Mesh, signed: bool = True
                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray, cKDTree, float]:
    """Clipped curvature (its absolute value unless ``signed``) at every vertex; the vertices the
    balls sum over (all, or :data:`FIELD_MAX` of them), their curvature and areas in a KD-tree; and
    sqrt(area). Cached on the mesh."""
    key = ("curvature_field",) if signed else ("curvature_field", "unsigned")
    if key not in mesh.store:
        H, mass = signed_mean_curvature(mesh)
        # On a boundary the Laplacian of the coordinates is one-sided, not a curvature: those
        # vertices get no weight in the ball averages (a ball of boundary vertices only keeps them).
        mass = np.where(_on_boundary(mesh), 0.0, mass)
        interior = mass > 0
        H = H if signed else np.abs(H)
        H = np.clip(H, *np.percentile(H[interior] if interior.any() else H, [1.0, 99.0]))
        kept = np.arange(mesh.n_vertices)
        if mesh.n_vertices > FIELD_MAX:
            kept = np.sort(np.random.default_rng(0).choice(mesh.n_vertices, size=FIELD_MAX, replace=False))
        tree = cKDTree(np.asarray(mesh.vertices, dtype=float)[kept])
        mesh.store.put(key, (H, H[kept], mass[kept], tree, float(np.sqrt(mass.sum()))))
    return mesh.store[key]


def _on_boundary(mesh: Mesh) -> np.ndarray:
    """``(n,)`` bool: vertices on an edge that only one face uses."""
    boundary = np.zeros(mesh.n_vertices, dtype=bool)
    boundary[mesh_boundary(mesh).vertices] = True  # cached on the mesh: the partiality check uses it too
    return boundary


def smoothed_curvature(mesh: Mesh, vertices: np.ndarray, radius: float, *, signed: bool = True) -> np.ndarray:
    """Average signed mean curvature (or its absolute value) over balls around some vertices.

    Parameters
    ----------
    mesh : Mesh
    vertices : (s,) int
        Where to evaluate.
    radius : float
        Ball radius as a fraction of :math:`\\sqrt{A}`.
    signed : bool
        Average :math:`H`; False: :math:`|H|` (see :func:`curvature_disagreement`).

    Returns
    -------
    curvature : (s,) float
        :math:`\\sum_{j \\in B_i} m_j H_j / \\sum_{j \\in B_i} m_j` over the
        vertices :math:`j` within Euclidean distance ``radius`` of vertex
        :math:`i` (module docstring): the curvature integrated over the ball
        divided by its area, so that meshes of different resolution agree.
        Above :data:`FIELD_MAX` vertices, :math:`j` runs over a seeded
        uniform sample of that many vertices.
    """
    H, field, mass, tree, length = _curvature_field(mesh, signed)
    vertices = np.asarray(vertices, dtype=np.int64)
    if vertices.size == 0:
        return np.zeros(0)
    balls = tree.query_ball_point(np.asarray(mesh.vertices)[vertices], radius * length, return_sorted=False)
    sizes = np.fromiter((len(b) for b in balls), dtype=np.int64, count=len(balls))
    members = np.fromiter(itertools.chain.from_iterable(balls), dtype=np.int64, count=int(sizes.sum()))
    starts = np.concatenate([[0], np.cumsum(sizes)[:-1]])
    weight = np.add.reduceat(mass[members], starts)
    total = np.add.reduceat(mass[members] * field[members], starts)
    # A ball of boundary vertices only (no weight): its centre's own value.
    return np.where(weight > 0, total / np.where(weight > 0, weight, 1.0), H[vertices])


#: Meshes of at most this many vertices get :func:`smoothed_curvature` at every vertex once, cached
#: (:func:`mapped_curvature`): a pair's candidate maps look up ~10 x 1000 mapped vertices, more than
#: the 5k of a TOSCA shape; larger meshes are evaluated at the mapped vertices only.
CURVATURE_TABLE_MAX = 20_000


def mapped_curvature(mesh: Mesh, vertices: np.ndarray, radius: float, *, signed: bool = True) -> np.ndarray:
    """:func:`smoothed_curvature` at ``vertices``, from a per-mesh table when the mesh is small enough.

    Parameters
    ----------
    mesh : Mesh
    vertices : (s,) int
    radius : float
        As :func:`smoothed_curvature`.
    signed : bool
        As :func:`smoothed_curvature`.

    Returns
    -------
    curvature : (s,) float
        The same values as ``smoothed_curvature(mesh, vertices, radius)``, bit for bit: each
        ball is found and summed alone, whatever the other vertices asked. Up to
        :data:`CURVATURE_TABLE_MAX` vertices they come from a table of every vertex, cached on the
        mesh (and saved with a :class:`~meshcorr.shapes.prepared.PreparedShape`).
    """
    vertices = np.asarray(vertices, dtype=np.int64)
    if mesh.n_vertices > CURVATURE_TABLE_MAX:
        return smoothed_curvature(mesh, vertices, radius, signed=signed)
    key = ("curvature_table", float(radius)) + (() if signed else ("unsigned",))
    if key not in mesh.store:
        table = smoothed_curvature(mesh, np.arange(mesh.n_vertices), radius, signed=signed)
        table.flags.writeable = False
        mesh.store.put(key, table)
    return mesh.store[key][vertices]


def curvature_disagreement(source: Mesh, target: Mesh, mapping: np.ndarray, *,
                           radii: tuple[float, ...] = CURVATURE_RADII, n_sample: int = 1000,
                           random_state: int | None = 0) -> float:
    """Mean difference of smoothed, standardised mean curvature across a map.

    Parameters
    ----------
    source, target : Mesh
    mapping : (n1,) int
        ``mapping[i]`` is the target vertex of source vertex i.
    radii : tuple of float
        Ball radii of :func:`smoothed_curvature`.
    n_sample : int
        Source vertices :math:`S` compared (a seeded area-weighted sample),
        and target vertices drawn the same way to standardise the target's
        curvature.
    random_state : int or None
        Seed of the samples.

    Returns
    -------
    disagreement : float
        :math:`\\frac{1}{|R||S|} \\sum_{r \\in R} \\sum_{i \\in S}
        |\\hat h^1_r(i) - \\hat h^2_r(f(i))|`, with :math:`\\hat h_r` the
        ball-averaged curvature standardised by its mean and standard
        deviation over the mesh's sample: about 0 for an exact copy, about
        1.1 (the mean absolute difference of two independent standard
        normal variables) for an unrelated map.

    Notes
    -----
    When either shape is a point cloud, both are compared by the unsigned
    curvature :math:`|H|`: a cloud's normals are estimated, and the
    estimate turns the wrong way on small parts thinner than its
    neighbourhoods (:mod:`meshcorr.core.normals`), which flips the sign of
    :math:`H` there. Measured on TOSCA michael3 and dog3 as vertex clouds,
    per-vertex correlation with the mesh's curvature: 0.57 and 0.50 signed
    with the estimated normals, 0.72 and 0.61 unsigned.
    """
    n_sample = check_int("n_sample", n_sample, minimum=2)
    mapping = np.asarray(mapping)
    if mapping.shape != (source.n_vertices,) or (mapping.size and (
            mapping.min() < 0 or mapping.max() >= target.n_vertices)):
        raise ParameterError(f"The map must hold one target vertex in [0, {target.n_vertices}) per "
                             f"source vertex ({source.n_vertices}). Got shape {mapping.shape}.")
    sample = _area_sample(source, n_sample, random_state)
    signed = not (source.is_cloud or target.is_cloud)
    total = 0.0
    for r in radii:
        h1, mean1, std1 = _sample_curvature(source, n_sample, random_state, r, signed)
        _, mean2, std2 = _sample_curvature(target, n_sample, random_state, r, signed)
        h2 = mapped_curvature(target, mapping[sample], r, signed=signed)
        total += float(np.abs((h1 - mean1) / std1 - (h2 - mean2) / std2).mean())
    return total / len(radii)


def _area_sample(mesh: Mesh, n: int, random_state: int | None) -> np.ndarray:
    """``n`` vertices drawn with probability proportional to their area (all if fewer), cached."""
    key = ("area_sample", n, random_state)
    if key not in mesh.store:
        _, mass = oriented_normals(mesh)
        if mesh.n_vertices <= n:
            mesh.store.put(key, np.arange(mesh.n_vertices))
        else:
            rng = np.random.default_rng(random_state)
            mesh.store.put(key, np.sort(rng.choice(mesh.n_vertices, size=n, replace=False, p=mass / mass.sum())))
    return mesh.store[key]


def _sample_curvature(mesh: Mesh, n: int, random_state: int | None, radius: float, signed: bool = True
                      ) -> tuple[np.ndarray, float, float]:
    """:func:`smoothed_curvature` on the mesh's :func:`_area_sample`, its mean and standard deviation; cached."""
    key = ("sample_curvature", n, random_state, float(radius)) + (() if signed else ("unsigned",))
    if key not in mesh.store:
        values = smoothed_curvature(mesh, _area_sample(mesh, n, random_state), radius, signed=signed)
        mesh.store.put(key, (values, float(values.mean()), float(values.std()) or 1.0))
    return mesh.store[key]
