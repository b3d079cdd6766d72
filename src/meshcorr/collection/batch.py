"""Many pairs at once (:func:`meshcorr.batch`): each shape prepared once, one task per pair, on Dask.

:func:`batch` maps a list of (source, target) mesh files. It builds a Dask
graph with one task per shape preparation (:func:`meshcorr.prepare`) and one
per pair (:func:`meshcorr.match` of the two prepared shapes), each pair
depending on the futures of its two shapes: a prepared shape travels to a
worker once, when Dask first needs it there, not once per pair (it pickles
as its ``.npz`` file, :meth:`~meshcorr.shapes.prepared.PreparedShape.to_bytes`).
The workers write each map themselves (atomically) and return a small
record; the caller streams finished pairs (``as_completed``) into
``summary.json`` and ``summary.csv``, rewritten atomically every
:data:`SUMMARY_EVERY` seconds and at the end (also when interrupted).

Task keys are derived from the file (path, size, modification time) and the
settings, so a rerun into the same folder is idempotent: pairs recorded as
done whose map exists are skipped, the others (failed, or never finished
because the run was killed) run again. A folder holding results made with
other settings is refused. A pair that fails (unreadable or unsuitable mesh,
any error) is a record with ``status="failed"`` and its error; it never
stops the batch.

Without a ``client``, :func:`batch` starts a
``dask.distributed.LocalCluster`` (one single-threaded worker process per
core, BLAS held to one thread in each) and shuts it down at the end; pass a
``distributed.Client`` connected to any cluster (``dask-scheduler`` and
``dask-worker`` on several machines, dask-jobqueue) to run the same graph
there: the workers must see the mesh files and the output folder at the
same paths. Dask is the optional extra ``meshcorr[dask]``.

With ``hub`` (every ordered pair of a collection), only the maps from each
shape onto one shape, the hub, are matched; the hub's map onto a shape is
the inverse of that shape's map onto the hub, and each other map is the
composition source -> hub -> target (:mod:`meshcorr.collection.consistency`), each a
task that depends on the maps it is made of: :math:`n-1` matches instead of
:math:`n(n-1)`, and maps that agree with each other through the hub.
``hub="auto"`` takes the shape whose Laplace-Beltrami spectrum is most like
the others' (:func:`meshcorr.collection.consistency.spectral_medoid`), computed on the
workers from the prepared shapes.
"""

from __future__ import annotations

import csv
import hashlib
import io
import json
import logging
import os
import signal
import threading
import time
from contextlib import contextmanager
from pathlib import Path
from typing import Callable, Sequence

import numpy as np

from ..runtime.threads import single_blas_thread
from ..evaluation.benchmark import _check_run_settings, _one_line
from ..errors import OutputError, ParameterError
from ..io import atomic_write
from ..spectral.modes import SCALABLE_ABOVE
from ..core.holes import fills, unfilled
from ..pipeline.settings import SHAPE_SETTINGS, shape_settings
from ..shapes.prepared import PreparedShape

#: ``progress(done, total, failed, seconds_left)``: called after each finished pair
#: (``seconds_left`` is None until a pair has finished).
BatchProgress = Callable[[int, int, int, "float | None"], None]

#: Columns of ``summary.csv``.
FIELDS = ["source", "target", "map", "status", "seconds", "cpu_seconds", "mean_error", "error", "via", "made"]
#: ``status`` of a pair whose map was written.
DONE = "ok"
FAILED = "failed"
#: Seconds between two rewrites of the summary while pairs finish (and once at the end).
SUMMARY_EVERY = 1.0
#: Seconds :func:`connect` waits for a scheduler to answer.
CONNECT_TIMEOUT = 30
DASK_MISSING = ("meshcorr batch runs on Dask, which is not installed: pip install \"meshcorr[dask]\" "
                "(or pip install \"dask[distributed]\").")


