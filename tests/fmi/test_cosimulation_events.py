"""Co-Simulation with every event of a run: the FMU's doStep advances the stepping core
(sim::Simulator over sim::HybridOde), so when clauses (reinit, terminate) and exact
stick-slip friction are handled inside the communication steps as `kanesim run` handles
them, and a terminate(...) reaches the master as the standard says: fmi2DoStep returns
fmi2Discard with fmi2Terminated true at the event's time (FMI 2.0.4, 4.2.3); fmi3DoStep sets
terminateSimulation and lastSuccessfulTime (FMI 3.0, 4.2.1)."""
import math

import numpy as np
import pytest
from fmpy import simulate_fmu
from fmpy.validation import validate_fmu

from conftest import open_instance
from test_events import G, LIFT, SLIDER, WHEN_BALL, assert_grid_rows_equal, run

with open(WHEN_BALL) as f:  # the model's text (test_events.py names its file)
    WHEN_TEXT = f.read().replace("Interval = 0.1, Tolerance = 1e-12", "Interval = 0.01, Tolerance = 1e-10")


def test_when_clauses_in_fmi2_co_simulation_equal_run_and_terminate_at_its_time(export, write_model):
    # FMPy's CS loop stops at fmi2Discard + fmi2Terminated and records fmi2LastSuccessfulTime.
    path = write_model("when.mech", WHEN_TEXT)
    fmu = export(path, fmi=2, kind="cs")
    assert validate_fmu(fmu) == []
    ref, events = run(path)
    messages = []
    r = simulate_fmu(fmu, fmi_type="CoSimulation", stop_time=3, output_interval=0.01, relative_tolerance=1e-10,
                     output=["p.q", "p.u"], logger=lambda c, n, status, cat, m: messages.append(m.decode()))
    assert r["time"][-1] == pytest.approx(2.0, abs=1e-9) and r["time"][-1] == ref["time"][-1]
    assert any("terminate at t = 2" in m and "two seconds" in m for m in messages), messages
    assert_grid_rows_equal(r, ref, "p.q", 150, 1e-7)
    # The bounces happened inside the steps: the speed after each is -e times the one before,
    # so the rows on the grid hold the run's rebounds (3 fires before t = 2).
    assert len([e for e in events if e["kind"] == "fires"]) >= 3
    assert r["p.u"][-1] == pytest.approx(ref["p.u"][-1], abs=1e-7)


def test_when_clauses_in_fmi3_co_simulation_signal_terminate_simulation(export, write_model, tmp_path):
    path = write_model("when.mech", WHEN_TEXT)
    ref, _ = run(path)
    fmu = export(path, fmi=3, kind="cs")
    assert validate_fmu(fmu) == []
    s, _, vr = open_instance(fmu, tmp_path / "u3", 3, "cs", tolerance=1e-10)
    t, h = 0.0, 0.03
    for _ in range(200):
        event, terminate, early, last = s.doStep(t, h)
        if terminate:
            break
        assert not early and last == pytest.approx(t + h)
        t += h
    assert terminate and not early  # earlyReturn only where the master allowed it
    assert last == pytest.approx(2.0, abs=1e-9) and t < last < t + h
    q, u, time = s.getFloat64([vr["p.q"], vr["p.u"], vr["time"]])
    assert time == last
    assert q == pytest.approx(ref["p.q"][-1], abs=1e-7) and u == pytest.approx(ref["p.u"][-1], abs=1e-7)
    with pytest.raises(Exception):  # no step after the terminate
        s.doStep(last, h)
    s.terminate()
    s.freeInstance()


@pytest.mark.parametrize("fmi", [2, 3])
def test_exact_friction_in_co_simulation_slides_then_sticks_as_run(export, write_model, fmi):
    # Sliding back from x0 = 1, stuck for good at pi / w, x = 2 c - x0 (test_events.py's
    # closed form); the regularized law would creep on instead.
    path = write_model("slider.mech", SLIDER)
    fmu = export(path, fmi=fmi, kind="cs")
    assert validate_fmu(fmu) == []
    ref, _ = run(path)
    r = simulate_fmu(fmu, fmi_type="CoSimulation", stop_time=1.5, output_interval=0.01, relative_tolerance=1e-10,
                     output=["slide.q", "slide.u"])
    assert_grid_rows_equal(r, ref, "slide.q", 140, 1e-8)
    c, w = 0.3 * G / 10, math.sqrt(10.0)
    stuck = r["time"] > math.pi / w + 1e-6
    assert np.max(np.abs(r["slide.q"][stuck] - (2 * c - 1))) < 1e-9
    assert np.max(np.abs(r["slide.u"][stuck])) < 1e-12


def test_a_saved_state_in_co_simulation_continues_across_the_stick_bit_for_bit(export, write_model, tmp_path):
    # Saved while sliding (before the stick at pi / w = 0.993) and while stuck: the FMU state
    # holds the friction's mode and holding force, so the continuation, from the state and from
    # its serialized bytes, is the same bit for bit.
    fmu = export(write_model("slider.mech", SLIDER), fmi=2, kind="cs")
    s, _, vrs = open_instance(fmu, tmp_path / "u2", 2, "cs", tolerance=1e-10)
    vr = [vrs["slide.q"], vrs["slide.u"]]

    def steps(k0, n):
        out = []
        for k in range(k0, k0 + n):
            s.doStep(k * 0.01, 0.01)
            out.append(s.getReal(vr))
        return np.array(out)

    steps(0, 90)
    for k0 in (90, 120):
        state = s.getFMUstate()
        first = steps(k0, 30)
        s.setFMUstate(state)
        assert np.array_equal(steps(k0, 30), first)
        s.setFMUstate(s.deSerializeFMUstate(s.serializeFMUstate(state)))
        assert np.array_equal(steps(k0, 30), first)
        s.freeFMUstate(state)
    assert abs(first[-1][1]) < 1e-12  # stuck
    s.terminate()
    s.freeInstance()


def test_a_rolling_contact_that_would_pull_fails_the_co_simulation_step(export, write_model):
    # As the run stops at t = g / 2 (exit 2): fmi2DoStep returns fmi2Error with the cause.
    fmu = export(write_model("lift.mech", LIFT), fmi=2, kind="cs")
    messages = []
    with pytest.raises(Exception, match="fmi2DoStep failed"):
        simulate_fmu(fmu, fmi_type="CoSimulation", stop_time=6, output_interval=0.1, relative_tolerance=1e-9,
                     logger=lambda c, name, status, category, message: messages.append(message.decode()))
    assert any("its normal force turns tensile" in m for m in messages), messages
    failed = [m for m in messages if "numerical failure at t = " in m][0]
    assert float(failed.split("at t = ")[1].split(":")[0]) == pytest.approx(G / 2, abs=1e-7)
