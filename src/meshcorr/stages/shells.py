"""Refinement of a vertex map in the product of spectral and embedding space (after Smooth Shells).

ZoomOut (:mod:`meshcorr.stages.refine`) maps each vertex to its nearest neighbour
in a 40-function Laplace-Beltrami basis. When the shapes are not isometric
(a gorilla and a man, two people of different builds) the higher
eigenfunctions of the two shapes stop corresponding, and the map slides
locally. The shapes themselves still say where a point goes once one is
deformed onto the other: this stage aligns the two surfaces *extrinsically*,
by a smooth deformation expressed in the same bases, coarse to fine.

It follows Smooth Shells (M. Eisenberger, Z. Lähner, D. Cremers, "Smooth
Shells: Multi-Scale Shape Registration with Functional Maps", CVPR 2020): a
shape's *shell* at scale :math:`k` is its coordinates low-passed to the first
:math:`k` eigenfunctions,

.. math::

    X_i^{(k)} = \\Phi_i^{(k)} \\Phi_i^{(k)\\top} M_i X_i ,

(coordinates scaled to unit area and centred; :math:`\\Phi_i^\\top M_i \\Phi_i = I`).
For :math:`k = k_0 < \\dots < K`, given the current map :math:`T`:

- **rigid motion**: the orthogonal motion and translation that best move the
  source shell onto the target shell's images (Kabsch, weighted by vertex
  area): the shapes may come in any position. It is a rotation when the
  given map keeps the orientation (:func:`meshcorr.core.map_orientation.orientation_score`
  >= 0.5, decided once for the whole map) and a reflection when it mirrors
  it (the deformed normals are then turned): the stage refines the map it is
  given, it does not choose between mirror images;
- **deformation**: the displacement the map still asks of the source shell,
  low-passed to the same :math:`k` functions (the least-squares smooth
  deformation in the span of :math:`\\Phi_1^{(k)}`),
  :math:`D = \\Phi_1^{(k)} \\Phi_1^{(k)\\top} M_1 (X_2^{(k)}[T] - X_1^{(k)})`,
  and the deformed shell :math:`Y = X_1^{(k)} + D`;
- **functional map**: :math:`C_k`, the orthogonal fit of
  :math:`\\Phi_1^{(k)} C \\approx \\Phi_2^{(k)}[T]` (as in ZoomOut);
- **new map**: each source vertex goes to the nearest target vertex in the
  product space
  :math:`[\\,Y,\\; w_n\\, n(Y),\\; w_s\\, \\Phi_1^{(k)} C_k\\,]` against
  :math:`[\\,X_2^{(k)},\\; w_n\\, n(X_2^{(k)}),\\; w_s\\, \\Phi_2^{(k)}\\,]`,
  with :math:`n(\\cdot)` the vertex normals of a shell. Given descriptors
  that should agree at corresponding points (the geodesic distances to the
  user's landmarks), they join both sides with weight :data:`DESCRIPTOR_WEIGHT`,
  as landmark distances join a functional map's descriptors (Ovsjanikov et
  al., "Functional maps", SIGGRAPH 2012, section 6).

A last step does the same with the coordinates themselves (:math:`k = K`,
no low pass). Unlike Smooth Shells this uses hard nearest-neighbour
assignments (no soft correspondences, no Markov-chain search for the
start): each start is a candidate map of the pipeline's whole-map choice
(every candidate that keeps the orientation is refined here before the
choice, :func:`meshcorr.choice.selection.shell_candidates`), and this stage only
refines it. The soft correspondences were measured and made no difference
(``benchmarks/RESULTS-robustness-trials.md``). The normals keep facing surfaces apart (an arm against the
body); the spectral term keeps the map on the part ZoomOut put it on.

A source that is a *part* of the target (``part_fraction`` r, the partial
mode of :mod:`meshcorr.pipeline.partial`) keeps the target's units, takes
:math:`\\lceil k / r \\rceil` functions on the target for :math:`k` on the part
(the slanted-diagonal spectrum of a part: Rodolà et al., "Partial functional
correspondence", CGF 2017), compares the spectral coordinates through the
projection of :func:`meshcorr.stages.partial_zoomout.partial_zoomout`, and starts at
:data:`PART_FIRST_SCALE` functions, the coarser shells of a part not
resembling the whole's.

Measured (``benchmarks/RESULTS-robustness.md``): on the development pairs of
every set the error from the same start drops by 20-30 % (TOSCA 5k
0.029 -> 0.021, gorilla -> human 0.12 -> 0.10, SHREC'07 humans 0.077 ->
0.058, four-legged 0.12 -> 0.09). The weights :data:`NORMAL_WEIGHT` and
:data:`SPECTRAL_WEIGHT` were chosen on those sets together
(``benchmarks/RESULTS-robustness-trials.md``).
"""

