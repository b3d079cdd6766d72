"""A million vertices: time, peak memory per stage and error at the markers (issue 33).

One command reproduces the table of ``benchmarks/RESULTS-scale.md`` (section "issue 33")::

    nice -n 10 python benchmarks/million.py [--sizes 80k 320k 1.28M] [--data ../shared/data]

The pairs are Sumner's lion reference -> lion-05 (5000 vertices each, the
same connectivity), each subdivided 2, 3 and 4 times (80k, 320k and 1.28M
vertices) by midpoint subdivision (``trimesh.remesh.subdivide``), written
once as binary PLY into ``benchmarks/cache/million/`` (git-ignored).
Subdivision keeps the original vertices first, so the truth is the identity
on the shared numbering and the 55 lion markers of
``sumner/markers-cat-lion.yml`` stay valid vertex numbers. The original 5k
pair is run too: the targets compare the markers' error with its error.

Every run is a fresh ``meshcorr match ... --json`` process under
``/usr/bin/time`` (wall seconds, peak resident memory) with ``--max-memory``;
the per-stage seconds and peak memory come from the run's JSON report
(``timings``, ``stage_memory``). Errors: the mean Euclidean distance between
each mapped vertex and its truth over sqrt(area of the target), at the 55
markers and at every vertex. Needs ``../shared/data`` (skips with a message
without it).
"""

from __future__ import annotations

import argparse
import json
import re
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
DATA = HERE.parents[0].parent / "shared" / "data"
CACHE = HERE / "cache" / "million"
LEVELS = {"5k": 0, "20k": 1, "80k": 2, "320k": 3, "1.28M": 4}


def lion_markers(data: Path) -> np.ndarray:
    """(55,) int: the lion ends of the cat <-> lion markers (0-based lion vertices)."""
    text = (data / "sumner" / "markers-cat-lion.yml").read_text()
    return np.array([int(b) for _, b in re.findall(r'"(\d+):(\d+)"', text)], dtype=np.int64)


def build_pair(data: Path, level: int) -> tuple[Path, Path]:
    """Lion reference and lion-05 subdivided ``level`` times, written once into ``CACHE`` (binary PLY)."""
    import trimesh

    files = []
    for name in ("lion-reference", "lion-05"):
        source = data / "sumner" / "lion-poses" / f"{name}.obj"
        if level == 0:
            files.append(source)
            continue
        path = CACHE / f"{name}-x{level}.ply"
        if not path.is_file():
            mesh = trimesh.load(source, process=False)
            vertices, faces = mesh.vertices, mesh.faces
            for _ in range(level):
                vertices, faces = trimesh.remesh.subdivide(vertices, faces)
            CACHE.mkdir(parents=True, exist_ok=True)
            trimesh.Trimesh(vertices, faces, process=False).export(path)
        files.append(path)
    return files[0], files[1]


def run_match(a: Path, b: Path, out: Path, max_memory: str, extra: list[str]) -> dict:
    """One fresh ``meshcorr match`` process: its JSON report, wall seconds and peak resident MiB."""
    argv = ["/usr/bin/time", "-f", "TIME %e %M", sys.executable, "-m", "meshcorr", "match", str(a), str(b),
            "-o", str(out), "--json", "-q", "--max-memory", max_memory, *extra]
    done = subprocess.run(argv, capture_output=True, text=True)
    lines = [x for x in done.stderr.splitlines() if x.startswith("TIME ")]
    wall, peak = (float(lines[-1].split()[1]), float(lines[-1].split()[2]) / 1024) if lines else (np.nan, np.nan)
    report = {}
    if done.returncode == 0:
        try:
            report = json.loads(done.stdout)
        except json.JSONDecodeError:
            report = {}
    return dict(rc=done.returncode, wall=wall, peak=peak, report=report, stderr=done.stderr[-1500:])


