"""Ctrl-C at random moments of ``meshcorr match``: every run must exit 130 with no output file.

Runs ``meshcorr match`` on one pair many times, sends SIGINT after a random
delay spread over the whole run, and counts the exit codes by the stage the
signal reached (read from ``--json`` stage timings of one uninterrupted run).
A crash (exit 139, "Fatal Python error") is printed with its faulthandler
dump. Exit 130 with no output is right; so is exit 0 when the map was
written before the signal was sent, and -2 (killed by the signal, Python's
KeyboardInterrupt traceback) when the signal came while the child imported
``meshcorr.runtime.threads`` for ``--threads``, before the command line runs (the
``meshcorr`` console script itself catches that moment: ``meshcorr._console``,
``tests/test_console.py``). ``--threads N`` pretends the machine has N cores, so that the
TPS-ICP candidates run in N worker threads.

Usage::

    nice -n 10 python benchmarks/interrupt.py SOURCE TARGET [--tries 50] [--no-refine] [--threads 8]

Without SOURCE and TARGET it uses a generated pair (meshcorr.datasets).
"""

from __future__ import annotations

import argparse
import collections
import json
import os
import random
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

# Run as a child: pretend to have N cores, then the CLI.
CHILD = """
import sys, meshcorr.runtime.threads as t
n = int(sys.argv[1])
if n > 0:
    t._cores = lambda: n
from meshcorr.cli import main
sys.argv = ["meshcorr"] + sys.argv[2:]
sys.exit(main())  # as the console script runs it
"""


def _generated_pair(folder: Path) -> tuple[str, str]:
    from meshcorr import datasets
    from meshcorr.io import write_mesh

    a, b = datasets.creature(resolution=4), datasets.creature(resolution=4, pose=0.3)
    write_mesh(folder / "a.off", a.vertices, a.faces)
    write_mesh(folder / "b.off", b.vertices, b.faces)
    return str(folder / "a.off"), str(folder / "b.off")


def _command(args, source, target, output, extra=()) -> list[str]:
    cmd = [sys.executable, "-c", CHILD, str(args.threads), "match", source, target, "-o", output, "-q"]
    if not args.refine:
        cmd.append("--no-refine")
    return cmd + list(extra)


def _stage_at(timings: list[tuple[str, float]], t: float) -> str:
    elapsed = 0.0
    for stage, seconds in timings:
        elapsed += seconds
        if t < elapsed:
            return stage
    return "after"


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("source", nargs="?")
    parser.add_argument("target", nargs="?")
    parser.add_argument("--tries", type=int, default=50)
    parser.add_argument("--threads", type=int, default=0, help="pretend to have this many cores")
    parser.add_argument("--no-refine", dest="refine", action="store_false")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    rng = random.Random(args.seed)
    # A child inherits an ignored SIGINT (this script run with '&' or nohup) and Python then keeps
    # ignoring it: handle it here, so that the children start with the default disposition.
    signal.signal(signal.SIGINT, signal.default_int_handler)
    env = dict(os.environ, PYTHONFAULTHANDLER="1")
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        source, target = (args.source, args.target) if args.source else _generated_pair(folder)
        output = str(folder / "map.txt")
        start = time.perf_counter()
        first = subprocess.run(_command(args, source, target, output, ["--json"]), capture_output=True,
                               text=True, env=env)
        total = time.perf_counter() - start
        if first.returncode != 0:
            print(first.stderr)
            return 1
        summary = json.loads(first.stdout)
        os.unlink(output)
        # Process start and imports come before the first stage.
        setup = max(total - sum(summary["timings"].values()), 0.0)
        timings = [("startup", setup)] + list(summary["timings"].items())
        print(f"{source} -> {target}: {total:.1f} s uninterrupted; stages "
              + ", ".join(f"{s} {t:.2f}" for s, t in timings), flush=True)
        counts: dict = collections.defaultdict(collections.Counter)
        bad = 0
        for attempt in range(args.tries):
            delay = rng.uniform(0.3 * setup, total)
            proc = subprocess.Popen(_command(args, source, target, output), stdout=subprocess.PIPE,
                                    stderr=subprocess.PIPE, text=True, env=env)
            time.sleep(delay)
            sent = time.time()
            proc.send_signal(signal.SIGINT)
            out, err = proc.communicate(timeout=600)
            stage = _stage_at(timings, delay)
            written = os.path.exists(output)
            # Exit 0 is right only for a run that had written its map before the signal came
            # (the stage estimate is rough on a loaded machine); -2 is the signal's own exit
            # while the child imports meshcorr.runtime.threads, before the CLI runs.
            finished_first = written and os.path.getmtime(output) <= sent
            ok = (proc.returncode in (130, -2) and not written) or (proc.returncode == 0 and finished_first)
            if proc.returncode == 0 and finished_first:
                stage = "after"
            counts[stage][proc.returncode] += 1
            if os.path.exists(output):
                os.unlink(output)
            leftovers = [p.name for p in folder.iterdir() if p.name.startswith(".")]
            if not ok or leftovers:
                bad += 1
                print(f"try {attempt}: SIGINT at {delay:.2f} s ({stage}): exit {proc.returncode}, "
                      f"output written: {written}, temporary files: {leftovers}\n{err[-3000:]}", flush=True)
        print(f"{args.tries} tries, {bad} bad. Exit codes by stage:")
        for stage, _ in timings + [("after", 0)]:
            if stage in counts:
                print(f"  {stage}: " + ", ".join(f"exit {c}: {n}" for c, n in sorted(counts[stage].items())))
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
