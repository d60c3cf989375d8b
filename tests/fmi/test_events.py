"""Model Exchange with events: the FMU's event indicators are the run's event functions
(end stops, plane contacts, when clauses, exact friction), and its event mode applies the
run's handling, so FMPy's own CVODE, which locates the indicators' crossings, reproduces
`kanesim run`: the same event times and states, and both equal the closed forms."""
import csv
import io
import math
import os

import numpy as np
import pytest
from fmpy import read_model_description, simulate_fmu
from fmpy.validation import validate_fmu

from conftest import SOURCE, kanesim

G = 9.81


def _text(name):
    """A model of tests/data/ (shared with python/tests/test_stepping_events.py), as text."""
    with open(os.path.join(SOURCE, "tests", "data", name)) as f:
        return f.read()


BALL = _text("plane_ball.mech")

# The ball of docs/events.md (reinit(p.u, -e pre(p.u)), e = 0.8, terminate at 2 s), shared
# with python/tests/test_events.py.
WHEN_BALL = os.path.join(SOURCE, "tests", "data", "when_ball.mech")

# A pendulum bouncing on its end stop (e = 0.5) until it rests on q_min, shared with
# python/tests/test_events.py.
STOPPED = os.path.join(SOURCE, "tests", "data", "stopped_pendulum.mech")


def run(path, *args):
    """`kanesim run` rows and its events CSV (time, element, kind)."""
    ev = path + ".events.csv"
    out = kanesim("run", path, "--events", ev, *args).stdout
    rows = np.genfromtxt(io.StringIO(out), delimiter=",", names=True, deletechars="")
    with open(ev) as f:
        events = [r for r in csv.DictReader(f)]
    return rows, events


def me(fmu, stop, names, rtol=1e-10):
    """FMPy's Model Exchange simulation (its CVODE, root finding on the event indicators), a
    row at each side of every event."""
    return simulate_fmu(fmu, fmi_type="ModelExchange", stop_time=stop, output_interval=0.01, relative_tolerance=rtol,
                        record_events=True, output=names)


def on_grid(r, name, interval=0.01):
    """{k: value} at the rows at t = k interval that are no event's (one row at that time)."""
    t = r["time"]
    out = {}
    for k in range(len(t)):
        single = (k == 0 or t[k] != t[k - 1]) and (k + 1 == len(t) or t[k + 1] != t[k])
        if single and abs(t[k] / interval - round(t[k] / interval)) < 1e-9:
            out[round(t[k] / interval)] = r[name][k]
    return out


def assert_grid_rows_equal(r, ref, name, at_least, tol):
    """More than `at_least` rows on the grid common to the FMU's `r` and the run's `ref`, and
    their `name` within `tol`."""
    fmu_q, run_q = on_grid(r, name), on_grid(ref, name)
    common = sorted(set(fmu_q) & set(run_q))
    assert len(common) > at_least and max(abs(fmu_q[k] - run_q[k]) for k in common) < tol


def exported_copy(export, write_model, source, name, fmi):
    """The model file `source` copied to the test's folder as `name` (run() writes its events
    CSV beside it), its path and its Model Exchange FMU, which FMPy validates."""
    with open(source) as f:
        path = write_model(name, f.read())
    fmu = export(path, fmi=fmi, kind="me")
    assert validate_fmu(fmu) == []
    return path, fmu


def impact_times(events):
    """The run's impact times: the events CSV has a row per state entry an event changed (an
    impact that also puts q exactly on its stop has two), so one time per impact."""
    return sorted({float(e["time"]) for e in events if e["kind"].startswith("impact")})


def jumps(r, speed):
    """The times where the FMU's speed jumped (an event's left and right rows)."""
    t, u = r["time"], r[speed]
    return np.array([t[k] for k in range(1, len(t)) if t[k] == t[k - 1] and u[k] != u[k - 1]])


