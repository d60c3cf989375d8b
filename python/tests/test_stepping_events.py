"""Events while stepping (docs/python.md "Stepping", docs/events.md): Model.simulator() handles
every event a run handles, located inside the steps, so a model stepped at 10 ms has the run's
events and the closed forms' (a bouncing ball: t1 = sqrt(2h/g), t_{k+1} - t_k = 2 e^k t1; a
Coulomb block: slides back, sticks at pi / w), a terminate ends the step at its event, and a
state saved across an event continues bit for bit. If these fail, the stepping core integrates
through the contacts, the when clauses or the friction's stick, or loses their modes."""
import math
import pickle

import numpy as np
import pytest

import kanesim
from conftest import SOURCE_DIR

G = 9.81

# The models the FMU tests (tests/fmi/test_events.py) read too: one .mech each in tests/data.
DATA = SOURCE_DIR / "tests" / "data"
PLANE_BALL = (DATA / "plane_ball.mech").read_text()
WHEN_BALL = (DATA / "when_ball.mech").read_text()
SLIDER = (DATA / "coulomb_slider.mech").read_text()


def step_to(sim, stop, dt):
    """Steps of dt from sim.time to stop (or to a terminate); the outputs after each step."""
    rows, t0 = [], sim.time
    for k in range(1, round((stop - t0) / dt) + 1):
        sim.advance_to(t0 + k * dt)
        rows.append((sim.time, *sim.outputs))
        if sim.terminated:
            break
    return np.array(rows)


def times(events, kind):
    return [e["time"] for e in events if e["kind"].startswith(kind)]


def flights(t1, e, n):
    """The closed form's impact times: t1, then flights of 2 e^k t1."""
    return t1 + np.concatenate([[0], np.cumsum([2 * e ** k * t1 for k in range(1, n)])])


@pytest.mark.parametrize("integrator,dt", [("dop853", 0.01), ("dop853", 0.37), ("cvode", 0.01), ("ida", 0.01),
                                           ("arkode", 0.01)])
def test_a_bouncing_ball_stepped_has_the_runs_impacts_and_the_closed_form(integrator, dt):
    # The impacts are located inside the steps (dt = 0.37 holds several), not at their ends,
    # by each integrator's own event location (DOP853's dense output, SUNDIALS' root finding).
    m = kanesim.loads(PLANE_BALL, name="ball.mech")
    run = m.run(rtol=1e-10, integrator=integrator)
    sim = m.simulator(rtol=1e-10, integrator=integrator, outputs=["lift.q", "lift.u"])
    rows = step_to(sim, 2.5, dt)
    got, want = times(sim.events, "impact"), times(run.events, "impact")
    assert len(got) == len(want) >= 8
    assert np.max(np.abs(np.array(got) - want)) < 1e-7
    closed = flights(math.sqrt(2 / G), 0.6, 8)
    assert np.max(np.abs(np.array(got[:8]) - closed)) < 1e-8
    # Never through the floor; at rest from the accumulation point t1 (1 + e) / (1 - e) on.
    assert rows[:, 1].min() > -1e-9
    assert times(sim.events, "rests")[0] == pytest.approx(math.sqrt(2 / G) * 1.6 / 0.4, abs=1e-6)
    assert np.max(np.abs(rows[rows[:, 0] > 1.85, 1:])) < 1e-9


