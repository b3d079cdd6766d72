"""Evaluation of vertex maps against ground truth.

The field's protocol (Kim, Lipman & Funkhouser, "Blended intrinsic maps",
SIGGRAPH 2011; the Princeton benchmark): the error of a predicted match is
the geodesic distance on the target between the predicted and the true
vertex, divided by the square root of the target's surface area,

.. math::

    e_k = \\frac{g_T(C(s_k), t_k)}{\\sqrt{\\operatorname{area}(T)}},

reported as the mean and as the cumulative curve (fraction of points with
:math:`e_k \\le \\tau` for :math:`\\tau \\in [0, 0.25]`). The paper's own
measures (Jain & Zhang 2006) are the total geodesic error
:math:`\\sum_k g_T(C(s_k), t_k)` and the percentage of feature points
matched correctly (here: within a geodesic tolerance).

Geodesics come from single-source solves (:mod:`meshcorr.core.geodesics`), kept
in a :class:`GeodesicCache` keyed on the mesh's content and the solver, so
a map, its mirrored truth and further maps onto the same target cost no
new solves. Plots live in :mod:`meshcorr.viz.plots` (optional matplotlib).

Measures that need no ground truth (:func:`map_quality`), for a map
:math:`T: S \\to T` between meshes of areas :math:`A_S, A_T`:

- *coverage*: the share of the target's area reached,
  :math:`\\sum_{j \\in T(S)} a_j / A_T` with the lumped vertex areas
  :math:`a_j`;
- *bijectivity*: distinct images over mapped source vertices,
  :math:`|T(S)| / |S|` (1 for a one-to-one map);
- *continuity*: over the source edges :math:`(i, j)`, the mean ratio of the
  images' distance to the edge's length, each divided by the square root of
  its mesh's area,
  :math:`\\operatorname{mean} \\frac{\\lVert x_{T(i)} - x_{T(j)} \\rVert / \\sqrt{A_T}}
  {\\lVert x_i - x_j \\rVert / \\sqrt{A_S}}` (about 1 for a smooth,
  area-preserving map; larger where neighbours are torn apart), and the
  share of edges stretched more than :data:`TEAR_RATIO` times (tears).
"""

from __future__ import annotations

import hashlib
from collections import OrderedDict
from contextlib import contextmanager
from typing import Sequence

import numpy as np

from ..runtime.checks import MapMessages, check_choice, check_float, check_int, check_vertex_map
from ..errors import ParameterError
from ..core.geodesics import GEODESIC_METHODS, geodesic_solver
from .ground_truth import GroundTruth
from ..core.mesh import Mesh, MeshLike, as_mesh
from ..runtime.progress import as_progress
from ..core.geodesics import DEFAULT_GEODESIC

__all__ = ["THRESHOLDS", "TEAR_RATIO", "GeodesicCache", "cumulative_curve", "evaluate_map",
           "feature_point_accuracy", "geodesic_errors", "map_quality", "scalar_summary"]

#: Error thresholds reported by default (fractions of sqrt(target area)).
THRESHOLDS = (0.05, 0.1, 0.25)
#: An edge whose normalised image is this many times longer than itself counts as torn.
TEAR_RATIO = 5.0


