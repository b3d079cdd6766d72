"""The result of a correspondence computation."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .reorder import Configuration


@dataclass
class Correspondence:
    """A vertex map from a source mesh to a target mesh, with how it was found.

    Attributes
    ----------
    map : (n_source,) int
        ``map[i]`` is the target vertex matched to source vertex i, in the
        vertex numbering of the input files. -1 for source vertices that
        were not mapped (dropped by ``largest_component=True``).
    cost : (n_source,) float or None
        Final matching cost of each pair (NaN where unmapped).
    method : str
        The method that produced the map ("spectral" or a baseline's name).
        Attributes below that a method does not produce are None or empty.
    source_vertices : (n1,) int
        Input indices of the source vertices that were mapped.
    target_vertices : (n2,) int
        Input indices of the target vertices that could be matched.
    source_embedding : (n1, d) float
        Spectral embedding of the source (d = k - 1).
    target_embedding : (n2, d) float
        Spectral embedding of the target after reordering and sign
        correction, before the non-rigid alignment.
    aligned_target_embedding : (n2, d) float
        The target embedding after thin-plate-spline ICP.
    eigenvalues : dict
        ``{"source": (k,), "target": (k,)}`` top eigenvalues, descending.
    configuration : Configuration
        The chosen eigenvector permutation and signs.
    alternatives : list of Configuration
        All ranked configurations: the chosen one first, then the
        alternative candidate (usually the mirror-image map on symmetric
        shapes; see ``candidates``), then the rest in ascending cost.
    anchors : (h, 2) int
        Anchor pairs (source vertex, target vertex), input numbering.
    icp_history : list of dict
        Per ICP iteration: cost, fraction of matches changed, lambda.
    icp_converged : bool
    timings : dict
        Seconds per stage. The stages run one after another: their sum is
        the end-to-end time.
    background_timings : dict
        Seconds of work done in a worker thread while the stages ran
        (``"refine_bases"``: the refinement's Laplace-Beltrami bases, see
        :func:`meshcorr.refine.prefetch_bases`); not part of the sum above.
    params : dict
        The options used.
    candidates : list of dict
        The near-tied configurations whose maps were scored to resolve the
        left/right mirror (:mod:`meshcorr.symmetry`): rank, perm, signs,
        cost, orientation score, curvature disagreement, metric distortion
        (None unless the orientation was unreliable), and which one was
        chosen / kept as the alternative.
    alternative_map : (n_source,) int or None
        The map of the alternative candidate (usually the mirror image of
        ``map``), same numbering and conventions as ``map``; it is not
        refined.
    orientation_reliable : bool or None
        Whether both meshes have a well-defined outside, so orientation
        scores mean something (see :mod:`meshcorr.orientation`).
    refine_history : list of dict
        Per ZoomOut iteration (:mod:`meshcorr.refine`): basis size, fraction changed.
    map_candidates : list of dict
        The complete maps judged by the whole-map choice
        (:mod:`meshcorr.selection`): origin ("spectral", "extremities-r",
        "landmarks"), orientation, distortion, regional orientation, landmark
        error, and ``chosen`` / ``alternative`` flags. Empty when that stage
        did not run (``symmetry="cost"`` or ``"mirror"``, ``extremities=False``
        without landmarks).
    """

    map: np.ndarray
    cost: np.ndarray | None = None
    method: str = "spectral"
    source_vertices: np.ndarray | None = None
    target_vertices: np.ndarray | None = None
    source_embedding: np.ndarray | None = None
    target_embedding: np.ndarray | None = None
    aligned_target_embedding: np.ndarray | None = None
    eigenvalues: dict = field(default_factory=dict)
    configuration: Configuration | None = None
    alternatives: list[Configuration] = field(default_factory=list)
    anchors: np.ndarray | None = None
    icp_history: list = field(default_factory=list)
    icp_converged: bool = False
    timings: dict = field(default_factory=dict)
    background_timings: dict = field(default_factory=dict)
    params: dict = field(default_factory=dict)
    candidates: list[dict] = field(default_factory=list)
    alternative_map: np.ndarray | None = None
    orientation_reliable: bool | None = None
    refine_history: list = field(default_factory=list)
    map_candidates: list[dict] = field(default_factory=list)

    @property
    def runner_up(self) -> Configuration | None:
        """The second-ranked configuration, or None if there is only one."""
        return self.alternatives[1] if len(self.alternatives) > 1 else None

    def summary(self) -> dict:
        """A JSON-serialisable summary (no per-vertex arrays)."""
        mapped = self.map >= 0
        has_cost = self.cost is not None and bool(np.isfinite(self.cost).any())
        return {
            "method": self.method,
            "n_source": int(len(self.map)),
            "n_mapped": int(mapped.sum()),
            "n_target_hit": int(len(np.unique(self.map[mapped]))),
            "configuration": self.configuration.to_dict() if self.configuration else None,
            "map_candidates": self.map_candidates,
            "runner_up": self.runner_up.to_dict() if self.runner_up else None,
            "n_configurations": len(self.alternatives),
            "eigenvalues": {k: [float(x) for x in v] for k, v in self.eigenvalues.items()},
            "anchors": self.anchors.tolist() if self.anchors is not None else None,
            "mean_cost": float(np.nanmean(self.cost)) if has_cost else None,
            "icp": {"iterations": len(self.icp_history), "converged": self.icp_converged,
                    "history": self.icp_history},
            "timings": {k: round(v, 4) for k, v in self.timings.items()},
            "background_timings": {k: round(v, 4) for k, v in self.background_timings.items()},
            "params": self.params,
            "candidates": self.candidates,
            "orientation_reliable": self.orientation_reliable,
            "refine": {"iterations": len(self.refine_history), "history": self.refine_history},
        }