from __future__ import annotations

import numpy as np

from ..runtime.checks import check_float, check_int
from ..runtime.threads import parallel_map
from ..errors import ParameterError
from ..core.laplacian import vertex_areas
from ..core.mesh import Mesh
from ..core.orientation import mesh_orientation, vertex_normals
from ..core.map_orientation import orientation_score
from ..runtime.checks import check_vertex_map
from ..spectral.basis import basis_size, laplace_basis, orthogonal_fit, pair_bases
from ..spectral.nearest import nearest_vertices
from .refine import REFINE_K, REFINED_MAP

#: Weight of the shells' unit normals against coordinates of a unit-area shape.
NORMAL_WEIGHT = 0.3
#: Weight of the spectral coordinates (unit-area normalised eigenfunctions).
SPECTRAL_WEIGHT = 0.1
#: Weight of the landmark-distance descriptors (distances over their mean), when landmarks are given.
DESCRIPTOR_WEIGHT = 0.3
#: Basis sizes of the coarse-to-fine steps (clipped to the basis size): small, even steps let the
#: deformation follow proportions that differ (on 30 gorilla -> human pairs 0.125 -> 0.114 against a
#: coarser schedule 8, 12, 16, 24, 32, 40 followed by 16..40 on the chosen map alone;
#: ``benchmarks/RESULTS-robustness-trials.md``).
SCALES = tuple(range(6, 41, 2))
#: Source vertices sampled for the coarse steps (all of them below this).
N_SAMPLE = 1000
#: A part's first step (``part_fraction``): the coarser shells of a part and of the whole do not
#: correspond (measured on the partial cases of ``benchmarks/scans.py``: from 6 functions the maps
#: got worse, from 16 better; ``benchmarks/RESULTS-scans.md``).
PART_FIRST_SCALE = 16
#: The least area fraction used to size the whole's bases (at most ``k / PART_MIN_FRACTION`` functions).
PART_MIN_FRACTION = 0.5


