"""The settings of a correspondence run, in one documented, validated object.

:class:`Settings` groups every option of :func:`meshcorr.match` by what it
controls (the method, the spectral pipeline's stages, resources); the
staged :class:`meshcorr.Matcher` and :func:`meshcorr.match` share it. An
option changed from its default that the chosen method does not use raises
:class:`~meshcorr.errors.ParameterError` naming it
(:func:`meshcorr.pipeline.methods.reject_inapplicable`); the values themselves are
checked by :func:`meshcorr.match` where they are used, with one message
shape ("The 'k' parameter must be an int <= 10. Got 12 instead.").
"""

from __future__ import annotations

import dataclasses
import inspect
from dataclasses import dataclass
from typing import Sequence

import numpy as np

from ..errors import ParameterError
from .methods import METHOD_NAMES, reject_inapplicable
from .run import match as _match

__all__ = ["Settings", "match_keywords"]

_MATCH_PARAMETERS = inspect.signature(_match).parameters


def _match_default(*names: str):
    """The default of the first of ``names`` that :func:`meshcorr.match` has (one source of truth)."""
    for name in names:
        if name in _MATCH_PARAMETERS:
            return _MATCH_PARAMETERS[name].default
    raise ImportError(f"meshcorr.match has none of the parameters {names}")  # pragma: no cover