def read_pairs(path) -> list[tuple[str, str]]:
    """``(source, target)`` paths from a file of one "SOURCE TARGET" pair a line.

    Blank lines and lines starting with ``#`` are skipped; relative paths are
    relative to the file's folder.

    Raises
    ------
    ParameterError
        A missing file, or a line without exactly two paths.
    """
    path = Path(path)
    if not path.is_file():
        raise ParameterError(f"The pairs file {path} does not exist.")
    pairs = []
    for number, line in enumerate(path.read_text().splitlines(), start=1):
        words = line.split()
        if not words or words[0].startswith("#"):
            continue
        if len(words) != 2:
            raise ParameterError(f"{path}, line {number}: expected two mesh paths 'SOURCE TARGET', got "
                                 f"{line.strip()!r}. Quote nothing; paths with spaces are not supported.")
        pairs.append(tuple(str(path.parent / w) if not os.path.isabs(w) else w for w in words))
    if not pairs:
        raise ParameterError(f"The pairs file {path} lists no pairs.")
    return pairs


def all_pairs(shapes: Sequence[str]) -> list[tuple[str, str]]:
    """Every ordered pair ``(a, b)``, ``a != b``, of ``shapes``: ``n (n - 1)`` maps."""
    _check_shapes(shapes, 2)
    return [(a, b) for a in shapes for b in shapes if a != b]


def template_pairs(template: str, shapes: Sequence[str]) -> list[tuple[str, str]]:
    """``(template, shape)`` for each shape: maps from the template's vertices onto each shape."""
    _check_shapes(shapes, 1)
    return [(template, s) for s in shapes if s != template]


def _check_shapes(shapes: Sequence[str], minimum: int) -> None:
    if not shapes:
        raise ParameterError(f"No mesh files were given: list at least {minimum} "
                             f"({'after --all-pairs' if minimum > 1 else 'after --template T'}).")
    if len(set(shapes)) < minimum or len(set(shapes)) != len(shapes):
        raise ParameterError(f"Give at least {minimum} distinct mesh file{'s' if minimum > 1 else ''} (each "
                             f"once). Got {list(shapes)}.")


def map_name(source: str, target: str) -> str:
    """File name of the map of a pair: ``SOURCESTEM__TARGETSTEM.txt``."""
    return f"{Path(source).stem}__{Path(target).stem}.txt"


