"""Many pairs at once (:func:`meshcorr.batch`): each shape prepared once, one task per pair, on Dask.

:func:`batch` maps a list of (source, target) mesh files. It builds a Dask
graph with one task per shape preparation (:func:`meshcorr.prepare`) and one
per pair (:func:`meshcorr.match` of the two prepared shapes), each pair
depending on the futures of its two shapes: a prepared shape travels to a
worker once, when Dask first needs it there, not once per pair (it pickles
as its ``.npz`` file, :meth:`~meshcorr.shapes.prepared.PreparedShape.to_bytes`).
The workers return each pair's record with its map; the caller streams
finished pairs (``as_completed``), writes each map (atomically) and records
it in ``summary.json`` and ``summary.csv``, rewritten atomically every
:data:`SUMMARY_EVERY` seconds and at the end (also when interrupted, after
cancelling the pairs not finished: a pair that a worker finishes later writes
nothing, so every map file of the folder is in its summary). One run at a
time writes into a folder (:func:`~meshcorr.collection.folder.output_lock`).

Task keys are derived from the files (path and SHA-256 of the content) and
the settings, so a rerun into the same folder is idempotent: pairs recorded
as done whose map file is complete (readable, of the recorded length) are
skipped, the others (failed, never finished because the run was killed, a
mesh changed, a map file damaged) run again. A folder holding results made with
other settings is refused. A pair that fails (unreadable or unsuitable mesh,
any error) is a record with ``status="failed"`` and its error; it never
stops the batch.

Without a ``client``, :func:`batch` starts a
``dask.distributed.LocalCluster`` (one single-threaded worker process per
core, BLAS held to one thread in each) and shuts it down at the end; pass a
``distributed.Client`` connected to any cluster (``dask-scheduler`` and
``dask-worker`` on several machines, dask-jobqueue) to run the same graph
there: the workers must see the mesh files and the output folder at the
same paths (:mod:`meshcorr.collection.cluster`). Dask is the optional extra
``meshcorr[dask]``.

With ``hub`` (every ordered pair of a collection), only the maps from each
shape onto one shape, the hub, are matched; the hub's map onto a shape is
the inverse of that shape's map onto the hub, and each other map is the
composition source -> hub -> target (:mod:`meshcorr.collection.consistency`), each a
task that depends on the maps it is made of: :math:`n-1` matches instead of
:math:`n(n-1)`, and maps that agree with each other through the hub.
``hub="auto"`` takes the shape whose Laplace-Beltrami spectrum is most like
the others' (:func:`meshcorr.collection.consistency.spectral_medoid`), computed on the
workers from the prepared shapes.

The steps live beside this module: the pair lists
(:mod:`~meshcorr.collection.pairs`), the options and the keys
(:mod:`~meshcorr.collection.options`), the workers' tasks
(:mod:`~meshcorr.collection.tasks`) and the records and summary files
(:mod:`~meshcorr.collection.summary`).
"""

from __future__ import annotations

import os
import time
import uuid
import warnings
from contextlib import contextmanager
from dataclasses import dataclass, field
from itertools import chain
from pathlib import Path
from typing import Callable, Sequence

from ..errors import OutputError, ParameterError
from ..evaluation.run_settings import check_run_settings
from ..pipeline.settings import Settings
from ..runtime.messages import one_line
from .cluster import MAX_WORKERS, WORKERS_PER_CORE, import_distributed, local_client, max_workers
from .folder import output_lock
from .options import jsonable, split_options, task_key
from .pairs import all_pairs, map_name
from .summary import (DONE, in_order, made_how, map_complete, new_record, read_summary, write_record_map,
                      write_summary)
from .tasks import MAPPING, compose_task, dna_task, invert_task, pair_task, prepare_task

__all__ = ["BatchProgress", "SUMMARY_EVERY", "batch"]

#: ``progress(done, total, failed, seconds_left)``: called after each finished pair
#: (``seconds_left`` is None until a pair has finished).
BatchProgress = Callable[[int, int, int, "float | None"], None]

#: Seconds between two rewrites of the summary while pairs finish (and once at the end).
SUMMARY_EVERY = 1.0