@pytest.mark.parametrize("fmi", [2, 3])
def test_a_bouncing_ball_through_fmpy_model_exchange_equals_run_and_the_closed_form(export, write_model, fmi):
    # Without event indicators FMPy's integrator would let the ball fall through the floor;
    # with indicators but without the run's handling the impacts or the rest would differ.
    path = write_model("ball.mech", BALL)
    fmu = export(path, fmi=fmi, kind="me")
    assert validate_fmu(fmu) == []
    md = read_model_description(fmu)
    assert md.numberOfEventIndicators == 2  # the gap and its graze guard
    ref, events = run(path)
    r = me(fmu, 2.5, ["lift.q", "lift.u"])
    assert np.min(r["lift.q"]) > -1e-7  # never through the floor
    # The impacts: t_1 = sqrt(2 h / g), then flights 2 e^k t_1 (closed form), as the run has them.
    impacts = impact_times(events)
    got = jumps(r, "lift.u")
    assert len(got) == len(impacts) >= 8
    t1 = math.sqrt(2 / G)
    closed = t1 + np.concatenate([[0], np.cumsum([2 * 0.6 ** k * t1 for k in range(1, len(got))])])
    # Each flight's error carries into the next rebound speed and grows by 1 / e per bounce
    # (measured: 4e-11 at the first impact, 1.1e-6 at the 17th, just before they accumulate).
    assert np.max(np.abs(got[:8] - impacts[:8])) < 1e-8 and np.max(np.abs(got - impacts)) < 1e-5
    assert np.max(np.abs(got[:8] - closed[:8])) < 1e-8
    # At rest from the accumulation point t_1 (1 + e) / (1 - e) on: held on the floor.
    rest = t1 * 1.6 / 0.4
    after = r["time"] > rest + 0.01
    assert np.max(np.abs(r["lift.q"][after])) < 1e-7 and np.max(np.abs(r["lift.u"][after])) < 1e-7
    # The rows on the output grid equal the run's.
    assert_grid_rows_equal(r, ref, "lift.q", 200, 1e-6)


@pytest.mark.parametrize("fmi", [2, 3])
def test_a_pendulum_on_end_stops_through_fmpy_model_exchange_equals_run(export, write_model, fmi):
    path, fmu = exported_copy(export, write_model, STOPPED, "stopped.mech", fmi)
    assert read_model_description(fmu).numberOfEventIndicators == 4  # q_min, q_max, their graze guards
    ref, events = run(path)
    r = me(fmu, 2, ["hinge.q", "hinge.u"])
    assert np.min(r["hinge.q"]) > -0.5 - 1e-7 and np.max(r["hinge.q"]) < 0.5 + 1e-7
    impacts = impact_times(events)
    got = jumps(r, "hinge.u")
    # (The error grows by 1 / e per bounce, as the ball's: 1.3e-10 at the first, 9e-7 at the 13th.)
    assert len(got) == len(impacts) >= 10
    assert np.max(np.abs(got[:6] - impacts[:6])) < 1e-8 and np.max(np.abs(got - impacts)) < 1e-5
    # Then at rest on q_min, held there by its reaction (gravity pulls it on), as in the run.
    after = r["time"] > impacts[-1] + 0.01
    assert np.max(np.abs(r["hinge.q"][after] + 0.5)) < 1e-7 and np.max(np.abs(r["hinge.u"][after])) < 1e-7
    assert_grid_rows_equal(r, ref, "hinge.q", 150, 1e-6)


@pytest.mark.parametrize("fmi", [2, 3])
def test_when_clauses_reinit_and_terminate_through_fmpy_model_exchange(export, write_model, fmi):
    # reinit(p.u, -e pre(p.u)) at p.q = 0, terminate at t = 2: the run's events, the closed
    # form's impact times t_1 (1 + 2 e + ... + 2 e^(k-1)), and the simulation ends at 2.
    path, fmu = exported_copy(export, write_model, WHEN_BALL, "when.mech", fmi)
    ref, events = run(path)
    r = me(fmu, 3, ["p.q", "p.u"])
    assert r["time"][-1] == pytest.approx(2.0, abs=1e-9) and ref["time"][-1] == pytest.approx(2.0, abs=1e-9)
    got = jumps(r, "p.u")
    fires = [float(e["time"]) for e in events if e["kind"] == "fires"]
    t1 = math.sqrt(2 / G)
    closed = t1 + np.concatenate([[0], np.cumsum([2 * 0.8 ** k * t1 for k in range(1, len(got))])])
    assert len(got) == len(fires) >= 3
    assert np.max(np.abs(got - fires)) < 1e-7 and np.max(np.abs(got - closed)) < 1e-7
    assert r["p.u"][-1] == pytest.approx(ref["p.u"][-1], abs=1e-6)


RESTING = os.path.join(SOURCE, "tests", "data", "resting_reinit.mech")


