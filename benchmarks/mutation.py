"""Mutation checks of the test suite: break the code on purpose and see whether its tests notice.

Two runs, each in a temporary copy of ``src/``, ``tests/`` and ``pyproject.toml`` (the
working tree is never mutated; the copy is imported through ``PYTHONPATH``):

``hand``
    The mutants of issue #17, applied by text replacement. Each runs against the tests
    as they were before the issue (``git show BASE:tests/...``) and as they are now:
    "survived" before and "killed" after is the fix.
``cosmic``
    cosmic-ray's mutants of the core modules, each module against its own test files
    only (``MODULES``), sampled with a seed when there are more than ``--sample``.

Not part of the test command: it takes minutes to an hour. Usage::

    pip install -r benchmarks/requirements.txt
    nice -n 10 python benchmarks/mutation.py hand
    nice -n 10 python benchmarks/mutation.py cosmic --sample 40 --seed 0
    nice -n 10 python benchmarks/mutation.py cosmic --module validate --sample 0  # all
    python benchmarks/mutation.py report KEEP_FOLDER --diffs  # survivors of a --keep run
    nice -n 10 python benchmarks/mutation.py recheck KEEP_FOLDER  # those survivors, tests of today

Both print a Markdown table (``benchmarks/RESULTS-tests.md`` holds the last ones).
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import random
import shutil
import sqlite3
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
BASE = "c95391a"  # the tests as issue #17 found them
PYTEST = [sys.executable, "-m", "pytest", "-x", "-q", "-p", "no:cacheprovider", "-o", "addopts="]


@dataclasses.dataclass(frozen=True)
class Mutant:
    """A hand-made break: ``old`` replaced by ``new`` (exactly once) in ``path``."""

    name: str
    path: str
    old: str
    new: str
    before: tuple[str, ...]  # pytest arguments: the tests at BASE that should have noticed
    after: tuple[str, ...]  # the tests now


GREEDY = """        rows, cols = np.arange(n1), np.empty(n1, dtype=np.int64)
        free = np.ones(n2, dtype=bool)
        for r in range(n1):  # mutant: each row takes its cheapest free column in turn
            cols[r] = int(np.argmin(np.where(free, C[r], np.inf)))
            free[cols[r]] = False
