"""Choosing among near-tied eigenvector configurations: resolving the mirror.

On a shape with an intrinsic (left/right) symmetry, the eigenvector sign
configuration of the true map and that of its mirror image cost nearly the
same (docs/method.md, "Departures from the paper": the lowest-cost configuration was the
mirror in 7 of 10 TOSCA and Sumner pairs). A low-dimensional embedding also
confuses the front and the back of thin shapes (a person's chest and
back), which is not an isometry. Two measures on each candidate's map tell
these apart:

- the **orientation score** (:func:`meshcorr.core.map_orientation.orientation_score`):
  near 1 for an orientation-preserving map, near 0 for a mirrored one. The
  left/right mirror reverses orientation; it is invisible to every intrinsic
  measure.
- the **curvature disagreement**
  (:func:`meshcorr.choice.curvature.curvature_disagreement`): how much the smoothed
  signed mean curvature changes across the map. Besides the mirror, the
  near-tied configurations of a person hold a *half turn* about the body's
  long axis (front to back and left to right): it preserves orientation
  and, a person being thin, it is almost an isometry, but it takes a nose to
  the back of a head and knee caps to the backs of the knees. Measured on
  TOSCA pairs, the metric distortion below could not tell it from the right
  map (differences of 1 %, either way), while the curvature disagreement of
  the half turn was 1.2-1.6x the right map's on each of the 9 of 40 pairs
  that had one among their candidates (benchmarks/RESULTS-symmetry.md).
- the **metric distortion**, the mean over a few source vertices :math:`i`
  and all vertices :math:`j` of
  :math:`|g_1(i, j) - g_2(f(i), f(j))|` with geodesics normalised by each
  mesh's largest one: 0 for an isometry (the Gromov-Hausdorff-type
  criterion of isometric matching; Bronstein, Bronstein & Kimmel, PNAS
  2006). Signed curvature needs an outward normal: when a mesh's outside is
  undefined (:mod:`meshcorr.core.orientation`), both orientation and curvature
  are set aside and the distortion decides.

:func:`choose` takes the orientation-preserving candidate whose curvature
agrees best (``"auto"``), the cheapest configuration (``"cost"``, the
paper's choice), or the alternative of ``"auto"`` (``"mirror"``). The
alternative kept in the result is the best-agreeing candidate of the
opposite orientation.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from ..core.map_orientation import orientation_score
from ..runtime.checks import check_choice, check_float, check_int
from ..runtime.threads import parallel_map
from ..stages.icp import tps_icp
from ..stages.reorder import Configuration
from .curvature import curvature_disagreement

SYMMETRY_MODES = ("auto", "cost", "mirror")
#: See :func:`right_map_missing`.
WIDEN_RATIO = 1.15
#: Configurations scored when the near-tied set is widened.
WIDE_CANDIDATES = 6
#: Geodesic rows sampled on the source for the metric distortion of a candidate
#: (measured only when the orientation is unreliable).
N_DISTORTION_SOURCES = 16


@dataclass
class ConfigurationCandidate:
    """First round of the map choice: one near-tied eigenvector configuration and the scores of its aligned map.

    The pipeline aligns each near-tied configuration of step 4 (thin-plate-spline
    ICP) and scores the map it gives (orientation, curvature, distortion);
    :func:`choose` keeps one and its alternative. The second round scores
    whole candidate maps the same way (:class:`meshcorr.choice.selection.MapCandidate`).

    Attributes
    ----------
    rank : int
        Position of the configuration in the ranked list (0 = cheapest).
    configuration : Configuration
    orientation : float
        Orientation score of the candidate's map, in [0, 1].
    curvature : float
        Curvature disagreement of the candidate's map (NaN if not measured).
    distortion : float
        Metric distortion of the candidate's map (normalised geodesics; NaN
        if not measured).
    mapping : (n1,) int
        The candidate's map (source vertex -> target vertex, local numbering).
    extra : dict
        Whatever the pipeline attaches (the alignment it came from).
    """

    rank: int
    configuration: Configuration
    orientation: float
    curvature: float
    distortion: float
    mapping: np.ndarray
    extra: dict = field(default_factory=dict)

    def to_dict(self) -> dict:
        return {"rank": self.rank, **self.configuration.to_dict(),
                "orientation": round(float(self.orientation), 4),
                "curvature": rounded(self.curvature, 4), "distortion": rounded(self.distortion, 5)}


def rounded(value: float, digits: int) -> float | None:
    """``value`` rounded to ``digits`` for JSON summaries of candidates; None when it was not measured (NaN)."""
    return None if not np.isfinite(value) else round(float(value), digits)


def candidate_ranks(configurations: list[Configuration], *, tolerance: float = 0.25,
                    max_candidates: int = 6) -> list[int]:
    """Ranks of the configurations near-tied with the cheapest one.

    Parameters
    ----------
    configurations : list of Configuration
        Ranked as :func:`meshcorr.stages.reorder.rank_configurations` returns them.
    tolerance : float
        Relative cost margin: configuration r is a candidate when
        ``cost_r <= (1 + tolerance) * min cost``.
    max_candidates : int
        At most this many (the cheapest).

    Returns
    -------
    ranks : list of int
        Always ranks 0 and 1 (the paper's runner-up) when they exist.
    """
    tolerance = check_float("symmetry_tolerance", tolerance, minimum=0.0)
    max_candidates = check_int("max_candidates", max_candidates, minimum=2)
    if not configurations:
        return []
    costs = np.array([c.cost for c in configurations])
    limit = (1.0 + tolerance) * costs.min()
    near = [r for r in np.argsort(costs, kind="stable") if costs[r] <= limit]
    ranks = list(dict.fromkeys([0, 1][:len(configurations)] + [int(r) for r in near]))
    return ranks[:max(max_candidates, 2)]


def right_map_missing(candidates: list[ConfigurationCandidate], *, ratio: float = WIDEN_RATIO) -> bool:
    """Whether the near-tied set seems to lack the right map's configuration.

    The left/right mirror of the right map agrees with the target's curvature
    as well as the right map does (mean curvature does not change under a
    reflection, and the shapes are symmetric), so among candidates that hold
    both, the best orientation-preserving candidate agrees about as well as
    the best orientation-reversing one. When every orientation-preserving
    candidate agrees clearly worse, the right configuration is probably
    missing (its cost was not near-tied) and more configurations should be
    scored. Measured on 47 TOSCA pairs: the ratio below was 0.85-1.09 where
    the near-tied set held the right map and 1.19 on the one pair where it did
    not (benchmarks/RESULTS-symmetry.md).

    Parameters
    ----------
    candidates : list of ConfigurationCandidate
        Scored, with a reliable orientation.
    ratio : float
        Widen when min curvature (preserving) > ``ratio`` x min curvature (reversing).

    Returns
    -------
    missing : bool
        Also True when no candidate preserves orientation.
    """
    ratio = check_float("ratio", ratio, minimum=1.0)
    preserving = [c.curvature for c in candidates if c.orientation >= 0.5]
    reversing = [c.curvature for c in candidates if c.orientation < 0.5]
    if not preserving:
        return True
    return bool(reversing) and min(preserving) > ratio * min(reversing)


def metric_distortion(source_geodesics: Callable[[int], np.ndarray],
                      target_geodesics: Callable[[int], np.ndarray], mapping: np.ndarray,
                      sources: np.ndarray, source_rows: dict | None = None) -> float:
    """Mean :math:`|g_1(i, j) - g_2(f(i), f(j))|` over ``i`` in ``sources`` and all ``j``.

    Parameters
    ----------
    source_geodesics, target_geodesics : callable
        ``f(i)`` returns the normalised geodesic distances from vertex i, ``(n,)``.
    mapping : (n1,) int
    sources : (m,) int
        Source vertices used.
    source_rows : dict, optional
        Cache of source rows shared between candidates.

    Returns
    -------
    distortion : float
    """
    rows = {} if source_rows is None else source_rows
    total = 0.0
    for i in np.asarray(sources, dtype=np.int64):
        if int(i) not in rows:
            rows[int(i)] = np.asarray(source_geodesics(int(i)))
        total += float(np.abs(rows[int(i)] - np.asarray(target_geodesics(int(mapping[i])))[mapping]).mean())
    return total / max(1, len(sources))


def choose(candidates: list[ConfigurationCandidate], symmetry: str = "auto", *,
           orientation_reliable: bool = True) -> tuple[ConfigurationCandidate, ConfigurationCandidate | None]:
    """Pick the map and its alternative among scored candidates.

    Parameters
    ----------
    candidates : list of ConfigurationCandidate
        In rank order (``candidates[0]`` is the cheapest configuration).
    symmetry : {"auto", "cost", "mirror"}
        ``"auto"``: among the orientation-preserving candidates (score >=
        0.5; all of them if none is), the one whose curvature agrees best;
        with an unreliable orientation, the least distorted candidate.
        ``"cost"``: the cheapest configuration. ``"mirror"``: the
        alternative ``"auto"`` would keep.
    orientation_reliable : bool
        False when a mesh's outside is undefined (see
        :mod:`meshcorr.core.orientation`): orientation scores and the signed
        curvature are then ignored, and each candidate's ``distortion``
        must be measured.

    Returns
    -------
    chosen : ConfigurationCandidate
    alternative : ConfigurationCandidate or None
        The best candidate (same criterion) of the orientation opposite to
        the chosen one's (for ``"cost"``: to the cheapest one's); None with a
        single candidate.
    """
    check_choice("symmetry", symmetry, SYMMETRY_MODES)
    if not candidates:
        raise ValueError("No candidate configuration to choose from.")
    criterion = "curvature" if orientation_reliable else "distortion"

    def best(pool):
        return min(pool, key=lambda c: (getattr(c, criterion), c.rank)) if pool else None

    def opposite(of: ConfigurationCandidate) -> ConfigurationCandidate | None:
        rest = [c for c in candidates if c is not of]
        if not orientation_reliable:
            return best(rest)
        preserving = of.orientation >= 0.5
        return best([c for c in rest if (c.orientation >= 0.5) != preserving]) or best(rest)

    if symmetry == "cost":
        chosen = candidates[0]
        return chosen, opposite(chosen)
    if orientation_reliable:
        chosen = best([c for c in candidates if c.orientation >= 0.5]) or best(candidates)
    else:
        chosen = best(candidates)
    other = opposite(chosen)
    if symmetry == "mirror" and other is not None:
        return other, chosen
    return chosen, other


def score_configurations(source, target, spectra, configurations: list[Configuration], *, icp_iterations: int,
                         n_control: int, anneal: float, reliable: bool, random_state: int | None,
                         timer) -> list[ConfigurationCandidate]:
    """Step 5 for each near-tied configuration, and the scores of its map: the first round of the choice.

    Parameters
    ----------
    source, target : Mesh
    spectra : (Spectrum, Spectrum)
        The two shapes' spectra (embeddings ``(n, k - 1)`` and geodesic rows).
    configurations : list of Configuration
        Ranked by cost (:func:`meshcorr.stages.reorder.rank_configurations`).
    icp_iterations, n_control, anneal : int, int, float
        TPS-ICP's settings (:func:`meshcorr.stages.icp.tps_icp`).
    reliable : bool
        Both meshes have a reliable outside; else the orientation and
        curvature are set aside and the metric distortion is measured.
    random_state : int or None
    timer : StageTimer
        Times the stages "icp" and "symmetry".

    Returns
    -------
    candidates : list of ConfigurationCandidate
        One per near-tied configuration (:func:`candidate_ranks`), its
        TPS-ICP nearest-neighbour map scored by orientation, curvature and
        (unreliable orientation only) metric distortion. When the near-tied
        set seems to lack the right map (:func:`right_map_missing`), the
        cheapest :data:`WIDE_CANDIDATES` configurations are scored too. The
        anchors and the refinement run later, for the chosen map and its
        alternative only.
    """
    X, Y = spectra[0].embedding, spectra[1].embedding
    g1, g2 = spectra[0].geodesics_from, spectra[1].geodesics_from
    rng = np.random.default_rng(random_state)
    sources = rng.choice(len(X), size=min(N_DISTORTION_SOURCES, len(X)), replace=False)
    source_rows: dict = {}

    def align(rank: int):
        return tps_icp(X, configurations[rank].apply(Y), max_iter=icp_iterations, n_control=n_control,
                       anneal=anneal, random_state=random_state)

    def score(ranks: list[int]) -> list[ConfigurationCandidate]:
        # The candidates' alignments are independent: one thread per core (meshcorr.runtime.threads).
        with timer.stage("icp"):
            icps = parallel_map(align, ranks)
        with timer.stage("symmetry"):
            return [ConfigurationCandidate(
                rank=rank, configuration=configurations[rank],
                orientation=orientation_score(source, target, icp.matches, random_state=random_state),
                curvature=curvature_disagreement(source, target, icp.matches, random_state=random_state),
                distortion=(np.nan if reliable else metric_distortion(g1, g2, icp.matches, sources, source_rows)),
                mapping=icp.matches, extra={"icp": icp, "anchors": np.zeros((0, 2), dtype=np.int64), "cost": None})
                for rank, icp in zip(ranks, icps)]

    ranks = candidate_ranks(configurations)
    candidates = score(ranks)
    if reliable and right_map_missing(candidates):
        candidates += score([rank for rank in range(min(WIDE_CANDIDATES, len(configurations)))
                             if rank not in ranks])
    return candidates