def shell_refine(source: Mesh, target: Mesh, mapping: np.ndarray, *, k: int = REFINE_K,
                 scales: tuple[int, ...] = SCALES, n_sample: int = N_SAMPLE,
                 landmarks: np.ndarray | None = None, orientation: float | None = None,
                 descriptors: tuple[np.ndarray, np.ndarray] | None = None,
                 part_fraction: float | None = None, region: np.ndarray | None = None,
                 weights: np.ndarray | None = None, random_state: int | None = 0,
                 energy: dict | None = None) -> np.ndarray:
    """Refine a vertex map by aligning the shapes' smooth shells (module docstring).

    Parameters
    ----------
    source, target : Mesh
        Triangle meshes (not point clouds: the shells' normals need faces).
    mapping : (n1,) int
        ``mapping[i]``: target vertex of source vertex i, e.g. ZoomOut's map.
    k : int
        Laplace-Beltrami basis size :math:`K` (clipped to the vertex counts;
        the same bases as the ZoomOut refinement's, cached on the meshes).
    scales : tuple of int
        Basis sizes of the coarse-to-fine steps, ascending.
    n_sample : int
        Source vertices sampled (seeded) for the coarse steps; the last step
        maps every vertex.
    landmarks : (L, 2) int, optional
        Known (source, target) vertex pairs, held in the map at every step.
    orientation : float, optional
        The given map's :func:`~meshcorr.core.map_orientation.orientation_score` with
        the same ``random_state``, when the caller has it (it decides between
        a rotation and a reflection); measured here when None.
    descriptors : ((n1, d), (n2, d)) float, optional
        Descriptors that should agree at corresponding vertices (the
        pipeline's: geodesic distances to the user's landmarks divided by
        their mean, :func:`meshcorr.stages.landmarks.landmark_descriptors`),
        appended to the product space with weight :data:`DESCRIPTOR_WEIGHT`.
    part_fraction : float, optional
        The source is a part of the target covering this fraction r of its
        area (:mod:`meshcorr.pipeline.partial`). The part keeps the target's units
        (its coordinates over :math:`\\sqrt{\\operatorname{area}/r}`); a
        step of :math:`k` functions on the part takes :math:`\\lceil k / r
        \\rceil` on the target (the slanted-diagonal spectrum of a part,
        r floored at :data:`PART_MIN_FRACTION`); the spectral coordinates
        are compared as in :func:`meshcorr.stages.partial_zoomout.partial_zoomout`, the
        target's functions projected on the part's (the part's scaled by
        :math:`\\sqrt r`); the steps start at :data:`PART_FIRST_SCALE`.
    region : (n2,) bool, optional
        Target vertices the map may reach (the matched region of a part).
    weights : (n1,) float, optional
        Weight of each source vertex in the rigid motion, the deformation
        and the spectral fit, times its area (e.g. a part's vertices near
        its cut weighted down).
    random_state : int or None
        Seed of the bases' start vectors and of the sample.
    energy : dict, optional
        Filled with what is left of the alignment after the last step, the
        mass-weighted mean over source vertices of the squared distance to
        the image in the product space (``"alignment"``) and in the
        coordinates alone (``"extrinsic"``), and the mass-weighted squared
        norm of the last step's smooth deformation (``"deformation"``),
        shapes at unit area.

    Returns
    -------
    mapping : (n1,) int
        The refined map.
    """
    if source.is_cloud or target.is_cloud:
        raise ParameterError("Shell refinement needs triangle meshes (the shells' normals need faces); "
                             "point clouds keep the ZoomOut map.")
    n1 = source.n_vertices
    mapping = check_vertex_map(mapping, source.n_vertices, target.n_vertices, messages=REFINED_MAP)
    mapping = mapping.astype(np.int64)  # a copy, refined in place
    n_sample = check_int("n_sample", n_sample, minimum=1)
    if descriptors is not None:
        descriptors = _checked_descriptors(descriptors, n1, target.n_vertices)
    k = basis_size(k, source, target)
    part = part_fraction is not None
    if part:
        part_fraction = check_float("part_fraction", part_fraction, minimum=1e-3, maximum=1.0)
        scales = tuple(s for s in scales if s >= PART_FIRST_SCALE)
    basis_fraction = max(part_fraction, PART_MIN_FRACTION) if part else 1.0

    def k2(size: int) -> int:
        """The target's basis size for ``size`` functions on the source (the same for whole shapes)."""
        return min(int(np.ceil(size / basis_fraction)), target.n_vertices - 1) if part else size

    if part:
        phi1, phi2 = parallel_map(lambda item: laplace_basis(*item, random_state=random_state)[1],
                                  ((source, k), (target, k2(k))))
    else:
        phi1, phi2 = pair_bases(source, target, k, random_state=random_state)
    scales = tuple(s for s in scales if s < k)
    (x1, m1), (x2, m2) = _unit_shape(source, 1.0 if part_fraction is None else part_fraction), _unit_shape(target)
    rng = np.random.default_rng(random_state)
    sample = np.arange(n1) if n1 <= n_sample else np.sort(rng.choice(n1, size=n_sample, replace=False))
    mass = m1[sample] if weights is None else m1[sample] * _checked_weights(weights, n1)[sample]
    weights = mass / mass.sum()  # the sample's share of the mass-weighted projection
    # Whether the given map keeps the orientation or mirrors it (decided once, on the whole map:
    # at the coarse scales a thin shape's shell fits its reflection nearly as well).
    if orientation is None:
        orientation = orientation_score(source, target, mapping, random_state=random_state)
    orientation = check_float("orientation", orientation, minimum=0.0, maximum=1.0)
    side = 1.0 if orientation >= 0.5 else -1.0
    # The shells' normals from the outward-facing triangles (a file may come inside out).
    pool = None if region is None else np.flatnonzero(_checked_region(region, target.n_vertices))
    step = _Step(mesh_orientation(source).faces, sample, weights, landmarks, side, descriptors,
                 part_fraction=part_fraction, pool=pool)
    faces2 = mesh_orientation(target).faces
    for size in scales:
        p1 = phi1[:, :size]
        points = _shell_points(phi2, m2, x2, faces2, k2(size), spectral=not part)
        mapping[sample] = step(p1, phi2[:, :k2(size)], _low_pass(p1, m1, x1), points, mapping, sample)
    points = _shell_points(phi2, m2, x2, faces2, k2(k), low_pass=False, spectral=not part)
    mapping = step(phi1, phi2, x1, points, mapping, np.arange(n1))
    if energy is not None:  # the area-weighted mean squared residual of the last step
        energy.update(alignment=float(m1 @ step.residual[0]), extrinsic=float(m1 @ step.residual[1]),
                      deformation=step.deformation)
    return step.pin(mapping)


