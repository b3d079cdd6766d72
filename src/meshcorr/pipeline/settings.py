"""The settings of a correspondence run: every option, its one default and its checks, in one object.

:class:`Settings` groups every option of :func:`meshcorr.match` by what it
controls (the method, the spectral pipeline's stages, resources). It is the
single source of the options' defaults: :func:`meshcorr.match`,
:func:`meshcorr.prepare`, :class:`meshcorr.Matcher` and the command line
(``meshcorr match``) take them from its fields, and a default that a lower
layer needs itself (:data:`meshcorr.spectral.modes.N_SAMPLES`,
:data:`~meshcorr.spectral.modes.SCALABLE_ABOVE`) is that layer's constant,
which the field refers to. A Settings is checked when it is made
(:meth:`Settings.__post_init__`), once, with one message shape ("The 'k'
parameter must be an int <= 10. Got 12 instead."): an option changed from
its default that the chosen method does not use raises
:class:`~meshcorr.errors.ParameterError` naming it
(:func:`meshcorr.pipeline.methods.reject_inapplicable`), as does an option
that another makes certain to be ignored (``refine_k`` with
``refine=False``, ``n_samples`` with ``mode="dense"``, ...), a partial-mode
option that does not go with the others raises
:class:`~meshcorr.errors.PartialityError`. Checks that need the meshes
(landmark indices, anchors against the vertex count) are left to the run.

:func:`shape_settings` derives the per-shape subset (:data:`SHAPE_SETTINGS`,
what :func:`meshcorr.prepare` computes depends on) that prepared shapes and
the shape cache record.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Sequence

import numpy as np

from ..choice.symmetry import SYMMETRY_MODES
from ..core.geodesics import DEFAULT_GEODESIC, GEODESIC_METHODS
from ..core.coarse import COARSE_VERTICES
from ..core.holes import fills
from ..errors import ParameterError
from ..runtime.checks import check_bool, check_choice, check_float, check_int, check_seed
from ..runtime.memory import parse_memory
from ..shapes.prepared import SHAPE_SETTING_NAMES
from ..spectral.modes import MODES, N_SAMPLES, SCALABLE_ABOVE
from ..spectral.embedding import N_EIGENPAIRS
from ..stages.anchors import ANCHOR_SCALES, ANCHOR_WEIGHT, N_ANCHORS
from ..stages.icp import ANNEAL, ICP_ITERATIONS, N_CONTROL
from ..stages.refine import REFINE_K
from ..stages.landmarks import landmark_table
from ..stages.part_checks import check_partial_options
from ..stages.reorder import REORDER_MODES
from .methods import METHOD_NAMES, reject_inapplicable

__all__ = ["Settings", "SHAPE_SETTINGS", "REFINE_K", "shape_settings", "as_settings"]

#: The fewest vertices of a coarse copy: fewer blur a hand or a foot into the arm or leg.
MIN_COARSE_VERTICES = 300
#: The largest ``refine_k``: ZoomOut's basis grows to it one step at a time, and each step costs more;
#: 200 is five times the default (a basis larger than a mesh's vertices - 1 is clipped to that).
MAX_REFINE_K = 200
#: Settings whose value must be True or False (numpy's too), in the order they are checked.
_SWITCHES = ("bijective", "shells", "extremities", "oriented_starts", "sign_search", "check_reverse", "prealign")
#: The spectral pipeline's switches that only it checks (with :data:`_SWITCHES`).
_SPECTRAL_SWITCHES = ("scale_eigenvalues", "refine", "largest_component", "fill_holes")


@dataclass(frozen=True)
class Settings:
    """Options of a correspondence run, each with its one default and what it does.

    ``Settings()`` holds every default; ``Settings(k=8)`` or
    ``Settings.from_options(**keywords)`` changes some. It is checked when
    made (the module docstring): an invalid Settings cannot exist.

    Attributes
    ----------
    method : {"spectral", "shapiro-brady", "shapiro-brady-scaled", "tps-rpm", "icp", "shape-context"}
        "spectral" is the pipeline of :func:`meshcorr.match`; the others are
        the paper's baselines (:mod:`meshcorr.baselines`,
        :mod:`meshcorr.pipeline.methods`), which take ``k``, ``geodesic``,
        ``bijective`` and ``largest_component`` where they apply; an option
        changed from its default that the method does not use raises
        :class:`ParameterError` naming it (:func:`meshcorr.pipeline.methods.reject_inapplicable`).
    random_state : int or None
        Seed for everything random (eigensolver start, samples).
    k : int
        Eigenpairs computed; the embedding has ``k - 1`` dimensions (paper: 6).
    geodesic : {"heat", "fmm", "exact", "dijkstra"}
        Geodesic solver (see :mod:`meshcorr.core.geodesics`).
    scale_eigenvalues : bool
        Scale eigenvectors by sqrt(eigenvalue) (the paper's default).
    reorder : {"exhaustive", "greedy", "signs", "signs-greedy", "none"}
        Eigenvector reordering and sign correction (see :mod:`meshcorr.stages.reorder`).
    icp_iterations : int
        Most thin-plate-spline ICP iterations; 0 skips the alignment.
    n_control : int
        Spline control points.
    anneal : float
        Factor lowering the spline regulariser each iteration.
    n_anchors : int
        h, anchor pairs for proximity-aided matching (0 disables it).
    anchor_weight : float
        alpha, weight of each anchor's geodesic term.
    bijective : bool
        One-to-one map by linear assignment (equal vertex counts only; each
        landmark vertex given once): every target vertex exactly once
        (:mod:`meshcorr.stages.bijection`).
    largest_component : bool
        Map only the largest connected component of each mesh instead of
        raising on several components.
    mode : {"auto", "dense", "scalable"}
        "dense": all-pairs geodesics and the exact eigenpairs (``O(n^2)``
        memory, the reference); "scalable": landmark geodesics and the
        Nyström extension (``O(n m)``); "auto": dense up to
        ``scalable_above`` vertices if it fits in ``max_memory``, else
        scalable (see :mod:`meshcorr.spectral.modes`).
    n_samples : int
        m, Nyström samples (landmark vertices) of the scalable mode
        (formerly ``n_landmarks``, which now raises :class:`ParameterError`
        naming ``n_samples``).
    max_memory : int or str, optional
        Bytes (or a size such as ``"4GiB"``) the dense mode may use; it
        refuses larger inputs. Default: 80 % of the memory available now.
    scalable_above : int
        Vertex count above which "auto" picks the scalable mode.
    prealign : bool
        Pre-align the inputs to their principal axes (spatial baselines only).
    symmetry : {"auto", "cost", "mirror"}
        How to choose among near-tied eigenvector configurations (the
        left/right mirror, :mod:`meshcorr.choice.symmetry`): "auto" keeps the
        orientation-preserving map whose curvature agrees best, then the
        whole-map choice (``extremities``, ``landmarks``); "cost" the cheapest
        configuration (the paper); "mirror" the configuration of the other
        orientation than "auto"'s (it may be the cheapest, and then the same
        map as "cost"). "cost" and "mirror" skip the whole-map choice and do
        not go with ``landmarks`` (:class:`ParameterError`).
    refine : bool
        Refine the map by ZoomOut spectral upsampling (:mod:`meshcorr.stages.refine`).
    refine_k : int
        Laplace-Beltrami basis size of the refinement, 2 to :data:`MAX_REFINE_K`
        (clipped to a mesh's vertices - 1).
    shells : bool
        After the refinement, align the shapes' smooth shells (their
        coordinates low-passed to a growing number of Laplace-Beltrami
        functions) by a rigid motion and a smooth deformation, and map in the
        product of that space and the spectral one (:mod:`meshcorr.stages.shells`,
        after Smooth Shells), on a schedule of small steps
        (:data:`meshcorr.stages.shells.SCALES`). With ``landmarks`` their geodesic
        distances join that space. Meshes only, with ``refine`` and without
        ``bijective`` (point clouds and one-to-one maps keep the ZoomOut
        map); a declared part is aligned with the whole's shells from 16
        functions on (:mod:`meshcorr.pipeline.partial`, step 6).
    anchor_scale : {"embedding", "geodesic"}
        "embedding": the anchor term is expressed in the embedding's length
        scale (its geodesics times mean embedding distance / (h x mean
        normalised geodesic distance)), so it is commensurate with the
        embedding term; "geodesic": geodesics divided by the largest one,
        as the paper does (docs/method.md, step 6).
    landmarks : sequence of (source_index, target_index), optional
        Vertices the user knows to correspond (0-based, input numbering).
        They start a candidate map of their own, decide among the candidate
        maps (the one that agrees with them wins: this settles the left/right
        choice), join the descriptors of the smooth-shell alignment (their
        geodesic distances) and are mapped exactly (:mod:`meshcorr.choice.selection`).
    extremities : bool
        Also try maps started from matched shape extremities
        (:mod:`meshcorr.choice.extremities`) and keep the map the whole-map energies
        prefer (:mod:`meshcorr.choice.selection`); needed when the shapes'
        proportions differ. Used with ``symmetry="auto"``.
    oriented_starts : bool
        Also turn each tip assignment into a map by an orientation-preserving
        functional-map fit (:mod:`meshcorr.choice.oriented_start`), not only by
        distances to the tips. Distances to tips that lie near one plane (a
        person standing: head, hands and feet) cannot tell front from back;
        the fit can. Measured better on people of one species (SHREC'07
        humans) and worse across species (gorilla -> human: the fit turns a
        mirrored assignment into a map turned front to back that the energies
        do not always reject), so it is off by default
        (``benchmarks/RESULTS-robustness.md``). Needs a reliable orientation.
    sign_search : bool
        Also start the whole-map choice from the configurations of the first
        Laplace-Beltrami functions' signs, the best by their smooth-shell
        alignment energy (:mod:`meshcorr.choice.sign_search`, after Smooth
        Shells): a wider search for the global configuration, on coarse
        copies. Used with ``symmetry="auto"``. Off by default: measured better
        on four-legged animals and worse on people, whose added maps turned
        front to back the energies cannot reject (docs/method.md).
    check_reverse : bool
        Also match the pair the other way round and report how far a round
        trip (source -> target -> source) moves source vertices
        (``result.confidence["cycle_error"]``, :mod:`meshcorr.choice.reverse_check`):
        two choices made apart that disagree mean one of them turned or
        mirrored the shape. Above the limit the choice is reported as unsure.
        Doubles the time of a match.
    partial : {None, "source", "target"}
        None: both shapes are whole (they may have small holes).
        ``"source"``: the source is a part of the target (one side of a scan,
        a shape cut by a plane or with large holes); ``"target"``: the target
        is a part of the source. The map then covers the part only (with
        ``"target"``, source vertices outside the matched region get -1), and
        ``result.matched_region`` / ``result.matched_area_fraction`` say which
        region of the whole shape was matched (:mod:`meshcorr.pipeline.partial`; the
        options of steps 1-7 shape one of its starting maps). A declared part
        must have a boundary and must not be larger than the whole;
        ``bijective=True``, a ``symmetry`` other than "auto" and a method
        other than "spectral" do not go with it (each raises
        :class:`~meshcorr.errors.PartialityError`). When it is None and one
        shape has a long open boundary the other lacks,
        :class:`~meshcorr.errors.PartialShapeWarning` names the mode to use.
    coarse_vertices : int
        Make the global choice on coarse copies of about this many vertices
        (:mod:`meshcorr.core.coarse`): a mesh with more vertices is decimated,
        steps 1-6 and the whole-map choice run on the copies, and only the
        chosen map is carried to every vertex and refined there (ZoomOut, then
        the smooth shells). The choice then costs the same at any vertex
        count. 0 runs every step on the meshes themselves (the reference; also
        what ``refine=False``, ``bijective``, ``symmetry`` other than "auto"
        and point clouds do).
    fill_holes : bool
        Close the meshes' holes before matching: each simple boundary loop
        gets a fan of triangles around a new centre vertex, and the map is
        reported on the input's vertices only (a vertex sent onto a cap goes
        to the nearest vertex of its hole's rim; :mod:`meshcorr.core.holes`).
        Holes change geodesics, the Laplace-Beltrami functions and the
        extremities; closed, a shape with holes maps about as well as
        without them. Not done with ``partial`` (a part's boundary is its
        cut) nor with ``bijective`` (the vertex counts must stay).
    """

    method: str = "spectral"
    random_state: int | None = 0
    # the spectral pipeline's stages
    k: int = N_EIGENPAIRS
    geodesic: str = DEFAULT_GEODESIC
    scale_eigenvalues: bool = True
    reorder: str = "exhaustive"
    icp_iterations: int = ICP_ITERATIONS
    n_control: int = N_CONTROL
    anneal: float = ANNEAL
    n_anchors: int = N_ANCHORS
    anchor_weight: float = ANCHOR_WEIGHT
    anchor_scale: str = "embedding"
    symmetry: str = "auto"
    refine: bool = True
    refine_k: int = REFINE_K
    shells: bool = True
    landmarks: Sequence[tuple[int, int]] | np.ndarray | None = None
    extremities: bool = True
    oriented_starts: bool = False
    sign_search: bool = False
    check_reverse: bool = False
    partial: str | None = None
    fill_holes: bool = True
    coarse_vertices: int = COARSE_VERTICES
    # the output and the input
    bijective: bool = False
    largest_component: bool = False
    prealign: bool = True
    # resources
    mode: str = "auto"
    n_samples: int = N_SAMPLES
    max_memory: int | str | None = None
    scalable_above: int = SCALABLE_ABOVE

    def __post_init__(self) -> None:
        """Check every setting, in the order :func:`meshcorr.match` always has; store the checked values.

        Raises
        ------
        ParameterError
            A value out of range or of the wrong type, or an option changed
            from its default that the method does not use.
        PartialityError
            ``partial`` with options that do not go with it
            (:func:`meshcorr.stages.part_checks.check_partial_options`).
        """
        check_choice("method", self.method, METHOD_NAMES)
        has_pairs = landmark_table(self.landmarks) is not None  # checked here; against the meshes by the run
        changed = self.changed()
        check_partial_options(self.partial, self.method, changed)
        reject_inapplicable(self.method, changed)
        checked = {"random_state": check_seed(self.random_state)}
        checked.update((name, check_bool(name, getattr(self, name))) for name in _SWITCHES)
        if self.method == "spectral":
            checked.update(self._spectral_values(has_pairs))
        for name, value in checked.items():
            object.__setattr__(self, name, value)

    def _spectral_values(self, has_pairs: bool) -> dict:
        """The checked values of the spectral pipeline's settings (the baselines check their own)."""
        k = check_int("k", self.k, minimum=2, maximum=10)
        values = dict(k=k, geodesic=check_choice("geodesic", self.geodesic, GEODESIC_METHODS),
                      n_samples=check_int("n_samples", self.n_samples, minimum=k + 1))
        values.update((name, check_bool(name, getattr(self, name))) for name in _SPECTRAL_SWITCHES)
        values.update(refine_k=_refine_size(self.refine_k),
                      reorder=check_choice("reorder", self.reorder, REORDER_MODES),
                      n_anchors=check_int("n_anchors", self.n_anchors, minimum=0, flag="--anchors"),
                      coarse_vertices=_coarse_size(self.coarse_vertices),
                      anchor_weight=check_float("anchor_weight", self.anchor_weight, minimum=0.0,
                                                  flag="--alpha"),
                      mode=check_choice("mode", self.mode, MODES))
        if self.max_memory is not None:
            parse_memory(self.max_memory)  # a size it cannot read raises here (the run resolves it)
        check_choice("symmetry", self.symmetry, SYMMETRY_MODES)
        check_choice("anchor_scale", self.anchor_scale, ANCHOR_SCALES)
        _reject_ignored(self.changed(), bijective=self.bijective)
        if has_pairs and self.symmetry != "auto":
            raise ParameterError(f"Landmarks settle the left/right choice in the whole-map choice "
                                 f"(symmetry='auto'); symmetry={self.symmetry!r} (--symmetry {self.symmetry}) "
                                 "would set them aside. Keep symmetry='auto' (the default) with landmarks.")
        return values

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


