"""Benchmark correspondence methods on a dataset of shape pairs with ground truth.

A dataset folder holds ``NAME.off`` meshes, ``corres/NAME.vts`` ground truth
(1-based template samples; ``corres/NAME.sym.vts`` optionally gives the
mirrored truth) and ``test_pairs.txt`` (one ``SOURCE TARGET`` pair of names
per line): the TOSCA / SHREC layout of Ren et al. (2018).

:func:`run_benchmark` maps every selected pair with every method, scores the
map with :func:`meshcorr.evaluation.metrics.evaluate_map`, and rewrites
``results.csv`` atomically after each (pair, method), so an interrupted run
restarted on the same output folder skips what is done; ``run.json`` there
keeps the settings and the dataset's identity (:func:`dataset_identity`), and
a restart with other settings, on another dataset or on one whose meshes or
truth files changed is refused before any work. A method that
raises on one pair is recorded as a failed row; the run goes on.
:func:`summarize` turns the rows into a per-method table and curves.
"""

from __future__ import annotations

import csv
import hashlib
import io
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Sequence

import numpy as np

from ..runtime.checks import check_int
from ..errors import InputError, MeshcorrError, ParameterError
from .metrics import THRESHOLDS, GeodesicCache, cumulative_curve, evaluate_map
from .ground_truth import load_ground_truth
from ..io import atomic_write
from ..core.mesh import Mesh, as_mesh
from ..pipeline.methods import check_options, run_method
from ..runtime.messages import ONE_LINE_LENGTH, one_line
from .run_settings import check_run_settings
from ..core.geodesics import DEFAULT_GEODESIC

__all__ = ["METHODS", "Dataset", "FIELDS", "dataset_identity", "load_dataset", "read_rows", "run_benchmark",
           "stratified_sample", "summarize", "write_summary"]

#: Methods the benchmark knows; all but "spectral" come from meshcorr.baselines.
METHODS = ("spectral", "shapiro-brady", "shapiro-brady-scaled", "tps-rpm", "icp", "shape-context")
#: Methods that take the spectral options (k, geodesic).
SPECTRAL_FAMILY = ("spectral", "shapiro-brady", "shapiro-brady-scaled")

_UNDER = [f"under_{t:g}" for t in THRESHOLDS]
#: Columns of results.csv, one row per (pair, method).
FIELDS = ["source", "target", "class", "method", "status", "mean_error", "median_error", *_UNDER,
          "sym_mean_error", "flipped", "best_mean_error", "total_error", "total_error_normalized",
          "n_points", "n_unmapped", "seconds", "eval_seconds", "error"]

#: ``progress(done, total, message)`` after each finished (pair, method) and before each start.
BenchProgress = Callable[[int, int, str], None]


@dataclass(frozen=True)
class Dataset:
    """A folder of meshes with ground truth and a list of test pairs.

    Attributes
    ----------
    root : Path
    pairs : list of (str, str)
        ``(source name, target name)`` in file order.
    """

    root: Path
    pairs: list

    def mesh_path(self, name: str) -> Path:
        return self.root / f"{name}.off"

    def vts_path(self, name: str, sym: bool = False) -> Path:
        return self.root / "corres" / f"{name}{'.sym' if sym else ''}.vts"


def shape_class(name: str) -> str:
    """The class of a shape name: the name without its trailing digits (``david10`` -> ``david``)."""
    return name.rstrip("0123456789") or name


def load_dataset(root) -> Dataset:
    """Read and check a dataset folder (see the module docstring).

    Raises
    ------
    ParameterError
        If the folder, ``test_pairs.txt``, a listed mesh or its ``.vts`` file
        is missing, or a line of ``test_pairs.txt`` is not two names.
    """
    root = Path(root)
    if not root.is_dir():
        raise ParameterError(f"No such dataset folder: {root}")
    listing = root / "test_pairs.txt"
    if not listing.is_file():
        raise ParameterError(f"{root} has no test_pairs.txt; a dataset folder holds NAME.off meshes, "
                             "corres/NAME.vts ground truth and test_pairs.txt (one pair per line).")
    pairs = []
    for number, line in enumerate(listing.read_text().splitlines(), 1):
        fields = line.split("#", 1)[0].split()
        if not fields:
            continue
        if len(fields) != 2:
            raise ParameterError(f"{listing}, line {number}: expected two shape names, got {line!r}.")
        pairs.append((fields[0], fields[1]))
    if not pairs:
        raise ParameterError(f"{listing} lists no pairs.")
    dataset = Dataset(root, pairs)
    for name in sorted({n for pair in pairs for n in pair}):
        for path in (dataset.mesh_path(name), dataset.vts_path(name)):
            if not path.is_file():
                raise ParameterError(f"{listing} names {name!r}, but {path} is missing.")
    return dataset


