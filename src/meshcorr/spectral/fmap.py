"""Functional maps: a vertex map written in Laplace-Beltrami bases, and back.

A vertex map :math:`T` from the source :math:`S` to the target :math:`T`
(``mapping[i]`` = target vertex of source vertex i) pulls functions back,
:math:`f_S = f_T \\circ T = \\Pi f_T` with the ``(n_S, n_T)`` matrix
:math:`\\Pi_{i, T(i)} = 1`. In the first ``k`` Laplace-Beltrami
eigenfunctions of each mesh, :math:`\\Phi_S` and :math:`\\Phi_T`, the
*functional map* is the ``(k_S, k_T)`` matrix (Ovsjanikov et al.,
"Functional maps", SIGGRAPH 2012)

.. math::

    C = \\Phi_S^{+} \\, \\Pi \\, \\Phi_T = \\Phi_S^\\top M_S \\, \\Phi_T[T],

which maps the coefficients of a target function to those of its pull-back
on the source (:math:`a_S = C a_T`); :math:`M_S` is the lumped (barycentric)
mass matrix and the bases are :math:`M`-orthonormal,
:math:`\\Phi^\\top M \\Phi = I`, each mesh scaled to unit area (as pyFM's
``TriMesh(..., area_normalize=True)``), so that :math:`C` is orthogonal for
an isometry whatever the meshes' sizes. Back to a vertex
map: :math:`T(i) = \\arg\\min_j \\lVert (\\Phi_S C)_i - (\\Phi_T)_j \\rVert`.

Conventions compared with pyFM: pyFM's ``p2p_21[i]`` is the vertex of mesh 1
matched to vertex i of mesh 2, and ``FM_12 = evects2^+ Pi_21 evects1`` maps
functions on mesh 1 to mesh 2. meshcorr's ``mapping`` is therefore pyFM's
``p2p_21`` with mesh 1 = meshcorr's *target* and mesh 2 = meshcorr's
*source*, and ``C`` is pyFM's ``FM_12`` for that naming. A functional map
only means something together with its bases (eigenvector signs differ
between tools): :meth:`FunctionalMap.save` writes ``C``, both bases, their
eigenvalues and masses, so that another tool can use them as they are.
"""

from __future__ import annotations

import os
from dataclasses import dataclass

import numpy as np

from ..runtime.checks import check_int
from ..errors import InputError, ParameterError
from ..core.mesh import Mesh
from ..runtime.checks import check_vertex_map
from ..io.arrays import read_npz, write_npz
from .basis import laplace_basis
from .nearest import nearest_rows

__all__ = ["FunctionalMap", "laplace_beltrami", "functional_map", "point_map"]