@dataclass(frozen=True)
class Settings:
    """Options of a correspondence run (see :func:`meshcorr.match` for each one's maths).

    Attributes
    ----------
    method : {"spectral", "shapiro-brady", "shapiro-brady-scaled", "tps-rpm", "icp", "shape-context"}
        The method (:mod:`meshcorr.pipeline.methods`).
    random_state : int or None
        The one seed of everything random.
    k : int
        Eigenpairs of the affinity; the embedding has ``k - 1`` dimensions.
    geodesic : {"heat", "fmm", "exact", "dijkstra"}
        Geodesic solver.
    scale_eigenvalues : bool
        Scale eigenvectors by sqrt(eigenvalue).
    reorder : {"exhaustive", "greedy", "signs", "signs-greedy", "none"}
        Eigenvector reordering and sign correction.
    icp_iterations, n_control : int
        Thin-plate-spline ICP: most iterations (0 skips it), control points.
    anneal : float
        Factor lowering the spline regulariser each iteration.
    n_anchors : int
        h, anchor pairs of the proximity-aided matching.
    anchor_weight : float
        alpha, weight of each anchor's geodesic term.
    anchor_scale : {"embedding", "geodesic"}
        Length scale of the anchor term.
    symmetry : {"auto", "cost", "mirror"}
        Choice among near-tied configurations (the left/right mirror).
    refine : bool
        ZoomOut refinement of the map.
    refine_k : int
        Laplace-Beltrami basis size of the refinement.
    shells : bool
        Align the shapes' smooth shells after the refinement (:mod:`meshcorr.stages.shells`).
    landmarks : (p, 2) int or None
        Known vertex pairs ``(source vertex, target vertex)``, input
        numbering: they start a candidate map, decide among the candidates
        and are mapped exactly.
    extremities : bool
        Also try maps started from matched shape extremities and keep the
        one the whole-map energies prefer (with ``symmetry="auto"``).
    oriented_starts : bool
        Also start maps from the tips by an orientation-preserving fit
        (people standing; worse across species).
    partial : {None, "source", "target"}
        Which shape is a part of the other (:mod:`meshcorr.pipeline.partial`); None:
        both are whole.
    fill_holes : bool
        Close the meshes' holes before matching (:mod:`meshcorr.core.holes`);
        not with ``partial`` or ``bijective``.
    bijective : bool
        One-to-one map (equal vertex counts only).
    largest_component : bool
        Map only each mesh's largest connected component.
    prealign : bool
        Pre-align to the principal axes (spatial baselines only).
    mode : {"auto", "dense", "scalable"}
        All-pairs geodesics and exact eigenpairs, or samples and Nyström.
    n_samples : int
        m, sample vertices of the scalable mode's Nyström extension.
    max_memory : int, str or None
        Memory the dense mode may use (bytes or e.g. ``"4GiB"``).
    scalable_above : int
        Vertex count above which ``mode="auto"`` picks the scalable mode.
    """

    method: str = "spectral"
    random_state: int | None = 0
    # the spectral pipeline's stages
    k: int = 6
    geodesic: str = "heat"
    scale_eigenvalues: bool = True
    reorder: str = "exhaustive"
    icp_iterations: int = 10
    n_control: int = 500
    anneal: float = 0.5
    n_anchors: int = 3
    anchor_weight: float = 1.0
    anchor_scale: str = "embedding"
    symmetry: str = "auto"
    refine: bool = True
    refine_k: int = _match_default("refine_k")
    shells: bool = True
    landmarks: Sequence[tuple[int, int]] | np.ndarray | None = None
    extremities: bool = True
    oriented_starts: bool = False
    partial: str | None = None
    fill_holes: bool = True
    # the output and the input
    bijective: bool = False
    largest_component: bool = False
    prealign: bool = True
    # resources
    mode: str = "auto"
    n_samples: int = _match_default("n_samples", "n_landmarks")
    max_memory: int | str | None = None
    scalable_above: int = _match_default("scalable_above")

    def __post_init__(self) -> None:
        if self.method not in METHOD_NAMES:
            options = ", ".join(repr(m) for m in METHOD_NAMES)
            raise ParameterError(f"The 'method' parameter must be one of {options}. Got {self.method!r} instead.")
        if self.landmarks is not None:
            pairs = np.asarray(self.landmarks)
            if pairs.ndim != 2 or pairs.shape[1] != 2 or not np.issubdtype(pairs.dtype, np.integer):
                raise ParameterError("The 'landmarks' parameter must be (source vertex, target vertex) integer "
                                     f"pairs, e.g. [(0, 12), (5, 40)]. Got an array of shape {pairs.shape} "
                                     f"and dtype {pairs.dtype} instead.")
        reject_inapplicable(self.method, match_keywords(self))

    @classmethod
    def from_options(cls, **options) -> "Settings":
        """Settings from keywords, with a message naming any unknown one.

        Raises
        ------
        ParameterError
            For a keyword that is no setting (the message lists them all).
        """
        names = [f.name for f in dataclasses.fields(cls)]
        unknown = sorted(set(options) - set(names))
        if unknown:
            hint = " ('n_landmarks' is now 'n_samples')" if "n_landmarks" in unknown else ""
            raise ParameterError(f"Unknown setting {unknown[0]!r}{hint}. The settings are: {', '.join(names)}.")
        return cls(**options)

    def changed(self) -> dict:
        """The settings that differ from their defaults, ``{name: value}``."""
        out = {}
        for f in dataclasses.fields(self):
            value = getattr(self, f.name)
            if f.name == "landmarks":
                if value is not None:
                    out[f.name] = value
            elif not (value is f.default or (type(value) is type(f.default) and value == f.default)):
                out[f.name] = value
        return out

    def replace(self, **changes) -> "Settings":
        """A copy with some settings changed (validated again)."""
        current = {f.name: getattr(self, f.name) for f in dataclasses.fields(self)}
        return Settings.from_options(**{**current, **changes})

    def as_dict(self) -> dict:
        """Every setting, ``{name: value}`` (landmarks as a list of pairs)."""
        out = {f.name: getattr(self, f.name) for f in dataclasses.fields(self)}
        if out["landmarks"] is not None:
            out["landmarks"] = np.asarray(out["landmarks"]).tolist()
        return out


def match_keywords(settings: Settings) -> dict:
    """The keywords of :func:`meshcorr.match` for ``settings``: the changed ones only.

    Maps ``n_samples`` to the name :func:`meshcorr.match` has for it, and
    refuses ``landmarks`` when this version of :func:`meshcorr.match` does
    not take them.
    """
    accepted = _MATCH_PARAMETERS
    keywords = settings.changed()
    if "n_samples" in keywords and "n_samples" not in accepted:
        keywords["n_landmarks"] = keywords.pop("n_samples")
    if "landmarks" in keywords and "landmarks" not in accepted:
        raise ParameterError("This version of meshcorr.match does not take landmarks yet; remove the "
                             "'landmarks' setting.")
    return keywords