def batch(pairs: Sequence[tuple[str, str]], out_dir, *, client=None, ground_truth: str | None = None,
          cache=None, progress: BatchProgress | None = None, n_workers: int | None = None,
          hub: str | None = None, **options) -> list[dict]:
    """Map every pair, writing ``OUT/maps/SOURCE__TARGET.txt`` and a summary as each finishes.

    Parameters
    ----------
    pairs : sequence of (str, str)
        Source and target mesh paths (see :func:`read_pairs`,
        :func:`all_pairs`, :func:`template_pairs`).
    out_dir : str or PathLike
        Created if missing. Holds ``maps/``, ``summary.json``,
        ``summary.csv`` and ``run.json`` (the settings).
    client : distributed.Client, optional
        Run on this cluster; default: a local cluster started and shut down here.
    ground_truth : str, optional
        ``"identity"`` (same vertex order) or a folder of ``SHAPESTEM.vts``
        files (TOSCA's convention): each record then holds the mean
        geodesic error / sqrt(target area) (:func:`meshcorr.evaluation.metrics.evaluate_map`).
    cache : ShapeCache, path or True, optional
        Prepared shapes are looked up in and stored to this on-disk cache.
    progress : callable, optional
        ``progress(done, total, failed, seconds_left)``.
    n_workers : int, optional
        Worker processes of the local cluster (default: one per core).
    hub : str, optional
        A mesh path among the shapes, or ``"auto"``: match only each shape
        onto the hub, invert those maps and compose every other map through
        the hub (module docstring). ``pairs`` must then be every ordered
        pair of its shapes (:func:`all_pairs`), without ``partial``.
    **options
        Options of :func:`meshcorr.match` for the spectral method (e.g.
        ``k``, ``random_state``, ``refine``, ``mode``, ``n_samples``); the
        maps equal those of :func:`meshcorr.match` on each pair.

    Returns
    -------
    records : list of dict
        One per pair, in the order of ``pairs``: ``source``, ``target``,
        ``map`` (path), ``status`` ("ok" or "failed"), ``seconds`` (the
        pair's matching time), ``cpu_seconds`` (the CPU time of the worker
        process meanwhile), ``mean_error`` (with ``ground_truth``),
        ``error`` (the failure's message); with ``hub``, ``via`` (the hub,
        for a map made from the hub's maps) and ``made`` ("match",
        "inverse" or "composition"; the seconds are those of its making).

    Raises
    ------
    ParameterError
        Dask is not installed (:data:`DASK_MISSING`), bad options (checked
        before any work: also ``n_workers`` < 1, and relative paths with a
        ``client``, whose workers may run elsewhere), two pairs writing the
        same map file, an output folder holding results of other settings,
        or a ``hub`` that is not one of the shapes of every ordered pair.
    OutputError
        The output folder cannot be created.
    """
    distributed = _import_distributed()
    settings, options = _split_options(options)
    pairs = [(str(a), str(b)) for a, b in pairs]
    if not pairs:
        raise ParameterError("The batch has no pairs: give --pairs FILE, --all-pairs SHAPES or --template T SHAPES.")
    names = [map_name(a, b) for a, b in pairs]
    if len(set(names)) != len(names):
        name = next(n for n in names if names.count(n) > 1)
        clash = [f"{a} -> {b}" for (a, b), n in zip(pairs, names) if n == name][:2]
        raise ParameterError(f"Two pairs would write the same map file {name} ({clash[0]} and {clash[1]}): maps "
                             "are named after the meshes' file names without folder and extension. Rename the "
                             "meshes so that those names are distinct.")
    if ground_truth is not None and ground_truth != "identity" and not Path(ground_truth).is_dir():
        raise ParameterError(f"The ground truth must be 'identity' or a folder of SHAPE.vts files. "
                             f"Got {ground_truth!r}, which is not a folder.")
    if ground_truth is not None and ground_truth != "identity":
        missing = sorted({Path(p).stem for pair in pairs for p in pair
                          if not (Path(ground_truth) / f"{Path(p).stem}.vts").is_file()})
        if missing:
            raise ParameterError(f"The ground-truth folder {ground_truth} has no {missing[0]}.vts"
                                 f"{f' (nor {len(missing) - 1} more)' if len(missing) > 1 else ''}: every shape "
                                 "needs SHAPESTEM.vts there to be scored.")
    hub = None if hub is None else _check_hub(hub, pairs, options)
    if n_workers is not None and (isinstance(n_workers, bool) or not isinstance(n_workers, int) or n_workers < 1):
        raise ParameterError(f"The number of worker processes must be a whole number >= 1 (--workers N); got "
                             f"{n_workers!r}.")
    if client is not None:  # its workers may run in other folders, or on other machines
        relative = [p for pair in pairs for p in pair if not os.path.isabs(p)] + \
            ([] if os.path.isabs(str(out_dir)) else [str(out_dir)])
        if relative:
            raise ParameterError(f"On an existing Dask cluster (--scheduler) the workers open the files by the "
                                 f"paths given, from their own working folders: give absolute paths (e.g. "
                                 f"{os.path.abspath(relative[0])} for {relative[0]}).")
    out = Path(out_dir)
    try:
        (out / "maps").mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise OutputError(f"Cannot create the output folder {out / 'maps'} ({exc.strerror or exc}): give "
                          "--out a folder that can be written.") from None
    cache_root = None if cache is None else str(_cache_root(cache))
    run = {"settings": settings, "options": _jsonable(options)}
    _check_run_settings(out, run if hub is None else dict(run, hub=hub))  # old folders have no "hub"
    records = {(r["source"], r["target"]): r for r in _read_summary(out)}

    def inputs(a: str, b: str) -> str:
        """What a pair's map was made from: both files (path, size, modification time), the options, the truth."""
        return _task_key(a + chr(0) + b, settings, options, ground_truth)

    def done_before(a: str, b: str) -> bool:
        record = records.get((a, b), {})
        if record.get("status") != DONE or not (out / "maps" / map_name(a, b)).is_file():
            return False
        key = inputs(a, b)
        return record.get("inputs", key) == key  # a changed mesh or --gt: again (older records lack the key)

    todo = [(a, b) for a, b in pairs if not done_before(a, b)]
    if not todo:  # all done before: no cluster to start
        if progress is not None:
            progress(0, 0, 0, None)
        _write_summary(out, _in_order(records, pairs))
        return [records[p] for p in pairs]

    try:
        with _client(distributed, client, n_workers) as dask_client:
            shape_keys = {}
            wanted = {p for pair in (pairs if hub == "auto" and todo else todo) for p in pair}
            for path in sorted(wanted):
                shape_keys[path] = dask_client.submit(_prepare_task, path, settings, options, cache_root,
                                                      key=f"prepare-{_task_key(path, settings, options)}")
            if hub == "auto" and todo:
                hub = _auto_hub(dask_client, shape_keys, settings, options)
            futures, matched = {}, {}
            for a, b in todo:
                if _made_how(a, b, hub) != "match":
                    continue  # made below, from the maps onto the hub
                map_path = str(out / "maps" / map_name(a, b))
                key = f"match-{_task_key(a + chr(0) + b, settings, options, ground_truth, map_path)}"
                future = dask_client.submit(_pair_task, shape_keys[a], shape_keys[b], a, b, map_path, settings,
                                            options, ground_truth, key=key)
                futures[future], matched[a, b] = (a, b, map_path), future
            inverses = {}
            for a, b in todo:
                if _made_how(a, b, hub) != "inverse":
                    continue
                map_path = str(out / "maps" / map_name(a, b))
                key = f"invert-{_task_key(a + chr(0) + b, settings, options, ground_truth, map_path)}"
                future = dask_client.submit(_invert_task, shape_keys[a], shape_keys[b],
                                            matched.get((b, a), records.get((b, a))), a, b, map_path, settings,
                                            ground_truth, key=key)
                futures[future], inverses[a, b] = (a, b, map_path), future
            for a, b in todo:
                if _made_how(a, b, hub) != "composition":
                    continue
                map_path = str(out / "maps" / map_name(a, b))
                steps = [matched.get((a, hub), records.get((a, hub))),
                         inverses.get((hub, b), records.get((hub, b)))]
                key = f"compose-{_task_key(a + chr(0) + b, settings, options, ground_truth, map_path, hub)}"
                future = dask_client.submit(_compose_task, shape_keys[a], shape_keys[b], *steps, a, b, hub,
                                            map_path, settings, ground_truth, key=key)
                futures[future] = (a, b, map_path)
            start, done, failed, written = time.perf_counter(), 0, 0, time.perf_counter()
            eta = _Estimate(len(matched), len(futures) - len(matched), start)
            if progress is not None:
                progress(0, len(todo), 0, None)
            for future in distributed.as_completed(list(futures)):
                try:
                    record = future.result()
                except Exception as exc:  # noqa: BLE001 - e.g. KilledWorker: the pair crashed its worker
                    record = dict(_record(*futures[future], hub), error=_one_line(exc))
                future.release()
                record["inputs"] = inputs(record["source"], record["target"])
                records[(record["source"], record["target"])] = record
                done, failed = done + 1, failed + (record["status"] != DONE)
                eta.finished(record["made"] == "match")
                if time.perf_counter() - written > SUMMARY_EVERY:  # a rerun redoes the pairs not yet written
                    _write_summary(out, _in_order(records, pairs))
                    written = time.perf_counter()
                if progress is not None:
                    progress(done, len(todo), failed, eta.seconds_left())
    finally:  # after an interruption too: a rerun skips what is recorded
        _write_summary(out, _in_order(records, pairs))
    return [records[p] for p in pairs]


