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
