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
    cost : (n_source,) float
        Final matching cost of each pair (NaN where unmapped).
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
        All ranked configurations, chosen first; ``alternatives[1]`` is the
        runner-up (often the mirror-image map on symmetric shapes).
    anchors : (h, 2) int
        Anchor pairs (source vertex, target vertex), input numbering.
    icp_history : list of dict
        Per ICP iteration: cost, fraction of matches changed, lambda.
    icp_converged : bool
    timings : dict
        Seconds per stage.
    params : dict
        The options used.
    """

    map: np.ndarray
    cost: np.ndarray
    source_vertices: np.ndarray
    target_vertices: np.ndarray
    source_embedding: np.ndarray
    target_embedding: np.ndarray
    aligned_target_embedding: np.ndarray
    eigenvalues: dict
    configuration: Configuration
    alternatives: list[Configuration]
    anchors: np.ndarray
    icp_history: list = field(default_factory=list)
    icp_converged: bool = False
    timings: dict = field(default_factory=dict)
    params: dict = field(default_factory=dict)

    @property
    def runner_up(self) -> Configuration | None:
        """The second-ranked configuration, or None if there is only one."""
        return self.alternatives[1] if len(self.alternatives) > 1 else None

    def summary(self) -> dict:
        """A JSON-serialisable summary (no per-vertex arrays)."""
        mapped = self.map >= 0
        return {
            "n_source": int(len(self.map)),
            "n_mapped": int(mapped.sum()),
            "n_target_hit": int(len(np.unique(self.map[mapped]))),
            "configuration": self.configuration.to_dict(),
            "runner_up": self.runner_up.to_dict() if self.runner_up else None,
            "n_configurations": len(self.alternatives),
            "eigenvalues": {k: [float(x) for x in v] for k, v in self.eigenvalues.items()},
            "anchors": self.anchors.tolist(),
            "mean_cost": float(np.nanmean(self.cost)) if mapped.any() else None,
            "icp": {"iterations": len(self.icp_history), "converged": self.icp_converged,
                    "history": self.icp_history},
            "timings": {k: round(v, 4) for k, v in self.timings.items()},
            "params": self.params,
        }
