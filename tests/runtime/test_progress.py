"""meshcorr.runtime.progress: what the ``progress`` option of match turns into."""

import io
import threading
import time
from pathlib import Path

import pytest

import meshcorr
import meshcorr.runtime.progress as progress_module
from meshcorr.errors import ParameterError
from meshcorr.runtime.progress import RunPlan, RunProgress, StderrProgress, as_progress

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


def test_no_progress_for_none_and_false():
    assert as_progress(None) is None
    assert as_progress(False) is None


def test_a_callable_is_used_as_it_is():
    def callback(stage, done, total):
        pass

    assert as_progress(callback) is callback


@pytest.mark.parametrize("value", [1, "yes", 0.5])
def test_anything_else_is_refused(value):
    with pytest.raises(ParameterError, match="The 'progress' parameter must be True, False, None or a callable"):
        as_progress(value)


def test_true_without_a_plan_gives_a_bar_per_stage():
    """The other callers of progress=True (figures, geodesic errors): their stages have no plan."""
    pytest.importorskip("tqdm")
    bar = as_progress(True)
    try:
        bar("geodesics", 2, 4)
        assert bar.bar.total == 4 and bar.bar.n == 2
        bar("geodesics", 9, 4)  # never beyond the total
        assert bar.bar.n == 4
        bar("embedding", 0, 1)
        assert bar.stages == ["geodesics", "embedding"]
        assert bar.bar.n == 0
    finally:
        bar.close()


class FakeClock:
    def __init__(self):
        self.now = 0.0

    def __call__(self):
        return self.now


PLAN = RunPlan(stages=(("load", 1.0), ("geodesics", 4.0), ("refine", 2.0), ("shells", 3.0)),
               paths={"coarse": (("load", 1.0), ("coarse", 1.0), ("refine", 1.0), ("shells", 7.0))})


def _timer_reports(run, *stages):
    """The reports of StageTimer for stages without sub-steps: start, end."""
    seen = []
    for stage in stages:
        for done in (0, 1):
            run.update(stage, done, 1)
            seen.append(run.fraction)
    return seen


def test_run_progress_follows_the_plan_and_never_goes_back():
    run = RunProgress(PLAN, clock=FakeClock())
    assert run.fraction == 0.0
    run.update("load", 0, 1)
    run.update("load", 1, 1)
    assert run.fraction == pytest.approx(0.1)
    run.update("geodesics", 0, 1)  # a stage counting its sub-steps: through its share
    run.update("geodesics", 0, 8)
    run.update("geodesics", 4, 8)
    assert run.stage == "geodesics" and run.fraction == pytest.approx(0.3)
    run.update("geodesics", 8, 8)  # the sub-steps end the stage; the timer's end is then nothing new
    assert run.stage is None and run.fraction == pytest.approx(0.5)
    assert not run.update("geodesics", 1, 1)
    # A stage met again with no entry left, and an unknown one, leave the fraction where it is.
    seen = _timer_reports(run, "shells", "load", "geodesics", "made-up", "shells")
    assert seen == sorted(seen) and run.fraction == pytest.approx(1.0)
    assert run.label == "shells"


def test_run_progress_jumps_over_stages_that_do_not_run_and_fills_at_the_end():
    run = RunProgress(PLAN, clock=FakeClock())
    _timer_reports(run, "load", "refine")  # no geodesics (a prepared shape)
    assert run.fraction == pytest.approx(0.7)
    run.finish()
    assert run.fraction == 1.0 and run.stage is None


def test_run_progress_takes_the_path_its_opening_stage_names():
    run = RunProgress(PLAN, clock=FakeClock())
    _timer_reports(run, "load", "coarse", "refine")
    assert run.fraction == pytest.approx(0.3)  # the coarse-to-fine path: load 1, coarse 1, refine 1 of 10
    run.update("shells", 0, 1)
    run.update("shells", 0, 7)
    run.update("shells", 1, 7)
    assert run.fraction == pytest.approx(0.4)


