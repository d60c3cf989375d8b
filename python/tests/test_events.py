"""Events in the Python result (docs/events.md): r.events against the closed form of a
bouncing ball (impact times t1 = sqrt(2h/g), t_{k+1} - t_k = 2 e^k t1) and against the command
line's --events file, and terminate's (time, message) in r.terminated."""
import csv
import math
import subprocess

import kanesim

BALL = """model Ball
  parameter Real e = 0.8;
  World world(g = {0, -9.81, 0});
  Prismatic p(axis = {0, 1, 0}, q(start = 1));
  Body b(m = 1, I = diagonal({1, 1, 1}));
equation
  connect(world.frame_b, p.frame_a);
  connect(p.frame_b, b.frame_a);
  when p.q < 0 then
    reinit(p.u, -e * pre(p.u));
  end when;
  when time > 2 then
    terminate("two seconds");
  end when;
  annotation(experiment(StopTime = 3, Interval = 0.1, Tolerance = 1e-12));
end Ball;
"""


def test_events_and_terminate_in_the_result(kanesim_exe, tmp_path):
    r = kanesim.loads(BALL, name="ball.mech").run()
    t1, e = math.sqrt(2 / 9.81), 0.8
    want = [t1, t1 + 2 * e * t1, t1 + 2 * e * t1 + 2 * e * e * t1]
    bounces = [ev for ev in r.events if ev["kind"] == "fires"]
    assert [round(ev["time"], 9) for ev in bounces] == [round(t, 9) for t in want]
    for ev in bounces:
        before, after = ev["changes"]["p.u"]
        assert after == -e * before and before < 0
        assert ev["element"] == "when (ball.mech:9)"
    assert r.terminated == (r.events[-1]["time"], "two seconds") and abs(r.terminated[0] - 2) < 1e-12
    assert r.time[-1] == r.terminated[0] and r.time[-2] == r.terminated[0]  # left and right limits
    assert "events" not in r.stats

    model = tmp_path / "ball.mech"
    model.write_text(BALL)
    events = tmp_path / "events.csv"
    p = subprocess.run([kanesim_exe, "run", str(model), "-o", str(tmp_path / "out.csv"), "--events", str(events)],
                       capture_output=True, text=True, check=True)
    assert "terminated at t = 2" in p.stderr and "two seconds" in p.stderr
    with open(events, newline="") as f:
        rows = list(csv.DictReader(f))
    assert [float(x["time"]) for x in rows] == [ev["time"] for ev in r.events]
    assert [x["kind"] for x in rows] == [ev["kind"] for ev in r.events]
    assert [float(x["after"]) for x in rows[:3]] == [ev["changes"]["p.u"][1] for ev in bounces]
    assert rows[-1]["signal"] == "" and rows[-1]["kind"] == "terminate: two seconds"