def batch(pairs: Sequence[tuple[str, str]], out_dir, *, client=None, ground_truth: str | None = None,
          cache=None, progress: BatchProgress | None = None, n_workers: int | None = None,
          hub: str | None = None, **options) -> list[dict]:
    """Map every pair, writing ``OUT/maps/SOURCE__TARGET.txt`` and a summary as each finishes.

    Parameters
    ----------
    pairs : sequence of (str, str)
        Source and target mesh paths (see :func:`~meshcorr.collection.pairs.read_pair_list`,
        :func:`~meshcorr.collection.pairs.all_pairs`,
        :func:`~meshcorr.collection.pairs.template_pairs`).
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
        pair of its shapes (:func:`~meshcorr.collection.pairs.all_pairs`), without ``partial``.
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
        Dask is not installed (:data:`~meshcorr.collection.cluster.DASK_MISSING`), bad options (checked
        before any work: also ``n_workers`` < 1, and relative paths with a
        ``client``, whose workers may run elsewhere), two pairs writing the
        same map file, an output folder holding results of other settings,
        or a ``hub`` that is not one of the shapes of every ordered pair.
    OutputError
        The output folder cannot be created, or another batch is writing into it.

    Warns
    -----
    CacheWarning
        The ``cache`` folder cannot be written: the batch runs without it.
    """
    distributed = import_distributed()
    settings, options = split_options(options)
    pairs = [(str(a), str(b)) for a, b in pairs]
    _check_pairs(pairs)
    _check_ground_truth(ground_truth, pairs)
    hub = None if hub is None else _check_hub(hub, pairs, options)
    _check_cluster(client, n_workers, pairs, out_dir)
    out = _output_folder(out_dir)
    with output_lock(out):  # one run at a time into a folder: each rewrites the summary from its records
        root = None if cache is None else _writable_cache(cache)
        run = _Run.open(out, pairs, settings, options, ground_truth, hub)
        if not run.todo:  # all done before: no cluster to start
            if progress is not None:
                progress(0, 0, 0, None)
            write_summary(out, in_order(run.records, pairs))
            return run.results()
        try:
            with _client(distributed, client, n_workers) as dask_client:
                futures, n_matched = _submit(dask_client, run, root)
                try:
                    _collect(distributed, futures, n_matched, run, progress)
                except BaseException:  # Ctrl-C, SIGTERM: the cluster (maybe another's) stops the pairs left
                    _cancel(dask_client, futures)
                    raise
        finally:  # after an interruption too: a rerun skips what is recorded
            write_summary(out, in_order(run.records, pairs))
        return run.results()


@dataclass
class _Run:
    """One batch into a folder: its pairs and settings, and the records of this run and of earlier ones there.

    ``todo`` are the pairs not done before (:meth:`done_before`); ``hub`` is
    "auto" until :func:`_submit` has chosen it.
    """

    out: Path
    pairs: list
    settings: dict
    options: dict
    ground_truth: str | None
    hub: str | None
    records: dict  # (source, target) -> record
    todo: list = field(default_factory=list)
    digests: dict = field(default_factory=dict)  # mesh path -> SHA-256 of its file, read once a run

    @property
    def matching(self) -> Settings:
        """The :class:`~meshcorr.Settings` every preparation and match of the run uses (the keys use the dicts)."""
        return Settings.from_options(**self.options, **self.settings)

    @classmethod
    def open(cls, out: Path, pairs: list, settings: dict, options: dict, ground_truth: str | None,
             hub: str | None) -> "_Run":
        """The run into ``out``: its settings checked against ``run.json``, the records of ``summary.json`` read."""
        run = {"settings": settings, "options": jsonable(options)}
        check_run_settings(out, run if hub is None else dict(run, hub=hub))  # old folders have no "hub"
        records = {(r["source"], r["target"]): r for r in read_summary(out)}
        self = cls(out, pairs, settings, options, ground_truth, hub, records)
        self.todo = [(a, b) for a, b in pairs if not self.done_before(a, b)]
        # One token per run in every Dask key: a key cancelled by an interrupted run on the same cluster
        # would otherwise cancel the same task of the next run too (FutureCancelledError).
        self.token = uuid.uuid4().hex[:8]
        return self

    def inputs(self, a: str, b: str) -> str:
        """What a pair's map was made from: both files (path and content), the options, the truth."""
        return task_key(a + chr(0) + b, self.settings, self.options, self.ground_truth, digests=self.digests)

    def shape_key(self, kind: str, path: str) -> str:
        """The Dask key of the task ``kind`` ("prepare", "dna") of one shape: its file and the settings."""
        return f"{kind}-{task_key(path, self.settings, self.options, digests=self.digests)}-{self.token}"

    def done_before(self, a: str, b: str) -> bool:
        record = self.records.get((a, b), {})
        if record.get("status") != DONE or not map_complete(dict(record, map=self.map_path(a, b))):
            return False  # not done, or its map file gone, cut short or damaged: again
        key = self.inputs(a, b)
        return record.get("inputs", key) == key  # a changed mesh or --gt: again (older records lack the key)

    def map_path(self, a: str, b: str) -> str:
        return str(self.out / "maps" / map_name(a, b))

    def key(self, kind: str, a: str, b: str, *extra) -> str:
        """The Dask key of the task ``kind`` ("match", "invert", "compose") of a pair."""
        made_of = (self.settings, self.options, self.ground_truth, self.map_path(a, b), *extra)
        return f"{kind}-{task_key(a + chr(0) + b, *made_of, digests=self.digests)}-{self.token}"

    def made(self, pair: tuple[str, str], futures: dict):
        """The future of a map made in this run, else its record from an earlier run (or None)."""
        return futures.get(pair, self.records.get(pair))

    def results(self) -> list[dict]:
        return [self.records[p] for p in self.pairs]