def _in_order(records: dict, pairs: list[tuple[str, str]]) -> list[dict]:
    """This run's records in its order, then those of earlier runs into the folder for other pairs (kept)."""
    wanted = set(pairs)
    return [records[p] for p in pairs if p in records] + [r for p, r in records.items() if p not in wanted]


class _Estimate:
    """Seconds left: matches at their own pace, then compositions (milliseconds each) at theirs."""

    def __init__(self, n_matched: int, n_composed: int, start: float) -> None:
        self.left = [n_matched, n_composed]  # pairs left to match, maps left to compose
        self.done = [0, 0]
        self.start = self.last_match = start

    def finished(self, was_matched: bool) -> None:
        kind = 0 if was_matched else 1
        self.left[kind] -= 1
        self.done[kind] += 1
        if was_matched:
            self.last_match = time.perf_counter()

    def seconds_left(self) -> float:
        now = time.perf_counter()
        if self.left[0] and self.done[0]:  # compositions run beside the matches: their time is not counted
            return (now - self.start) / self.done[0] * self.left[0]
        if not self.left[0]:  # only compositions left, at the pace since the last match
            return (now - self.last_match) / max(self.done[1], 1) * self.left[1]
        return (now - self.start) / max(sum(self.done), 1) * sum(self.left)


