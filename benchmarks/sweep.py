"""Rerun the reliability sweep: every case of ``benchmarks/sweep_cases/*.py`` through the real command line.

Each module of ``sweep_cases`` defines ``CASES``, a list of dicts:

- ``name``: what the case is (unique);
- ``argv``: the ``meshcorr`` arguments; ``{R}`` and ``{B}`` stand for the
  bundled examples ``creature_rest.off`` and ``creature_bent.off``,
  ``{tmp}`` for a fresh folder of the case;
- ``setup`` (optional): ``setup(tmp: Path) -> None``, run first to make
  the case's files in ``{tmp}``;
- ``exit``: the exit code expected;
- ``stderr`` (optional): a text the error output must contain;
- ``check`` (optional): ``check(tmp: Path) -> str | None``, run last; a
  string is a failure (e.g. a file left behind).

Every case runs in a fresh ``meshcorr`` process (``python -m meshcorr``),
with a time limit. Usage::

    python benchmarks/sweep.py [--only NAME_PART] [--timeout 120]

It prints one line per case and a summary, and exits 1 when a case fails.
The suite runs the cases too (``tests/test_sweep.py``), without the slow
ones (``"slow": True``).
"""

from __future__ import annotations

import argparse
import importlib.util
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = {"R": ROOT / "examples" / "creature_rest.off", "B": ROOT / "examples" / "creature_bent.off"}


def load_cases() -> list[dict]:
    """Every case of every module of ``benchmarks/sweep_cases``, in file order."""
    cases = []
    for path in sorted((Path(__file__).parent / "sweep_cases").glob("*.py")):
        spec = importlib.util.spec_from_file_location(f"sweep_cases.{path.stem}", path)
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
        cases += [dict(case, module=path.stem) for case in module.CASES]
    names = [case["name"] for case in cases]
    duplicates = sorted({name for name in names if names.count(name) > 1})
    if duplicates:
        raise SystemExit(f"sweep: duplicate case names: {duplicates}")
    return cases


def run_case(case: dict, timeout: float) -> str | None:
    """None when the case behaves as expected, else what went wrong."""
    with tempfile.TemporaryDirectory() as folder:
        tmp = Path(folder)
        if case.get("setup"):
            case["setup"](tmp)
        argv = [arg.format(tmp=tmp, **EXAMPLES) for arg in case["argv"]]
        try:
            done = subprocess.run([sys.executable, "-m", "meshcorr", *argv], capture_output=True, text=True,
                                  timeout=timeout, cwd=tmp)
        except subprocess.TimeoutExpired:
            return f"still running after {timeout} s"
        if done.returncode != case["exit"]:
            return f"exit {done.returncode}, expected {case['exit']}: {done.stderr.strip()[-300:]}"
        if case.get("stderr") and case["stderr"] not in done.stderr:
            return f"stderr lacks {case['stderr']!r}: {done.stderr.strip()[-300:]}"
        if "Traceback" in done.stderr:
            return f"a traceback: {done.stderr.strip()[-300:]}"
        return case["check"](tmp) if case.get("check") else None


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--only", default=None, help="run the cases whose name contains this")
    parser.add_argument("--timeout", type=float, default=120.0, help="seconds a case may run")
    args = parser.parse_args(argv)
    cases = [c for c in load_cases() if args.only is None or args.only in c["name"]]
    failures = 0
    for case in cases:
        problem = run_case(case, args.timeout)
        failures += problem is not None
        print(f"{'FAIL' if problem else 'ok  '} {case['module']}: {case['name']}" + (f": {problem}" if problem else ""))
    print(f"sweep: {len(cases) - failures} of {len(cases)} cases as expected")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
