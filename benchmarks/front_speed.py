"""Old vs new: the stages before the refinement, side by side in one run (issue 5).

One command reproduces ``benchmarks/RESULTS-front.md``::

    nice -n 10 python benchmarks/front_speed.py [--base-commit d691c85] [--rounds 5] [--refine] \
        [--data ../shared/data] [--out benchmarks/RESULTS-front.md]

The "old" code is ``git archive <base-commit> src`` unpacked into
``benchmarks/cache/front-base`` and put first on ``PYTHONPATH`` of its runs;
"new" is this checkout. Every run is a fresh process of
``benchmarks/scale.py --worker`` (the same worker, timings and error as the
scaling report), running ``meshcorr.match(..., refine=False)`` (with
``--refine``: the default settings, refinement included) in the default
(auto, hence scalable) mode; old and new runs alternate, so both see
the same machine load, and the report gives their ratios.

Sections:

1. **Speed, 5k**: TOSCA cat0 -> cat1, ``--rounds`` rounds.
2. **Speed, 115k**: the Sumner cat-reference -> cat-01 pair subdivided twice
   (115 282 vertices; built by ``scale.prepare_pairs``), ``--rounds-large`` rounds.
3. **Accuracy**: mean geodesic error (/ sqrt(area)) on 8 TOSCA pairs, one
   per class (``meshcorr.evaluation.benchmark.stratified_sample``), old vs new.

Data: ``../shared/data`` beside the repository; the script exits with a
message when it is absent.
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

import scale  # noqa: E402  (the worker and the pair builder of the scaling report)

BASE_DIR = HERE / "cache" / "front-base"
STAGES = ("load", "geodesics", "embedding", "reorder", "symmetry", "icp", "matching")


def base_tree(commit: str) -> Path:
    """The ``src`` folder of ``commit``, unpacked once into ``BASE_DIR / commit``."""
    target = BASE_DIR / commit
    if not (target / "src" / "meshcorr").is_dir():
        target.mkdir(parents=True, exist_ok=True)
        archive = subprocess.run(["git", "-C", str(HERE.parent), "archive", commit, "src"],
                                 capture_output=True, check=True).stdout
        subprocess.run(["tar", "-x", "-C", str(target)], input=archive, check=True)
    return target / "src"


def run_both(job: dict, rounds: int, old_src: Path) -> dict[str, list[dict]]:
    """``rounds`` alternating runs of the old and the new code on one job."""
    runs: dict[str, list[dict]] = {"old": [], "new": []}
    for r in range(rounds):
        for version in (("old", "new") if r % 2 == 0 else ("new", "old")):
            env = {"PYTHONPATH": str(old_src)} if version == "old" else {}
            out = scale.run_job(job, env=env)
            if "failed" in out:
                raise RuntimeError(f"{job['name']} ({version}): {out['failed']}")
            runs[version].append(out)
            scale._log(f"{job['name']} {version} round {r + 1}: {out['wall']:.2f} s, error {out['error']:.4f}")
    return runs


def _median(values) -> float:
    return float(statistics.median(values))


def speed_section(title: str, runs: dict[str, list[dict]], stages: tuple = STAGES) -> list[str]:
    med = {v: _median(r["wall"] for r in runs[v]) for v in runs}
    ratios = [o["wall"] / n["wall"] for o, n in zip(runs["old"], runs["new"])]
    lines = [f"### {title}", "",
             "| version | wall s, each run | median wall s | " + " | ".join(f"{s} s" for s in stages)
             + " | mean error | load avg |", "|---" * (len(stages) + 5) + "|"]
    for version in ("old", "new"):
        stage = [_median(r["timings"].get(s, 0.0) for r in runs[version]) for s in stages]
        walls = ", ".join(f"{r['wall']:.2f}" for r in runs[version])
        lines.append(f"| {version} | {walls} | "
                     f"{med[version]:.2f} | " + " | ".join(f"{t:.2f}" for t in stage)
                     + f" | {runs[version][0]['error']:.4f} | {_median(r['load'] for r in runs[version]):.1f} |")
    lines += ["", f"**old / new: {med['old'] / med['new']:.2f}x** (medians; per-round ratios "
              f"{', '.join(f'{x:.2f}' for x in ratios)}).", ""]
    return lines


def accuracy_section(data: Path, old_src: Path) -> list[str]:
    from meshcorr.evaluation.benchmark import load_dataset, stratified_sample

    dataset = load_dataset(data / "tosca5k")
    lines = ["| pair | old error | new error | old s | new s |", "|---|---|---|---|---|"]
    totals = {"old": [], "new": []}
    for a, b in stratified_sample(dataset.pairs, 8, random_state=0):
        job = dict(name=f"{a}-{b}", source=str(dataset.mesh_path(a)), target=str(dataset.mesh_path(b)),
                   truth=("vts", [str(dataset.vts_path(a)), str(dataset.vts_path(b))]),
                   options={"refine": False}, sample=False)
        runs = run_both(job, 1, old_src)
        for v in totals:
            totals[v].append(runs[v][0]["error"])
        lines.append(f"| {a} -> {b} | {runs['old'][0]['error']:.4f} | {runs['new'][0]['error']:.4f} | "
                     f"{runs['old'][0]['wall']:.2f} | {runs['new'][0]['wall']:.2f} |")
    mean = {v: sum(t) / len(t) for v, t in totals.items()}
    lines += ["", f"Mean over the 8 pairs: old {mean['old']:.4f}, new {mean['new']:.4f} "
              f"(new / old {mean['new'] / mean['old']:.3f}).", ""]
    return lines


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--data", type=Path, default=scale.DEFAULT_DATA)
    parser.add_argument("--base-commit", default="d691c85", help="the old code (default: before issue 5's front work)")
    parser.add_argument("--old-src", type=Path, default=None,
                        help="a src folder to run as 'old' instead of --base-commit's (e.g. a patched copy)")
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--rounds-large", type=int, default=2)
    parser.add_argument("--sections", default="5k,115k,accuracy")
    parser.add_argument("--refine", action="store_true",
                        help="time the default settings, ZoomOut refinement included (5k and 115k sections)")
    parser.add_argument("--out", type=Path, default=None, help="write the Markdown report here (default: stdout)")
    args = parser.parse_args()
    if not (args.data / "tosca5k").is_dir():
        print(f"Data not found at {args.data}; nothing to do.", file=sys.stderr)
        return 0
    old_src = args.old_src.resolve() if args.old_src else base_tree(args.base_commit)
    sections = set(args.sections.split(","))
    tosca = args.data / "tosca5k"
    old = f"--old-src {args.old_src}" if args.old_src else f"--base-commit {args.base_commit}"
    lines = [f"Command: `nice -n 10 python benchmarks/front_speed.py {old} "
             f"--rounds {args.rounds} --rounds-large {args.rounds_large} --sections {args.sections}"
             f"{' --refine' if args.refine else ''}`", "",
             f"Machine: {scale.machine()}", ""]
    # Default settings time the refinement too; refine=False the stages before it only.
    options, setting, stages = ({}, "default settings", STAGES + ("refine",)) if args.refine else (
        {"refine": False}, "refine=False", STAGES)
    if "5k" in sections:
        job = dict(name="tosca-cat", source=str(tosca / "cat0.off"), target=str(tosca / "cat1.off"),
                   truth=("vts", [str(tosca / "corres" / f"{s}.vts") for s in ("cat0", "cat1")]),
                   options=options)
        lines += speed_section(f"TOSCA cat0 -> cat1, 5000 vertices, {setting}", run_both(job, args.rounds, old_src),
                               stages)
    if "115k" in sections:
        pair = next(p for p in scale.prepare_pairs(args.data) if p["name"] == "sumner-cat-x2")
        job = dict(pair, options=options)
        lines += speed_section(f"Sumner cat pair subdivided twice, 115 282 vertices, {setting}",
                               run_both(job, args.rounds_large, old_src), stages)
    if "accuracy" in sections:
        lines += ["### Accuracy on 8 TOSCA pairs (one per class), refine=False", ""]
        lines += accuracy_section(args.data, old_src)
    text = "\n".join(lines) + "\n"
    if args.out is None:
        print(text)
    else:
        args.out.write_text(text)
    return 0


if __name__ == "__main__":
    if len(sys.argv) > 2 and sys.argv[1] == "--worker":
        scale.worker(sys.argv[2])
    else:
        sys.exit(main())
