"""The result of a correspondence computation, and what can be done with it.

:class:`Correspondence` holds the vertex map and how it was found, and keeps
both meshes it was computed on, so that in a notebook or a script the map
can be evaluated (:meth:`~Correspondence.evaluate`), turned into a precise
map (:meth:`~Correspondence.precise_map`) or a functional map
(:meth:`~Correspondence.functional_map`), used to carry values
(:meth:`~Correspondence.transfer`), inverted, composed, saved, loaded and
shown (:meth:`~Correspondence.show`).
"""

from __future__ import annotations

import html
import json
import os
from dataclasses import dataclass, field, fields

import numpy as np

from .._version import __version__
from ..errors import InputError, ParameterError
from ..core.mesh import Mesh
from ..stages.reorder import Configuration
from ..core.geodesics import DEFAULT_GEODESIC

#: The ``match`` function "Match again" of :meth:`Correspondence.pick` runs; :mod:`meshcorr.pipeline.run` sets
#: it to :func:`meshcorr.match` when it loads (``maps`` is below ``pipeline`` and may not import it).
RERUN = None

#: Array attributes written by :meth:`Correspondence.save`.
_ARRAYS = ("map", "cost", "source_vertices", "target_vertices", "source_embedding", "target_embedding",
           "aligned_target_embedding", "anchors", "alternative_map", "matched_region")
#: Attributes that are no JSON and no array.
_SPECIAL = ("configuration", "alternatives", "eigenvalues", "source", "target")


def _light_copy(mesh: Mesh | None) -> Mesh | None:
    """The mesh without its large cached data (geodesic matrices); Laplace-Beltrami bases are kept."""
    if mesh is None:
        return None
    copy = Mesh(mesh.vertices, mesh.faces, name=mesh.name, kept=mesh.kept, n_original=mesh.n_original,
                n_caps=mesh.n_caps)
    for key, value in mesh.store.items():
        if key[0] == "laplace_basis":
            copy.store.put(key, value)
    return copy