def _check_hub(hub: str, pairs: list[tuple[str, str]], options: dict) -> str:
    """``hub`` as spelled in ``pairs`` (or "auto"), checked: the pairs are every ordered pair of their shapes."""
    shapes = sorted({p for pair in pairs for p in pair})
    if set(pairs) != set(all_pairs(shapes)) or len(shapes) < 3:
        raise ParameterError("Mapping through a hub needs every ordered pair of at least three shapes "
                             "(meshcorr.collection.batch.all_pairs, or meshcorr batch --all-pairs).")
    if options.get("partial") is not None:
        raise ParameterError("A hub composes whole-shape maps: it does not go with partial (each shape "
                             "a part of every other); drop --hub or --partial.")
    if hub == "auto":
        return hub
    same = [p for p in shapes if os.path.abspath(p) == os.path.abspath(str(hub))]
    if not same:
        raise ParameterError(f"The hub {hub} is not one of the shapes of the batch; give one of them "
                             "(as listed) or 'auto'.")
    return same[0]


def _auto_hub(dask_client, shape_keys: dict, settings: dict, options: dict) -> str:
    """The shapes' spectral medoid (:func:`meshcorr.collection.consistency.spectral_medoid`); Shape-DNA from the workers."""
    from .consistency import spectral_medoid

    paths = sorted(shape_keys)
    dna = dask_client.gather([dask_client.submit(_dna_task, shape_keys[p], settings,
                                                 key=f"dna-{_task_key(p, settings, options)}") for p in paths])
    known = {p: d for p, d in zip(paths, dna) if d is not None}
    return spectral_medoid(known) if known else paths[0]  # no shape prepared: every pair fails anyway


def _dna_task(shape, settings: dict):
    """Worker: :func:`meshcorr.collection.consistency.shape_dna` of a prepared shape (None for a failed preparation)."""
    from .consistency import shape_dna

    if not isinstance(shape, PreparedShape):
        return None
    with single_blas_thread():
        return shape_dna(shape.mesh, settings["refine_k"], random_state=settings["random_state"])


def _import_distributed():
    try:
        import distributed
    except ImportError:
        raise ParameterError(DASK_MISSING) from None
    return distributed


