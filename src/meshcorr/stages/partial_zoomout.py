"""ZoomOut for a part: a rectangular functional map from the part's basis into the whole's.

A part's Laplace-Beltrami spectrum is "stretched": its first :math:`k`
eigenfunctions correspond to about the first :math:`k / r` of the whole's,
:math:`r = \\operatorname{area}(P) / \\operatorname{area}(W)` (Rodolà, Cosmo,
Bronstein, Torsello & Cremers, "Partial functional correspondence", Computer
Graphics Forum 36(1), 2017: the functional map of a part is
slanted-diagonal with that slope; docs/method.md, "Partial shapes", step 5).
:func:`partial_zoomout` refines a part -> whole map in bases of :math:`k`
functions on the part and :math:`\\lceil k / r \\rceil` on the whole, with a
rectangular functional map whose rows are orthonormal up to a common scale
(:math:`C C^\\top \\approx I / r`), the whole's vertices restricted to the
matched region (the part's "indicator function" of Rodolà et al., here
estimated from the map instead of optimised) and the vertices near the cut
weighted down in every fit.
"""

from __future__ import annotations

from math import ceil

import numpy as np

from ..spectral.nearest import nearest_rows


def partial_zoomout(part_basis: np.ndarray, whole_basis: np.ndarray, mapping: np.ndarray, *, ratio: float,
                    allowed: np.ndarray | None = None, weights: np.ndarray | None = None, k_start: int = 16,
                    step: int = 2, n_sample: int = 500, random_state: int | None = 0
                    ) -> tuple[np.ndarray, list[dict]]:
    """Refine a part -> whole map by ZoomOut with a rectangular functional map (module docstring).

    For :math:`k = k_0, k_0 + s, \\dots, K` with :math:`k_W = \\lceil k / r \\rceil`,

    .. math::

        C = \\sigma U V^\\top, \\quad U \\Sigma V^\\top = A^\\top W B, \\qquad
        T(i) = \\arg\\min_{j \\in R} \\lVert \\Phi_P^{(k)}(i) - \\Phi_W^{(k_W)}(j) C^\\top / \\sigma \\rVert

    with :math:`A = \\Phi_P^{(k)}[S]` and :math:`B = \\Phi_W^{(k_W)}[T(S)]` on a
    seeded sample :math:`S` of the part, :math:`W` the vertex weights,
    :math:`\\sigma` the least-squares scale of :math:`A U V^\\top \\approx B`
    (about :math:`1 / \\sqrt r`), and :math:`R` the allowed whole vertices.
    The search runs in the part's :math:`k` dimensions, the whole's
    functions projected by :math:`C^\\top`: functions of the whole beyond the
    part's reach are projected away instead of adding noise.

    Parameters
    ----------
    part_basis : (n_p, K) float
    whole_basis : (n_w, K_W) float
        :math:`K_W \\ge \\lceil K / r \\rceil` (fewer are used if not).
    mapping : (n_p,) int
        Initial map.
    ratio : float
        r, the part's area fraction of the whole, in (0, 1].
    allowed : (n_w,) bool, optional
        Whole vertices the map may reach (default all).
    weights : (n_p,) float, optional
        Weight of each part vertex in the fits (default 1).
    k_start, step, n_sample, random_state
        As :func:`meshcorr.stages.refine.zoomout`.

    Returns
    -------
    mapping : (n_p,) int
    history : list of dict
        ``k``, ``k_whole`` and ``changed`` (fraction of the sampled part vertices whose image changed).
    """
    K, K_whole = part_basis.shape[1], whole_basis.shape[1]
    n1, n2 = len(part_basis), len(whole_basis)
    pool = np.arange(n2) if allowed is None else np.flatnonzero(allowed)
    rng = np.random.default_rng(random_state)
    s1 = np.arange(n1) if n1 <= n_sample else np.sort(rng.choice(n1, size=n_sample, replace=False))
    s2 = pool if len(pool) <= n_sample else np.sort(rng.choice(pool, size=n_sample, replace=False))
    w = np.ones(len(s1)) if weights is None else np.asarray(weights, dtype=float)[s1]
    images = np.asarray(mapping, dtype=np.int64)[s1]
    history: list[dict] = []
    projection = None
    for k in list(range(min(k_start, K), K, step)) + [K]:
        kw = min(K_whole, int(ceil(k / ratio)))
        A, B = part_basis[s1, :k], whole_basis[images, :kw]
        U, S, Vt = np.linalg.svd((A * w[:, None]).T @ (B * w[:, None]), full_matrices=False)
        projection = (U @ Vt).T  # (kw, k): C^T / sigma
        new = s2[nearest_rows(A, whole_basis[s2, :kw] @ projection)]
        history.append({"k": int(k), "k_whole": int(kw), "changed": float(np.mean(new != images))})
        images = new
    kw = projection.shape[0]
    return pool[nearest_rows(part_basis, whole_basis[pool, :kw] @ projection)], history