@pytest.mark.parametrize("fmi", [2, 3])
def test_a_reinit_that_flings_a_resting_joint_off_its_stop_through_fmpy_model_exchange(export, write_model, fmi):
    # The rod rests on q_max = -2 until a when clause sets its speed to -2 at t = 1: the FMU's
    # event update releases it as the run does (docs/events.md), so it swings free and strikes
    # the stop again at the run's time, at speed 2 (energy kept), bouncing back at -1.
    path, fmu = exported_copy(export, write_model, RESTING, "resting.mech", fmi)
    ref, events = run(path)
    r = me(fmu, 2, ["j1.q", "j1.u"])
    t, q, u = r["time"], r["j1.q"], r["j1.u"]
    assert np.max(q) < -2 + 1e-7
    assert np.all(q[t < 1 - 1e-9] == -2) and np.all(u[t < 1 - 1e-9] == 0)  # held on the stop
    got = jumps(r, "j1.u")
    impacts = impact_times(events)
    assert len(got) >= 2 and abs(got[0] - 1) < 1e-9 and abs(got[1] - impacts[0]) < 1e-7
    k = int(np.nonzero(t == got[1])[0][0])
    assert u[k] == pytest.approx(2, abs=1e-6) and u[k + 1] == pytest.approx(-1, abs=1e-6)
    assert_grid_rows_equal(r, ref, "j1.q", 150, 1e-6)


SLIDER = _text("coulomb_slider.mech")


def test_exact_friction_slides_then_sticks_through_fmpy_model_exchange(export, write_model):
    # Sliding back from x0 = 1: x = c + (x0 - c) cos(w t), c = mu m g / k, w = sqrt(k / m),
    # until the speed reaches zero at pi / w, x = 2 c - x0, where the spring's pull k |x|
    # (4.11 N) is within mu_s m g (4.91 N): stuck there for good. The FMU's derivatives must
    # follow the mode (sliding, then held); the regularized law would creep on.
    path = write_model("slider.mech", SLIDER)
    fmu = export(path, fmi=2, kind="me")
    assert validate_fmu(fmu) == []
    ref, events = run(path)
    r = me(fmu, 1.5, ["slide.q", "slide.u"])
    c, w = 0.3 * G / 10, math.sqrt(10.0)
    t_stick = math.pi / w
    assert [e["kind"].split(" ")[0] for e in events] == ["slips,", "sticks"]
    assert float(events[1]["time"]) == pytest.approx(t_stick, abs=1e-8)
    t, x = r["time"], r["slide.q"]
    sliding = t < t_stick - 1e-6
    assert np.max(np.abs(x[sliding] - (c + (1 - c) * np.cos(w * t[sliding])))) < 1e-7
    stuck = t > t_stick + 1e-6
    assert np.max(np.abs(x[stuck] - (2 * c - 1))) < 1e-7 and np.max(np.abs(r["slide.u"][stuck])) < 1e-9


LIFT = _text("lift_sphere.mech")


def test_a_rolling_contact_that_would_pull_is_an_error_where_the_run_stops(export, write_model):
    # The normal force m g - 2 t crosses zero at t = g / 2: `kanesim run` stops there (exit 2);
    # the FMU's event update returns fmi2Error with the same cause and time, not a motion
    # held to the plane by a pull.
    fmu = export(write_model("lift.mech", LIFT), fmi=2, kind="me")
    messages = []
    with pytest.raises(Exception, match="fmi2NewDiscreteStates failed"):
        simulate_fmu(fmu, fmi_type="ModelExchange", stop_time=6, relative_tolerance=1e-9,
                     logger=lambda c, name, status, category, message: messages.append(message.decode()))
    assert len(messages) == 1 and "its normal force turns tensile" in messages[0]
    assert float(messages[0].split("at t = ")[1].split(":")[0]) == pytest.approx(G / 2, abs=1e-7)


@pytest.mark.parametrize("fmi", [2, 3])
def test_a_bouncing_ball_in_co_simulation_equals_run(export, write_model, fmi):
    # Co-Simulation's stepping core handles plane contacts as a run does: the impacts inside
    # doStep, the accumulation, the rest; the rows at the communication points are the run's.
    path = write_model("ball.mech", BALL)
    ref, _ = run(path)
    r = simulate_fmu(export(path, fmi=fmi, kind="cs"), fmi_type="CoSimulation", stop_time=2.5, output_interval=0.01,
                     relative_tolerance=1e-10, output=["lift.q", "lift.u"])
    assert np.min(r["lift.q"]) > -1e-7
    assert_grid_rows_equal(r, ref, "lift.q", 200, 1e-6)
    after = r["time"] > 1.9  # at rest from the accumulation point 1.806 on
    assert np.max(np.abs(r["lift.q"][after])) < 1e-7 and np.max(np.abs(r["lift.u"][after])) < 1e-7