def _reject_ignored(changed: dict, *, bijective: bool) -> None:
    """Refuse an option changed from its default that another option makes certain to be ignored.

    ``n_samples`` with ``mode="dense"``, ``max_memory`` with ``mode="scalable"`` (without
    ``bijective``, whose cost matrix it bounds), ``refine_k`` with ``refine=False``, ``n_control`` or
    ``anneal`` with ``icp_iterations=0``: the map would be the same without them. ``mode="auto"`` may
    resolve to either mode at run time, so it goes with both ``n_samples`` and ``max_memory``.
    """
    pairs = []
    if changed.get("mode") == "dense" and "n_samples" in changed:
        pairs.append(("n_samples", "--samples", "the Nystrom sample count of the scalable mode",
                      "mode='dense' (--mode dense)", "use mode='scalable' or 'auto'"))
    if changed.get("mode") == "scalable" and "max_memory" in changed and not bijective:
        pairs.append(("max_memory", "--max-memory", "the memory the dense mode (or a one-to-one map) may use",
                      "mode='scalable' (--mode scalable)", "use mode='auto' or 'dense'"))
    if "refine" in changed and not changed["refine"] and "refine_k" in changed:
        pairs.append(("refine_k", "--refine-k", "the basis size of the ZoomOut refinement",
                      "refine=False (--no-refine)", "keep refine=True"))
    if changed.get("icp_iterations") == 0:
        pairs += [(name, flag, "a setting of the thin-plate-spline ICP", "icp_iterations=0 (--icp-iterations 0)",
                   "give icp_iterations > 0") for name, flag in (("n_control", "--control-points"),
                                                                  ("anneal", "--anneal")) if name in changed]
    if pairs:
        name, flag, what, other, instead = pairs[0]
        raise ParameterError(f"{name}={changed[name]!r} ({flag}) is {what}, which {other} skips: it would be "
                             f"ignored. Remove {name} ({flag}), or {instead}.")


