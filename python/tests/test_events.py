"""Events in the Python result (docs/events.md): r.events against the closed form of a
bouncing ball (impact times t1 = sqrt(2h/g), t_{k+1} - t_k = 2 e^k t1) and against the command
line's --events file, and terminate's (time, message) in r.terminated; the stepping core
(model.simulator()) through a pendulum's impacts on its end stops."""
import csv
import math
import subprocess

import pytest

import kanesim


@pytest.fixture(scope="module")
def ball(source_dir):
    """The ball of docs/events.md (e = 0.8, from 1 m, terminate at 2 s; Tolerance 1e-12),
    shared with tests/fmi/test_events.py."""
    return source_dir / "tests" / "data" / "when_ball.mech"


def test_events_and_terminate_in_the_result(kanesim_exe, tmp_path, ball):
    r = kanesim.load(ball).run()
    t1, e = math.sqrt(2 / 9.81), 0.8
    want = [t1, t1 + 2 * e * t1, t1 + 2 * e * t1 + 2 * e * e * t1]
    bounces = [ev for ev in r.events if ev["kind"] == "fires"]
    assert [round(ev["time"], 9) for ev in bounces] == [round(t, 9) for t in want]
    for ev in bounces:
        before, after = ev["changes"]["p.u"]
        assert after == -e * before and before < 0
        assert ev["element"] == "when (when_ball.mech:9)"
    assert r.terminated == (r.events[-1]["time"], "two seconds") and abs(r.terminated[0] - 2) < 1e-12
    assert r.time[-1] == r.terminated[0] and r.time[-2] == r.terminated[0]  # left and right limits
    assert "events" not in r.stats

    events = tmp_path / "events.csv"
    p = subprocess.run([kanesim_exe, "run", str(ball), "-o", str(tmp_path / "out.csv"), "--events", str(events)],
                       capture_output=True, text=True, check=True)
    assert "terminated at t = 2" in p.stderr and "two seconds" in p.stderr
    with open(events, newline="") as f:
        rows = list(csv.DictReader(f))
    assert [float(x["time"]) for x in rows] == [ev["time"] for ev in r.events]
    assert [x["kind"] for x in rows] == [ev["kind"] for ev in r.events]
    assert [float(x["after"]) for x in rows[:3]] == [ev["changes"]["p.u"][1] for ev in bounces]
    assert rows[-1]["signal"] == "" and rows[-1]["kind"] == "terminate: two seconds"


def test_the_stepping_core_takes_end_stops_as_a_run_does(source_dir):
    # model.simulator() advanced over the output grid: its impacts and rest on the stops are
    # the run's, so the states at the grid times equal the run's rows there (to the
    # tolerance's reach) and never pass a stop. If this fails, the stepping core loses the
    # stops (a motion through them) or handles them differently from a run.
    model = kanesim.load(source_dir / "tests" / "data" / "stopped_pendulum.mech")
    r = model.run()
    t, q = r.time, r["hinge.q"]
    assert sum(1 for ev in r.events if ev["kind"].startswith("impact")) >= 10
    grid = {}
    for k in range(len(t)):  # rows of the grid, not an event's two
        if (k == 0 or t[k] != t[k - 1]) and (k + 1 == len(t) or t[k + 1] != t[k]):
            grid[round(t[k] / 0.01)] = q[k]
    s = model.simulator()
    worst = 0.0
    for k in range(1, 201):
        s.advance_to(0.01 * k)
        qk = s.state[0]
        assert -0.5 - 1e-9 <= qk <= 0.5 + 1e-9
        if k in grid:
            worst = max(worst, abs(qk - grid[k]))
    assert worst < 1e-8
    assert s.state[0] == -0.5 and s.state[1] == 0.0  # at rest on q_min at the end, held there