def _check_pairs(pairs: list[tuple[str, str]]) -> None:
    """Some pairs, and no two of them writing the same map file."""
    if not pairs:
        raise ParameterError("The batch has no pairs: give --pairs FILE, --all-pairs SHAPES or --template T SHAPES.")
    names = [map_name(a, b) for a, b in pairs]
    if len(set(names)) != len(names):
        name = next(n for n in names if names.count(n) > 1)
        clash = [f"{a} -> {b}" for (a, b), n in zip(pairs, names) if n == name][:2]
        raise ParameterError(f"Two pairs would write the same map file {name} ({clash[0]} and {clash[1]}): maps "
                             "are named after the meshes' file names without folder and extension. Rename the "
                             "meshes so that those names are distinct.")


def _check_ground_truth(ground_truth: str | None, pairs: list[tuple[str, str]]) -> None:
    """``"identity"``, or a folder with ``SHAPESTEM.vts`` for every shape of the pairs."""
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


def _check_cluster(client, n_workers, pairs: list[tuple[str, str]], out_dir) -> None:
    """A whole ``n_workers`` >= 1; with a ``client`` (whose workers may run elsewhere), absolute paths only."""
    if n_workers is not None and (isinstance(n_workers, bool) or not isinstance(n_workers, int) or n_workers < 1):
        raise ParameterError(f"The number of worker processes must be a whole number >= 1 (--workers N); got "
                             f"{n_workers!r}.")
    if n_workers is not None and client is None and n_workers > max_workers():  # it started processes until
        # the machine gave out
        raise ParameterError(f"n_workers={n_workers} (--workers) would start {n_workers} processes on this "
                             f"machine's {os.cpu_count() or 1} core(s): give at most {max_workers()} "
                             f"({WORKERS_PER_CORE} per core, at most {MAX_WORKERS}), or run a larger cluster and "
                             "pass its client (--scheduler).")
    if client is not None:  # its workers may run in other folders, or on other machines
        relative = [p for pair in pairs for p in pair if not os.path.isabs(p)] + \
            ([] if os.path.isabs(str(out_dir)) else [str(out_dir)])
        if relative:
            raise ParameterError(f"On an existing Dask cluster (--scheduler) the workers open the files by the "
                                 f"paths given, from their own working folders: give absolute paths (e.g. "
                                 f"{os.path.abspath(relative[0])} for {relative[0]}).")


def _output_folder(out_dir) -> Path:
    """``out_dir`` with its ``maps/`` folder, created if missing."""
    out = Path(out_dir)
    try:
        (out / "maps").mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise OutputError(f"Cannot create the output folder {out / 'maps'} ({exc.strerror or exc}): give "
                          "--out a folder that can be written.") from None
    return out


