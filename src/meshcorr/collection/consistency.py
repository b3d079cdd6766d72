"""Consistency of the maps of a collection: cycle error, and maps composed through a hub shape.

Maps computed pair by pair need not agree with each other: going from A to
B and then to C may land elsewhere than going from A to C. With
:math:`f_{AB}` the map from A's vertices to B's, the **cycle-consistency
error** of a triple is

.. math::

    e(A, B, C) = \\frac{1}{|S| \\sqrt{\\mathrm{area}(C)}} \\sum_{i \\in S}
    d_C\\big(f_{BC}(f_{AB}(i)),\\ f_{AC}(i)\\big)

over a seeded sample :math:`S` of A's vertices, with :math:`d_C` the geodesic
distance on C (0 for a consistent collection; it is no error against ground
truth, but each cycle error is at most the sum of the three maps' errors).

**Maps through a hub** (a star-shaped synchronisation, in the spirit of
template-based map networks, e.g. Huang, Wang & Guibas, "Functional map
networks for analyzing and browsing large shape collections", SIGGRAPH
2014, who synchronise through a latent basis): the hub :math:`H` is the shape
whose two-step maps agree best with the direct ones (the smallest mean
Euclidean distance, divided by :math:`\\sqrt{\\mathrm{area}}`, between
:math:`f_{HB}(f_{AH}(i))` and :math:`f_{AB}(i)` over the sampled A, B), and
every map between two other shapes is replaced by
:math:`f_{HB} \\circ f_{AH}`. Whether that lowers the error against ground
truth is measured, not assumed (``benchmarks/RESULTS-collections.md``).

Choosing the hub that way needs every map. A batch that maps through a hub
from the start (``meshcorr batch --hub``) matches only the :math:`n-1` pairs
from each shape onto the hub; the hub's map onto a shape B is the
:func:`invert` of B's map onto the hub, and every other map is composed,
:math:`f_{AB} = f_{HB} \\circ f_{AH}` (:func:`compose`). Inverting measured as
accurate as matching the hub onto each shape (TOSCA michael, cat and dog
through michael3, cat3 and dog5: 0.0486 / 0.0545 / 0.0475 with both
directions matched, 0.0485 / 0.0539 / 0.0473 with one matched and inverted;
``benchmarks/RESULTS-collections.md``) at half the matches. The batch's
automatic hub (:func:`spectral_medoid`) is the shape whose Laplace-Beltrami
spectrum is nearest to all the others' (the medoid of the "Shape-DNA": M.
Reuter, F.-E. Wolter, N. Peinecke, "Laplace-Beltrami spectra as 'Shape-DNA'
of surfaces and solids", Computer-Aided Design 38, 2006): the shape most
like the rest, cheap to find before any map exists. A wrong map to or from
the hub is repeated in the :math:`n - 2` maps composed with it.
"""

from __future__ import annotations

import itertools
import json
from pathlib import Path
from typing import Mapping, Sequence

import numpy as np

from ..runtime.checks import check_int
from ..errors import ParameterError
from ..evaluation.metrics import GeodesicCache
from ..io import atomic_write, read_map, write_map
from ..core.mesh import Mesh, as_mesh
from ..core.geodesics import DEFAULT_GEODESIC

Maps = Mapping[tuple[str, str], np.ndarray]


def compose(first: np.ndarray, second: np.ndarray) -> np.ndarray:
    """The map A -> C of ``first`` (A -> B) then ``second`` (B -> C), ``(n_A,)`` int: ``second[first]``.

    A vertex a map leaves unmapped (-1: dropped by ``largest_component``, or
    outside a part) stays unmapped; it is never sent to B's last vertex.
    """
    first, second = np.asarray(first, dtype=np.int64), np.asarray(second, dtype=np.int64)
    if len(second) == 0:
        return np.full(len(first), -1, dtype=np.int64)
    return np.where(first >= 0, second[np.maximum(first, 0)], -1)


def invert(mapping: np.ndarray, target_points: np.ndarray) -> np.ndarray:
    """The map T -> S of a vertex map S -> T: each T vertex to the S vertex whose image is nearest to it.

    Parameters
    ----------
    mapping : (n_S,) int
        ``mapping[i]``: the T vertex of S vertex i; -1 for an unmapped one.
    target_points : (n_T, 3) float
        T's vertex positions; a NaN row is a vertex T does not have (dropped
        by ``largest_component``) and is left unmapped (-1).

    Returns
    -------
    inverse : (n_T,) int
        :math:`g(t) = \\arg\\min_{i} \\lVert x_t - x_{f(i)} \\rVert`: exact where
        ``mapping`` hits t (a vertex sent there), else the source vertex of the
        nearest image; -1 only for missing vertices or an empty map. Euclidean
        on T, the surface the images lie on: a KD-tree query (scipy), because
        no library inverts a many-to-one vertex map.
    """
    from scipy.spatial import cKDTree

    mapping = np.asarray(mapping, dtype=np.int64)
    points = np.asarray(target_points, dtype=np.float64)
    out = np.full(len(points), -1, dtype=np.int64)
    present = np.isfinite(points).all(axis=1)
    sources = np.flatnonzero(mapping >= 0)
    sources = sources[present[mapping[sources]]]
    if sources.size:  # the images of these are present vertices
        out[present] = sources[cKDTree(points[mapping[sources]]).query(points[present])[1]]
    return out


