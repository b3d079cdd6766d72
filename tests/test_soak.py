"""A short soak (issue 16): consecutive match runs in one process, some failing, leave no thread
or temporary file behind and keep memory flat. The 200-run version is benchmarks/soak.py."""

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "benchmarks"))

import soak  # noqa: E402


def test_consecutive_runs_leave_nothing_behind_and_keep_memory_flat():
    result = soak.main_loop(runs=24, warmup=8)
    assert result["failures"] == []
    assert result["codes"]["ok"] > 10 and result["codes"]["failed as expected"] > 5
    # 16 runs after the warm-up: a leak of the meshes or bases of each run (~1 MiB or more
    # per run at these sizes) would exceed this; allocator noise stays well below it.
    growth = result["rss"]["end"] - result["rss"]["after warm-up"]
    assert growth < 15.0, result["rss"]