def test_run_progress_moves_through_a_silent_stage_by_its_time_and_estimates_the_rest():
    clock = FakeClock()
    run = RunProgress(PLAN, clock=clock)
    assert run.seconds_left() is None
    run.update("load", 0, 1)
    clock.now = 1.0
    run.update("load", 1, 1)  # 10 % in 1 s: 9 s left at that pace
    assert run.seconds_left() == pytest.approx(9.0)
    run.update("geodesics", 0, 1)  # expected to take 4 s (40 % of 10 s)
    clock.now = 3.0
    run.tick()
    assert run.fraction == pytest.approx(0.3)
    clock.now = 100.0  # much longer than expected: at most TIME_FILL of the share, then its end
    run.tick()
    assert run.fraction == pytest.approx(0.1 + 0.4 * RunProgress.TIME_FILL)
    run.update("geodesics", 1, 1)
    assert run.fraction == pytest.approx(0.5)
    assert run.seconds_left() == pytest.approx(100.0)
    run.update("refine", 0, 1)
    run.update("refine", 0, 10)  # a stage counting sub-steps moves by them only
    clock.now = 200.0
    run.tick()
    assert run.fraction == pytest.approx(0.5)


@pytest.fixture()
def recorded_bars(monkeypatch):
    """progress=True's bars, each recording its value after every report, drawn into a string."""
    pytest.importorskip("tqdm")
    bars = []

    class Recording(progress_module.TqdmProgress):
        def __init__(self, plan=progress_module.MATCH_PLAN, **options):
            super().__init__(plan, file=io.StringIO(), **options)
            self.values, self.closed = [], False
            bars.append(self)

        def __call__(self, stage, done, total):
            super().__call__(stage, done, total)
            self.values.append(self.bar.n)

        def finish(self):
            super().finish()
            self.values.append(self.bar.n)

        def close(self):
            self.closed = True
            super().close()

    monkeypatch.setattr(progress_module, "TqdmProgress", Recording)
    return bars