def _refine_size(value) -> int:
    """``refine_k`` checked: 2 to :data:`MAX_REFINE_K`."""
    value = check_int("refine_k", value, minimum=2)
    if value > MAX_REFINE_K:
        raise ParameterError(f"refine_k={value} (--refine-k) is more than the refinement uses: give at most "
                             f"{MAX_REFINE_K} (default {REFINE_K}). A larger basis takes minutes: 100000, clipped "
                             "to a mesh's vertices - 1, took 131 s on a 500-vertex mesh.")
    return value


def _coarse_size(value) -> int:
    """``coarse_vertices`` checked: 0 (off) or at least :data:`MIN_COARSE_VERTICES`."""
    value = check_int("coarse_vertices", value, minimum=0)
    if 0 < value < MIN_COARSE_VERTICES:
        raise ParameterError(f"coarse_vertices={value} (--coarse-vertices) is too few for the global choice: "
                             f"give 0 (every step on the full meshes) or at least {MIN_COARSE_VERTICES} "
                             f"(default {COARSE_VERTICES}).")
    return value


def as_settings(settings: Settings | None, overrides: dict) -> Settings:
    """``settings`` (default: ``Settings()``) with the keywords ``overrides`` replacing single fields, checked.

    Raises
    ------
    ParameterError
        ``settings`` that is no Settings, or an unknown keyword (the message
        of :meth:`Settings.from_options`, with its ``n_landmarks`` hint), or
        a value :class:`Settings` refuses.
    """
    if settings is None:
        return Settings.from_options(**overrides)
    if not isinstance(settings, Settings):
        raise ParameterError(f"settings must be a meshcorr.Settings (or None); got {type(settings).__name__}. "
                             "Pass single settings as keywords: match(source, target, k=8, ...).")
    return settings.replace(**overrides) if overrides else settings


def shape_settings(settings: Settings | None = None, **overrides) -> dict:
    """The per-shape settings of ``settings``: :data:`SHAPE_SETTINGS`' names, as prepared shapes record them.

    What :func:`meshcorr.prepare` computes depends on these alone; the dict
    is stored in prepared-shape files and is part of the shape cache's keys
    (:mod:`meshcorr.shapes.cache`), so its keys, order and value types stay
    as they are. ``fill_holes`` is what the run does: False with
    ``partial`` or ``bijective`` (:func:`meshcorr.core.holes.fills`).
    """
    settings = as_settings(settings, overrides)
    out = {name: getattr(settings, name) for name in SHAPE_SETTING_NAMES}
    out["fill_holes"] = fills(settings.fill_holes, partial=settings.partial, bijective=settings.bijective)
    return out


#: The per-shape settings and their defaults (:func:`shape_settings` of ``Settings()``).
SHAPE_SETTINGS: dict = shape_settings()
