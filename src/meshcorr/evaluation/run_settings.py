"""``run.json`` of an output folder: results made with other settings, or of another dataset, are not mixed.

``meshcorr bench`` (:func:`meshcorr.evaluation.benchmark.run_benchmark`) and
``meshcorr batch`` (:func:`meshcorr.collection.batch.batch`) resume in the
folder of an earlier run; :func:`check_run_settings` keeps that run's
settings (and the benchmark's dataset identity) in ``run.json`` and refuses a
run with others before any work.
"""

from __future__ import annotations

import json
from pathlib import Path

from ..errors import InputError, ParameterError
from ..io import atomic_write

__all__ = ["check_run_settings"]


def _same_dataset(previous, current: dict) -> bool:
    return previous["pairs"] == current["pairs"] and previous["content"] == current["content"]


def _n_pairs(n) -> str:
    return f"{n} pair{'' if n == 1 else 's'}" if isinstance(n, int) else "? pairs"


def _dataset_mismatch(out: Path, previous: dict, current: dict) -> str:
    """One paragraph: which dataset ``out`` holds results of, which one this run is of, what to do."""
    old_files, new_files = previous.get("files"), current["files"]
    changes = []
    if previous["pairs"] != current["pairs"]:
        changes.append(f"pair list ({_n_pairs(previous.get('n_pairs'))} recorded, {_n_pairs(current['n_pairs'])} now)")
    if previous["content"] != current["content"]:
        if isinstance(old_files, dict):
            changed = sorted(k for k in old_files.keys() | new_files.keys() if old_files.get(k) != new_files.get(k))
            changes.append("mesh / truth files (" + ", ".join(changed[:3])
                           + (f" and {len(changed) - 3} more" if len(changed) > 3 else "") + ")")
        else:
            changes.append("mesh / truth files")
    if previous["path"] == current["path"]:
        what = (f"{out} holds results of the dataset {previous['path']}, but that folder's "
                f"{' and '.join(changes)} changed since")
    else:
        what = (f"{out} holds results of the dataset {previous['path']}, and this run is of another "
                f"dataset, {current['path']}, whose {' and '.join(changes)} differ")
    return (f"{what}: resuming would report those records as this dataset's results. Use another --out "
            f"folder, or delete {out} (its results.csv, run.json, maps/ and errors/) to start over; delete "
            f"only {out / 'run.json'} if you know the records there still hold for this dataset.")


def check_run_settings(out: Path, settings: dict, *, dataset: dict | None = None) -> None:
    """Refuse to mix results made with different settings (or, given ``dataset``, data) in one folder.

    ``dataset`` is :func:`dataset_identity` of this run's data, kept in ``run.json`` under
    ``"dataset"``; a ``run.json`` written before it was kept (no such key) is taken as of this
    dataset, which is then recorded.
    """
    path = out / "run.json"
    current = dict(settings) if dataset is None else dict(settings, dataset=dataset)
    if path.is_file():
        try:
            previous = json.loads(path.read_text())
        except (ValueError, UnicodeDecodeError):
            raise InputError(f"{path} is damaged (not JSON): delete it to run again with the current "
                             "settings, or use another --out folder.") from None
        if not isinstance(previous, dict):
            raise InputError(f"{path} is damaged (not a JSON object): delete it to run again with the "
                             "current settings, or use another --out folder.")
        if dataset is not None:
            recorded = previous.pop("dataset", None)
            if recorded is not None:
                if not (isinstance(recorded, dict) and all(isinstance(recorded.get(k), str)
                                                           for k in ("path", "pairs", "content"))):
                    raise InputError(f"{path} is damaged (its 'dataset' entry is not one this version "
                                     "writes): delete it to run again, or use another --out folder.")
                if not _same_dataset(recorded, dataset):
                    raise ParameterError(_dataset_mismatch(out, recorded, dataset))
        if previous != settings:
            raise ParameterError(
                f"{out} holds results made with other settings ({previous}); this run uses "
                f"{settings}. Use another --out folder or delete the old results."
            )
        if dataset is None or recorded is not None:
            return
    payload = json.dumps(current, indent=2, sort_keys=True).encode()
    atomic_write(path, lambda file: file.write(payload))