def test_progress_true_is_one_bar_that_only_rises_and_ends_full(recorded_bars):
    result = meshcorr.match(EXAMPLES / "creature_rest.off", EXAMPLES / "creature_bent.off", progress=True)
    assert result.map.shape == (500,)
    [bar] = recorded_bars
    assert bar.closed and bar.bar.total == 100
    assert len(bar.values) > 20
    assert all(b >= a for a, b in zip(bar.values, bar.values[1:])), "the bar went back"
    assert bar.values[-1] == bar.bar.total
    assert bar.values[len(bar.values) // 2] < bar.bar.total  # it moved during the run, not only at its end
    assert {"load", "geodesics", "refine", "shells"} <= set(bar.stages)
    assert bar.bar.desc == "meshcorr: done"


def test_a_bar_is_closed_when_the_run_fails(recorded_bars):
    with pytest.raises(ParameterError):
        meshcorr.match(EXAMPLES / "creature_rest.off", EXAMPLES / "creature_bent.off", progress=True, n_anchors=10**6)
    [bar] = recorded_bars
    assert bar.closed and bar.bar.n < bar.bar.total


def test_a_users_callback_gets_the_stages_reports_as_before():
    calls = []
    meshcorr.match(EXAMPLES / "creature_rest.off", EXAMPLES / "creature_bent.off", refine=False,
                   progress=lambda *report: calls.append(report))
    assert calls[0] == ("load", 0, 1) and calls[1] == ("load", 1, 1)
    assert calls[-1][1:] == (1, 1) and ("geodesics", 0, 1) in calls
    starts = [stage for stage, done, total in calls if (done, total) == (0, 1)]
    ends = [stage for stage, done, total in calls if (done, total) == (1, 1)]
    assert starts == ends  # every start has its end, in order; nothing added by the reporters' machinery


def _lines(stream):
    return [line for line in stream.getvalue().replace("\r", "\n").split("\n") if line.strip()]


def test_stderr_line_ticks_through_a_stage_that_reports_nothing():
    stream = io.StringIO()
    progress = StderrProgress(stream, label="a -> b", delay=0.0, tick=0.05, plan=PLAN)
    try:
        progress("load", 0, 1)
        progress("load", 1, 1)
        progress("shells", 0, 1)
        time.sleep(0.6)  # no report meanwhile
        during = _lines(stream)
        progress("shells", 1, 1)
        progress.finish()
    finally:
        progress.close()
    shells = [line for line in during if "[shells]" in line]
    assert len(shells) >= 3, during  # the stage's start, then a line per tick
    assert all(line.startswith("meshcorr: a -> b [") for line in during)
    assert _lines(stream)[-1].startswith("meshcorr: a -> b [done] [########################] 100%, ")
    assert not [t for t in threading.enumerate() if t.name == "meshcorr-progress"]


def test_stderr_line_shows_the_stage_the_share_the_time_and_what_is_left():
    clock, stream = FakeClock(), io.StringIO()
    progress = StderrProgress(stream, label="x", delay=1.0, plan=PLAN, clock=clock, tick=60.0)
    try:
        progress("load", 0, 1)
        clock.now = 0.5
        progress("load", 1, 1)
        assert stream.getvalue() == ""  # nothing in the run's first second
        clock.now = 2.0
        progress("geodesics", 0, 1)
        progress("geodesics", 10, 20)
        assert _lines(stream) == ["meshcorr: x [geodesics] [##----------------------]  10%, 2s, ~18s left"]
        clock.now = 3.0
        progress("geodesics", 20, 20)
        progress("geodesics", 1, 1)
        progress("refine", 0, 1)
        assert _lines(stream)[-1] == "meshcorr: x [refine] [############------------]  50%, 3s, ~3s left"
    finally:
        progress.close()


def test_stderr_lines_per_stage_without_a_plan_rise_and_tick():
    stream = io.StringIO()
    progress = StderrProgress(stream, delay=0.0, interval=0.0, tick=0.05)
    try:
        progress("geodesic errors", 0, 10)
        progress("geodesic errors", 4, 10)
        progress("geodesic errors", 10, 10)
        time.sleep(0.2)  # through its sub-steps: no more ticks of it
        progress("drawing", 0, 1)
        time.sleep(0.3)
        progress("drawing", 1, 1)
    finally:
        progress.close()
    lines = _lines(stream)
    assert lines[:3] == ["[geodesic errors]   0% 0 s", "[geodesic errors]  40% 0 s", "[geodesic errors] 100% 0 s"]
    assert lines[3].startswith("[drawing] ")
    assert len([line for line in lines if line.startswith("[drawing] ")]) >= 2  # ticks, then its end
    assert lines[-1].startswith("[drawing] done in ")


def test_the_first_path_opened_holds_so_large_meshes_keep_their_plan_through_coarse():
    plan = RunPlan(stages=PLAN.stages, paths={**PLAN.paths, "large": (("load", 1.0), ("large", 0.0),
                                                                       ("coarse", 2.0), ("lift", 7.0))})
    run = RunProgress(plan, clock=FakeClock())
    _timer_reports(run, "load", "large", "coarse")
    assert run.fraction == pytest.approx(0.3)  # the large path's load 1 and coarse 2 of 10, not coarse's 2 of 10
    run.update("lift", 0, 1)
    run.update("lift", 1, 3)  # lift_to_fine's reports, one per search
    assert run.fraction == pytest.approx(0.3 + 0.7 / 3)


def test_the_match_plan_has_a_path_for_large_meshes_ending_in_the_lift():
    from meshcorr.runtime.progress import MATCH_PLAN

    names = [name for name, _ in MATCH_PLAN.paths["large"]]
    assert names[:3] == ["load", "large", "coarse"] and names[-1] == "lift"