def stratified_sample(pairs: Sequence[tuple[str, str]], n: int | None, random_state: int = 0
                      ) -> list[tuple[str, str]]:
    """A deterministic sample of pairs that spreads over the classes.

    Classes (by :func:`shape_class` of the source) are visited in turn in
    sorted order, taking each class's pairs in an order shuffled by
    ``random_state``, until ``n`` pairs are drawn; so ``n`` = 3 x the number
    of classes takes 3 pairs of each (when every class has 3).

    Parameters
    ----------
    pairs : list of (str, str)
    n : int or None
        Sample size; None or >= len(pairs) returns every pair.
    random_state : int

    Returns
    -------
    sample : list of (str, str)
        In the order of ``pairs``.
    """
    if n is None or n >= len(pairs):
        return list(pairs)
    n = check_int("pairs", n, minimum=1)
    rng = np.random.default_rng(random_state)
    by_class: dict[str, list[int]] = {}
    for index, (source, _) in enumerate(pairs):
        by_class.setdefault(shape_class(source), []).append(index)
    queues = {c: list(rng.permutation(idx)) for c, idx in sorted(by_class.items())}
    chosen: list[int] = []
    while len(chosen) < n:
        for queue in queues.values():
            if queue and len(chosen) < n:
                chosen.append(int(queue.pop(0)))
    return [pairs[i] for i in sorted(chosen)]


def check_methods(methods: Sequence[str]) -> list[str]:
    """Check method names (and that the baselines are importable) before a long run."""
    methods = list(dict.fromkeys(methods))
    if not methods:
        raise ParameterError("The 'methods' parameter must name at least one method.")
    for name in methods:
        if name not in METHODS:
            raise ParameterError(f"Unknown method {name!r}; choose from {', '.join(METHODS)}.")
    if any(name != "spectral" for name in methods):
        try:
            from .. import baselines  # noqa: F401
        except ImportError as exc:
            raise ParameterError("The baselines (meshcorr.baselines) are not available in this "
                                 "installation; run with --methods spectral.") from exc
    return methods


def _cell(value) -> str:
    if value is None:
        return ""
    if isinstance(value, bool):
        return "1" if value else "0"
    if isinstance(value, float):
        return f"{value:.6g}"
    return str(value)


def read_rows(path) -> list[dict]:
    """Rows of a ``results.csv`` (strings), or [] if it does not exist."""
    path = Path(path)
    if not path.is_file():
        return []
    with path.open(newline="") as file:
        return list(csv.DictReader(file))


def _write_rows(path: Path, rows: list[dict]) -> None:
    buffer = io.StringIO()
    writer = csv.DictWriter(buffer, fieldnames=FIELDS, lineterminator="\n")
    writer.writeheader()
    for row in rows:
        writer.writerow({key: _cell(row.get(key)) for key in FIELDS})
    payload = buffer.getvalue().encode()
    atomic_write(path, lambda file: file.write(payload))


def dataset_identity(dataset: Dataset) -> dict:
    """What a benchmark run was made from: the folder, its pair list and its files' content.

    ``path`` is the resolved folder; ``pairs`` a SHA-256 of the pair list (as read, so comments and
    spacing do not count); ``files`` the SHA-256 of each mesh and truth file the pairs name
    (``NAME.off``, ``corres/NAME.vts`` and ``corres/NAME.sym.vts`` where it exists), by path in the
    folder; ``content`` one SHA-256 of them all. Only file bytes are hashed, so this costs a read of
    the dataset.
    """
    pairs = hashlib.sha256("".join(f"{s}\t{t}\n" for s, t in dataset.pairs).encode()).hexdigest()
    files = {}
    for name in sorted({n for pair in dataset.pairs for n in pair}):
        for path in (dataset.mesh_path(name), dataset.vts_path(name), dataset.vts_path(name, sym=True)):
            if path.is_file():
                try:
                    with path.open("rb") as file:
                        digest = hashlib.file_digest(file, "sha256").hexdigest()
                except OSError as exc:
                    raise InputError(f"Cannot read {path}: {exc.strerror}.") from exc
                files[path.relative_to(dataset.root).as_posix()] = digest
    content = hashlib.sha256("".join(f"{k}\t{v}\n" for k, v in sorted(files.items())).encode()).hexdigest()
    return {"path": str(dataset.root.resolve()), "n_pairs": len(dataset.pairs), "pairs": pairs,
            "content": content, "files": files}


