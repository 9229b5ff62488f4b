"""Progress lines: the time left is the elapsed time scaled by the work left, capped by the
budget; lines are throttled; a callable receives them."""

import pytest

from bushenv import progress as progress_module
from bushenv.progress import Progress


@pytest.fixture
def clock(monkeypatch):
    now = [100.0]
    monkeypatch.setattr(progress_module.time, "perf_counter", lambda: now[0])
    return now


def test_time_left_scales_the_elapsed_time_by_the_work_left(clock):
    lines = []
    p = Progress(1000, sink=lines.append, label="nn", every_s=0.0)
    clock[0] += 10.0
    p.update(250, "a quarter")
    assert p.left_s() == pytest.approx(30.0)
    assert lines == ["[nn   10.0 s, ~30 s left] a quarter (25 %)"]


def test_the_budget_caps_the_estimate_and_a_bound_is_shown_as_one(clock):
    lines = []
    p = Progress(1000, sink=lines.append, label="nn", every_s=0.0, budget_s=25.0, upper_bound=True)
    clock[0] += 10.0
    p.update(100, "slow start")
    assert p.left_s() == pytest.approx(15.0)
    assert lines[-1].startswith("[nn   10.0 s, <=15 s left]")


def test_no_estimate_before_one_percent_nor_after_the_end(clock):
    lines = []
    p = Progress(1000, sink=lines.append, label="bw", every_s=0.0)
    clock[0] += 1.0
    p.update(5, "barely started")
    p.update(1000, "done")
    assert lines == ["[bw    1.0 s] barely started (0 %)", "[bw    1.0 s] done (100 %)"]


def test_lines_are_throttled_unless_forced_and_silent_when_off(clock, capsys):
    lines = []
    p = Progress(100, sink=lines.append, label="nn", every_s=3.0)
    for _ in range(5):
        clock[0] += 1.0
        p.update(None, "tick")
    p.update(None, "forced", force=True)
    assert [line.split("] ")[1] for line in lines] == ["tick (0 %)", "forced (0 %)"]
    Progress.of(False, total=100, label="nn", every_s=0.0).update(50, "nothing")
    Progress.of(True, total=100, label="nn", every_s=0.0).update(50, "to stderr")
    out = capsys.readouterr()
    assert out.out == "" and out.err.endswith("] to stderr (50 %)\n")