"""

VIZ = ("tests/test_viz.py", "tests/test_report.py")
SHOW = ("tests/test_viz.py::test_show_draws_both_meshes",
        "tests/test_viz.py::test_show_with_truth_adds_a_row_and_error_mode")

HAND = [
    Mutant("transfer: scalar field pulled back ignoring the map", "src/meshcorr/transfer.py",
           "    pulled = pull_back(values.astype(np.float64), mapping, fill=np.nan)\n",
           "    pulled = values.astype(np.float64)[: len(mapping)]\n", VIZ, VIZ),
    Mutant("show: source coloured by arange instead of the map", "src/meshcorr/viz/figures.py",
           "mapped_colors = pull_back(target_colors, mapping, fill=UNMAPPED_COLOR)",
           "mapped_colors = pull_back(target_colors, np.arange(len(mapping)), fill=UNMAPPED_COLOR)",
           SHOW, SHOW),
    Mutant("show: ground-truth row coloured by arange", "src/meshcorr/viz/figures.py",
           "true_colors = pull_back(target_colors, truth, fill=UNMAPPED_COLOR)",
           "true_colors = pull_back(target_colors, np.arange(len(truth)), fill=UNMAPPED_COLOR)",
           SHOW, SHOW),
    Mutant("anchors: greedy assignment instead of the optimal one", "src/meshcorr/anchors.py",
           "        rows, cols = linear_sum_assignment(C)\n", GREEDY,
           ("tests/test_anchors.py", "tests/test_pipeline.py", "tests/test_cli.py", "-k", "bijective"),
           ("tests/test_anchors.py", "tests/test_pipeline.py", "tests/test_cli.py", "-k", "bijective")),
    Mutant("validate: int64 row keys at every size (they overflow above ~1.6M vertices)",
           "src/meshcorr/validate.py", "    if n_values ** 3 < 2 ** 62:\n", "    if True:\n",
           ("tests/test_validate.py", "-k", "repeated_rows"),
           ("tests/test_validate.py", "-k", "repeated_rows")),
    Mutant("validate: ragged lists reach numpy's ValueError", "src/meshcorr/validate.py",
           "    except ValueError as error:  # numpy >= 1.24", "    except TypeError as error:  # numpy >= 1.24",
           ("tests/test_validate.py",), ("tests/test_validate.py",)),
    Mutant("validate: no check that coordinates are real numbers", "src/meshcorr/validate.py",
           "    if not np.issubdtype(vertices.dtype, np.number) or np.iscomplexobj(vertices):\n",
           "    if False:\n", ("tests/test_validate.py",), ("tests/test_validate.py",)),
    Mutant("threads: a plain sequential loop", "src/meshcorr/_threads.py",
           "    if workers < 2:\n", "    if True:\n", ("tests/test_threads.py",), ("tests/test_threads.py",)),
    Mutant("threads: results (and the error) in completion order", "src/meshcorr/_threads.py",
           "        return list(pool.map(function, items))\n",
           "        from concurrent.futures import as_completed\n"
           "        return [f.result() for f in as_completed([pool.submit(function, i) for i in items])]\n",
           ("tests/test_threads.py",), ("tests/test_threads.py",)),
    Mutant("refine: a cancelled basis worker runs its eigensolve to the end", "src/meshcorr/refine.py",
           "            if cancel is not None and cancel.is_set():\n", "            if False:\n",
           ("tests/test_refine.py", "-k", "prefetch_reraises"), ("tests/test_refine.py", "-k", "prefetch_reraises")),
    Mutant("timing: stage times in milliseconds", "src/meshcorr/timing.py",
           "self.timings.get(name, 0.0) + time.perf_counter() - start",
           "self.timings.get(name, 0.0) + 1000 * (time.perf_counter() - start)",
           ("tests/test_pipeline.py::test_result_holds_every_stage",),
           ("tests/test_pipeline.py::test_result_holds_every_stage",)),
    Mutant("icp: 'changed' counts the unchanged matches", "src/meshcorr/icp.py",
           "changed = float(np.mean(new_matches != matches))", "changed = float(np.mean(new_matches == matches))",
           ("tests/test_icp.py::test_icp_undoes_a_smooth_warp",), ("tests/test_icp.py::test_icp_undoes_a_smooth_warp",)),
    Mutant("symmetry: the summary's curvature is the orientation score", "src/meshcorr/symmetry.py",
           '"curvature": _rounded(self.curvature, 4)', '"curvature": _rounded(self.orientation, 4)',
           ("tests/test_symmetry.py::test_mirror_option_gives_the_other_side",),
           ("tests/test_symmetry.py::test_mirror_option_gives_the_other_side",)),
    Mutant("shape context: the similarity 1 - cost reported as the cost",
           "src/meshcorr/baselines/shape_context.py",
           "    local_cost = cost[np.arange(len(sp)), match][nearest_sample]\n",
           "    local_cost = 1.0 - cost[np.arange(len(sp)), match][nearest_sample]\n",
           ("tests/test_baselines.py::test_shape_context_follows_a_mild_bend",),
           ("tests/test_baselines.py::test_shape_context_follows_a_mild_bend",)),
    Mutant("evaluation: 'under' is the fraction over the threshold", "src/meshcorr/evaluation.py",
           'return thresholds, np.searchsorted(finite, thresholds, side="right") / errors.size',
           'return thresholds, 1 - np.searchsorted(finite, thresholds, side="right") / errors.size',
           ("tests/test_cli_evaluate.py::test_evaluate_json_with_vts_and_sym",),
           ("tests/test_cli_evaluate.py::test_evaluate_json_with_vts_and_sym",)),
    Mutant("evaluation: total_error sums the normalised errors", "src/meshcorr/evaluation.py",
           '"total_error": float(np.nansum(raw))', '"total_error": float(np.nansum(errors))',
           ("tests/test_cli_evaluate.py::test_evaluate_json_with_vts_and_sym",),
           ("tests/test_cli_evaluate.py::test_evaluate_json_with_vts_and_sym",)),
    Mutant("bench: a pair's seconds in milliseconds", "src/meshcorr/benchmark.py",
           'row["seconds"] = time.perf_counter() - start', 'row["seconds"] = 1000 * (time.perf_counter() - start)',
           ("tests/test_cli_evaluate.py::test_bench_real_spectral_run_and_curves",),
           ("tests/test_cli_evaluate.py::test_bench_real_spectral_run_and_curves",)),
]

#: Core module -> the test files that exercise it (the cosmic run's test command).
MODULES = {
    "anchors": ["tests/stages/test_anchors.py", "tests/test_scalable.py"],
    "reorder": ["tests/stages/test_reorder.py"],
    "transfer": ["tests/cli/test_show.py", "tests/maps/test_transfer.py"],
    "validate": ["tests/core/test_validate.py"],
    "io": ["tests/io"],
    "symmetry": ["tests/choice/test_symmetry.py"],
    "evaluation": ["tests/evaluation/test_metrics.py", "tests/evaluation/test_metrics_maps.py",
                   "tests/cli/test_evaluate.py"],
}
#: Where each cosmic module's source lives since the subpackage layout (issue 30).
MODULE_FILES = {"anchors": "stages/anchors.py", "reorder": "stages/reorder.py", "transfer": "maps/transfer.py",
                "validate": "core/validate.py", "io": "io/meshes.py", "symmetry": "choice/symmetry.py",
                "evaluation": "evaluation/metrics.py"}
#: The hand mutants' test files before the subpackage layout (issue 30) -> where they are now; the
#: ``before`` runs use the files of BASE as they were.
TESTS_NOW = {"tests/test_viz.py": "tests/cli/test_show.py", "tests/test_report.py": "tests/viz/test_report.py",
             "tests/test_anchors.py": "tests/stages/test_anchors.py", "tests/test_pipeline.py": "tests/pipeline/test_run.py",
             "tests/test_cli.py": "tests/cli/test_match.py", "tests/test_validate.py": "tests/core/test_validate.py",
             "tests/test_threads.py": "tests/runtime/test_threads.py", "tests/test_refine.py": "tests/stages/test_refine.py",
             "tests/test_icp.py": "tests/stages/test_icp.py", "tests/test_symmetry.py": "tests/choice/test_symmetry.py",
             "tests/test_baselines.py": "tests/baselines/test_baselines.py",
             "tests/test_cli_evaluate.py": "tests/cli/test_evaluate.py"}


def _tests_now(args) -> tuple[str, ...]:
    """A mutant's ``after`` arguments with its test files where they are now."""
    out = []
    for arg in args:
        file, sep, test = arg.partition("::")
        out.append(TESTS_NOW.get(file, file) + sep + test)
    return tuple(out)