def _row_error(exc: BaseException) -> str:
    """The ``error`` cell of a failed row: :func:`~meshcorr.runtime.messages.one_line`, or a pair's own line."""
    return str(exc)[:ONE_LINE_LENGTH] if isinstance(exc, _PairError) else one_line(exc)


def run_benchmark(dataset_dir, methods: Sequence[str], out_dir, *, n_pairs: int | None = None,
                  method_options: dict[str, dict] | None = None, geodesic: str = DEFAULT_GEODESIC,
                  random_state: int = 0, retry_failed: bool = False,
                  progress: BenchProgress | None = None) -> list[dict]:
    """Map and score every selected pair with every method, resumably.

    Parameters
    ----------
    dataset_dir : path
        Dataset folder (see the module docstring).
    methods : sequence of str
        Names from :data:`METHODS`.
    out_dir : path
        Created if missing. Receives ``results.csv`` (one row per pair and
        method, rewritten atomically after each), ``run.json`` (the settings
        and :func:`dataset_identity`; a restart with other settings, or on another dataset or one
        whose meshes or truth files changed, is refused), ``maps/METHOD/S-T.npy``
        and ``errors/METHOD/S-T.npz`` (per-point errors, for the curves).
    n_pairs : int, optional
        Use a class-stratified sample of this many pairs
        (:func:`stratified_sample`); all pairs by default.
    method_options : dict, optional
        ``{method: {option: value}}`` passed to that method; checked before any work
        (:func:`meshcorr.pipeline.methods.check_options`).
    geodesic : str
        Geodesic solver of the evaluation.
    random_state : int
        Seed of the sample and of every method.
    retry_failed : bool
        Run again the (pair, method) rows that failed before.
    progress : callable, optional
        ``progress(done, total, message)``.

    Returns
    -------
    rows : list of dict
        The rows of this run's pairs and methods (strings, as in the CSV).
    """
    dataset = load_dataset(dataset_dir)
    methods = check_methods(methods)
    method_options = {m: dict(o) for m, o in (method_options or {}).items() if m in methods}
    for method, options in method_options.items():  # a value every pair would fail on, refused before any work
        check_options(method, **options)
    out = Path(out_dir)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise ParameterError(f"Cannot create the output folder {out}: {exc.strerror}.") from exc
    check_run_settings(out, {"geodesic": geodesic, "random_state": random_state,
                             "method_options": method_options}, dataset=dataset_identity(dataset))
    pairs = stratified_sample(dataset.pairs, n_pairs, random_state)
    csv_path = out / "results.csv"
    rows = read_rows(csv_path)
    done = {(r["source"], r["target"], r["method"]): r for r in rows
            if r["status"] == "ok" or not retry_failed}
    rows = [r for r in rows if (r["source"], r["target"], r["method"]) in done]
    total = len(pairs) * len(methods)
    count = sum((s, t, m) in done for s, t in pairs for m in methods)
    cache = GeodesicCache(geodesic, max_meshes=2)
    for source_name, target_name in pairs:
        todo = [m for m in methods if (source_name, target_name, m) not in done]
        if not todo:
            continue
        pair = _scored_pair(dataset, source_name, target_name, cache, precompute=len(todo) > 1)
        for method in todo:
            label = f"{source_name}-{target_name} {method}"
            if progress is not None:
                progress(count, total, f"{label}: running")
            row = _run_row(pair, source_name, target_name, method, method_options.get(method, {}),
                           random_state=random_state, geodesic=geodesic, cache=cache, out=out)
            rows.append({key: _cell(row.get(key)) for key in FIELDS})
            _write_rows(csv_path, rows)
            count += 1
            if progress is not None:
                status = (f"error {row['mean_error']:.4f} in {row['seconds']:.1f} s"
                          if row["status"] == "ok" else f"FAILED ({row['error'][:80]})")
                progress(count, total, f"{label}: {status}")
    wanted = {(s, t, m) for s, t in pairs for m in methods}
    return [r for r in rows if (r["source"], r["target"], r["method"]) in wanted]


