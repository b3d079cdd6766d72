"""The records of a batch (one per pair) and the summary files they are kept in.

A record is a dict: ``source``, ``target``, ``map`` (paths), ``status``
(:data:`DONE` or :data:`FAILED`), ``seconds``, ``cpu_seconds``,
``mean_error``, ``error``, ``made`` (:func:`made_how`) and, for a map made
through a hub, ``via``. ``summary.json`` keeps them all (and ``inputs``, the
key of what each map was made from, and ``map_length`` and ``map_bytes``, what
:func:`map_complete` checks of a map file before a rerun skips its pair);
``summary.csv`` the columns :data:`FIELDS`. Both are rewritten atomically.
"""

from __future__ import annotations

import csv
import io
import json
from pathlib import Path

import numpy as np

from ..errors import MeshcorrError, ParameterError
from ..io import atomic_write, read_map, write_map
from ..runtime.messages import one_line

__all__ = ["DONE", "FAILED", "FIELDS", "in_order", "made_how", "map_complete", "new_record", "read_summary",
           "write_record_map", "write_summary"]

#: Columns of ``summary.csv``.
FIELDS = ["source", "target", "map", "status", "seconds", "cpu_seconds", "mean_error", "error", "via", "made"]
#: ``status`` of a pair whose map was written.
DONE = "ok"
FAILED = "failed"


def new_record(source_path: str, target_path: str, map_path: str, hub: str | None = None) -> dict:
    """The record of a pair not (yet) mapped: status "failed", no times, no error message."""
    record = {"source": source_path, "target": target_path, "map": map_path, "status": FAILED, "seconds": None,
              "cpu_seconds": None, "mean_error": None, "error": "",
              "made": made_how(source_path, target_path, hub)}
    if record["made"] != "match":
        record["via"] = hub
    return record


def made_how(source: str, target: str, hub: str | None) -> str:
    """How a batch makes the map of a pair: "match", or with a hub "inverse" (from the hub) or "composition"."""
    if hub is None or target == hub:
        return "match"
    return "inverse" if source == hub else "composition"


def read_summary(out: Path) -> list[dict]:
    """The records of ``out/summary.json`` ([] without one).

    Raises
    ------
    ParameterError
        The file is not a batch summary.
    """
    path = out / "summary.json"
    if not path.is_file():
        return []
    try:
        return list(json.loads(path.read_text())["pairs"])
    except (ValueError, KeyError, TypeError):
        raise ParameterError(f"{path} is not a batch summary (damaged?): delete it to run every pair again, "
                             "or use another --out folder.") from None


def write_summary(out: Path, records: list[dict]) -> None:
    """``out/summary.json`` (counts, mean seconds, the records) and ``out/summary.csv`` (:data:`FIELDS`), atomically."""
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


def in_order(records: dict, pairs: list[tuple[str, str]]) -> list[dict]:
    """This run's records in its order, then those of earlier runs into the folder for other pairs (kept)."""
    wanted = set(pairs)
    return [records[p] for p in pairs if p in records] + [r for p, r in records.items() if p not in wanted]


def write_record_map(record: dict, mapping) -> dict:
    """Write the map of a done pair's record to ``record["map"]`` (atomically); the record, with its length.

    A map that cannot be written (a full disk) fails the pair: its record says why.
    """
    if record["status"] != DONE:
        return record
    try:
        write_map(record["map"], mapping)
        record["map_length"], record["map_bytes"] = len(mapping), Path(record["map"]).stat().st_size
    except (MeshcorrError, OSError) as exc:
        record.update(status=FAILED, error=one_line(exc))
    return record


def map_complete(record: dict) -> bool:
    """Whether the map file of a done pair's record is whole: there, readable, of the recorded length.

    Records of older runs, without ``map_length`` and ``map_bytes``, need a readable, non-empty map.
    """
    path = Path(record["map"])
    try:
        if not path.is_file() or path.stat().st_size != record.get("map_bytes", path.stat().st_size):
            return False
        mapping = read_map(path)
    except (MeshcorrError, OSError, ValueError):
        return False
    return len(mapping) == record.get("map_length", len(mapping)) and len(mapping) > 0
