"""Long fuzz run of the mesh, map and ground-truth readers and the command line (issue 16).

The harness and properties are those of tests/fuzzing.py (the suite runs a
bounded, derandomised share of it in tests/test_fuzz.py). This script runs
hypothesis in rounds of random examples until ``--minutes`` have passed,
records every failing input (shrunk by hypothesis) and goes on, and prints
how many inputs each target tried, for how long, and what it found.

Usage::

    nice -n 10 python benchmarks/fuzz.py --minutes 15 [--targets reader,map,transfer,evaluate,show]
"""

from __future__ import annotations

import argparse
import collections
import platform
import re
import sys
import time
from datetime import datetime, timezone
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))

from hypothesis import HealthCheck, given, settings  # noqa: E402

import fuzzing  # noqa: E402

TARGETS = {
    "reader": (fuzzing.MESH_SEEDS, fuzzing.check_mesh_reader),
    "map": (["map.txt", "map.npy"], fuzzing.check_map_reader),
    "transfer": (fuzzing.MESH_SEEDS + ["map.txt", "map.npy"], lambda n, d: fuzzing.check_cli(n, d, "transfer")),
    "evaluate": (["map.txt", "map.npy", "pairs.txt", "a.vts", "mesh.off", "mesh.ply"],
                 lambda n, d: fuzzing.check_cli(n, d, "evaluate")),
    "show": (["map.txt", "map.npy", "mesh.off", "mesh.obj"], lambda n, d: fuzzing.check_cli(n, d, "show")),
}


def fuzz(target: str, seconds: float, deadline_ms: int, counts: collections.Counter, slowest: dict) -> list[str]:
    names, check = TARGETS[target]
    found: list[str] = []

    def timed(case):
        start = time.perf_counter()
        counts[target] += 1
        try:
            check(*case)
        finally:
            slowest[target] = max(slowest.get(target, 0.0), time.perf_counter() - start)

    test = settings(max_examples=200, deadline=deadline_ms, database=None,
                    suppress_health_check=list(HealthCheck))(given(fuzzing.mutated(names))(timed))
    end = time.perf_counter() + seconds
    while time.perf_counter() < end:
        try:
            test()
        except Exception as error:  # noqa: BLE001 - a finding: record it and go on
            for one in getattr(error, "exceptions", [error]):  # hypothesis groups distinct failures
                # One finding per message, whatever temporary folder it named.
                text = re.sub(r"/tmp/tmp\w+/", "", f"{type(one).__name__}: {str(one)[:400]}")
                if text not in found:
                    found.append(text)
                    notes = " / ".join(getattr(one, "__notes__", []))[:600]
                    print(f"[{target}] FOUND {text}\n    input: {notes}", flush=True)
    return found


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--minutes", type=float, default=15.0)
    parser.add_argument("--targets", default="reader,map,transfer,evaluate,show")
    parser.add_argument("--deadline-ms", type=int, default=10_000, help="time bound per input")
    args = parser.parse_args()
    targets = [t for t in args.targets.split(",") if t]
    counts: collections.Counter = collections.Counter()
    slowest: dict = {}
    started = datetime.now(timezone.utc)
    start = time.perf_counter()
    findings = {t: fuzz(t, 60 * args.minutes / len(targets), args.deadline_ms, counts, slowest) for t in targets}
    elapsed = time.perf_counter() - start
    print(f"\n{started:%Y-%m-%d %H:%M} UTC, {elapsed / 60:.1f} min on {platform.node()} "
          f"({platform.processor() or platform.machine()}), python {platform.python_version()}")
    print("| target | inputs | slowest input s | findings |\n|---|---|---|---|")
    for t in targets:
        print(f"| {t} | {counts[t]} | {slowest.get(t, 0):.2f} | {len(findings[t])} |")
    for t in targets:
        for text in findings[t]:
            print(f"- {t}: {text}")
    return 1 if any(findings.values()) else 0


if __name__ == "__main__":
    sys.exit(main())