def test_a_when_ball_stepped_equals_the_run_and_terminates_there():
    m = kanesim.loads(WHEN_BALL, name="when.mech")
    run = m.run(rtol=1e-10, interval=0.01, integrator="dop853", outputs=["p.q", "p.u"])  # the steps' grid
    sim = m.simulator(rtol=1e-10, integrator="dop853", outputs=["p.q", "p.u"])
    rows = step_to(sim, 3.0, 0.01)
    fires = times(sim.events, "fires")
    assert len(fires) == len(times(run.events, "fires")) >= 3
    assert np.max(np.abs(np.array(fires) - times(run.events, "fires"))) < 1e-9
    assert np.max(np.abs(np.array(fires) - flights(math.sqrt(2 / G), 0.8, len(fires)))) < 1e-8
    for e in sim.events:  # the reinit's jump, as the run's result has it
        if e["kind"] == "fires":
            before, after = e["changes"]["p.u"]
            assert after == pytest.approx(-0.8 * before, rel=1e-15)
    # terminate("two seconds") at t = 2: the step that crosses it ends there, as the run does.
    assert sim.terminated == (pytest.approx(2.0, abs=1e-12), "two seconds")
    assert sim.time == run.terminated[0] and rows[-1, 0] == sim.time
    assert rows[-1, 1:] == pytest.approx([run["p.q"][-1], run["p.u"][-1]], abs=1e-8)
    # The rows on the grid are the run's.
    grid = np.round(rows[:-1, 0] / 0.01).astype(int)
    k_run = {round(t / 0.01): i for i, t in enumerate(run.time) if abs(t / 0.01 - round(t / 0.01)) < 1e-9}
    assert max(abs(rows[i, 1] - run["p.q"][k_run[k]]) for i, k in enumerate(grid)) < 1e-8
    with pytest.raises(kanesim.SimulationError, match="terminated at t = 2"):
        sim.step(0.01)
    sim.reset()
    assert sim.terminated is None and sim.time == 0.0
    assert len(step_to(sim, 0.5, 0.01)) == 50 and times(sim.events, "fires") == fires[:1]


def test_exact_friction_stepped_slides_then_sticks_as_the_run():
    # x = c + (x0 - c) cos(w t) while sliding back (c = mu g m / k, w = sqrt(k / m)); stuck for
    # good at pi / w, x = 2 c - x0 (the spring's 4.11 N within mu_s m g = 4.91 N). A stepping
    # core with the regularized law would creep on instead.
    m = kanesim.loads(SLIDER, name="slider.mech")
    run = m.run(rtol=1e-10, outputs=["slide.q", "slide.u", "slide.a"])
    sim = m.simulator(rtol=1e-10, outputs=["slide.q", "slide.u", "slide.a"])
    rows = step_to(sim, 1.5, 0.01)
    c, w = 0.3 * G / 10, math.sqrt(10.0)
    t = rows[:, 0]
    sliding, stuck = t < math.pi / w - 1e-6, t > math.pi / w + 1e-6
    assert np.max(np.abs(rows[sliding, 1] - (c + (1 - c) * np.cos(w * t[sliding])))) < 1e-8
    assert np.max(np.abs(rows[stuck, 1] - (2 * c - 1))) < 1e-9 and np.max(np.abs(rows[stuck, 2])) < 1e-12
    # The outputs see the mode as the run's rows do: a = -k x / m + mu g sliding back, 0 stuck.
    assert np.max(np.abs(rows[sliding, 3] - (-10 * rows[sliding, 1] + 0.3 * G))) < 1e-9
    assert np.max(np.abs(rows[stuck, 3])) < 1e-9
    assert [e["kind"].split(" ")[0] for e in sim.events] == [e["kind"].split(" ")[0] for e in run.events]
    assert sim.events[-1]["time"] == pytest.approx(run.events[-1]["time"], abs=1e-9)
    assert sim.events[-1]["time"] == pytest.approx(math.pi / w, abs=1e-8)
    assert rows[-1, 1] == pytest.approx(run["slide.q"][-1], abs=1e-9)


@pytest.mark.parametrize("model,outputs,saves", [(PLANE_BALL, ["lift.q", "lift.u"], (0.4, 2.0)),
                                                 (WHEN_BALL, ["p.q", "p.u"], (0.4, 1.1)),
                                                 (SLIDER, ["slide.q", "slide.u"], (0.9, 1.2))],
                         ids=["plane contact", "when", "friction"])
