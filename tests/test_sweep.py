"""The reliability sweep's cases (benchmarks/sweep.py, benchmarks/sweep_cases/) through the real command line."""

import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "benchmarks"))

import sweep  # noqa: E402

CASES = [case for case in sweep.load_cases() if not case.get("slow")]


@pytest.mark.parametrize("case", CASES, ids=[case["name"] for case in CASES])
def test_sweep_case(case):
    assert sweep.run_case(case, timeout=120.0) is None


def test_a_case_that_misbehaves_is_reported(tmp_path):
    case = dict(name="exit expected wrongly", argv=["match", "{tmp}/missing.off", "{R}", "-o", "{tmp}/m.txt"], exit=0)
    assert "expected 0" in sweep.run_case(case, timeout=60.0)
    leftover = dict(name="a file said left behind", argv=["--version"], exit=0,
                    check=lambda tmp: "left behind" if True else None)
    assert sweep.run_case(leftover, timeout=60.0) == "left behind"