def _source_now(root: Path, mutant: "Mutant") -> Path | None:
    """The file of ``root``'s src/ that holds the mutant's code once (the code may have moved since)."""
    named = root / mutant.path
    if named.is_file() and named.read_text().count(mutant.old) == 1:
        return named
    holders = [p for p in (root / "src").rglob("*.py") if p.read_text().count(mutant.old) == 1]
    return holders[0] if len(holders) == 1 else None


def _copy_tree(into: Path) -> Path:
    """A copy of the code and tests, without caches; returns its root."""
    ignore = shutil.ignore_patterns("__pycache__", "*.pyc", "*.egg-info")
    for name in ("src", "tests"):
        shutil.copytree(ROOT / name, into / name, ignore=ignore)
    shutil.copy2(ROOT / "pyproject.toml", into / "pyproject.toml")
    return into


def _env(root: Path) -> dict:
    return {**os.environ, "PYTHONPATH": str(root / "src"), "MPLBACKEND": "Agg"}


def _pytest(root: Path, args, timeout: float) -> str:
    """'killed' (tests failed), 'survived' (tests passed) or 'timeout'."""
    try:
        done = subprocess.run(PYTEST + list(args), cwd=root, env=_env(root), timeout=timeout,
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    except subprocess.TimeoutExpired:
        return "timeout"
    return "survived" if done.returncode == 0 else "killed"


def _test_files(args) -> list[str]:
    return sorted({a.split("::")[0] for a in args if a.startswith("tests/")})


def run_hand(names: list[str] | None, timeout: float) -> None:
    print("| mutant | tests | before (" + BASE + ") | after (HEAD) |")
    print("|---|---|---|---|")
    for mutant in HAND:
        if names and not any(n in mutant.name for n in names):
            continue
        with tempfile.TemporaryDirectory(prefix="meshcorr-mut-") as folder:
            root = _copy_tree(Path(folder))
            target = _source_now(root, mutant)
            if target is None:
                print(f"| {mutant.name} | | not applicable: code changed | |", flush=True)
                continue
            text = target.read_text()
            control = _pytest(root, _tests_now(mutant.after), timeout)
            target.write_text(text.replace(mutant.old, mutant.new))
            after = _pytest(root, _tests_now(mutant.after), timeout)
            for test_file in _test_files(mutant.before):
                old = subprocess.run(["git", "show", f"{BASE}:{test_file}"], cwd=ROOT, capture_output=True,
                                     text=True, check=True).stdout
                (root / test_file).write_text(old)
            before = _pytest(root, mutant.before, timeout)
        tests = " ".join(a.replace("tests/", "") for a in _tests_now(mutant.after))
        note = "" if control == "survived" else f" (unmutated: {control}!)"
        print(f"| {mutant.name} | `{tests}` | {before} | {after}{note} |", flush=True)


def _sample(session: Path, size: int, seed: int) -> tuple[int, int]:
    """Mark all but ``size`` seeded-random work items as skipped; returns (total, kept)."""
    from cosmic_ray.work_db import WorkDB, use_db
    from cosmic_ray.work_item import WorkerOutcome, WorkResult

    with use_db(str(session), WorkDB.Mode.open) as db:
        # Job ids are random: order the mutants by what they change, so a seed picks the same ones.
        def spec(item):
            m = item.mutations[0]
            return (tuple(m.start_pos), m.operator_name, m.occurrence)

        items = [item.job_id for item in sorted(db.pending_work_items, key=spec)]
        keep = set(items) if size <= 0 or size >= len(items) else set(random.Random(seed).sample(items, size))
        for job_id in items:
            if job_id not in keep:
                db.set_result(job_id, WorkResult(worker_outcome=WorkerOutcome.SKIPPED,
                                                 output="not sampled"))
    return len(items), len(keep)


def _counts(session: Path) -> dict[str, int]:
    """Sampled mutants per test outcome: ``{"killed": ..., "survived": ..., "incompetent": ...}``."""
    con = sqlite3.connect(session)
    try:
        return dict(con.execute("SELECT lower(test_outcome), COUNT(*) FROM work_results "
                                "WHERE lower(worker_outcome) != 'skipped' GROUP BY lower(test_outcome)"))
    finally:
        con.close()


def _surviving_mutations(session: Path) -> list[tuple[str, str, str]]:
    """``(module_path, operator, occurrence)`` and the diff of each survivor of a session."""
    from cosmic_ray.work_db import WorkDB, use_db
    from cosmic_ray.work_item import TestOutcome

    found = []
    with use_db(str(session), WorkDB.Mode.open) as db:
        for item, result in db.completed_work_items:
            if result.test_outcome == TestOutcome.SURVIVED:
                for m in item.mutations:
                    found.append(((str(m.module_path), m.operator_name, str(m.occurrence)), result.diff or "",
                                  f"{Path(m.module_path).name}:{m.start_pos[0]} {m.operator_name} #{m.occurrence}"))
    return sorted(found, key=lambda f: f[2])


def _survivors(session: Path) -> list[tuple[str, str]]:
    """``("file:line operator #occurrence", diff)`` of each survivor, from the session database."""
    return [(where, diff) for _, diff, where in _surviving_mutations(session)]


def run_recheck(folder: Path, timeout: float) -> None:
    """Apply each survivor of the kept sessions again and run its module's tests as they are now."""
    print("| survivor (first run) | change | now |")
    print("|---|---|---|")
    for session in sorted(folder.glob("*.sqlite")):
        for (module_path, operator, occurrence), diff, where in _surviving_mutations(session):
            with tempfile.TemporaryDirectory(prefix="meshcorr-re-") as tmp:
                root = _copy_tree(Path(tmp))
                subprocess.run(["cosmic-ray", "apply", module_path, operator, occurrence], cwd=root,
                               env=_env(root), check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
                now = _pytest(root, MODULES[session.stem], timeout)
            print(f"| {where} | `{_diff_lines(diff)}` | {now} |", flush=True)


def _diff_lines(diff: str) -> str:
    """The changed lines of a unified diff, ``-old`` / ``+new``, on one line."""
    changed = " / ".join(line.strip() for line in diff.splitlines()
                         if line[:1] in "+-" and not line.startswith(("+++", "---")))
    return changed.replace("|", "\\|")  # inside a Markdown table


def run_report(folder: Path, diffs: bool) -> None:
    """Counts and survivors of the session databases (``*.sqlite``) kept by ``cosmic --keep``."""
    print("| module | killed | survived | incompetent |")
    print("|---|---|---|---|")
    sessions = sorted(folder.glob("*.sqlite"))
    for session in sessions:
        counts = _counts(session)
        print(f"| {session.stem} | {counts.get('killed', 0)} | {counts.get('survived', 0)} | "
              f"{counts.get('incompetent', 0)} |")
    print()
    for session in sessions:
        for where, diff in _survivors(session):
            print(f"- {where}" + (f": `{_diff_lines(diff)}`" if diffs else ""))


def run_cosmic(modules: list[str], size: int, seed: int, timeout: float, keep: Path | None) -> None:
    print("| module | tests | mutants | sampled | killed | survived | incompetent | minutes |")
    print("|---|---|---|---|---|---|---|---|")
    survivors: dict[str, list[tuple[str, str]]] = {}
    for module in modules:
        with tempfile.TemporaryDirectory(prefix="meshcorr-cr-") as folder:
            root = _copy_tree(Path(folder))
            tests = MODULES[module]
            command = " ".join(PYTEST + tests)
            config = root / "cosmic-ray.toml"
            config.write_text(
                "[cosmic-ray]\n"
                f'module-path = "src/meshcorr/{MODULE_FILES[module]}"\n'
                f"timeout = {timeout}\n"
                "excluded-modules = []\n"
                f"test-command = {command!r}\n"  # a TOML literal string
                "\n[cosmic-ray.distributor]\nname = \"local\"\n")
            session = root / f"{module}.sqlite"
            env = _env(root)
            start = time.perf_counter()
            subprocess.run(["cosmic-ray", "init", str(config), str(session)], cwd=root, env=env, check=True)
            total, kept = _sample(session, size, seed)
            subprocess.run(["cosmic-ray", "exec", str(config), str(session)], cwd=root, env=env, check=True,
                           stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
            minutes = (time.perf_counter() - start) / 60
            counts = _counts(session)
            survivors[module] = _survivors(session)
            if keep is not None:
                keep.mkdir(parents=True, exist_ok=True)
                shutil.copy2(session, keep / session.name)
        print(f"| {module} | {' '.join(t.replace('tests/', '') for t in tests)} | {total} | {kept} | "
              f"{counts.get('killed', 0)} | {counts.get('survived', 0)} | {counts.get('incompetent', 0)} | "
              f"{minutes:.1f} |", flush=True)
    print()
    for found in survivors.values():
        for where, diff in found:
            print(f"- survivor {where}: `{_diff_lines(diff)}`")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    sub = parser.add_subparsers(dest="run", required=True)
    hand = sub.add_parser("hand", help="issue #17's mutants, before and after")
    hand.add_argument("--only", nargs="*", help="mutants whose name contains one of these words")
    hand.add_argument("--timeout", type=float, default=300.0, help="seconds per test run")
    cosmic = sub.add_parser("cosmic", help="cosmic-ray over the core modules")
    cosmic.add_argument("--module", nargs="*", choices=sorted(MODULES), default=list(MODULES))
    cosmic.add_argument("--sample", type=int, default=40, help="mutants per module (0: all)")
    cosmic.add_argument("--seed", type=int, default=0)
    cosmic.add_argument("--timeout", type=float, default=120.0, help="seconds per mutant")
    cosmic.add_argument("--keep", type=Path, help="copy the session databases here")
    report = sub.add_parser("report", help="counts and survivors of kept cosmic-ray sessions")
    report.add_argument("folder", type=Path, help="the --keep folder of a cosmic run")
    report.add_argument("--diffs", action="store_true", help="show each survivor's change")
    recheck = sub.add_parser("recheck", help="survivors of kept cosmic-ray sessions against today's tests")
    recheck.add_argument("folder", type=Path, help="the --keep folder of a cosmic run")
    recheck.add_argument("--timeout", type=float, default=300.0, help="seconds per test run")
    args = parser.parse_args()
    if args.run == "hand":
        run_hand(args.only, args.timeout)
    elif args.run == "report":
        run_report(args.folder, args.diffs)
    elif args.run == "recheck":
        run_recheck(args.folder, args.timeout)
    else:
        run_cosmic(args.module, args.sample, args.seed, args.timeout, args.keep)


if __name__ == "__main__":
    main()
