"""meshcorr.runtime.timing: stages are timed, repeated stages add up, progress is forwarded."""

import time

import pytest

from meshcorr.runtime.timing import StageTimer


def test_stage_times_add_up_and_are_kept_on_errors():
    timer = StageTimer()
    with timer.stage("icp"):
        time.sleep(0.01)
    with timer.stage("icp"):
        time.sleep(0.01)
    with pytest.raises(ValueError), timer.stage("refine"):
        raise ValueError("stop")
    assert set(timer.timings) == {"icp", "refine"}
    assert 0.02 <= timer.timings["icp"] < 1.0
    assert timer.timings["refine"] >= 0.0


def test_progress_callback_sees_start_steps_and_end():
    calls = []
    timer = StageTimer(lambda *args: calls.append(args))
    with timer.stage("geodesics"):
        report = timer.reporter("geodesics")
        report(3, 10)
    assert calls == [("geodesics", 0, 1), ("geodesics", 3, 10), ("geodesics", 1, 1)]


def test_no_reporter_without_a_callback():
    assert StageTimer(None).reporter("geodesics") is None


def test_each_stage_records_the_peak_resident_memory_while_it_ran():
    import numpy as np
    import pytest

    from meshcorr.runtime.timing import peak_resident_mib

    if peak_resident_mib() is None:
        pytest.skip("no /proc/self/status here")
    timer = StageTimer(None)
    with timer.stage("small"):
        pass
    with timer.stage("large"):
        block = np.ones(64 * 1024 ** 2 // 8)  # 64 MiB, touched
        del block
    assert set(timer.memory) == {"small", "large"}
    assert timer.memory["large"] > 0 and timer.memory["small"] > 0
    if timer.memory["large"] >= timer.memory["small"] + 50:  # the high-water mark was reset between them
        assert timer.memory["large"] - timer.memory["small"] < 200