def _scored_pair(dataset: Dataset, source_name: str, target_name: str, cache: GeodesicCache, *,
                 precompute: bool):
    """``(source, target, truth, sym)`` of a pair (:func:`_load_pair`), or the one-line error that prevents it.

    With ``precompute`` (several methods to score), the geodesics from the true
    target vertices are solved once into ``cache``.
    """
    try:
        source, target, truth, sym = _load_pair(dataset, source_name, target_name)
        if precompute:  # every map scores from the true vertices' rows: solve them once
            cache.precompute(target, np.concatenate([truth.target] + ([sym.target] if sym else [])))
    except MeshcorrError as exc:  # a bad pair is recorded, not fatal
        return one_line(exc)
    return source, target, truth, sym


def _run_row(pair, source_name: str, target_name: str, method: str, options: dict, *, random_state: int,
             geodesic: str, cache: GeodesicCache, out: Path) -> dict:
    """The row of one (pair, method): the map made, scored and saved, or the failure's message.

    ``pair`` is :func:`_scored_pair`'s answer. Values are not yet cells (:func:`_cell`).
    """
    row = {"source": source_name, "target": target_name, "class": shape_class(source_name), "method": method}
    start = time.perf_counter()
    try:
        if isinstance(pair, str):
            raise _PairError(pair)
        source, target, truth, sym = pair
        # fresh Mesh objects: no method may reuse geodesics another one cached on them
        result = run_method(method, _fresh(source), _fresh(target), random_state=random_state, **options)
        row["seconds"] = time.perf_counter() - start
        start = time.perf_counter()
        report = evaluate_map(target, result.map, truth, sym_truth=sym, geodesic=geodesic, cache=cache)
        row["eval_seconds"] = time.perf_counter() - start
    except (KeyboardInterrupt, MemoryError):
        raise
    except Exception as exc:  # noqa: BLE001 - a failing method must not end the run
        row.update(status="failed", error=_row_error(exc), seconds=row.get("seconds", time.perf_counter() - start))
    else:
        row.update(status="ok", **{k: report.get(k) for k in FIELDS if k in report},
                   **{f"under_{t}": f for t, f in report["under"].items()})
        _save_arrays(out, method, source_name, target_name, result.map, report)
    return row


def _fresh(mesh: Mesh) -> Mesh:
    """A copy of ``mesh`` with an empty cache, so that each method's time includes its geodesics."""
    return Mesh(mesh.vertices, mesh.faces, name=mesh.name)


class _PairError(Exception):
    """The pair itself could not be loaded; the message is already one line."""

    def __str__(self) -> str:
        return self.args[0]


def _load_pair(dataset: Dataset, source_name: str, target_name: str):
    """Meshes and ground truth (direct, and mirrored when ``.sym.vts`` exists) of one pair."""
    source = as_mesh(dataset.mesh_path(source_name), name=source_name)
    target = as_mesh(dataset.mesh_path(target_name), name=target_name)
    vts = [dataset.vts_path(source_name), dataset.vts_path(target_name)]
    truth = load_ground_truth(vts, n_source=source.n_vertices, n_target=target.n_vertices)
    sym_path = dataset.vts_path(target_name, sym=True)
    sym = (load_ground_truth([vts[0], sym_path], n_source=source.n_vertices,
                             n_target=target.n_vertices) if sym_path.is_file() else None)
    return source, target, truth, sym


def _save_arrays(out: Path, method: str, source: str, target: str, mapping, report: dict) -> None:
    for kind in ("maps", "errors"):
        (out / kind / method).mkdir(parents=True, exist_ok=True)
    stem = f"{source}-{target}"
    np_map = np.asarray(mapping, dtype=np.int32)
    atomic_write(out / "maps" / method / f"{stem}.npy", lambda f: np.save(f, np_map))
    arrays = {"errors": report["errors"].astype(np.float32)}
    if "sym_errors" in report:
        arrays["sym_errors"] = report["sym_errors"].astype(np.float32)
    atomic_write(out / "errors" / method / f"{stem}.npz", lambda f: np.savez_compressed(f, **arrays))


def _float(row: dict, key: str) -> float:
    value = row.get(key, "")
    return float(value) if value not in ("", None) else float("nan")


