"""Shapiro & Brady's eigenvector correspondence, and its "improved" variant.

The first baseline of Jain & Zhang (2006), built from the same spectral
blocks as the main method (:mod:`meshcorr.spectral.spectrum`, :mod:`meshcorr.stages.reorder`,
:mod:`meshcorr.stages.anchors`) with the later stages switched off:

1. Gaussian affinities of all-pairs geodesic distances on each mesh,
   :math:`A_{ij} = \\exp(-D_{ij}^2 / 2\\sigma^2)`, :math:`\\sigma` the largest
   geodesic distance;
2. the top ``k`` eigenvectors, the first dropped: *unscaled* for
   Shapiro & Brady, scaled by :math:`\\sqrt{\\lambda}` for the improved
   variant (``shapiro-brady-scaled``);
3. eigenvalue order kept (no reordering); signs fixed greedily one
   eigenvector at a time by the nearest-neighbour cost
   (``reorder="signs-greedy"``);
4. no thin-plate-spline ICP, no anchors: :math:`C(i) = \\arg\\min_j
   \\lVert X_i - Y_j \\rVert` (or a linear assignment with ``bijective``).

References
----------
L. S. Shapiro, J. M. Brady, "Feature-based correspondence: an eigenvector
approach", Image and Vision Computing 10(5):283-288, 1992.
V. Jain, H. Zhang, "Robust 3D shape correspondence in the spectral domain",
Shape Modeling International 2006 (the scaled "improved" variant, sec. 4).
"""

from __future__ import annotations

from ..runtime.checks import check_choice, check_int
from ..core.geodesics import GEODESIC_METHODS
from ..core.mesh import MeshLike
from ..stages.reorder import rank_configurations
from ..maps.result import Correspondence
from ..spectral.spectrum import dense_spectrum
from ..runtime.timing import StageProgress, StageTimer
from ._common import finish, load_pair, nearest_map
from ..core.geodesics import DEFAULT_GEODESIC
from ..spectral.embedding import N_EIGENPAIRS


def _shapiro_brady(method: str, source: MeshLike, target: MeshLike, *, scale: bool, k: int, geodesic: str,
                   bijective: bool, largest_component: bool, random_state: int | None,
                   progress: StageProgress | None) -> Correspondence:
    k = check_int("k", k, minimum=2, maximum=10)
    check_choice("geodesic", geodesic, GEODESIC_METHODS)
    timer = StageTimer(progress)
    why = f"The spectral embedding with k={k} needs at least {k + 2} vertices."
    src, tgt = load_pair(source, target, largest_component=largest_component, timer=timer,
                         min_vertices=k + 2, reason=why)
    spectra = [dense_spectrum(mesh, k=k, geodesic=geodesic, scale=scale, random_state=random_state,
                              timer=timer) for mesh in (src, tgt)]
    X, Y = spectra[0].embedding, spectra[1].embedding
    with timer.stage("reorder"):
        configurations = rank_configurations(X, Y, "signs-greedy", random_state=random_state)
        Y_configured = configurations[0].apply(Y)
    with timer.stage("matching"):
        local_map, local_cost = nearest_map(X, Y_configured, bijective=bijective)
    params = dict(k=k, geodesic=geodesic, scale_eigenvalues=scale, reorder="signs-greedy",
                  bijective=bijective, largest_component=largest_component, random_state=random_state)
    return finish(method, src, tgt, local_map, local_cost, timer, params,
                  source_embedding=X, target_embedding=Y_configured,
                  eigenvalues={"source": spectra[0].eigenvalues, "target": spectra[1].eigenvalues},
                  configuration=configurations[0], alternatives=configurations)


def match_shapiro_brady(source: MeshLike, target: MeshLike, *, k: int = N_EIGENPAIRS, geodesic: str = DEFAULT_GEODESIC,
                        bijective: bool = False, largest_component: bool = False,
                        random_state: int | None = 0, progress: StageProgress | None = None) -> Correspondence:
    """Shapiro & Brady: unscaled eigenvectors, greedy signs, nearest match.

    Parameters
    ----------
    source, target : path, trimesh.Trimesh, Mesh or (vertices, faces)
    k : int
        Eigenpairs computed; the embedding has ``k - 1`` dimensions.
    geodesic : {"heat", "fmm", "exact", "dijkstra"}
        Geodesic solver.
    bijective : bool
        One-to-one map by linear assignment (equal vertex counts only).
    largest_component : bool
        Map only the largest connected component of each mesh.
    random_state : int or None
        Seed of the eigensolver start and the sign-fixing sample.
    progress : callable, optional
        ``progress(stage, done, total)``.

    Returns
    -------
    result : Correspondence
        ``method="shapiro-brady"``; ``cost`` is the embedding distance of
        each pair; embeddings, eigenvalues and the sign configuration are
        filled in.
    """
    return _shapiro_brady("shapiro-brady", source, target, scale=False, k=k, geodesic=geodesic,
                          bijective=bijective, largest_component=largest_component,
                          random_state=random_state, progress=progress)


def match_shapiro_brady_scaled(source: MeshLike, target: MeshLike, *, k: int = N_EIGENPAIRS, geodesic: str = DEFAULT_GEODESIC,
                               bijective: bool = False, largest_component: bool = False,
                               random_state: int | None = 0,
                               progress: StageProgress | None = None) -> Correspondence:
    """Improved Shapiro & Brady: as :func:`match_shapiro_brady` with eigenvectors scaled by sqrt(eigenvalue).

    Parameters and result as :func:`match_shapiro_brady` (``method="shapiro-brady-scaled"``).
    """
    return _shapiro_brady("shapiro-brady-scaled", source, target, scale=True, k=k, geodesic=geodesic,
                          bijective=bijective, largest_component=largest_component,
                          random_state=random_state, progress=progress)