@dataclass
class Correspondence:
    """A vertex map from a source mesh to a target mesh, with how it was found.

    Attributes
    ----------
    map : (n_source,) int
        ``map[i]`` is the target vertex matched to source vertex i, in the
        vertex numbering of the input files. -1 for source vertices that
        were not mapped (dropped by ``largest_component=True``). In pyFM's
        naming this is ``p2p_21`` with mesh 1 = target, mesh 2 = source.
    cost : (n_source,) float or None
        Final matching cost of each pair (NaN where unmapped): the
        proximity-aided matching's embedding-plus-anchor distance, or a
        baseline's final distance. None when the last stage has no per-pair
        cost: the ZoomOut refinement (on by default), a map of the whole-map
        choice other than the spectral one, a baseline without one.
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
        :func:`meshcorr.stages.refine.prefetch_bases`); not part of the sum above.
    stage_memory : dict
        Peak resident memory of the process (MiB) while each stage ran
        (:class:`meshcorr.runtime.timing.StageTimer`; empty off Linux).
    params : dict
        The options used; ``shells`` and ``fill_holes`` as they ran (False
        where they do not apply: point clouds, ``bijective``, ``partial``,
        ``refine=False`` for the shells).
    candidates : list of dict
        The near-tied configurations whose maps were scored to resolve the
        left/right mirror (:mod:`meshcorr.choice.symmetry`): rank, perm, signs,
        cost, orientation score, curvature disagreement, metric distortion
        (None unless the orientation was unreliable), and which one was
        chosen / kept as the alternative.
    alternative_map : (n_source,) int or None
        The map of the alternative candidate (usually the mirror image of
        ``map``), same numbering and conventions as ``map``; it is not
        refined.
    orientation_reliable : bool or None
        Whether both meshes have a well-defined outside, so orientation
        scores mean something (see :mod:`meshcorr.core.orientation`).
    refine_history : list of dict
        Per ZoomOut iteration (:mod:`meshcorr.stages.refine`): basis size, fraction changed.
    map_candidates : list of dict
        The complete maps judged by the whole-map choice
        (:mod:`meshcorr.choice.selection`, where each energy is defined and cited),
        one dict each: ``origin`` ("spectral", "extremities-r", "landmarks",
        "repaired-..."; with ``partial``: "whole-to-whole", ...),
        ``orientation`` (area fraction kept in orientation, after the smooth
        shells for a shelled map), ``distortion`` (metric distortion),
        ``curvature`` (curvature disagreement), ``regional_orientation``
        (worst region's orientation), ``landmark_error`` and ``landmarks_kept``
        (NaN without landmarks), ``energy`` (the value the choice minimises:
        distortion x curvature^3, times the reversed area fractions before and
        after the shells for a shelled map; only maps that keep the most
        landmarks and, with a reliable orientation, have orientation >= 0.6
        compete), ``chosen`` / ``alternative``, and where they apply
        ``extremity_energy`` (the tip assignment's cost), ``shells`` (1: the
        map was refined by the smooth shells) and ``zoomout_orientation``
        (its orientation before them). Empty when that stage did not run
        (``symmetry="cost"`` or ``"mirror"``, ``extremities=False`` without
        landmarks).
    confidence : dict or None
        How sure the whole-map choice is (:mod:`meshcorr.choice.confidence`):
        ``margin``, :math:`\\log P(\\text{chosen}) / P(\\text{rival})`, how much more
        probable the chosen map is than the best map of a different global
        configuration (the rival: a mirror, a front/back turn, limbs
        exchanged; None without a rival); ``probability``, that the chosen
        configuration is the right one among the candidates' (1 without a rival);
        ``low``, whether it is below the unsure threshold; ``rival``, that
        map's origin; ``suggested_landmarks``, a few ``{"source", "chosen",
        "rival"}`` vertices (input numbering) where the two maps disagree
        most: a landmark on each settles the choice; with ``check_reverse``,
        ``cycle_error``, how far a round trip through the map and the map
        back moves source vertices (geodesic distance over sqrt(area)).
        None when no whole-map choice was made.
    partial : {None, "source", "target"}
        Which shape was declared a part of the other (:mod:`meshcorr.pipeline.partial`);
        None for a whole-to-whole map.
    matched_region : (n_whole,) bool or None
        With ``partial``: the vertices of the whole shape (the target for
        ``"source"``, the source for ``"target"``; input numbering) that have
        a counterpart on the part. None for a whole-to-whole map.
    matched_area_fraction : float or None
        With ``partial``: the area of ``matched_region`` over the whole shape's area.
    source, target : Mesh or None
        The meshes as matched (after ``largest_component``), kept without
        their cached geodesic matrices; None if not recorded.
    version : str
        The meshcorr version that computed the map (also ``params["meshcorr_version"]``).
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
    stage_memory: dict = field(default_factory=dict)
    params: dict = field(default_factory=dict)
    candidates: list[dict] = field(default_factory=list)
    alternative_map: np.ndarray | None = None
    orientation_reliable: bool | None = None
    refine_history: list = field(default_factory=list)
    map_candidates: list[dict] = field(default_factory=list)
    confidence: dict | None = None
    partial: str | None = None
    matched_region: np.ndarray | None = None
    matched_area_fraction: float | None = None
    source: Mesh | None = field(default=None, repr=False, compare=False)
    target: Mesh | None = field(default=None, repr=False, compare=False)
    version: str = __version__

    def __post_init__(self) -> None:
        self.params = {**self.params, "meshcorr_version": self.params.get("meshcorr_version", self.version)}
        self.source, self.target = _light_copy(self.source), _light_copy(self.target)

    def attach_meshes(self, source: Mesh, target: Mesh) -> None:
        """Record the meshes the map was computed on (as :func:`meshcorr.match` does)."""
        self.source, self.target = _light_copy(source), _light_copy(target)

    @property
    def runner_up(self) -> Configuration | None:
        """The second-ranked configuration, or None if there is only one."""
        return self.alternatives[1] if len(self.alternatives) > 1 else None

    def summary(self) -> dict:
        """A JSON-serialisable summary (no per-vertex arrays)."""
        mapped = self.map >= 0
        has_cost = self.cost is not None and bool(np.isfinite(self.cost).any())
        return {
            "meshcorr_version": self.version,
            "method": self.method,
            "n_source": int(len(self.map)),
            "n_mapped": int(mapped.sum()),
            "n_target_hit": int(len(np.unique(self.map[mapped]))),
            "configuration": self.configuration.to_dict() if self.configuration else None,
            "map_candidates": self.map_candidates,
            "confidence": self.confidence,
            "runner_up": self.runner_up.to_dict() if self.runner_up else None,
            "n_configurations": len(self.alternatives),
            "eigenvalues": {k: [float(x) for x in v] for k, v in self.eigenvalues.items()},
            "anchors": self.anchors.tolist() if self.anchors is not None else None,
            "mean_cost": float(np.nanmean(self.cost)) if has_cost else None,
            "icp": {"iterations": len(self.icp_history), "converged": self.icp_converged,
                    "history": self.icp_history},
            "timings": {k: round(v, 4) for k, v in self.timings.items()},
            "background_timings": {k: round(v, 4) for k, v in self.background_timings.items()},
            "stage_memory": {k: round(v, 1) for k, v in self.stage_memory.items()},
            "params": self.params,
            "candidates": self.candidates,
            "orientation_reliable": self.orientation_reliable,
            "refine": {"iterations": len(self.refine_history), "history": self.refine_history},
            "partial": self._partial_summary(),
        }

    def _partial_summary(self) -> dict | None:
        """The partial mode's report: which shape is whole, the matched region's vertices and area share."""
        if self.partial is None or self.matched_region is None:
            return None
        matched = np.flatnonzero(self.matched_region)
        return {"part": self.partial, "whole": "target" if self.partial == "source" else "source",
                "matched_area_fraction": round(float(self.matched_area_fraction), 4),
                "n_matched_vertices": int(len(matched)), "matched_vertices": matched.tolist()}

    # ------------------------------------------------------------------ display

    def _headline(self) -> dict:
        mapped = self.map >= 0
        n_target = self.target.n_original if self.target is not None else None
        return {"method": self.method, "n_source": int(len(self.map)), "n_mapped": int(mapped.sum()),
                "n_target": n_target, "n_target_hit": int(len(np.unique(self.map[mapped]))),
                "partial": self.partial,
                "matched_area_fraction": (None if self.matched_area_fraction is None
                                          else round(float(self.matched_area_fraction), 3)),
                "confidence": (None if not self.confidence or self.confidence.get("margin") is None
                               else round(float(self.confidence["margin"]), 2)),
                "seconds": round(float(sum(self.timings.values())), 2), "version": self.version}

    def __repr__(self) -> str:
        head = self._headline()
        text = ", ".join(f"{key}={value!r}" for key, value in head.items() if value is not None)
        return f"Correspondence({text})"

    def _repr_html_(self) -> str:
        head = self._headline()
        rows = [("method", head["method"]),
                ("source vertices mapped", f"{head['n_mapped']} of {head['n_source']}"),
                ("target vertices reached", f"{head['n_target_hit']}"
                 + (f" of {head['n_target']}" if head["n_target"] is not None else "")),
                ("configuration", self.configuration.to_dict() if self.configuration else "-"),
                ("ICP iterations", f"{len(self.icp_history)} (converged: {self.icp_converged})"),
                ("refinement iterations", len(self.refine_history)),
                *([("partial", f"the {head['partial']} is a part; matched region: "
                       f"{head['matched_area_fraction']:.1%} of the whole")] if head["partial"] else []),
                ("seconds", head["seconds"]),
                ("meshcorr", self.version)]
        cells = "".join(f"<tr><th style='text-align:left'>{html.escape(str(k))}</th>"
                        f"<td style='text-align:left'>{html.escape(str(v))}</td></tr>" for k, v in rows)
        return f"<table><caption>meshcorr.Correspondence</caption>{cells}</table>"

    # ------------------------------------------------------------------ meshes and maps

    def _meshes(self, what: str) -> tuple[Mesh, Mesh]:
        if self.source is None or self.target is None:
            raise ParameterError(f"{what} needs the meshes, which this result does not hold; compute it "
                                 "with meshcorr.match or meshcorr.Matcher (they record them), or call "
                                 "result.attach_meshes(source, target).")
        return self.source, self.target

    def local_map(self) -> np.ndarray:
        """``(n1,)`` int: the map in the numbering of the matched meshes ``source`` / ``target``.

        The same as :attr:`map` unless ``largest_component`` dropped
        vertices; -1 where unmapped.
        """
        src, tgt = self._meshes("local_map")
        to_local = np.full(tgt.n_original, -1, dtype=np.int64)
        to_local[tgt.kept] = np.arange(tgt.n_vertices)
        images = self.map[src.kept]
        return np.where(images >= 0, to_local[np.maximum(images, 0)], -1)

    def precise_map(self, *, k: int | None = None, n_nearest: int = 4):
        """Each source vertex on a target triangle (:func:`meshcorr.maps.precise.precise_map`).

        Parameters
        ----------
        k : int, optional
            Laplace-Beltrami basis size; default the refinement's (``params["refine_k"]``, else 30),
            clipped to the smaller mesh's vertex count - 1 as the refinement clips it. A ``k``
            given larger than that is refused.
        n_nearest : int
            Target vertices whose triangles are searched.

        Returns
        -------
        precise : meshcorr.maps.precise.PreciseMap
            In the input files' numbering (``faces`` index the target's triangles).
        """
        from .precise import precise_map

        src, tgt = self._meshes("precise_map")
        if k is None:
            k = min(int(self.params.get("refine_k", 30)), src.n_vertices - 1, tgt.n_vertices - 1)
        return precise_map(src, tgt, self.local_map(), k=k, n_nearest=n_nearest,
                           random_state=self.params.get("random_state", 0))

    def functional_map(self, k: int = 30, *, k_target: int | None = None):
        """The map's functional map in Laplace-Beltrami bases of size ``k`` (:mod:`meshcorr.spectral.fmap`).

        Returns
        -------
        fmap : meshcorr.spectral.fmap.FunctionalMap
            ``C`` is ``(k, k_target)``: target coefficients to source
            coefficients (pyFM's ``FM_12`` with mesh 1 = target, mesh 2 = source).
        """
        from ..spectral.fmap import functional_map

        src, tgt = self._meshes("functional_map")
        return functional_map(src, tgt, self.local_map(), k, k_target=k_target,
                              random_state=self.params.get("random_state", 0))

    def transfer(self, values, *, precise: bool = False, fill=np.nan) -> np.ndarray:
        """Carry per-vertex target values to the source (pull-back, :mod:`meshcorr.maps.transfer`).

        Parameters
        ----------
        values : (n_target,) or (n_target, c) array
            E.g. labels, a scalar field, RGB colours, UV coordinates.
        precise : bool
            Interpolate barycentrically at the precise map's points
            (:meth:`precise_map`) instead of copying each matched vertex's
            value; integer values (e.g. RGB colours) are rounded back to their type.
        fill : scalar
            Value of unmapped source vertices (0 for integer values carried precisely).

        Returns
        -------
        pulled : (n_source,) or (n_source, c) array
        """
        from .transfer import check_map, pull_back

        values = np.asarray(values)
        if values.ndim not in (1, 2) or not np.issubdtype(values.dtype, np.number) and values.dtype != bool:
            raise ParameterError(f"transfer needs numbers, one value (or row) per target vertex: an (n_target,) or "
                                 f"(n_target, c) array; got shape {values.shape} and dtype {values.dtype}.")
        n_target = self.target.n_original if self.target is not None else None
        if n_target is not None and len(values) != n_target:
            raise ParameterError(f"transfer needs one value per target vertex ({n_target}); got {len(values)}.")
        if precise:
            pulled = self.precise_map().interpolate(values)
            if values.dtype.kind in "iub":  # labels, colours: the nearest representable value
                pulled = np.round(np.nan_to_num(pulled, nan=fill if np.isfinite(fill) else 0)).astype(values.dtype)
            return pulled
        check_map(self.map, len(self.map), len(values), name="the map")
        return pull_back(values, self.map, fill=fill)

    def inverse(self) -> "Correspondence":
        """The map from the target back to the source.

        Each target vertex goes to a source vertex whose image is the
        target vertex nearest to it in space among all images (the source
        vertex itself where it was reached; the nearest reached vertex's
        source vertex elsewhere, so unreached target vertices are mapped too).

        Returns
        -------
        inverse : Correspondence
            ``method`` is ``"inverse of ..."``; meshes swapped.
        """
        from ..collection.consistency import input_positions, invert

        src, tgt = self._meshes("inverse")
        if not (self.map >= 0).any():
            raise ParameterError("The map sends no source vertex anywhere; it has no inverse.")
        full = invert(self.map, input_positions(tgt))
        return Correspondence(map=full, method=f"inverse of {self.method}", source_vertices=tgt.kept.copy(),
                              target_vertices=src.kept.copy(), params=dict(self.params), source=tgt, target=src)

    def compose(self, other: "Correspondence") -> "Correspondence":
        """This map followed by ``other``: source -> (this target = other's source) -> other's target.

        Raises
        ------
        ParameterError
            If ``other`` starts on a mesh with another vertex count than this map's target.
        """
        n_mid = self.target.n_original if self.target is not None else None
        if n_mid is not None and len(other.map) != n_mid:
            raise ParameterError(f"Cannot compose: this map's target has {n_mid} vertices but the other map "
                                 f"starts on a mesh with {len(other.map)}; compose maps A->B then B->C.")
        valid = (self.map >= 0) & (self.map < len(other.map))
        full = np.full(len(self.map), -1, dtype=np.int64)
        full[valid] = other.map[self.map[valid]]
        return Correspondence(map=full, method=f"{self.method} then {other.method}",
                              params={"first": self.params, "second": other.params},
                              source=self.source, target=other.target)

    # ------------------------------------------------------------------ evaluation and viewing

    def evaluate(self, truth, *, sym_truth=None, geodesic: str = DEFAULT_GEODESIC) -> dict:
        """Score the map: geodesic error against ground truth, and coverage, bijectivity, continuity.

        Parameters
        ----------
        truth : GroundTruth or (n_source,) int
            True pairs, or a dense true map (``truth[i]`` = true target vertex of source vertex i).
        sym_truth : GroundTruth or (n_source,) int, optional
            The mirrored truth.
        geodesic : str
            Geodesic solver of the errors.

        Returns
        -------
        report : dict
            :func:`meshcorr.evaluation.metrics.evaluate_map`'s report (without the
            per-point arrays) and :func:`meshcorr.evaluation.metrics.map_quality`'s measures.
        """
        from ..evaluation.metrics import evaluate_map, map_quality, scalar_summary
        from ..evaluation.ground_truth import GroundTruth

        src, tgt = self._meshes("evaluate")

        def as_truth(t, name):
            if t is None and name == "sym_truth" or isinstance(t, GroundTruth):
                return t
            t = np.asarray(t)
            if t.shape != self.map.shape or not np.issubdtype(t.dtype, np.integer):
                raise ParameterError(f"{name} must be a GroundTruth or a dense true map: one integer target vertex "
                                     f"per source vertex, shape {self.map.shape}; got shape {t.shape} and dtype "
                                     f"{t.dtype}.")
            return GroundTruth(np.arange(len(t)), t, description="the true map")

        full_target = tgt if tgt.n_vertices == tgt.n_original else None
        if full_target is None:
            raise ParameterError("evaluate needs the whole target mesh; this map was computed on its largest "
                                 "component: use meshcorr.evaluation.metrics.evaluate_map with the target file.")
        report = scalar_summary(evaluate_map(tgt, self.map, as_truth(truth, "truth"),
                                             sym_truth=as_truth(sym_truth, "sym_truth"), geodesic=geodesic))
        report.update(map_quality(src, tgt, self.local_map()))
        return report

    def show(self, **options):
        """Source and target side by side with linked colours (:func:`meshcorr.viz.notebook.show`)."""
        from ..viz.notebook import show

        src, tgt = self._meshes("show")
        return show(src, tgt, self.local_map(), **options)

    def pick(self, output: str | os.PathLike | None = None, *, port: int = 0, **options):
        """Click landmark pairs on both meshes in the browser, and match again with them.

        The picker of ``meshcorr pick`` (:mod:`meshcorr.viz.pick`), served
        from a background thread on 127.0.0.1 and shown in a frame in a
        notebook (or open ``picker.url``); it starts from this map and its
        suggested landmarks (``confidence``). "Match again" runs
        :func:`meshcorr.match` on these meshes with the pairs and ``options``
        (offered once :mod:`meshcorr.pipeline.run` is loaded: ``meshcorr.match``
        made this result or was used since).

        Parameters
        ----------
        output : path, optional
            The landmark file "Save" writes; None: the pairs stay in ``picker.landmarks``.
        port : int
            0: a free port.
        **options
            Options of :func:`meshcorr.match` for "Match again".

        Returns
        -------
        picker : meshcorr.viz.pick.Picker
            ``picker.landmarks`` ``(L, 2)`` int, input numbering (``landmarks=`` of
            :func:`meshcorr.match`); ``picker.mapping`` the latest map; ``picker.close()``.
        """
        from ..viz.pick import Picker, PickSession

        src, tgt = self._meshes("pick")
        rerun = RERUN

        def matcher(pairs, progress):
            result = rerun(src, tgt, landmarks=pairs.tolist() if len(pairs) else None, progress=progress, **options)
            return result.local_map(), result.confidence

        session = PickSession((src.vertices, src.faces), (tgt.vertices, tgt.faces), mapping=self.local_map(),
                              output=output, matcher=None if rerun is None else matcher, confidence=self.confidence,
                              source_ids=src.kept, target_ids=tgt.kept)
        return Picker(session, port=port)

    # ------------------------------------------------------------------ files

    def save(self, path: str | os.PathLike) -> None:
        """Write the whole result, meshes included, to one ``.npz`` file (atomically).

        :meth:`load` reads it back; arrays as they are, the rest as JSON.
        """
        from ..io import write_npz

        arrays = {name: getattr(self, name) for name in _ARRAYS if getattr(self, name) is not None}
        for role in ("source", "target"):
            mesh = getattr(self, role)
            if mesh is not None:
                arrays.update({f"{role}_mesh_vertices": mesh.vertices, f"{role}_mesh_faces": mesh.faces,
                               f"{role}_mesh_kept": mesh.kept,
                               f"{role}_mesh_n_original": np.array(mesh.n_original)})
        for role, values in self.eigenvalues.items():
            arrays[f"eigenvalues_{role}"] = np.asarray(values)
        rest = {f.name: getattr(self, f.name) for f in fields(self)
                if f.name not in _ARRAYS and f.name not in _SPECIAL}
        rest["configuration"] = self.configuration.to_dict() if self.configuration else None
        rest["alternatives"] = [c.to_dict() for c in self.alternatives]
        rest["mesh_names"] = {role: getattr(self, role).name for role in ("source", "target")
                              if getattr(self, role) is not None}
        text = json.dumps(rest, default=_json_default)
        write_npz(path, {**arrays, "json": np.frombuffer(text.encode(), dtype=np.uint8)})

    @classmethod
    def load(cls, path: str | os.PathLike) -> "Correspondence":
        """Read a result written by :meth:`save`.

        Raises
        ------
        InputError
            If the file is missing or is no saved result, or its map is not one integer target
            vertex (or -1) per source vertex of the meshes saved with it.
        """
        from ..io import read_npz

        arrays = read_npz(path, "a saved meshcorr result")
        if "json" not in arrays or "map" not in arrays:
            raise InputError(f"{path} is not a saved meshcorr result: it lacks the map or its metadata.")
        try:
            rest = json.loads(arrays.pop("json").tobytes().decode())
            configuration = rest.pop("configuration")
            to_config = lambda d: Configuration(tuple(d["perm"]), tuple(d["signs"]), d["cost"])  # noqa: E731
            rest["configuration"] = to_config(configuration) if configuration else None
            rest["alternatives"] = [to_config(d) for d in rest["alternatives"]]
            meshes, names = {}, rest.pop("mesh_names", {})  # files saved before the names were: the roles
            for role in ("source", "target"):
                if f"{role}_mesh_vertices" in arrays:
                    meshes[role] = Mesh(arrays.pop(f"{role}_mesh_vertices"), arrays.pop(f"{role}_mesh_faces"),
                                        name=names.get(role, role), kept=arrays.pop(f"{role}_mesh_kept"),
                                        n_original=int(arrays.pop(f"{role}_mesh_n_original")))
            eigenvalues = {key[len("eigenvalues_"):]: arrays.pop(key) for key in list(arrays)
                           if key.startswith("eigenvalues_")}
            for name in ("map", "alternative_map"):
                if name in arrays:
                    arrays[name] = _checked_map(path, name, arrays[name], meshes)
            return cls(**arrays, **rest, **meshes, eigenvalues=eigenvalues)
        except InputError:
            raise
        except (ValueError, KeyError, TypeError, AttributeError, UnicodeDecodeError) as exc:  # JSONDecodeError too
            raise InputError(f"{path} is not a saved meshcorr result (damaged or from another program: "
                             f"{type(exc).__name__}: {exc}). Save the result again.") from None


def _checked_map(path, name: str, mapping: np.ndarray, meshes: dict) -> np.ndarray:
    """``(n_source,)`` int64: a loaded map checked against the vertex counts recorded beside it.

    One integer target vertex per source vertex, each in ``[-1, n_target)``; the counts are the
    saved meshes' (``n_original``) where the file holds them. Anything else is refused with an
    :class:`InputError` naming the file, the problem and the fix (:meth:`Correspondence.load`).
    """
    n_source = meshes["source"].n_original if "source" in meshes else None
    n_target = meshes["target"].n_original if "target" in meshes else None
    fix = "The file was changed or written by another program: save the result again with Correspondence.save."
    where = f"{path} is not a usable saved meshcorr result: its {name}"
    if mapping.ndim != 1:
        raise InputError(f"{where} has shape {mapping.shape}, but a map is 1-D: one target vertex per source "
                         f"vertex. {fix}")
    if not np.issubdtype(mapping.dtype, np.integer):
        raise InputError(f"{where} holds {mapping.dtype} values, but a map holds whole target vertex indices "
                         f"(integers; -1 where unmapped). {fix}")
    if n_source is not None and len(mapping) != n_source:
        raise InputError(f"{where} has {len(mapping)} entries, but the source mesh saved with it has {n_source} "
                         f"vertices: a map needs one entry per source vertex. {fix}")
    too_high = mapping > np.iinfo(np.int64).max if n_target is None else mapping >= n_target
    bad = too_high | (mapping < -1) if mapping.dtype.kind == "i" else too_high
    if bad.any():
        entry = int(np.flatnonzero(bad)[0])
        allowed = (f"-1..{n_target - 1}, the saved target mesh's {n_target} vertices (-1: unmapped)"
                   if n_target is not None else "-1 (unmapped) or a target vertex index >= 0")
        raise InputError(f"{where} entry {entry} is {int(mapping[entry])}, outside {allowed}. {fix}")
    return mapping.astype(np.int64)


def _json_default(value):
    """JSON for numpy scalars and arrays in params and histories."""
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, np.ndarray):
        return value.tolist()
    raise TypeError(f"cannot write {type(value).__name__} to JSON")