def test_a_state_saved_before_an_event_or_in_a_mode_continues_bit_for_bit(model, outputs, saves):
    # Saved before the first impact / fire / stick, and in a mode (resting on the floor after the
    # accumulation, between bounces, stuck): the continuation across the events is the same
    # bit for bit, from the saved state and from its pickled copy.
    sim = kanesim.loads(model).simulator(rtol=1e-9, outputs=outputs)
    for t_save in saves:
        sim.advance_to(t_save)
        saved = sim.get_state()
        first = step_to(sim, 2.5, 0.01)[:, 1:]  # to 2.5 (or the terminate at 2)
        first_events = sim.events
        for state in (saved, pickle.loads(pickle.dumps(saved))):
            sim.set_state(state)
            assert sim.time == t_save
            again = step_to(sim, 2.5, 0.01)[:, 1:]
            assert np.array_equal(again, first) and sim.events == first_events
        sim.set_state(saved)


def test_a_rolling_contact_that_would_pull_fails_the_step_where_the_run_stops():
    # The normal force m g - 2 t turns tensile at t = g / 2: the run stops there (exit 2), and so
    # does the step that crosses it, instead of holding the sphere to the plane by a pull.
    m = kanesim.loads((DATA / "lift_sphere.mech").read_text())
    sim = m.simulator(rtol=1e-9)
    with pytest.raises(kanesim.SimulationError, match="normal force turns tensile") as e:
        step_to(sim, 6.0, 0.5)
    assert e.value.time == pytest.approx(G / 2, abs=1e-7) and sim.time == 4.5


# A geared pair stuck by exact friction 0.2, its drive c t sin(31 t) passing the bound by 2 % in
# a window of about 0.013 s near t = 1.064 (tests/compiler/held_step_test.cpp builds the same).
PULSE = """model Pulse
  World world(g = {0, 0, -9.81});
  Revolute j1(axis = {0, 0, 1}, friction_torque = 0.2, friction_exact = true);
  Rod r1(L = 1, m = 1);
  FixedTranslation base(r = {2, 0, 0});
  Revolute j2(axis = {0, 0, 1});
  Rod r2(L = 0.5, m = 2);
  JointCoupling gear(ratio = -0.5);
equation
  connect(world.frame_b, j1.frame_a);
  connect(j1.frame_b, r1.frame_a);
  connect(world.frame_b, base.frame_a);
  connect(base.frame_b, j2.frame_a);
  connect(j2.frame_b, r2.frame_a);
  connect(j1.drive, gear.flange_a);
  connect(j2.drive, gear.flange_b);
  j1.tau = 0.191713 * time * sin(31 * time);
end Pulse;
"""


def bisect(f, a, b):
    up = f(a) < 0
    for _ in range(200):
        m = 0.5 * (a + b)
        if m in (a, b):
            break
        if (f(m) < 0) == up:
            a = m
        else:
            b = m
    return 0.5 * (a + b)


@pytest.mark.parametrize("integrator", ["dop853", "cvode", "cvode-bdf", "ida", "arkode"])
def test_a_slip_window_shorter_than_the_step_is_found_inside_it(integrator):
    # The joint slips where c t sin(31 t) = 0.2 and sticks where the drive's impulse since then
    # equals the friction's (F(t) = 0 below): inside one step of 0.5 s. If this fails, the
    # stepping core stepped over the window (no error estimate bounds a step while stuck).
    c, w, peak = 0.191713, 31.0, (math.pi / 2 + 10 * math.pi) / 31.0
    ts = bisect(lambda t: c * t * math.sin(w * t) - 0.2, peak - 0.02, peak)
    prim = lambda s: c * (math.sin(w * s) / w ** 2 - s * math.cos(w * s) / w)
    te = bisect(lambda t: prim(t) - prim(ts) - 0.2 * (t - ts), peak + 1e-3, peak + 0.05)
    sim = kanesim.loads(PULSE, name="pulse.mech").simulator(rtol=1e-11, atol=1e-11, integrator=integrator)
    for t in (0.5, 1.0, 1.15):
        sim.advance_to(t)
    kinds = [e["kind"].split()[0].rstrip(",") for e in sim.events]
    assert kinds == ["sticks", "slips", "sticks"], kinds
    assert abs(sim.events[1]["time"] - ts) < 1e-8
    assert abs(sim.events[2]["time"] - te) < 1e-8