class GeodesicCache:
    """Single-source geodesic distance rows, computed on demand and kept for a run.

    Rows are keyed on the mesh's content (a hash of its vertex and face
    arrays) and the solver name, never on a file name, so they cannot go
    stale. Rows are stored as float32 (relative rounding 6e-8, far below
    any solver's error).

    Parameters
    ----------
    method : {"heat", "fmm", "exact", "dijkstra"}
        Geodesic solver (see :mod:`meshcorr.core.geodesics`).
    max_meshes : int
        Meshes whose rows are kept; the least recently used is dropped
        beyond that (each holds up to ``n_rows x n`` float32 values).
    progress : callable or bool, optional
        ``progress("geodesic errors", done, total)`` as the single-source
        solves of a :meth:`precompute` advance (``done`` of ``total``
        solves, from 0 to ``total``, about 100 reports; nothing when every
        row is cached), or True for a progress bar. The rows are the same
        with or without it. :meth:`reporting` sets it for a block,
        :meth:`phase` another stage name (:func:`evaluate_map`: "geodesic
        errors (mirrored truth)" for the mirrored truth's solves).

    Attributes
    ----------
    n_solves : int
        Single-source solves done so far (for tests and reports).
    """

    #: The stage named in the progress reports (:meth:`phase` names another for a block).
    STAGE = "geodesic errors"
    #: Most single-source solves per call of the solver (and between two progress reports).
    BLOCK = 256

    def __init__(self, method: str = DEFAULT_GEODESIC, *, max_meshes: int = 2, progress=None) -> None:
        self.method = check_choice("geodesic", method, GEODESIC_METHODS)
        self.max_meshes = check_int("max_meshes", max_meshes, minimum=1)
        self.progress = as_progress(progress)
        self.stage = self.STAGE
        self.n_solves = 0
        self._entries: OrderedDict[str, dict] = OrderedDict()

    @contextmanager
    def reporting(self, progress):
        """Within the block, the solves report to ``progress`` (as the ``progress`` parameter); then as before."""
        previous, self.progress = self.progress, as_progress(progress)
        try:
            yield self
        finally:
            self.progress = previous

    @contextmanager
    def phase(self, stage: str):
        """Within the block, the solves report as ``stage`` (a phase of their own, from 0 to its total)."""
        previous, self.stage = self.stage, stage
        try:
            yield self
        finally:
            self.stage = previous

    def _entry(self, mesh: Mesh) -> dict:
        digest = hashlib.blake2b(digest_size=16)
        for array in (mesh.vertices, mesh.faces):
            digest.update(str(array.shape).encode())
            digest.update(np.ascontiguousarray(array).tobytes())
        key = f"{self.method}:{digest.hexdigest()}"
        if key in self._entries:
            self._entries.move_to_end(key)
        else:
            self._entries[key] = {"mesh": mesh, "solver": None, "rows": {}}
            while len(self._entries) > self.max_meshes:
                self._entries.popitem(last=False)
        return self._entries[key]

    def precompute(self, mesh: Mesh, vertices: np.ndarray) -> None:
        """Solve from every vertex in ``vertices`` not solved yet.

        Parameters
        ----------
        mesh : Mesh
        vertices : (s,) int
            Source vertices; e.g. all true target vertices of a benchmark
            pair, so that every method's map onto it scores without solves.
        """
        entry = self._entry(mesh)
        todo = np.setdiff1d(np.asarray(vertices, dtype=np.int64), list(entry["rows"]))
        if todo.size == 0:
            return
        if entry["solver"] is None:
            entry["solver"] = geodesic_solver(mesh.vertices, mesh.faces, self.method)
        progress = self.progress
        # Blocks of at most BLOCK solves; reported, about 100 of them, each as it ends.
        block = self.BLOCK if progress is None else min(self.BLOCK, -(-todo.size // 100))
        if progress is not None:
            progress(self.stage, 0, todo.size)
        for start in range(0, todo.size, block):
            sources = todo[start:start + block]
            rows = entry["solver"].distances(sources).astype(np.float32)
            entry["rows"].update(zip(sources.tolist(), rows))
            self.n_solves += sources.size
            if progress is not None:
                progress(self.stage, start + sources.size, todo.size)

    def pair_distances(self, mesh: Mesh, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """Geodesic distance between ``a[k]`` and ``b[k]`` for every k.

        Parameters
        ----------
        mesh : Mesh
        a, b : (p,) int
            Vertex pairs.

        Returns
        -------
        distances : (p,) float64
            In the mesh's units. Each pair is read from the cached row of
            either endpoint; missing rows are solved for a small vertex
            cover of the uncovered pairs (greedy by number of pairs).
        """
        a = np.asarray(a, dtype=np.int64).reshape(-1)
        b = np.asarray(b, dtype=np.int64).reshape(-1)
        entry = self._entry(mesh)
        cached = np.fromiter(entry["rows"], dtype=np.int64, count=len(entry["rows"]))
        open_ = (a != b) & ~np.isin(a, cached) & ~np.isin(b, cached)
        self.precompute(mesh, _greedy_cover(a[open_], b[open_]))
        rows = entry["rows"]
        out = np.zeros(a.size)
        for k in np.flatnonzero(a != b):
            i, j = int(a[k]), int(b[k])
            out[k] = rows[j][i] if j in rows else rows[i][j]
        return out


def _greedy_cover(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Vertices touching every pair ``(a[k], b[k])``, picked by descending pair count.

    A static-order greedy vertex cover; ties go to ``b`` (the true vertices,
    which stay useful for later maps onto the same mesh).
    """
    if a.size == 0:
        return np.empty(0, dtype=np.int64)
    ends = np.concatenate([b, a])
    pair_of = np.tile(np.arange(a.size), 2)
    vertices, inverse, counts = np.unique(ends, return_inverse=True, return_counts=True)
    first_seen = np.full(vertices.size, ends.size)
    np.minimum.at(first_seen, inverse, np.arange(ends.size))
    order = np.lexsort((first_seen, -counts))
    by_vertex = np.argsort(inverse, kind="stable")
    starts = np.concatenate([[0], np.cumsum(counts)])
    covered = np.zeros(a.size, dtype=bool)
    chosen = []
    for v in order:
        pairs = pair_of[by_vertex[starts[v]:starts[v + 1]]]
        if not covered[pairs].all():
            covered[pairs] = True
            chosen.append(vertices[v])
    return np.array(chosen, dtype=np.int64)


def _target_mesh(target: MeshLike) -> Mesh:
    return target if isinstance(target, Mesh) else as_mesh(target, name="target")


def _cache_for(cache: GeodesicCache | None, method: str) -> GeodesicCache:
    if cache is None:
        return GeodesicCache(method)
    if cache.method != method:
        raise ParameterError(f"The cache holds {cache.method!r} geodesics but geodesic={method!r} "
                             "was asked for; use one solver per cache.")
    return cache


def geodesic_errors(target: MeshLike, predicted: np.ndarray, truth: np.ndarray, *,
                    method: str = DEFAULT_GEODESIC, normalize: bool = True,
                    cache: GeodesicCache | None = None) -> np.ndarray:
    """Geodesic distance between predicted and true target vertices.

    Parameters
    ----------
    target : mesh-like
        The mesh the map points into.
    predicted : (p,) int
        Predicted target vertex of each evaluated point.
    truth : (p,) int
        True target vertex of each evaluated point.
    method : str
        Geodesic solver (see :mod:`meshcorr.core.geodesics`).
    normalize : bool
        Divide by sqrt(surface area of the target).
    cache : GeodesicCache, optional
        Reuse rows across calls (its solver must be ``method``).

    Returns
    -------
    errors : (p,) float
        One distance per point.
    """
    mesh = _target_mesh(target)
    predicted, truth = (_vertex_indices(name, values, mesh.n_vertices)
                        for name, values in (("predicted", predicted), ("truth", truth)))
    if predicted.shape != truth.shape:
        raise ParameterError(f"predicted and truth must list the same points: got {predicted.size} and "
                             f"{truth.size} vertices.")
    errors = _cache_for(cache, method).pair_distances(mesh, predicted, truth)
    if normalize:
        errors /= np.sqrt(mesh.area)
    return errors


def _vertex_indices(name: str, values, n_vertices: int) -> np.ndarray:
    """``values`` as a 1-D int64 array of vertex indices in ``[0, n_vertices)``, or :class:`ParameterError`."""
    values = np.asarray(values)
    if values.ndim != 1 or not np.issubdtype(values.dtype, np.integer):
        raise ParameterError(f"{name} must be a 1-D array of integer vertex indices; got shape {values.shape} "
                             f"and dtype {values.dtype}.")
    bad = (values < 0) | (values >= n_vertices)
    if bad.any():
        first = int(np.flatnonzero(bad)[0])
        raise ParameterError(f"{name}[{first}] is {int(values[first])}, outside the target's vertices "
                             f"0..{n_vertices - 1}.")
    return values.astype(np.int64)


def _check_thresholds(thresholds) -> list[float]:
    """Error thresholds as floats, each finite and >= 0 (a NaN threshold counted every point as under it)."""
    return [check_float("threshold", t, minimum=0.0) for t in thresholds]


def cumulative_curve(errors: np.ndarray, thresholds: np.ndarray | None = None
                     ) -> tuple[np.ndarray, np.ndarray]:
    """Fraction of points whose error is at most each threshold.

    Parameters
    ----------
    errors : (p,) float
        Normalised errors; NaN (unmapped points) never counts as under.
    thresholds : (t,) float, optional
        Defaults to 101 values from 0 to 0.25 (the Princeton protocol).

    Returns
    -------
    thresholds : (t,) float
    fractions : (t,) float
        Non-decreasing in the threshold when ``thresholds`` is sorted.
    """
    errors = np.asarray(errors, dtype=np.float64).reshape(-1)
    thresholds = np.linspace(0.0, 0.25, 101) if thresholds is None else np.asarray(thresholds, float)
    if errors.size == 0:
        return thresholds, np.zeros(thresholds.shape)
    finite = np.sort(errors[np.isfinite(errors)])
    return thresholds, np.searchsorted(finite, thresholds, side="right") / errors.size


#: The words of a map that :func:`evaluate_map` refuses (:func:`meshcorr.runtime.checks.check_vertex_map`).
_EVALUATED_MAP = MapMessages(
    not_integer="A map must be a 1-D integer array; got shape {shape} and dtype {dtype}.",
    wrong_length="",  # the length is checked against the ground truth below
    out_of_range="Map entry {entry} is {value}, outside the target's vertices 0..{last} (-1 marks unmapped). "
                 "Check that the map points into this target.")


def _check_mapping(mapping: np.ndarray, truth: GroundTruth, n_target: int) -> np.ndarray:
    """``mapping`` as ``(n,)`` int64, checked against the ground truth's source vertices and the target."""
    mapping = check_vertex_map(mapping, messages=_EVALUATED_MAP).astype(np.int64)
    if len(truth) and truth.source.max() >= mapping.size:
        raise ParameterError(
            f"The ground truth names source vertex {int(truth.source.max())}, but the map has "
            f"only {mapping.size} entries. Check that map and ground truth belong together."
        )
    return check_vertex_map(mapping, n_target=n_target, messages=_EVALUATED_MAP)


def _truth_errors(mesh: Mesh, mapping: np.ndarray, truth: GroundTruth,
                  cache: GeodesicCache) -> tuple[np.ndarray, np.ndarray]:
    """Raw distances per truth pair (NaN where unmapped) and the mapped mask."""
    predicted = mapping[truth.source]
    mapped = predicted >= 0
    raw = np.full(len(truth), np.nan)
    raw[mapped] = cache.pair_distances(mesh, predicted[mapped], truth.target[mapped])
    return raw, mapped


def _stats(errors: np.ndarray, thresholds: Sequence[float]) -> dict:
    finite = errors[np.isfinite(errors)]
    _, under = cumulative_curve(errors, np.asarray(thresholds, dtype=np.float64))
    return {
        "mean_error": float(finite.mean()) if finite.size else float("nan"),
        "median_error": float(np.median(finite)) if finite.size else float("nan"),
        "under": {f"{t:g}": float(f) for t, f in zip(thresholds, under)},
    }


def evaluate_map(target: MeshLike, mapping: np.ndarray, truth: GroundTruth, *,
                 sym_truth: GroundTruth | None = None, thresholds: Sequence[float] = THRESHOLDS,
                 geodesic: str = DEFAULT_GEODESIC, cache: GeodesicCache | None = None) -> dict:
    """Score a vertex map against ground truth (and optionally its mirror image).

    Parameters
    ----------
    target : mesh-like
        The mesh the map points into.
    mapping : (n_source,) int
        ``mapping[i]`` is the target vertex of source vertex i; -1 = unmapped.
    truth : GroundTruth
        True pairs ``(source vertex, target vertex)``.
    sym_truth : GroundTruth, optional
        The left/right mirrored truth (e.g. TOSCA's ``.sym.vts``).
    thresholds : sequence of float
        Normalised errors at which the fraction of points under is reported.
    geodesic : str
        Geodesic solver.
    cache : GeodesicCache, optional
        Shared rows (its solver must be ``geodesic``).

    Returns
    -------
    report : dict
        ``n_points``, ``n_unmapped`` (truth points whose source vertex maps
        to -1: excluded from means, counted as misses in ``under``),
        ``sqrt_area``; ``mean_error``, ``median_error`` (normalised by
        sqrt(target area)); ``under`` ({"0.05": fraction, ...});
        ``total_error`` (the paper's sum of raw geodesic errors over mapped
        points, target units) and ``total_error_normalized``; ``errors``
        ((p,) float array, normalised, NaN where unmapped). With
        ``sym_truth`` also ``sym_mean_error``, ``sym_under``, ``sym_errors``,
        ``flipped`` (True when the map is closer to the mirrored truth:
        ``sym_mean_error < mean_error``) and ``best_mean_error`` (the
        smaller of the two: the error forgiving a left/right flip).
        :func:`scalar_summary` drops the arrays for JSON.
    """
    mesh = _target_mesh(target)
    cache = _cache_for(cache, geodesic)
    thresholds = _check_thresholds(thresholds)
    mapping = _check_mapping(mapping, truth, mesh.n_vertices)
    truth.check(mapping.size, mesh.n_vertices)
    sqrt_area = float(np.sqrt(mesh.area))
    raw, mapped = _truth_errors(mesh, mapping, truth, cache)
    errors = raw / sqrt_area
    report = {"n_points": len(truth), "n_unmapped": int((~mapped).sum()), "sqrt_area": sqrt_area,
              **_stats(errors, thresholds),
              "total_error": float(np.nansum(raw)), "total_error_normalized": float(np.nansum(errors)),
              "errors": errors}
    if sym_truth is not None:
        _check_mapping(mapping, sym_truth, mesh.n_vertices)
        sym_truth.check(mapping.size, mesh.n_vertices)
        with cache.phase(f"{cache.STAGE} (mirrored truth)"):  # its solves counted apart from the first truth's
            sym_errors = _truth_errors(mesh, mapping, sym_truth, cache)[0] / sqrt_area
        sym = _stats(sym_errors, thresholds)
        report.update(sym_mean_error=sym["mean_error"], sym_under=sym["under"],
                      sym_errors=sym_errors, flipped=bool(sym["mean_error"] < report["mean_error"]),
                      best_mean_error=float(min(sym["mean_error"], report["mean_error"])))
    return report


def scalar_summary(report: dict) -> dict:
    """The JSON-serialisable part of an :func:`evaluate_map` report (arrays dropped)."""
    return {key: value for key, value in report.items() if not isinstance(value, np.ndarray)}


def feature_point_accuracy(target: MeshLike, mapping: np.ndarray, truth: GroundTruth, *,
                           tolerance: float = 0.05, geodesic: str = DEFAULT_GEODESIC,
                           cache: GeodesicCache | None = None) -> float:
    """Fraction of feature points matched correctly (Jain & Zhang 2006, its Figure 5 measure).

    A feature point counts as correct when its predicted target vertex lies
    within ``tolerance * sqrt(area of target)`` geodesically of the true
    one (the paper judged "correct" by eye; a tolerance makes it repeatable).

    Parameters
    ----------
    target : mesh-like
    mapping : (n_source,) int
    truth : GroundTruth
        The sparse feature-point pairs.
    tolerance : float
        Normalised geodesic tolerance.
    geodesic : str
    cache : GeodesicCache, optional

    Returns
    -------
    fraction : float
        In [0, 1]; unmapped feature points count as wrong.
    """
    tolerance = check_float("tolerance", tolerance, minimum=0.0)
    report = evaluate_map(target, mapping, truth, thresholds=[tolerance], geodesic=geodesic,
                          cache=cache)
    return report["under"][f"{tolerance:g}"]


def map_quality(source: MeshLike, target: MeshLike, mapping: np.ndarray) -> dict:
    """Coverage, bijectivity and continuity of a vertex map (module docstring); no ground truth.

    Parameters
    ----------
    source, target : mesh-like
    mapping : (n_source,) int
        Target vertex of each source vertex; -1 = unmapped (left out).

    Returns
    -------
    measures : dict
        ``coverage`` (share of target area reached, in [0, 1]),
        ``bijectivity`` (distinct images / mapped vertices, in (0, 1]),
        ``continuity`` (mean normalised edge-length ratio over source edges
        with both ends mapped), ``torn_edges`` (share of those edges with a
        ratio above :data:`TEAR_RATIO`).

    Raises
    ------
    ParameterError
        If the map does not fit the meshes.
    """
    from ..core.laplacian import vertex_areas
    from ..core.pointcloud import edges as graph_edges

    src = source if isinstance(source, Mesh) else as_mesh(source, name="source")
    tgt = _target_mesh(target)
    mapping = check_vertex_map(mapping, src.n_vertices, tgt.n_vertices)
    mapped = mapping >= 0
    if not mapped.any():
        raise ParameterError("The map sends no source vertex anywhere; there is nothing to measure.")
    areas = vertex_areas(tgt)
    reached = np.unique(mapping[mapped])
    edges = graph_edges(src.vertices, src.faces)  # a cloud's: its neighbour graph (meshcorr.core.pointcloud)
    edges = edges[mapped[edges].all(axis=1)]
    length = np.linalg.norm(src.vertices[edges[:, 0]] - src.vertices[edges[:, 1]], axis=1) / np.sqrt(src.area)
    image = mapping[edges]
    stretch = np.linalg.norm(tgt.vertices[image[:, 0]] - tgt.vertices[image[:, 1]], axis=1) / np.sqrt(tgt.area)
    ratio = stretch / np.maximum(length, 1e-300)
    return {"coverage": float(areas[reached].sum() / areas.sum()),
            "bijectivity": float(reached.size / mapped.sum()),
            "continuity": float(ratio.mean()) if ratio.size else float("nan"),
            "torn_edges": float(np.mean(ratio > TEAR_RATIO)) if ratio.size else float("nan")}