@contextmanager
def _client(distributed, client, n_workers: int | None):
    """The given client, or one of a local cluster of single-threaded worker processes started here."""
    if client is not None:
        yield client
        return
    workers = n_workers or os.cpu_count() or 1
    # One process per core, so one thread each: for BLAS, and for the pipeline's own thread pools
    # (meshcorr.runtime.threads; the maps are those of the threaded runs).
    env = {name: "1" for name in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS",
                                  "MESHCORR_THREADS")}
    # silence_logs: Dask's own warnings and errors (the tasks cancelled by Ctrl-C, a worker's heartbeat to
    # the scheduler that an interrupt stopped first) are not the user's business; a pair's failure comes
    # back through its future and is recorded.
    # dashboard_address ":0": the scheduler's HTTP server on a free port (None still asked for 8787 and
    # warned "Port 8787 is already in use" beside another Dask cluster).
    with _workers_ignore_ctrl_c():
        cluster = distributed.LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                                           host="127.0.0.1", dashboard_address=":0", env=env,
                                           silence_logs=logging.CRITICAL)
    with cluster, distributed.Client(cluster) as local:
        yield local


@contextmanager
def _workers_ignore_ctrl_c():
    """SIGINT ignored while the local cluster starts its worker processes, which inherit that.

    Ctrl-C in a terminal goes to the whole process group: the workers got it too and each printed
    a traceback before this process could stop them. Ignored signals (not handlers) survive the
    workers' spawn; this process restores its own handler at once and stops the workers itself.
    An interrupt while the cluster starts is lost (press Ctrl-C again). Outside the main thread
    (where signals cannot be set) the cluster starts as it is.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)


def _split_options(options: dict) -> tuple[dict, dict]:
    """The per-shape settings and the other match options, every value checked before any work."""
    from ..pipeline.methods import check_options, method_parameters

    given = dict(options)
    if "method" in given and given["method"] != "spectral":
        raise ParameterError("meshcorr batch runs the spectral method only (prepared shapes); "
                             f"got method={given['method']!r}.")
    if given.get("landmarks") is not None:
        raise ParameterError("User landmarks belong to one pair: meshcorr batch does not take them (match "
                             "such pairs one by one with meshcorr.match(..., landmarks=...)).")
    shape = {key: given.pop(key, default) for key, default in SHAPE_SETTINGS.items()}
    settings = shape_settings(**shape)
    settings["fill_holes"] = fills(settings["fill_holes"], partial=given.get("partial"),
                                   bijective=given.get("bijective", False))
    taken = list(method_parameters("spectral"))
    unknown = sorted(set(given) - set(taken))
    if unknown:
        raise ParameterError(f"Unknown option of meshcorr.batch: {unknown[0]!r} is no option of meshcorr.match "
                             f"(its options are: {', '.join(taken)}).")
    # Every value as match would check it, those it checks only once the meshes are loaded
    # (e.g. icp_iterations) included, so that no pair fails for a bad option.
    check_options("spectral", **given, **settings)
    return settings, given


def _jsonable(options: dict) -> dict:
    return {key: (value if isinstance(value, (int, float, str, bool, type(None))) else repr(value))
            for key, value in sorted(options.items())}


def _task_key(text: str, *parts) -> str:
    """A deterministic key: the file's path, size and modification time (each path in ``text``) and the settings."""
    stats = []
    for path in text.split(chr(0)):
        try:
            info = os.stat(path)
            stats.append([os.path.abspath(path), info.st_size, info.st_mtime_ns])
        except OSError:
            stats.append([path])
    payload = json.dumps([stats, [_jsonable(p) if isinstance(p, dict) else p for p in parts]], sort_keys=True)
    return hashlib.sha256(payload.encode()).hexdigest()[:24]


def _cache_root(cache) -> Path:
    from ..shapes.cache import as_cache

    return as_cache(cache).root


def _prepare_task(path: str, settings: dict, options: dict, cache_root: str | None):
    """Worker: the :class:`PreparedShape` of one mesh file, or the one-line error that prevents it."""
    from ..pipeline.prepare import prepare

    try:
        with single_blas_thread():
            return prepare(path, mode=options.get("mode", "auto"), max_memory=options.get("max_memory"),
                           scalable_above=options.get("scalable_above", SCALABLE_ABOVE),
                           cache=cache_root, **settings)
    except Exception as exc:  # noqa: BLE001 - a failed shape fails its pairs, never the batch
        return _one_line(exc)