def errors(target: Path, map_file: Path, markers: np.ndarray) -> tuple[float, float]:
    """Mean Euclidean error / sqrt(area) at the markers and at every vertex (the truth: the identity)."""
    import trimesh

    mesh = trimesh.load(target, process=False)
    mapping = np.loadtxt(map_file, dtype=np.int64)
    vertices = np.asarray(mesh.vertices)
    scale = np.sqrt(mesh.area)
    distance = np.linalg.norm(vertices[mapping] - vertices, axis=1) / scale
    return float(distance[markers].mean()), float(distance.mean())


def interrupt_latency(a: Path, b: Path, delays: list[float], max_memory: str) -> list[tuple[float, float, int]]:
    """Ctrl-C (SIGINT) sent to fresh ``meshcorr match`` runs after each delay: (delay, seconds to exit, exit code)."""
    import signal
    import time

    rows = []
    with tempfile.TemporaryDirectory() as folder:
        for delay in delays:
            argv = [sys.executable, "-m", "meshcorr", "match", str(a), str(b), "-o", str(Path(folder) / "m.txt"),
                    "-q", "--max-memory", max_memory]
            process = subprocess.Popen(argv, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
            time.sleep(delay)
            sent = time.perf_counter()
            process.send_signal(signal.SIGINT)
            code = process.wait()
            rows.append((delay, time.perf_counter() - sent, code))
            print(f"million: Ctrl-C at {delay:.0f} s: exit {code} after {rows[-1][1]:.2f} s", file=sys.stderr,
                  flush=True)
    return rows


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--sizes", nargs="+", default=["5k", "80k", "320k", "1.28M"], choices=list(LEVELS))
    parser.add_argument("--data", type=Path, default=DATA)
    parser.add_argument("--max-memory", default="12G")
    parser.add_argument("--build-only", action="store_true", help="write the subdivided meshes and stop")
    parser.add_argument("--interrupt", nargs="+", type=float, metavar="SECONDS",
                        help="instead of the table: Ctrl-C the largest pair's run after each delay, "
                             "report the seconds to its exit")
    parser.add_argument("extra", nargs="*", help="further options of meshcorr match (after --)")
    args = parser.parse_args(argv)
    if not (args.data / "sumner" / "lion-poses").is_dir():
        print(f"million: {args.data}/sumner is absent; this benchmark needs ../shared/data. Skipping.",
              file=sys.stderr)
        return 0
    markers = lion_markers(args.data)
    pairs = {size: build_pair(args.data, LEVELS[size]) for size in args.sizes}
    if args.build_only:
        return 0
    if args.interrupt:
        size = args.sizes[-1]
        print(f"| pair | Ctrl-C after s | exit code | seconds to exit |\n|---|---|---|---|")
        for delay, seconds, code in interrupt_latency(*pairs[size], args.interrupt, args.max_memory):
            print(f"| {size} | {delay:.0f} | {code} | {seconds:.2f} |")
        return 0
    rows = []
    with tempfile.TemporaryDirectory() as folder:
        out = Path(folder) / "map.txt"
        for size, (a, b) in pairs.items():
            run = run_match(a, b, out, args.max_memory, args.extra)
            if run["rc"] != 0:
                print(f"million {size}: failed (rc {run['rc']}):\n{run['stderr']}", file=sys.stderr)
                rows.append((size, run, None))
                continue
            rows.append((size, run, errors(b, out, markers)))
            print(f"million {size}: {run['wall']:.1f} s, {run['peak']:.0f} MiB", file=sys.stderr, flush=True)
    print("| pair | vertices | wall s | peak MiB | stages: s / peak MiB | marker error | all-vertex error |")
    print("|---|---|---|---|---|---|---|")
    for size, run, error in rows:
        report = run["report"]
        timings, memory = report.get("timings", {}), report.get("stage_memory", {})
        stages = ", ".join(f"{name} {seconds:.1f}" + (f" / {memory[name]:.0f}" if name in memory else "")
                           for name, seconds in timings.items())
        n = report.get("n_source", "-")
        marker, whole = ("-", "-") if error is None else (f"{error[0]:.4f}", f"{error[1]:.4f}")
        print(f"| {size} | {n} | {run['wall']:.1f} | {run['peak']:.0f} | {stages or 'failed'} | {marker} | {whole} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