def summarize(rows: list[dict], out_dir=None) -> tuple[list[dict], dict]:
    """Per-method summary of benchmark rows, and pooled cumulative curves.

    Parameters
    ----------
    rows : list of dict
        Rows as returned by :func:`run_benchmark` / :func:`read_rows`.
    out_dir : path, optional
        Where ``errors/METHOD/S-T.npz`` live; without it no curves.

    Returns
    -------
    table : list of dict
        One per method, in order of first appearance: ``method``,
        ``pairs`` (scored), ``failed``, ``mean_error`` (mean over pairs of
        the per-pair mean, flips counted as errors), ``best_mean_error``
        (forgiving flips), ``under_T`` (pooled over points), ``flip_rate``
        (fraction of pairs closer to the mirrored truth), ``seconds``
        (mean per pair) and ``per_class`` (class -> mean error).
    curves : dict
        ``{method: (thresholds, fractions)}`` pooled over all points, and
        ``{method + " (flips forgiven)": ...}`` using per pair whichever of
        the direct and mirrored truth is closer.
    """
    table, curves = [], {}
    for method in dict.fromkeys(r["method"] for r in rows):
        mine = [r for r in rows if r["method"] == method]
        ok = [r for r in mine if r["status"] == "ok"]
        weights = np.array([_float(r, "n_points") for r in ok])
        entry = {"method": method, "pairs": len(ok), "failed": len(mine) - len(ok)}
        entry["mean_error"] = float(np.mean([_float(r, "mean_error") for r in ok])) if ok else float("nan")
        best = [_float(r, "best_mean_error") for r in ok]
        entry["best_mean_error"] = float(np.mean(best)) if ok and np.isfinite(best).all() else float("nan")
        for key in _UNDER:
            values = np.array([_float(r, key) for r in ok])
            entry[key] = float(np.sum(values * weights) / weights.sum()) if ok else float("nan")
        flips = [r["flipped"] == "1" for r in ok if r.get("flipped") not in ("", None)]
        entry["flip_rate"] = float(np.mean(flips)) if flips else float("nan")
        entry["seconds"] = float(np.mean([_float(r, "seconds") for r in mine])) if mine else float("nan")
        classes = dict.fromkeys(r["class"] for r in ok)
        entry["per_class"] = {c: float(np.mean([_float(r, "mean_error") for r in ok if r["class"] == c]))
                              for c in classes}
        table.append(entry)
        if out_dir is not None:
            direct, forgiving = [], []
            for r in ok:
                path = Path(out_dir) / "errors" / method / f"{r['source']}-{r['target']}.npz"
                if not path.is_file():
                    continue
                with np.load(path) as data:
                    direct.append(data["errors"])
                    flipped = "sym_errors" in data and r.get("flipped") == "1"
                    forgiving.append(data["sym_errors"] if flipped else data["errors"])
            if direct:
                curves[method] = cumulative_curve(np.concatenate(direct))
                curves[f"{method} (flips forgiven)"] = cumulative_curve(np.concatenate(forgiving))
    return table, curves


def write_summary(table: list[dict], out_dir, *, title: str = "") -> tuple[Path, Path]:
    """Write ``summary.md`` (markdown tables) and ``summary.csv``; return their paths."""
    out = Path(out_dir)
    columns = ["method", "pairs", "failed", "mean_error", "best_mean_error", *_UNDER, "flip_rate",
               "seconds"]
    heads = ["method", "pairs", "failed", "mean error", "mean error, flips forgiven",
             *[f"% under {t:g}" for t in THRESHOLDS], "flip rate", "s / pair"]

    def fmt(key, value):
        if isinstance(value, float):
            if np.isnan(value):
                return "-"
            if key.startswith("under_") or key == "flip_rate":
                return f"{100 * value:.1f}"
            return f"{value:.1f}" if key == "seconds" else f"{value:.4f}"
        return str(value)

    lines = [f"# {title}", ""] if title else []
    lines += ["| " + " | ".join(heads) + " |", "|" + "---|" * len(heads)]
    lines += ["| " + " | ".join(fmt(c, e[c]) for c in columns) + " |" for e in table]
    classes = list(dict.fromkeys(c for e in table for c in e["per_class"]))
    if classes:
        lines += ["", "Mean error per class (flips counted as errors):", "",
                  "| method | " + " | ".join(classes) + " |", "|" + "---|" * (len(classes) + 1)]
        lines += ["| " + e["method"] + " | " + " | ".join(fmt("e", e["per_class"].get(c, float("nan")))
                                                        for c in classes) + " |" for e in table]
    md, csv_path = out / "summary.md", out / "summary.csv"
    text = "\n".join(lines) + "\n"
    atomic_write(md, lambda f: f.write(text.encode()))
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(columns)
    writer.writerows([[_cell(e[c]) for c in columns] for e in table])
    payload = buffer.getvalue().encode()
    atomic_write(csv_path, lambda f: f.write(payload))
    return md, csv_path

