"""An orientation-preserving dense map from a few matched points: a functional-map fit.

The landmark-distance map of :mod:`meshcorr.stages.landmarks` cannot tell a
map from its mirror image through any plane that holds the landmarks: the
tips of a person (head, hands, feet) lie near one plane, and front and back
have the same geodesic distances to them. Orientation can tell them apart.
This module fits a functional map (Ovsjanikov et al., "Functional maps",
SIGGRAPH 2012) :math:`C`, ``(k, k)``, taking a target function's
coefficients in the first ``k`` Laplace-Beltrami eigenfunctions
:math:`\\Phi_T` to those of its pull-back on the source
(:math:`a_S = C a_T`, as in :mod:`meshcorr.spectral.fmap`), minimising

.. math::

    \\lVert C B - A \\rVert^2
    + w_\\Lambda \\lVert C \\Lambda_T - \\Lambda_S C \\rVert^2
    + w_O \\sum_d \\lVert C O_T^{d} - O_S^{d} C \\rVert^2,

- **descriptor preservation**: the columns of :math:`A` and :math:`B` are
  the coefficients of matching descriptors, functions of the geodesic
  distance to each matched point (the distance, and Gaussians of it at three
  widths);
- **Laplacian commutativity** with the diagonal eigenvalue matrices (an
  isometry commutes with the Laplace-Beltrami operator; Ovsjanikov et al.
  2012);
- **orientation-preserving operator commutativity** (Ren, Poulenard, Wonka
  and Ovsjanikov, "Continuous and orientation-preserving correspondences via
  functional maps", SIGGRAPH Asia 2018, section 4): for a descriptor
  :math:`d`, the operator :math:`O^d(h) = \\langle n \\times \\nabla d,
  \\nabla h \\rangle` (the derivative of ``h`` across the level lines of
  ``d``) commutes with a map that keeps the orientation and anti-commutes
  with one that reverses it; :math:`O^d` is written in each basis as
  :math:`O_{ab} = \\int \\phi_a \\langle n \\times \\nabla d, \\nabla \\phi_b
  \\rangle`, with face-wise gradients on the outward-oriented mesh. A point
  cloud has no faces: its operators are zero, and the fit keeps the first
  two terms (the orientation of the candidate is then judged by its score
  on the estimated normals, :mod:`meshcorr.choice.selection`).

The energy is quadratic in :math:`C`: its ``k^2`` normal equations are
solved directly (``k = 20``: a 400 x 400 system). The vertex map is the
nearest row of :math:`\\Phi_T` for each row of :math:`\\Phi_S C`; it is
coarse and is refined like the other candidates (:mod:`meshcorr.stages.refine`).
Written here because no maintained library offers this fit on its own
(pyFM's solver is bound to its own mesh and descriptor classes).
"""

from __future__ import annotations

import numpy as np

from ..stages.landmarks import RowFn, landmark_descriptors
from ..core.laplacian import vertex_areas
from ..core.mesh import Mesh
from ..core.orientation import mesh_orientation
from ..spectral.basis import laplace_basis
from ..spectral.nearest import nearest_rows

#: Basis size of the fit.
K_FIT = 20
#: Widths of the Gaussian descriptors, in units of the mean landmark distance.
WIDTHS = (0.25, 0.5, 1.0)
#: Weights of the Laplacian and orientation terms (each term normalised, see :func:`fit_oriented_map`).
W_LAPLACIAN = 1e-2
W_ORIENTATION = 0.3


def descriptors(geodesics_from: RowFn, points: np.ndarray) -> np.ndarray:
    """``(n, 4 L)``: the distance to each of ``points`` (divided by the mean) and Gaussians of it."""
    distance = landmark_descriptors(geodesics_from, points)
    return np.hstack([distance] + [np.exp(-(distance / w) ** 2) for w in WIDTHS])


def _face_gradients(vertices: np.ndarray, faces: np.ndarray, values: np.ndarray) -> tuple:
    """Face-wise gradients ``(m, 3, c)`` of vertex functions ``values`` ``(n, c)``, unit normals ``(m, 3)``, areas ``(m,)``.

    On a triangle with unit normal :math:`n` and area :math:`A`,
    :math:`\\nabla f = \\frac{1}{2A} \\sum_i f_i \\, (n \\times e_i)` with
    :math:`e_i` the edge opposite corner i, counter-clockwise.
    """
    v = vertices[faces]
    cross = np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0])
    double_area = np.linalg.norm(cross, axis=1)
    normal = cross / np.maximum(double_area, 1e-300)[:, None]
    gradient = 0.0
    for corner in range(3):
        edge = v[:, (corner + 2) % 3] - v[:, (corner + 1) % 3]
        rotated = np.cross(normal, edge) / np.maximum(double_area, 1e-300)[:, None]
        gradient = gradient + rotated[:, :, None] * values[faces[:, corner]][:, None, :]
    return gradient, normal, 0.5 * double_area