def _checked_weights(weights, n1: int) -> np.ndarray:
    """Per-source-vertex weights as float64, checked: one finite, non-negative value per vertex, some positive."""
    try:
        weights = np.asarray(weights, dtype=np.float64)
    except (TypeError, ValueError):
        weights = np.empty(0)
    if weights.shape != (n1,) or not np.isfinite(weights).all() or (weights < 0).any() or not weights.any():
        raise ParameterError(f"weights must be {n1} finite, non-negative numbers (one per source vertex), "
                             "not all zero.")
    return weights


def _checked_region(region, n2: int) -> np.ndarray:
    """The target vertices a map may reach, as a boolean mask, checked: one entry per vertex, some True."""
    region = np.asarray(region)
    if region.shape != (n2,) or region.dtype != bool or not region.any():
        raise ParameterError(f"region must be a boolean mask of the target's {n2} vertices with at least "
                             "one True entry.")
    return region


def _checked_descriptors(descriptors, n1: int, n2: int) -> tuple[np.ndarray, np.ndarray]:
    """The two descriptor arrays as float64, checked: one finite row per vertex, as many columns."""
    try:
        F1, F2 = (np.asarray(d, dtype=np.float64) for d in descriptors)
    except (TypeError, ValueError) as exc:
        raise ParameterError(f"descriptors must be a pair of (n, d) arrays of numbers: {exc}") from None
    if F1.ndim != 2 or F2.ndim != 2 or len(F1) != n1 or len(F2) != n2 or F1.shape[1] != F2.shape[1]:
        raise ParameterError(f"descriptors must be ({n1}, d) and ({n2}, d) arrays, one row per vertex of the "
                             f"source and of the target; got {F1.shape} and {F2.shape}.")
    if not (np.isfinite(F1).all() and np.isfinite(F2).all()):
        raise ParameterError("descriptors hold NaN or infinite values.")
    return F1, F2


def _shell_points(basis: np.ndarray, mass: np.ndarray, coords: np.ndarray, faces: np.ndarray, size: int, *,
                  low_pass: bool = True, spectral: bool = True) -> np.ndarray:
    """The target's side of the product space at one scale: ``[X2, w_n n(X2), w_s Phi2]`` (without Phi2 for a part)."""
    phi = basis[:, :size]
    shell = _low_pass(phi, mass, coords) if low_pass else coords
    columns = [shell, NORMAL_WEIGHT * _normals(shell, faces)]
    return np.hstack(columns + [SPECTRAL_WEIGHT * phi] if spectral else columns)


