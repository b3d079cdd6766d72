"""The tasks of a batch, run on the Dask workers: prepare a shape, match a pair, invert or compose maps.

Each returns something picklable: a prepared shape (or the one-line error
that prevented it), or a pair's record (:mod:`meshcorr.collection.summary`)
holding its map under :data:`MAPPING`. The tasks write no map file: the
process that runs the batch writes each one as it records the pair
(:func:`meshcorr.collection.batch.batch`), so that a pair still running on a
worker when the batch is interrupted cannot write a map after the summary
that does not list it. A task never raises for a bad mesh or a failed pair:
the record says so.
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Callable

import numpy as np

from ..core.holes import unfilled
from ..errors import ParameterError
from ..runtime.messages import one_line
from ..runtime.threads import single_blas_thread
from ..pipeline.settings import Settings
from ..shapes.prepared import PreparedShape
from ..spectral.modes import SCALABLE_ABOVE
from .summary import DONE, new_record

__all__ = ["MAPPING", "compose_task", "dna_task", "invert_task", "mapping_of", "mean_error", "pair_task",
           "prepare_task"]

#: The key of a record returned by a task that holds the map (taken out when the map is written).
MAPPING = "mapping"


def prepare_task(path: str, matching: Settings, cache_root: str | None):
    """Worker: the :class:`PreparedShape` of one mesh file, or the one-line error that prevents it."""
    from ..pipeline.prepare import prepare

    try:
        with single_blas_thread():
            return prepare(path, matching, cache=cache_root)
    except Exception as exc:  # noqa: BLE001 - a failed shape fails its pairs, never the batch
        return one_line(exc)


def pair_task(source, target, source_path: str, target_path: str, map_path: str, matching: Settings,
              settings: dict, options: dict, ground_truth: str | None) -> dict:
    """Worker: match two prepared shapes; the pair's record, with the map under :data:`MAPPING`."""
    from ..pipeline.run import match

    record = new_record(source_path, target_path, map_path)
    if failed_shape(record, (source, source_path), (target, target_path)):
        return record
    try:
        with single_blas_thread():
            source, target = in_pair_mode(source, target, settings, options)
            start, cpu = time.perf_counter(), time.process_time()
            result = match(source, target, matching)
            record["seconds"] = time.perf_counter() - start
            record["cpu_seconds"] = time.process_time() - cpu  # the worker's CPU time: load-independent
            record[MAPPING] = result.map
            if ground_truth is not None:
                record["mean_error"] = mean_error(source, target, result.map, source_path, target_path,
                                                   ground_truth, settings["geodesic"])
        record["status"] = DONE
    except Exception as exc:  # noqa: BLE001 - a failed pair is a record, never the end of the batch
        record["error"] = one_line(exc)
    return record


def compose_task(source, target, to_hub: dict | None, from_hub: dict | None, source_path: str,
                  target_path: str, hub: str, map_path: str, settings: dict, ground_truth: str | None) -> dict:
    """Worker: the map source -> hub -> target from the two matched maps' records; its record."""
    from .consistency import compose

    record = new_record(source_path, target_path, map_path, hub)
    for step, (a, b) in ((to_hub, (source_path, hub)), (from_hub, (hub, target_path))):
        if step is None or step["status"] != DONE:
            reason = "was not mapped" if step is None else f"failed: {step['error']}"
            record["error"] = f"Composed through the hub: its map {Path(a).name} -> {Path(b).name} {reason}"[:300]
            return record
    # f_HB o f_AH
    return made_map(record, source, target, lambda: compose(mapping_of(to_hub), mapping_of(from_hub)),
                     settings, ground_truth)


