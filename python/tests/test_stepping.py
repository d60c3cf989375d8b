"""Model.simulator(): a model's inputs driven step by step from Python (issue 42). If these
fail, the stepping API does not reach the model's inputs, does not continue one integration,
does not continue a saved state bit for bit, or a controller stepped from Python does not
reproduce the same law written in the model."""
import pickle
import threading
import time

import numpy as np
import pytest

import kanesim

ARM = """
model Arm
  {decls}
  World world(g = {{0, -9.81, 0}});
  Revolute j(axis = {{0, 0, 1}}, q(start = 0.5), u(start = 0));
  Rod rod(L = 1, m = 1);
equation
  connect(world.frame_b, j.frame_a);
  connect(j.frame_b, rod.frame_a);
  j.tau = {tau};
end Arm;
"""
KP, KD, REF = 20.0, 4.0, -0.3


def plant():
    return kanesim.loads(ARM.format(decls="input Real tau;", tau="tau"))


def test_pd_from_python_matches_the_pd_in_the_model():
    """The sampled law differs from the continuous one by O(dt): below 5e-3 at 1 kHz, and
    half of that at 2 kHz (first order in the period), so the gap is the sampling alone."""
    whole = kanesim.loads(ARM.format(decls="", tau=f"-{KP} * (j.q - ({REF})) - {KD} * j.u"))
    ref = whole.simulator(rtol=1e-10, integrator="dop853", outputs=["j.q", "j.u"])
    ref.advance_to(3.0)
    gaps = []
    for rate in (1000, 2000):
        sim = plant().simulator(rtol=1e-10, integrator="dop853", outputs=["j.q", "j.u"])
        for k in range(1, 3 * rate + 1):
            q, u = sim.outputs
            sim.advance_to(k / rate, inputs={"tau": -KP * (q - REF) - KD * u})
        gaps.append(np.abs(sim.outputs - ref.outputs).sum())
    assert gaps[0] < 5e-3
    assert gaps[1] / gaps[0] == pytest.approx(0.5, abs=0.1)


def test_steps_equal_a_whole_run_with_a_constant_input():
    """1 ms steps against the same model with the value written in: one integration."""
    fixed = kanesim.loads(ARM.format(decls="", tau="0.7")).run(stop_time=2, rtol=1e-10, outputs=["j.q", "j.u"])
    sim = plant().simulator(rtol=1e-10, outputs=["j.q", "j.u"])
    sim.set_inputs({"tau": 0.7})
    for k in range(1, 2001):
        sim.step(1e-3)
    assert sim.time == pytest.approx(2.0, abs=1e-12)
    assert sim["j.q"] == pytest.approx(fixed["j.q"][-1], abs=1e-7)
    assert sim["j.u"] == pytest.approx(fixed["j.u"][-1], abs=1e-7)
    assert sim["tau"] == 0.7


@pytest.mark.parametrize("integrator", ["dop853", "cvode", "cvode-bdf", "ida", "arkode"])
def test_get_set_state_continues_bit_for_bit(integrator):
    sim = plant().simulator(rtol=1e-8, integrator=integrator, outputs=["j.q", "j.u"])

    def run(steps):
        for _ in range(steps):
            q, u = sim.outputs
            sim.step(1e-3, inputs={"tau": -2 * q - 0.5 * u})

    run(300)
    saved = pickle.loads(pickle.dumps(sim.get_state()))
    run(300)
    first = sim.outputs.copy()
    sim.set_state(saved)
    run(300)
    assert np.array_equal(sim.outputs, first)
    sim.reset()
    assert sim.time == 0.0 and sim.inputs == {"tau": 0.0}
    run(300)
    assert np.array_equal(sim.get_state()[1], saved[1])


def test_errors():
    sim = plant().simulator()
    sim.advance_to(0.1)
    with pytest.raises(ValueError):
        sim.advance_to(0.05)  # backwards
    with pytest.raises(KeyError):
        sim.step(0.01, inputs={"torque": 1.0})
    with pytest.raises(ValueError):
        sim.step(0.01, inputs={"tau": float("nan")})
    failing = kanesim.loads(ARM.format(decls="input Real tau;", tau="sqrt(tau - time)")).simulator()
    failing.set_inputs({"tau": 0.5})
    with pytest.raises(kanesim.SimulationError) as e:
        failing.advance_to(1.0)
    assert 0.5 <= e.value.time <= 1.0 and e.value.result is None
    with pytest.raises(kanesim.SimulationError):
        failing.advance_to(1.0)  # refused until reset
    failing.reset()
    assert failing.time == 0.0
    failing.advance_to(0.2, inputs={"tau": 0.5})


def test_the_gil_is_released_while_stepping():
    """A Python thread runs while another is inside a long advance_to (it could not if the
    call held the GIL). The horizon doubles until one call lasts 20 ms (four of the GIL's
    switch intervals): a call at most twice the last short one stays far below the step limit
    between output instants (1e5 steps), where quadrupling up to 50 ms did not on a fast
    machine (an installed module at 1-2 us a step: 'too much work' at t = 5372)."""
    sim = plant().simulator(rtol=1e-12, integrator="dop853")
    sim.set_inputs({"tau": 0.1})
    count = [0]
    stop = threading.Event()

    def spin():
        while not stop.is_set():
            count[0] += 1

    t = threading.Thread(target=spin)
    t.start()
    try:
        horizon = 5.0
        while True:
            before, start = count[0], time.perf_counter()
            sim.advance_to(sim.time + horizon)
            if time.perf_counter() - start > 0.02:
                during = count[0] - before
                break
            horizon *= 2
    finally:
        stop.set()
        t.join()
    assert during > 1000


def test_a_stiff_model_stepped_under_auto_hands_over_as_run_does(source_dir):
    """A light link held by stiff joint friction (tests/sim/models/stiff_friction.mech): DOP853
    finds it stiff at t ~ 0.4 and, under the automatic choice, the simulator goes on with
    CVODE-BDF as run() does, in a small fraction of DOP853's evaluations, its steps equal to
    run()'s rows to the tolerance's reach; reset() starts over with DOP853."""
    model = kanesim.load(str(source_dir / "tests" / "sim" / "models" / "stiff_friction.mech"))
    r = model.run(stop_time=1, interval=0.01, rtol=1e-8, atol=1e-8, outputs=["hinge.q"])
    assert r.stats["switched"] and r.stats["method"] == "DOP853"

    def stepped(integrator):
        sim = model.simulator(rtol=1e-8, atol=1e-8, integrator=integrator, outputs=["hinge.q"])
        assert sim.method == "DOP853"
        q = []
        for k in range(1, 101):
            sim.advance_to(0.01 * k)
            q.append(sim["hinge.q"])
        return sim, np.array(q)

    sim, q = stepped("auto")
    dop, _ = stepped("dop853")
    st = sim.stats()
    assert st["switched"] and sim.method == "CVODE-BDF"
    assert st["stiff_time"] == pytest.approx(r.stats["stiff_time"], abs=0.01)
    assert not dop.stats()["switched"] and dop.stats()["stiff_time"] > 0  # explicit: noted only
    assert st["rhs_evals"] < 0.1 * dop.stats()["rhs_evals"]
    assert np.abs(q - r["hinge.q"][1:]).max() < 1e-5
    sim.reset()
    assert sim.method == "DOP853" and not sim.stats()["switched"]