class _Step:
    """One coarse-to-fine step: deform the source shell, fit C, map ``rows`` in the product space."""

    def __init__(self, faces1: np.ndarray, sample: np.ndarray, weights: np.ndarray,
                 landmarks: np.ndarray | None, side: float, descriptors=None, *,
                 part_fraction: float | None = None, pool: np.ndarray | None = None) -> None:
        self.faces1, self.sample, self.weights, self.side = faces1, sample, weights, side
        self.part_fraction, self.pool = part_fraction, pool
        self.landmarks = None if landmarks is None or len(landmarks) == 0 else np.asarray(landmarks)
        self.descriptors = None if descriptors is None else tuple(DESCRIPTOR_WEIGHT * d for d in descriptors)
        self.deformation = 0.0  # the last step's (see __call__)

    def pin(self, mapping: np.ndarray) -> np.ndarray:
        if self.landmarks is not None:
            mapping[self.landmarks[:, 0]] = self.landmarks[:, 1]
        return mapping

    def __call__(self, p1: np.ndarray, p2: np.ndarray, shell1: np.ndarray, points: np.ndarray,
                 mapping: np.ndarray, rows: np.ndarray) -> np.ndarray:
        s = self.sample
        images = self.pin(mapping.copy())[s]
        shell2 = points[:, :3]
        # A rigid motion first (the low-passed displacement of a rotation is not the rotation at
        # full resolution), then the smooth deformation: the displacement the map still asks for,
        # projected on the k functions (mass-weighted, estimated on the sample).
        side = self.side
        moved = rigid_motion(shell1[s], shell2[images], self.weights, side)(shell1)
        coefficients = p1[s].T @ (self.weights[:, None] * (shell2[images] - moved[s]))  # in the basis
        self.deformation = float(np.sum(coefficients ** 2))  # its mass-weighted squared norm (orthonormal basis)
        deformed = moved + p1 @ coefficients
        queries = [deformed[rows], side * NORMAL_WEIGHT * _normals(deformed, self.faces1)[rows]]
        if self.part_fraction is None:
            C = orthogonal_fit(p1[s], p2[images])  # Phi1 C ~ Phi2[T]
            queries.append(SPECTRAL_WEIGHT * p1[rows] @ C)
        else:  # a part: the whole's functions projected on the part's (meshcorr.stages.partial_zoomout.partial_zoomout)
            U, _, Vt = np.linalg.svd((self.weights[:, None] * p1[s]).T @ (self.weights[:, None] * p2[images]),
                                     full_matrices=False)
            queries.append(SPECTRAL_WEIGHT * np.sqrt(self.part_fraction) * p1[rows])
            points = np.hstack([points, SPECTRAL_WEIGHT * p2 @ (U @ Vt).T])
        if self.descriptors is not None:  # the landmarks' distances (pipeline: the user's landmarks)
            queries.append(self.descriptors[0][rows])
            points = np.hstack([points, self.descriptors[1]])
        queries = np.hstack(queries)
        found = (self.pool[nearest_vertices(queries, points[self.pool])] if self.pool is not None
                 else nearest_vertices(queries, points))
        # What is left of the alignment at these rows: the squared product-space distances
        # (kept for the whole-map choice, meshcorr.choice.selection), and the coordinates' part alone.
        gaps = queries - points[found]
        self.residual = (np.einsum("ij,ij->i", gaps, gaps), np.einsum("ij,ij->i", gaps[:, :3], gaps[:, :3]))
        return found


def rigid_motion(points: np.ndarray, onto: np.ndarray, weights: np.ndarray, side: float):
    """The orthogonal motion of least weighted squared distance from ``points`` to ``onto`` (Kabsch).

    Also the lift's (:mod:`meshcorr.stages.lift`).

    ``side``: +1 for a rotation, -1 for a reflection (the determinant is held to it, as Kabsch's
    correction holds it to +1). Returns the motion as a function of (m, 3) coordinates.
    """
    mean_p, mean_q = weights @ points, weights @ onto
    U, _, Vt = np.linalg.svd((points - mean_p).T @ (weights[:, None] * (onto - mean_q)))
    turn = side * (np.sign(np.linalg.det(U @ Vt)) or 1.0)
    rotation = U @ np.diag([1.0, 1.0, turn]) @ Vt  # row vectors: x -> x R
    return lambda x: (x - mean_p) @ rotation + mean_q


def _unit_shape(mesh: Mesh, fraction: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """Coordinates scaled to unit area (of the whole, for a part covering ``fraction`` of it) and centred
    on the centroid, and the unit-sum vertex masses."""
    areas = np.asarray(vertex_areas(mesh), dtype=np.float64)
    mass = areas / areas.sum()
    coords = np.asarray(mesh.vertices, dtype=np.float64) / np.sqrt(areas.sum() / fraction)
    return coords - mass @ coords, mass


def _low_pass(basis: np.ndarray, mass: np.ndarray, coords: np.ndarray) -> np.ndarray:
    """:math:`\\Phi \\Phi^\\top M X`: the coordinates projected on the basis functions (the shell)."""
    return basis @ (basis.T @ (mass[:, None] * coords))


def _normals(coords: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Area-weighted unit vertex normals of a shell (:func:`meshcorr.core.orientation.vertex_normals`)."""
    return vertex_normals(coords, faces)[0]