def invert_task(hub, target, onto_hub: dict | None, hub_path: str, target_path: str, map_path: str,
                 settings: dict, ground_truth: str | None) -> dict:
    """Worker: the hub's map onto a shape, the inverse of that shape's map onto the hub; its record."""
    from .consistency import input_positions, invert

    record = new_record(hub_path, target_path, map_path, hub_path)
    if onto_hub is None or onto_hub["status"] != DONE:
        reason = "was not mapped" if onto_hub is None else f"failed: {onto_hub['error']}"
        record["error"] = (f"Inverted from the map {Path(target_path).name} -> {Path(hub_path).name}, "
                           f"which {reason}")[:300]
        return record

    def inverse() -> np.ndarray:  # on the hub's own vertices, without the caps of its holes (meshcorr.core.holes)
        return invert(mapping_of(onto_hub), input_positions(unfilled(hub.mesh)))

    return made_map(record, hub, target, inverse, settings, ground_truth)


def made_map(record: dict, source, target, make: Callable[[], np.ndarray], settings: dict,
              ground_truth: str | None) -> dict:
    """Worker: ``make()`` the map of ``record`` from maps already made, score it; the record, with the map."""
    if failed_shape(record, (source, record["source"]), (target, record["target"])):
        return record
    try:
        start, cpu = time.perf_counter(), time.process_time()
        mapping = make()
        record[MAPPING] = mapping
        record["seconds"], record["cpu_seconds"] = time.perf_counter() - start, time.process_time() - cpu
        if ground_truth is not None:
            with single_blas_thread():
                record["mean_error"] = mean_error(source, target, mapping, record["source"], record["target"],
                                                   ground_truth, settings["geodesic"])
        record["status"] = DONE
    except Exception as exc:  # noqa: BLE001 - a failed pair is a record, never the end of the batch
        record["error"] = one_line(exc)
    return record


def mapping_of(record: dict) -> np.ndarray:
    """The map of a done pair's record: the one it holds (made in this run), else its file (an earlier run's)."""
    from ..io import read_map

    return record[MAPPING] if record.get(MAPPING) is not None else read_map(record["map"])


def failed_shape(record: dict, *shapes) -> bool:
    """Whether a ``(shape, path)`` failed its preparation; if so its message goes into ``record["error"]``."""
    for shape, path in shapes:
        if not isinstance(shape, PreparedShape):  # the message of the failed preparation
            name = Path(path).name
            record["error"] = shape if name in shape else f"{name}: {shape}"
            return True
    return False


def in_pair_mode(source: PreparedShape, target: PreparedShape, settings: dict, options: dict):
    """The two shapes prepared in the mode the pair runs in (a shape alone may resolve "auto" otherwise)."""
    from ..spectral.modes import resolve_memory, select_mode
    from ..shapes.prepared import prepare_mesh

    mode = select_mode(options.get("mode", "auto"), source.n_vertices, target.n_vertices,
                       max_memory=resolve_memory(options.get("max_memory")),
                       scalable_above=options.get("scalable_above", SCALABLE_ABOVE),
                       bijective=options.get("bijective", False))
    return tuple(shape if shape.settings["mode"] == mode else prepare_mesh(shape.mesh, settings, mode)
                 for shape in (source, target))


def mean_error(source, target, mapping, source_path, target_path, ground_truth, geodesic) -> float:
    from ..evaluation.metrics import evaluate_map
    from ..evaluation.ground_truth import load_ground_truth

    full_source, full_target = source.mesh.n_input, unfilled(target.mesh)
    spec = ground_truth if ground_truth == "identity" else [
        Path(ground_truth) / f"{Path(p).stem}.vts" for p in (source_path, target_path)]
    truth = load_ground_truth(spec, n_source=full_source, n_target=full_target.n_original)
    if full_target.n_original != full_target.n_vertices:
        raise ParameterError("Scoring a map against ground truth needs the whole target mesh "
                             "(without --largest-component).")
    return float(evaluate_map(full_target, mapping, truth, geodesic=geodesic)["mean_error"])


def dna_task(shape, settings: dict):
    """Worker: :func:`meshcorr.collection.consistency.shape_dna` of a prepared shape (None for a failed preparation)."""
    from .consistency import shape_dna

    if not isinstance(shape, PreparedShape):
        return None
    with single_blas_thread():
        return shape_dna(shape.mesh, settings["refine_k"], random_state=settings["random_state"])