def _submit(dask_client, run: _Run, cache: str | None) -> tuple[dict, int]:
    """The graph of ``run.todo``: a task per shape, then per pair one that matches it, or inverts or composes maps.

    Returns the futures of the pairs (future -> (source, target, map path)) and how many of them match.
    """
    wanted = {p for pair in (run.pairs if run.hub == "auto" else run.todo) for p in pair}
    matching = run.matching
    shapes = {path: dask_client.submit(prepare_task, path, matching, cache,
                                       key=run.shape_key("prepare", path))
              for path in sorted(wanted)}
    if run.hub == "auto":
        run.hub = _auto_hub(dask_client, shapes, run)

    def todo(how: str) -> list[tuple[str, str]]:
        return [(a, b) for a, b in run.todo if made_how(a, b, run.hub) == how]

    matched = {(a, b): dask_client.submit(pair_task, shapes[a], shapes[b], a, b, run.map_path(a, b), matching,
                                          run.settings, run.options, run.ground_truth, key=run.key("match", a, b))
               for a, b in todo("match")}
    inverses = {(a, b): dask_client.submit(invert_task, shapes[a], shapes[b], run.made((b, a), matched), a, b,
                                           run.map_path(a, b), run.settings, run.ground_truth,
                                           key=run.key("invert", a, b))
                for a, b in todo("inverse")}
    composed = {(a, b): dask_client.submit(compose_task, shapes[a], shapes[b], run.made((a, run.hub), matched),
                                           run.made((run.hub, b), inverses), a, b, run.hub, run.map_path(a, b),
                                           run.settings, run.ground_truth, key=run.key("compose", a, b, run.hub))
                for a, b in todo("composition")}
    futures = {future: (a, b, run.map_path(a, b))
               for (a, b), future in chain(matched.items(), inverses.items(), composed.items())}
    return futures, len(matched)


def _collect(distributed, futures: dict, n_matched: int, run: _Run, progress: BatchProgress | None) -> None:
    """Each pair's record into ``run.records`` as it finishes; the summary rewritten every :data:`SUMMARY_EVERY` s."""
    total = len(run.todo)
    start, done, failed, written = time.perf_counter(), 0, 0, time.perf_counter()
    eta = _Estimate(n_matched, len(futures) - n_matched, start)
    if progress is not None:
        progress(0, total, 0, None)
    for future in distributed.as_completed(list(futures)):
        try:
            record = future.result()
        except Exception as exc:  # noqa: BLE001 - e.g. KilledWorker: the pair crashed its worker
            record = dict(new_record(*futures[future], run.hub), error=one_line(exc))
        future.release()
        # Written here, not on the worker: no map appears that the summary written at the end does not list.
        write_record_map(record, record.pop(MAPPING, None))
        record["inputs"] = run.inputs(record["source"], record["target"])
        run.records[(record["source"], record["target"])] = record
        done, failed = done + 1, failed + (record["status"] != DONE)
        eta.finished(record["made"] == "match")
        if time.perf_counter() - written > SUMMARY_EVERY:  # a rerun redoes the pairs not yet written
            write_summary(run.out, in_order(run.records, run.pairs))
            written = time.perf_counter()
        if progress is not None:
            progress(done, total, failed, eta.seconds_left())


def _cancel(dask_client, futures: dict) -> None:
    """Cancel the pairs not finished, so that the cluster's workers do not go on with them."""
    pending = [future for future in futures if not future.done()]
    try:
        if pending:
            dask_client.cancel(pending)
    except Exception:  # noqa: BLE001 - a scheduler gone already: nothing left to cancel
        pass


def _writable_cache(cache) -> str | None:
    """The cache's folder, or None (with a :class:`~meshcorr.shapes.cache.CacheWarning`) if it cannot be written.

    Checked once before any work: a read-only or full cache folder would otherwise fail no pair but warn
    (and lose the time of a write) for every shape.
    """
    from ..shapes.cache import CacheWarning, as_cache

    shapes = as_cache(cache)
    try:
        shapes.check_writable()
    except OutputError as exc:
        warnings.warn(f"{exc} The batch runs without the cache: every shape is prepared and none is kept. "
                      "Give --cache a folder that can be written to keep them.", CacheWarning, stacklevel=3)
        return None
    return str(shapes.root)


@contextmanager
def _client(distributed, client, n_workers: int | None):
    """The given client, or one of a local cluster started here (:func:`~meshcorr.collection.cluster.local_client`)."""
    if client is not None:
        yield client
        return
    with local_client(distributed, n_workers) as local:
        yield local


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
                             "(meshcorr.collection.pairs.all_pairs, or meshcorr batch --all-pairs).")
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


def _auto_hub(dask_client, shape_keys: dict, run: _Run) -> str:
    """The shapes' spectral medoid (:func:`~meshcorr.collection.consistency.spectral_medoid`) by their Shape-DNA.

    The Shape-DNA of each prepared shape is computed on the workers; a shape
    that could not be prepared is no candidate.
    """
    from .consistency import spectral_medoid

    paths = sorted(shape_keys)
    dna = dask_client.gather([dask_client.submit(dna_task, shape_keys[p], run.settings, key=run.shape_key("dna", p))
                              for p in paths])
    known = {p: d for p, d in zip(paths, dna) if d is not None}
    return spectral_medoid(known) if known else paths[0]  # no shape prepared: every pair fails anyway
