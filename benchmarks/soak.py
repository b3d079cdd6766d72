"""Soak: many consecutive ``meshcorr match`` runs in one process keep memory flat and leave nothing behind.

Runs ``meshcorr.cli.main(["match", ...])`` ``--runs`` times in one process,
cycling through generated pairs of several shapes and sizes and through
failing inputs (a missing file, a truncated OFF, ``--bijective`` on unequal
counts, a bad ``-k``). After every run it
checks that no thread started during the runs is left and that no temporary file
is left in the output folder or the system temp folder; it reports the
resident memory (VmRSS) after the warm-up runs and at the end.

Usage::

    nice -n 10 python benchmarks/soak.py [--runs 200]
"""

from __future__ import annotations

import argparse
import contextlib
import gc
import io
import os
import platform
import sys
import tempfile
import threading
import time
from datetime import datetime, timezone
from pathlib import Path

from meshcorr import datasets as ds
from meshcorr.cli import main
from meshcorr.io import write_mesh


def rss_mib() -> float:
    """Resident memory of this process now (VmRSS), in MiB."""
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1]) / 1024
    return float("nan")


def make_inputs(folder: Path) -> list[tuple[str, list[str], bool]]:
    """(name, match arguments, whether it should succeed) for the runs to cycle through."""
    cases = []
    shapes = {"tube": lambda pose: ds.tube(n_along=20 + int(10 * pose), n_around=10),
              "figure": lambda pose: ds.figure(pose=pose), "creature": lambda pose: ds.creature(pose=pose)}
    for name, make in shapes.items():
        a, b = make(0.0), make(0.3)
        pa, pb = folder / f"{name}-a.off", folder / f"{name}-b.off"
        write_mesh(pa, a.vertices, a.faces)
        write_mesh(pb, b.vertices, b.faces)
        cases.append((name, [str(pa), str(pb)], True))
        cases.append((f"{name} no-refine", [str(pa), str(pb), "--no-refine"], True))
    tube = folder / "tube-a.off"
    cut = folder / "cut.off"
    cut.write_bytes(tube.read_bytes()[:-30])
    cases += [
        ("missing file", [str(folder / "none.off"), str(tube)], False),
        ("truncated OFF", [str(cut), str(tube)], False),
        ("bijective, unequal counts", [str(tube), str(folder / "tube-b.off"), "--bijective"], False),
        ("bad -k", [str(tube), str(tube), "-k", "1"], False),
    ]
    return cases


def main_loop(runs: int, warmup: int) -> dict:
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        cases = make_inputs(folder)
        out_dir, private_tmp = folder / "out", folder / "tmp"
        out_dir.mkdir()
        private_tmp.mkdir()
        # Everything that uses tempfile in this process writes here (other processes share /tmp).
        saved_tempdir, tempfile.tempdir = tempfile.tempdir, str(private_tmp)
        try:
            return _runs(runs, warmup, cases, out_dir, private_tmp)
        finally:
            tempfile.tempdir = saved_tempdir


def _runs(runs: int, warmup: int, cases: list, out_dir: Path, private_tmp: Path) -> dict:
    """The runs of :func:`main_loop`: exit codes, problems found after each run, RSS."""
    rss: dict[str, float] = {"start": rss_mib()}
    # Threads alive before the runs (e.g. a Dask cluster of an earlier test) are not theirs.
    before = set(threading.enumerate())
    failures, codes = [], {"ok": 0, "failed as expected": 0}
    start = time.perf_counter()
    for run in range(runs):
        name, args, should_work = cases[run % len(cases)]
        out = out_dir / f"map{run % 7}.txt"
        with contextlib.redirect_stderr(io.StringIO()) as err:
            code = main(["match", *args, "-o", str(out), "-q"])
        if (code == 0) != should_work or code not in (0, 2, 3):
            failures.append(f"run {run} ({name}): exit {code}: {err.getvalue()[-300:]}")
        codes["ok" if code == 0 else "failed as expected"] += 1
        threads = [t.name for t in threading.enumerate() if t not in before]
        temps = [f for f in os.listdir(out_dir) if f.startswith(".")]
        new_tmp = os.listdir(private_tmp)
        if threads or temps or new_tmp:
            failures.append(f"run {run} ({name}): threads {threads}, temporary files {temps}, "
                            f"left in the temp folder: {sorted(new_tmp)}")
        if run + 1 == warmup:
            gc.collect()
            rss["after warm-up"] = rss_mib()
    gc.collect()
    rss["end"] = rss_mib()
    return dict(runs=runs, warmup=warmup, seconds=time.perf_counter() - start, rss=rss, codes=codes,
                failures=failures, cases=len(cases))


def main_cli() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=200)
    parser.add_argument("--warmup", type=int, default=20)
    args = parser.parse_args()
    when = datetime.now(timezone.utc)
    result = main_loop(args.runs, args.warmup)
    rss = result["rss"]
    print(f"{when:%Y-%m-%d %H:%M} UTC on {platform.node()}, python {platform.python_version()}: "
          f"{result['runs']} match runs over {result['cases']} cases in {result['seconds']:.0f} s "
          f"({result['codes']['ok']} ok, {result['codes']['failed as expected']} failed as expected)")
    print(f"RSS: start {rss['start']:.0f} MiB, after {result['warmup']} warm-up runs "
          f"{rss['after warm-up']:.0f} MiB, end {rss['end']:.0f} MiB: growth after warm-up "
          f"{rss['end'] - rss['after warm-up']:+.1f} MiB")
    print(f"problems: {len(result['failures'])}")
    for line in result["failures"][:20]:
        print("  " + line)
    return 1 if result["failures"] else 0


if __name__ == "__main__":
    sys.exit(main_cli())
