"""Correspondences between synthetic shapes: of one family (:func:`ground_truth`) and of a rigid copy (:func:`rigid_copy`)."""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from ...errors import ParameterError
from .shape import SyntheticShape, positive_parameter, seed_parameter, shape_parameter
from .capsule import chart_embedding
from .creatures import creature_directions, creature_rest

__all__ = ["ground_truth", "rigid_copy"]

def ground_truth(source: SyntheticShape, target: SyntheticShape) -> np.ndarray:
    """The true map from the vertices of one shape to those of another.

    Both shapes must come from one family (one chart), in any poses and at
    any resolutions. Each source vertex is sent to the target vertex nearest
    to it on the family's *reference surface*, a fixed embedding of the
    chart, with a k-d tree:

    - ``chart="capsule"`` (:func:`tube`, :func:`figure`): chart coordinates
      ``(t, theta)`` are embedded as points of the straight, unbumped capsule
      (``(x(t), rho(t) cos theta, rho(t) sin theta)`` with ``rho`` the
      capsule's ring radius, 0 at the poles). This handles the periodic
      ``theta`` and the poles, and weighs ``t`` and ``theta`` by the lengths
      they span on the surface.
    - ``chart="creature"`` (:func:`creature`): the chart directions are
      mapped onto the creature's rest pose, where the limbs keep well apart,
      so nearness in space is nearness on the surface.

    Shapes made at one resolution and seed give the identity exactly.

    Parameters
    ----------
    source : SyntheticShape
        Shape with ``n_source`` vertices.
    target : SyntheticShape
        Shape with ``n_target`` vertices.

    Returns
    -------
    truth : (n_source,) int64
        ``truth[i]`` is the target vertex corresponding to source vertex ``i``
        (the ``p2p`` direction is source -> target).

    Raises
    ------
    ParameterError
        If either argument is not a SyntheticShape or the two shapes do not
        share a chart (different generators, or capsules whose poles differ,
        e.g. tubes of different lengths).
    """
    source = shape_parameter(source, "source", "ground_truth")
    target = shape_parameter(target, "target", "ground_truth")
    if source.chart != target.chart:
        raise ParameterError(
            f"ground_truth needs two shapes of one family, with one chart. {source.name!r} "
            f"has a {source.chart!r} chart and {target.name!r} a {target.chart!r} chart."
        )
    if source.chart == "capsule":
        limits = []
        for shape in (source, target):
            t = shape.params[:, 0]
            limits.append((t.min(), t.max()))
        (a0, a1), (b0, b1) = limits
        scale = max(abs(a1 - a0), abs(b1 - b0))
        if not (a0 < 0 and np.isclose(a0, b0, rtol=0, atol=1e-9 * scale)
                and np.isclose(a1, b1, rtol=0, atol=1e-9 * scale)):
            raise ParameterError(
                f"ground_truth needs two shapes of one family, with one chart. The chart of "
                f"{source.name!r} spans t in [{a0:.6g}, {a1:.6g}] and that of {target.name!r} "
                f"[{b0:.6g}, {b1:.6g}]."
            )
    if source.params.shape == target.params.shape and np.array_equal(source.params, target.params):
        return np.arange(source.n_vertices, dtype=np.int64)
    if source.chart == "capsule":
        tree = cKDTree(chart_embedding(target.params, b0, b1))
        _, nearest = tree.query(chart_embedding(source.params, a0, a1))
    else:
        tree = cKDTree(creature_rest(creature_directions(target.params)))
        _, nearest = tree.query(creature_rest(creature_directions(source.params)))
    return np.asarray(nearest, dtype=np.int64)


def _random_rotation(rng: np.random.Generator) -> np.ndarray:
    """A rotation matrix drawn uniformly from SO(3) (QR of a Gaussian matrix)."""
    q, r = np.linalg.qr(rng.standard_normal((3, 3)))
    q = q * np.sign(np.diag(r))
    if np.linalg.det(q) < 0:
        q[:, 0] = -q[:, 0]
    return q


def rigid_copy(shape: SyntheticShape, *, rotation=None, translation=None, scale: float = 1.0,
               permute: bool = True, random_state: int | None = 0
               ) -> tuple[SyntheticShape, np.ndarray]:
    """A rotated, translated, uniformly scaled and re-indexed copy of a shape.

    The copy's vertex ``truth[i]`` sits at ``scale * rotation @ v_i +
    translation`` where ``v_i`` is vertex ``i`` of ``shape``.

    Parameters
    ----------
    shape : SyntheticShape
        The original, with ``n`` vertices.
    rotation : (3, 3) float, optional
        A proper rotation matrix (orthonormal, determinant +1). ``None`` draws
        one uniformly from the seed.
    translation : (3,) float, optional
        ``None`` draws one from the seed (standard normal per coordinate).
    scale : float, default 1.0
        Uniform scale factor (> 0, so that orientation is kept).
    permute : bool, default True
        Re-index the vertices by a random permutation (faces and ``params``
        follow); ``False`` keeps the order, so ``truth`` is the identity.
    random_state : int or None, default 0
        Seed of the rotation, translation and permutation drawn here;
        ``None`` draws fresh entropy.

    Returns
    -------
    copy : SyntheticShape
        The transformed shape; same chart as ``shape``, so
        ``ground_truth(shape, copy)`` equals ``truth``.
    truth : (n,) int64
        ``truth[i]`` is the index in ``copy`` of original vertex ``i``:
        ``copy.vertices[truth] == scale * shape.vertices @ rotation.T +
        translation`` and ``copy.faces == truth[shape.faces]``.
    """
    func = "rigid_copy"
    shape = shape_parameter(shape, "shape", func)
    if random_state is not None:
        random_state = seed_parameter(random_state, func)
    rng = np.random.default_rng(random_state)
    if rotation is None:
        rotation = _random_rotation(rng)
    else:
        rotation = np.asarray(rotation, dtype=np.float64)
        if (rotation.shape != (3, 3) or not np.all(np.isfinite(rotation))
                or not np.allclose(rotation @ rotation.T, np.eye(3), atol=1e-8)
                or np.linalg.det(rotation) < 0):
            raise ParameterError(
                "The 'rotation' parameter of rigid_copy must be a (3, 3) rotation matrix "
                "(orthonormal, determinant +1) or None. Got "
                f"{np.array2string(rotation, precision=3)} instead."
            )
    if translation is None:
        translation = rng.standard_normal(3)
    else:
        translation = np.asarray(translation, dtype=np.float64)
        if translation.shape != (3,) or not np.all(np.isfinite(translation)):
            raise ParameterError(
                "The 'translation' parameter of rigid_copy must be a finite (3,) vector or "
                f"None. Got {np.array2string(translation, precision=3)} instead."
            )
    scale = positive_parameter(scale, "scale", func)
    if not isinstance(permute, (bool, np.bool_)):
        raise ParameterError(
            f"The 'permute' parameter of rigid_copy must be a bool. Got {permute!r} instead."
        )

    n = shape.n_vertices
    order = rng.permutation(n) if permute else np.arange(n)  # copy vertex j = original order[j]
    truth = np.empty(n, dtype=np.int64)
    truth[order] = np.arange(n)
    moved = scale * shape.vertices @ rotation.T + translation
    copy = SyntheticShape(
        vertices=moved[order],
        faces=truth[shape.faces],
        params=shape.params[order],
        name=f"{shape.name}-rigid",
        chart=shape.chart,
    )
    return copy, truth