def _pair_task(source, target, source_path: str, target_path: str, map_path: str, settings: dict,
               options: dict, ground_truth: str | None) -> dict:
    """Worker: match two prepared shapes, write the map, return the pair's record."""
    from ..io import write_map
    from ..pipeline.run import match

    record = _record(source_path, target_path, map_path)
    if _failed_shape(record, (source, source_path), (target, target_path)):
        return record
    try:
        with single_blas_thread():
            source, target = _in_pair_mode(source, target, settings, options)
            start, cpu = time.perf_counter(), time.process_time()
            result = match(source, target, **options, **settings)
            record["seconds"] = time.perf_counter() - start
            record["cpu_seconds"] = time.process_time() - cpu  # the worker's CPU time: load-independent
            write_map(map_path, result.map)
            if ground_truth is not None:
                record["mean_error"] = _mean_error(source, target, result.map, source_path, target_path,
                                                   ground_truth, settings["geodesic"])
        record["status"] = DONE
    except Exception as exc:  # noqa: BLE001 - a failed pair is a record, never the end of the batch
        record["error"] = _one_line(exc)
    return record


def _compose_task(source, target, to_hub: dict | None, from_hub: dict | None, source_path: str,
                  target_path: str, hub: str, map_path: str, settings: dict, ground_truth: str | None) -> dict:
    """Worker: the map source -> hub -> target from the two matched maps' records, written; its record."""
    from .consistency import compose
    from ..io import read_map

    record = _record(source_path, target_path, map_path, hub)
    for step, (a, b) in ((to_hub, (source_path, hub)), (from_hub, (hub, target_path))):
        if step is None or step["status"] != DONE:
            reason = "was not mapped" if step is None else f"failed: {step['error']}"
            record["error"] = f"Composed through the hub: its map {Path(a).name} -> {Path(b).name} {reason}"[:300]
            return record
    # f_HB o f_AH
    return _made_map(record, source, target, lambda: compose(read_map(to_hub["map"]), read_map(from_hub["map"])),
                     settings, ground_truth)


def _invert_task(hub, target, onto_hub: dict | None, hub_path: str, target_path: str, map_path: str,
                 settings: dict, ground_truth: str | None) -> dict:
    """Worker: the hub's map onto a shape, the inverse of that shape's map onto the hub, written; its record."""
    from .consistency import input_positions, invert
    from ..io import read_map

    record = _record(hub_path, target_path, map_path, hub_path)
    if onto_hub is None or onto_hub["status"] != DONE:
        reason = "was not mapped" if onto_hub is None else f"failed: {onto_hub['error']}"
        record["error"] = (f"Inverted from the map {Path(target_path).name} -> {Path(hub_path).name}, "
                           f"which {reason}")[:300]
        return record

    def inverse() -> np.ndarray:  # on the hub's own vertices, without the caps of its holes (meshcorr.core.holes)
        return invert(read_map(onto_hub["map"]), input_positions(unfilled(hub.mesh)))

    return _made_map(record, hub, target, inverse, settings, ground_truth)


def _made_map(record: dict, source, target, make: Callable[[], np.ndarray], settings: dict,
              ground_truth: str | None) -> dict:
    """Worker: ``make()`` the map of ``record`` from maps already written, write it, score it; the record."""
    from ..io import write_map

    if _failed_shape(record, (source, record["source"]), (target, record["target"])):
        return record
    try:
        start, cpu = time.perf_counter(), time.process_time()
        mapping = make()
        write_map(record["map"], mapping)
        record["seconds"], record["cpu_seconds"] = time.perf_counter() - start, time.process_time() - cpu
        if ground_truth is not None:
            with single_blas_thread():
                record["mean_error"] = _mean_error(source, target, mapping, record["source"], record["target"],
                                                   ground_truth, settings["geodesic"])
        record["status"] = DONE
    except Exception as exc:  # noqa: BLE001 - a failed pair is a record, never the end of the batch
        record["error"] = _one_line(exc)
    return record