def input_positions(mesh: Mesh) -> np.ndarray:
    """``(mesh.n_original, 3)`` float: each input vertex's position, in the numbering maps use; NaN for a
    vertex the mesh dropped (``largest_component``): the ``target_points`` of :func:`invert`."""
    points = np.full((mesh.n_original, 3), np.nan)
    points[mesh.kept] = mesh.vertices
    return points


def sample_triples(names: Sequence[str], maps: Maps, n_triples: int, random_state: int | None = 0
                   ) -> list[tuple[str, str, str]]:
    """Up to ``n_triples`` distinct ordered triples (A, B, C) whose three maps exist, seeded."""
    triples = [t for t in itertools.permutations(names, 3)
               if (t[0], t[1]) in maps and (t[1], t[2]) in maps and (t[0], t[2]) in maps]
    rng = np.random.default_rng(random_state)
    if len(triples) > n_triples:
        triples = [triples[i] for i in np.sort(rng.choice(len(triples), size=n_triples, replace=False))]
    return triples


def cycle_errors(maps: Maps, meshes: Mapping[str, Mesh], triples: Sequence[tuple[str, str, str]], *,
                 n_points: int = 200, geodesic: str = DEFAULT_GEODESIC, random_state: int | None = 0) -> np.ndarray:
    """:math:`e(A, B, C)` of each triple (module docstring), ``(t,)`` float.

    Parameters
    ----------
    maps : {(A, B): (n_A,) int}
        Vertex maps; ``maps[A, B][i]`` is the vertex of B matched to vertex i of A.
    meshes : {name: Mesh}
    triples : sequence of (A, B, C)
    n_points : int
        Sampled vertices of A per triple.
    geodesic : str
        Geodesic solver of :math:`d_C`.
    random_state : int or None
        Seed of the samples.

    A sampled vertex that one of the three maps leaves unmapped (-1) does
    not count; a triple with none left is NaN.
    """
    n_points = check_int("n_points", n_points, minimum=1)
    rng = np.random.default_rng(random_state)
    cache = GeodesicCache(geodesic, max_meshes=len(meshes))
    out = np.empty(len(triples))
    for t, (a, b, c) in enumerate(triples):
        n_a = len(maps[a, c])
        sample = rng.choice(n_a, size=min(n_points, n_a), replace=False)
        two_step, direct = _both_mapped(compose(maps[a, b][sample], maps[b, c]), maps[a, c][sample])
        if not len(direct):
            out[t] = np.nan
            continue
        distances = cache.pair_distances(meshes[c], two_step, direct)
        out[t] = distances.mean() / np.sqrt(meshes[c].area)
    return out