def _basis_gradients(mesh: Mesh, basis: np.ndarray) -> tuple:
    """The basis-dependent part of :func:`orientation_operators`, cached on the mesh.

    Returns the outward faces ``(m, 3)``, the unit-area vertices ``(n, 3)``,
    the basis gradients ``(m, 3, k)``, the face normals ``(m, 3)`` and the
    face weights ``(m, k)`` (face area times the basis averaged on the face).
    """
    key = ("orientation_operator_basis", basis.shape, hash(basis[::max(1, len(basis) // 64)].tobytes()))
    if key not in mesh.store:
        faces = mesh_orientation(mesh).faces
        vertices = np.asarray(mesh.vertices) / np.sqrt(mesh.area)
        gradients, normal, area = _face_gradients(vertices, faces, basis)
        mesh.store.put(key, (faces, vertices, gradients, normal, area[:, None] * basis[faces].mean(axis=1)))
    return mesh.store[key]


def orientation_operators(mesh: Mesh, basis: np.ndarray, functions: np.ndarray) -> np.ndarray:
    """``(c, k, k)``: each function's operator :math:`O^d` in ``basis`` (module docstring).

    Parameters
    ----------
    mesh : Mesh
        Scaled to unit area inside (the basis is unit-area normalised).
    basis : (n, k) float
    functions : (n, c) float
    """
    faces, vertices, grad_basis, normal, weight = _basis_gradients(mesh, np.asarray(basis))
    grad_functions = _face_gradients(vertices, faces, np.asarray(functions))[0]
    across = np.cross(normal[:, :, None], grad_functions, axis=1)  # n x grad d: (m, 3, c)
    inner = np.matmul(across.transpose(0, 2, 1), grad_basis)       # <n x grad d, grad phi_b>: (m, c, k)
    m, c, k = inner.shape
    return (weight.T @ inner.reshape(m, c * k)).reshape(k, c, k).transpose(1, 0, 2)


def _commutator_normal(o_s: np.ndarray, o_t: np.ndarray) -> np.ndarray:
    """:math:`M^T M` for :math:`M = O_t^T \\otimes I - I \\otimes O_s`, the map ``vec(C) -> vec(C O_t - O_s C)``.

    Expanded with :math:`(A \\otimes B)^T (C \\otimes D) = A^T C \\otimes B^T D`,
    without forming the ``(k^2, k^2)`` matrix :math:`M`.
    """
    eye = np.eye(len(o_s))
    return (np.kron(o_t @ o_t.T, eye) + np.kron(eye, o_s.T @ o_s)
            - np.kron(o_t, o_s) - np.kron(o_t.T, o_s.T))


def fit_oriented_map(source: Mesh, target: Mesh, source_geodesics: RowFn, target_geodesics: RowFn,
                     pairs: np.ndarray, *, k: int = K_FIT, basis_k: int = 40,
                     random_state: int | None = 0) -> np.ndarray:
    """Dense source -> target vertex map from matched points, orientation kept (module docstring).

    Parameters
    ----------
    source, target : Mesh
    source_geodesics, target_geodesics : callable
        ``f(i)``: geodesic distances from vertex i on that shape, ``(n,)``.
    pairs : (L, 2) int
        Matched (source vertex, target vertex) pairs, L >= 1.
    k : int
        Basis size of the fit (clipped to the meshes' vertex counts).
    basis_k : int
        Size of the Laplace-Beltrami basis computed (and cached on the
        meshes) of which the fit takes the first ``k``: the refinement's.
    random_state : int or None
        Seed of the eigensolver start.

    Returns
    -------
    mapping : (n1,) int
        The matched source vertices go exactly to their target vertices.
    """
    pairs = np.asarray(pairs, dtype=np.int64)
    basis_k = int(min(max(k, basis_k), source.n_vertices - 1, target.n_vertices - 1))
    k = min(k, basis_k)
    (lam_s, phi_s), (lam_t, phi_t) = ((values[:k], vectors[:, :k]) for values, vectors in
                                      (laplace_basis(m, basis_k, random_state=random_state)
                                       for m in (source, target)))
    d_s = descriptors(source_geodesics, pairs[:, 0])
    d_t = descriptors(target_geodesics, pairs[:, 1])
    mass_s, mass_t = _unit_masses(source), _unit_masses(target)
    A = phi_s.T @ (mass_s[:, None] * d_s)
    B = phi_t.T @ (mass_t[:, None] * d_t)
    scale = np.linalg.norm(B, axis=0) + 1e-12  # every descriptor weighs the same
    A, B = A / scale, B / scale
    n_distance = len(pairs)  # the raw distances: one operator each
    O_s = orientation_operators(source, phi_s, d_s[:, :n_distance])
    O_t = orientation_operators(target, phi_t, d_t[:, :n_distance])
    eye = np.eye(k)
    # vec(C X) = (X^T kron I) vec(C), vec(Y C) = (I kron Y) vec(C), column-major vec.
    H = np.kron(B @ B.T, eye)
    rhs = (A @ B.T).ravel(order="F")
    lam = np.concatenate([lam_s, lam_t])
    lam_scale = max(float(lam.max()), 1e-12)
    diag = (np.kron(lam_t, np.ones(k)) - np.kron(np.ones(k), lam_s)) / lam_scale
    H += W_LAPLACIAN * np.diag(diag ** 2) * np.trace(H) / k
    orientation = np.zeros((k * k, k * k))
    for o_s, o_t in zip(O_s, O_t):
        norm = 0.5 * (np.linalg.norm(o_s) + np.linalg.norm(o_t)) + 1e-12
        orientation += _commutator_normal(o_s / norm, o_t / norm)
    H += W_ORIENTATION * orientation * np.trace(H) / max(np.trace(orientation), 1e-12)
    C = np.linalg.solve(H + 1e-9 * np.trace(H) / (k * k) * np.eye(k * k), rhs).reshape((k, k), order="F")
    mapping = nearest_rows(phi_s @ C, phi_t)
    mapping[pairs[:, 0]] = pairs[:, 1]
    return mapping


def _unit_masses(mesh: Mesh) -> np.ndarray:
    """Lumped vertex areas summing to 1: the bases' mass matrix (a mesh's or a point cloud's)."""
    areas = vertex_areas(mesh)
    return areas / areas.sum()