def laplace_beltrami(mesh: Mesh, k: int, *, random_state: int | None = 0
                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The first ``k`` Laplace-Beltrami eigenpairs of the mesh scaled to unit area, and its mass.

    Parameters
    ----------
    mesh : Mesh
    k : int
        Basis size (<= n_vertices - 1).
    random_state : int or None
        Seed of the eigensolver's start vector.

    Returns
    -------
    eigenvalues : (k,) float
        Ascending, of :math:`L \\phi = \\lambda M \\phi` (cotangent Laplacian, unit area).
    basis : (n, k) float, read-only
        :math:`\\Phi^\\top M \\Phi = I` for the mass below; signs by
        :func:`meshcorr.spectral.embedding.sign_convention` (:func:`meshcorr.spectral.basis.laplace_basis`).
    mass : (n,) float
        Lumped (barycentric) vertex areas divided by the total area: they sum to 1
        (:func:`meshcorr.core.laplacian.vertex_areas`, also for point clouds).
    """
    from ..core.laplacian import vertex_areas

    k = check_int("k", k, minimum=2, maximum=max(2, mesh.n_vertices - 1))  # named as here, not as refine_k
    values, basis = laplace_basis(mesh, k, random_state=random_state)
    mass = vertex_areas(mesh)  # of a point cloud: its Laplacian's (meshcorr.core.laplacian)
    return values, basis, mass / mass.sum()


@dataclass(frozen=True)
class FunctionalMap:
    """A functional map and the bases it is written in (module docstring).

    Attributes
    ----------
    C : (k_source, k_target) float
        Target coefficients to source coefficients: :math:`a_S = C a_T`.
    source_basis : (n_source, k_source) float
    target_basis : (n_target, k_target) float
    source_eigenvalues : (k_source,) float
    target_eigenvalues : (k_target,) float
    source_mass : (n_source,) float
    target_mass : (n_target,) float
    """

    C: np.ndarray
    source_basis: np.ndarray
    target_basis: np.ndarray
    source_eigenvalues: np.ndarray
    target_eigenvalues: np.ndarray
    source_mass: np.ndarray
    target_mass: np.ndarray

    def point_map(self) -> np.ndarray:
        """The vertex map of :math:`C`: ``(n_source,)`` int, the nearest target row of :math:`\\Phi_S C`."""
        return point_map(self.C, self.source_basis, self.target_basis)

    def transfer(self, values: np.ndarray) -> np.ndarray:
        """Pull per-vertex target values back to the source through :math:`C`.

        Parameters
        ----------
        values : (n_target,) or (n_target, c) float

        Returns
        -------
        pulled : (n_source,) or (n_source, c) float
            :math:`\\Phi_S C \\Phi_T^\\top M_T f`: the smooth (band-limited)
            part of ``values`` carried to the source.
        """
        values = np.asarray(values, dtype=np.float64)
        if values.ndim not in (1, 2) or len(values) != len(self.target_basis):
            raise ParameterError(f"transfer needs one value (or row) per target vertex ({len(self.target_basis)}); "
                                 f"got shape {values.shape}.")
        coefficients = self.target_basis.T @ (self.target_mass.reshape((-1,) + (1,) * (values.ndim - 1)) * values)
        return self.source_basis @ (self.C @ coefficients)

    def save(self, path: str | os.PathLike) -> None:
        """Write every array to one ``.npz`` file, atomically (names as the attributes)."""
        write_npz(path, {name: getattr(self, name) for name in self.__dataclass_fields__})

    @classmethod
    def load(cls, path: str | os.PathLike) -> "FunctionalMap":
        """Read a file written by :meth:`save` (or by another tool with the same array names).

        Raises
        ------
        InputError
            If the file is missing, unreadable, lacks an array or its shapes disagree.
        """
        arrays = read_npz(path, "a functional map file")  # ParameterError if missing or unreadable
        missing = [name for name in cls.__dataclass_fields__ if name not in arrays]
        if missing:
            raise InputError(f"{path} lacks the array {missing[0]!r}; a functional map file holds "
                                 f"{', '.join(cls.__dataclass_fields__)}.")
        arrays = {name: arrays[name] for name in cls.__dataclass_fields__}
        C, phi_s, phi_t = arrays["C"], arrays["source_basis"], arrays["target_basis"]
        if C.ndim != 2 or phi_s.ndim != 2 or phi_t.ndim != 2 or C.shape != (phi_s.shape[1], phi_t.shape[1]):
            raise InputError(f"{path}: C has shape {C.shape} but the bases have shapes {phi_s.shape} "
                                 f"and {phi_t.shape}; C must be (source basis size, target basis size).")
        return cls(**arrays)


def functional_map(source: Mesh, target: Mesh, mapping: np.ndarray, k: int = 30, *,
                   k_target: int | None = None, random_state: int | None = 0) -> FunctionalMap:
    """The functional map of a vertex map, :math:`C = \\Phi_S^\\top M_S \\Phi_T[T]`.

    Parameters
    ----------
    source, target : Mesh
    mapping : (n_source,) int
        Target vertex of each source vertex (numbering of these meshes);
        -1 rows (unmapped) are left out of the projection.
    k : int
        Source basis size (and the target's unless ``k_target``).
    k_target : int, optional
    random_state : int or None
        Seed of the eigensolvers.

    Returns
    -------
    fmap : FunctionalMap

    Raises
    ------
    ParameterError
        A basis size outside [1, n_vertices - 1] or a map that does not fit the meshes.
    """
    k = check_int("k", k, minimum=1, maximum=max(1, min(source.n_vertices, target.n_vertices) - 1))
    k_target = k if k_target is None else check_int("k_target", k_target, minimum=1,
                                                    maximum=max(1, target.n_vertices - 1))
    mapping = check_vertex_map(mapping, source.n_vertices, target.n_vertices)
    values_s, phi_s, mass_s = laplace_beltrami(source, max(k, 2), random_state=random_state)
    values_t, phi_t, mass_t = laplace_beltrami(target, max(k_target, 2), random_state=random_state)
    phi_s, phi_t, values_s, values_t = phi_s[:, :k], phi_t[:, :k_target], values_s[:k], values_t[:k_target]
    mapped = mapping >= 0
    C = phi_s[mapped].T @ (mass_s[mapped, None] * phi_t[mapping[mapped]])
    return FunctionalMap(C=C, source_basis=phi_s, target_basis=phi_t, source_eigenvalues=values_s,
                         target_eigenvalues=values_t, source_mass=mass_s, target_mass=mass_t)


def point_map(C: np.ndarray, source_basis: np.ndarray, target_basis: np.ndarray) -> np.ndarray:
    """The vertex map of a functional map: ``T(i) = argmin_j || (Phi_S C)_i - (Phi_T)_j ||``.

    Parameters
    ----------
    C : (k_source, k_target) float
    source_basis : (n_source, k_source) float
    target_basis : (n_target, k_target) float

    Returns
    -------
    mapping : (n_source,) int
    """
    C = np.asarray(C, dtype=np.float64)
    if C.shape != (source_basis.shape[1], target_basis.shape[1]):
        raise ParameterError(f"C has shape {C.shape} but the bases have {source_basis.shape[1]} and "
                             f"{target_basis.shape[1]} columns; C must be (k_source, k_target).")
    for name, array in (("C", C), ("source_basis", source_basis), ("target_basis", target_basis)):
        if not np.isfinite(array).all():  # NaN distances made every vertex map to vertex 0
            raise ParameterError(f"{name} holds NaN or infinite values; a functional map needs finite numbers.")
    return nearest_rows(np.asarray(source_basis) @ C, np.asarray(target_basis))