def _both_mapped(two_step: np.ndarray, direct: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The entries where both maps send the sampled vertex somewhere (vertices a map leaves out do not count)."""
    mapped = (two_step >= 0) & (direct >= 0)
    return two_step[mapped], direct[mapped]


def choose_hub(maps: Maps, meshes: Mapping[str, Mesh], *, n_points: int = 200,
               random_state: int | None = 0) -> str:
    """The shape whose two-step maps agree best with the direct maps (module docstring)."""
    names = list(meshes)
    rng = np.random.default_rng(random_state)
    best, best_score = None, np.inf
    for hub in names:
        scores = []
        for a, b in itertools.permutations([n for n in names if n != hub], 2):
            if (a, hub) not in maps or (hub, b) not in maps or (a, b) not in maps:
                continue
            n_a = len(maps[a, b])
            sample = rng.choice(n_a, size=min(n_points, n_a), replace=False)
            V = meshes[b].vertices
            two_step, direct = _both_mapped(compose(maps[a, hub][sample], maps[hub, b]), maps[a, b][sample])
            if len(direct):
                gap = np.linalg.norm(V[two_step] - V[direct], axis=1)
                scores.append(gap.mean() / np.sqrt(meshes[b].area))
        covers = all((a, hub) in maps and (hub, a) in maps for a in names if a != hub)
        if scores and covers and np.mean(scores) < best_score:
            best, best_score = hub, float(np.mean(scores))
    if best is None:
        raise ParameterError("No shape has maps to and from every other shape: the hub needs them "
                             "(run the collection with --all-pairs and no failed pairs through it).")
    return best


def shape_dna(mesh: Mesh, k: int = 40, *, random_state: int | None = 0) -> np.ndarray:
    """``(k - 1,)``: the mesh's Laplace-Beltrami eigenvalues at unit area, the zero one dropped (scale-free).

    Parameters
    ----------
    mesh : Mesh
        A triangle mesh or a point cloud (its robust Laplacian).
    k : int
        Eigenvalues computed (:func:`meshcorr.spectral.basis.laplace_basis`, cached
        on the mesh: the refinement's basis when ``k`` is its size). They are
        those of the shape scaled to unit area, :math:`\\lambda_i A`, so the
        Shape-DNA does not change with a uniform scale.
    random_state : int or None
        Seed of the eigensolver's start vector.
    """
    from ..spectral.basis import laplace_basis

    return _positive(laplace_basis(mesh, k, random_state=random_state)[0])


def _positive(eigenvalues: np.ndarray) -> np.ndarray:
    """The eigenvalues after the first, checked finite and positive."""
    values = np.asarray(eigenvalues, dtype=np.float64)[1:]
    if values.size == 0 or not np.all(np.isfinite(values)) or np.any(values <= 0):
        raise ParameterError("A Shape-DNA needs at least two finite eigenvalues, the ones after the "
                             "first positive.")
    return values


def spectral_medoid(dna: Mapping[str, np.ndarray]) -> str:
    """The shape of least total Shape-DNA distance to the others (module docstring).

    The distance of two shapes is the mean of :math:`|\\log a_i - \\log b_i|`
    over their first :math:`\\min(k_a, k_b)` scaled eigenvalues
    (:func:`shape_dna`): relative differences, so that the many high
    eigenvalues do not outweigh the first ones. Ties go to the first name.

    Parameters
    ----------
    dna : {name: (k - 1,) float}
        :func:`shape_dna` of each shape, at least one.
    """
    names = list(dna)
    if not names:
        raise ParameterError("The hub is chosen among at least one shape; got none.")
    logs = {name: np.log(np.asarray(dna[name], dtype=np.float64)) for name in names}
    size = min(len(v) for v in logs.values())
    total = [sum(np.abs(logs[a][:size] - logs[b][:size]).mean() for b in names if b != a) for a in names]
    return names[int(np.argmin(total))]


def through_hub(maps: Maps, hub: str) -> dict[tuple[str, str], np.ndarray]:
    """Every map between two shapes other than ``hub`` replaced by :math:`f_{HB} \\circ f_{AH}`."""
    out = {}
    for (a, b), mapping in maps.items():
        out[a, b] = mapping if hub in (a, b) else compose(maps[a, hub], maps[hub, b])
    return out


def consistency_report(out_dir, shapes: Sequence[str], records: Sequence[dict], *, n_triples: int = 30,
                       n_points: int = 200, geodesic: str = DEFAULT_GEODESIC, random_state: int | None = 0) -> dict:
    """Cycle errors of a batch's maps and of the maps through a hub; writes ``consistent/`` and ``consistency.json``.

    Parameters
    ----------
    out_dir : path
        The folder of :func:`meshcorr.collection.batch.batch`.
    shapes : sequence of str
        The mesh files of ``--all-pairs``.
    records : sequence of dict
        The batch's records (failed pairs are left out, and the shapes of no
        mapped pair).

    Returns
    -------
    report : dict
        ``hub``, ``cycle_error`` and ``consistent_cycle_error`` (means over
        the same sampled triples), ``n_triples``, ``path`` (the JSON file).
    """
    out = Path(out_dir)
    names = {path: Path(path).stem for path in shapes}
    mapped = [r for r in records if r["status"] == "ok"]
    # Only the shapes of some mapped pair: a shape whose every pair failed (a bad mesh) is left out.
    used = {path for r in mapped for path in (r["source"], r["target"])}
    meshes = {names[p]: as_mesh(p) for p in shapes if p in used}
    maps = {(names[r["source"]], names[r["target"]]): read_map(r["map"]) for r in mapped}
    triples = sample_triples(list(meshes), maps, n_triples, random_state)
    if not triples:
        raise ParameterError("The cycle-consistency error needs three shapes whose maps all succeeded.")
    hub = choose_hub(maps, meshes, n_points=n_points, random_state=random_state)
    consistent = through_hub(maps, hub)
    direct_errors = cycle_errors(maps, meshes, triples, n_points=n_points, geodesic=geodesic,
                                 random_state=random_state)
    hub_errors = cycle_errors(consistent, meshes, triples, n_points=n_points, geodesic=geodesic,
                              random_state=random_state)
    (out / "consistent").mkdir(exist_ok=True)
    for (a, b), mapping in consistent.items():
        write_map(out / "consistent" / f"{a}__{b}.txt", mapping)
    report = {"hub": hub, "cycle_error": _mean(direct_errors),
              "consistent_cycle_error": _mean(hub_errors), "n_triples": len(triples),
              "n_points": n_points, "triples": [list(t) for t in triples],
              "path": str(out / "consistency.json")}
    payload = json.dumps(report, indent=1).encode()
    atomic_write(out / "consistency.json", lambda file: file.write(payload))
    return report


def _mean(errors: np.ndarray) -> float | None:
    """The mean of the finite errors (None if there is none: JSON has no NaN)."""
    finite = errors[np.isfinite(errors)]
    return float(finite.mean()) if finite.size else None
