"""Events in the Python result (docs/events.md): r.events against the closed form of a
bouncing ball (impact times t1 = sqrt(2h/g), t_{k+1} - t_k = 2 e^k t1) and against the command
line's --events file, and terminate's (time, message) in r.terminated; the stepping core
(model.simulator()) through a pendulum's impacts on its end stops; kanesim.sweep over a
PlaneContact ball's restitution and height against its closed form and single runs."""
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


def test_a_sweep_of_bounces_has_each_scenarios_events(source_dir):
    # kanesim.sweep over the restitution and the drop height of examples/bouncing_ball.mech
    # (a PlaneContact): each scenario's first impact at t1 = sqrt(2h/g) (cross:height=0 is the
    # event row's own time), its ball at rest on the floor after t_inf = t1 (1 + e)/(1 - e)
    # (final height and vertical speed 0), in forked workers as on threads and as a single
    # run. If this fails, a sweep's scenario loses its events or its rest (a ball still
    # bouncing or through the floor at the end), or a worker runs events otherwise than a run.
    model = kanesim.load(source_dir / "examples" / "bouncing_ball.mech")
    grid = {"e": [0.3, 0.5, 0.7], "h": [0.5, 1.0]}
    metrics = ["cross:height=0", "final:height", "final:free.u[2]", "min:height"]
    tables = [kanesim.sweep(model, grid=grid, metrics=metrics, stop_time=6, threads=2, isolation=how)
              for how in ("process", "thread")]
    for t in tables:
        assert len(t) == 6 and t.failed == 0 and list(t["status"]) == ["ok"] * 6
    process, thread = tables
    for k in range(6):
        e, h = process["e"][k], process["h"][k]
        t1 = math.sqrt(2 * h / 9.81)
        assert t1 * (1 + e) / (1 - e) < 6  # at rest before the end
        assert abs(process["cross:height=0"][k] - t1) < 1e-9 * t1, (e, h)
        assert abs(process["final:height"][k]) < 1e-9 and abs(process["final:free.u[2]"][k]) < 1e-12, (e, h)
        assert process["min:height"][k] > -1e-9, (e, h)  # never through the floor
        for c in metrics:
            assert process[c][k] == thread[c][k], (c, e, h)
        single = model.run(set={"e": e, "h": h}, stop_time=6)
        impacts = [ev["time"] for ev in single.events if ev["kind"].startswith("impact")]
        assert impacts[0] == process["cross:height=0"][k], (e, h)