def _failed_shape(record: dict, *shapes) -> bool:
    """Whether a ``(shape, path)`` failed its preparation; if so its message goes into ``record["error"]``."""
    for shape, path in shapes:
        if not isinstance(shape, PreparedShape):  # the message of the failed preparation
            name = Path(path).name
            record["error"] = shape if name in shape else f"{name}: {shape}"
            return True
    return False


def _record(source_path: str, target_path: str, map_path: str, hub: str | None = None) -> dict:
    """The record of a pair not (yet) mapped: status "failed", no times, no error message."""
    record = {"source": source_path, "target": target_path, "map": map_path, "status": FAILED, "seconds": None,
              "cpu_seconds": None, "mean_error": None, "error": "",
              "made": _made_how(source_path, target_path, hub)}
    if record["made"] != "match":
        record["via"] = hub
    return record


def _made_how(source: str, target: str, hub: str | None) -> str:
    """How a batch makes the map of a pair: "match", or with a hub "inverse" (from the hub) or "composition"."""
    if hub is None or target == hub:
        return "match"
    return "inverse" if source == hub else "composition"


def _in_pair_mode(source: PreparedShape, target: PreparedShape, settings: dict, options: dict):
    """The two shapes prepared in the mode the pair runs in (a shape alone may resolve "auto" otherwise)."""
    from ..spectral.modes import resolve_memory, select_mode
    from ..shapes.prepared import prepare_mesh

    mode = select_mode(options.get("mode", "auto"), source.n_vertices, target.n_vertices,
                       max_memory=resolve_memory(options.get("max_memory")),
                       scalable_above=options.get("scalable_above", SCALABLE_ABOVE),
                       bijective=options.get("bijective", False))
    return tuple(shape if shape.settings["mode"] == mode else prepare_mesh(shape.mesh, settings, mode)
                 for shape in (source, target))


def _mean_error(source, target, mapping, source_path, target_path, ground_truth, geodesic) -> float:
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


def _read_summary(out: Path) -> list[dict]:
    path = out / "summary.json"
    if not path.is_file():
        return []
    try:
        return list(json.loads(path.read_text())["pairs"])
    except (ValueError, KeyError, TypeError):
        raise ParameterError(f"{path} is not a batch summary (damaged?): delete it to run every pair again, "
                             "or use another --out folder.") from None


def _write_summary(out: Path, records: list[dict]) -> None:
    failed = sum(r["status"] != DONE for r in records)
    seconds = [r["seconds"] for r in records if r["status"] == DONE and r["seconds"] is not None]
    payload = json.dumps({"n_pairs": len(records), "n_failed": failed,
                          "mean_seconds": float(np.mean(seconds)) if seconds else None, "pairs": records},
                         indent=1).encode()
    atomic_write(out / "summary.json", lambda file: file.write(payload))
    buffer = io.StringIO()
    writer = csv.DictWriter(buffer, fieldnames=FIELDS, lineterminator="\n", extrasaction="ignore")
    writer.writeheader()
    for record in records:
        writer.writerow({key: "" if record.get(key) is None else record[key] for key in FIELDS})
    text = buffer.getvalue().encode()
    atomic_write(out / "summary.csv", lambda file: file.write(text))


def connect(address: str):
    """A ``distributed.Client`` of the scheduler at ``address`` (e.g. ``tcp://10.0.0.5:8786``).

    Raises
    ------
    ParameterError
        Dask is missing, or no scheduler answers at ``address`` within :data:`CONNECT_TIMEOUT` seconds.
    """
    distributed = _import_distributed()
    try:
        return distributed.Client(address, timeout=CONNECT_TIMEOUT)
    except (OSError, TimeoutError, ValueError) as exc:
        raise ParameterError(f"No Dask scheduler answered at {address} ({_one_line(exc)}): start one with "
                            "'dask scheduler' and workers with 'dask worker ADDRESS', or omit --scheduler "
                            "to use a local cluster.") from None
