"""The FMU from a master's side through FMPy's low-level API: its state saved and restored
(and serialized) continues bit for bit, reset starts over bit for bit, two instances in one
process do not see each other, and hostile calls and numerical failures come back as
fmi2Error with the reason through the logger, never as a crash of the master."""
import os
from ctypes import POINTER, byref, c_double

import numpy as np
import pytest
from fmpy import extract, read_model_description
from fmpy.fmi2 import (fmi2CallbackAllocateMemoryTYPE, fmi2CallbackFreeMemoryTYPE, fmi2CallbackFunctions,
                       fmi2CallbackLoggerTYPE)
from fmpy.fmi1 import calloc, free
from fmpy.logging import addLoggerProxy

from conftest import EXAMPLES, initialize, instantiate, open_instance
from fmu_models import single_pendulum

DDP = os.path.join(EXAMPLES, "damped_driven_pendulum.mech")


class Master:
    """One FMU unzipped once; instances of it with a logger that keeps the messages."""

    def __init__(self, fmu, tmp_path):
        self.dir = extract(fmu, unzipdir=str(tmp_path / "unzipped"))
        self.md = read_model_description(self.dir)
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        self.messages = []
        self._keep = []

    def callbacks(self):
        def log(env, name, status, category, message):
            self.messages.append(message.decode())

        cb = fmi2CallbackFunctions()
        cb.logger = fmi2CallbackLoggerTYPE(log)
        cb.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
        cb.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
        addLoggerProxy(byref(cb))
        self._keep.append(cb)
        return cb

    def slave(self, name="a", params=None, initialize=True):
        s = instantiate(self.dir, self.md, 2, "cs", name, callbacks=self.callbacks())
        if initialize:
            start(s, self.vr, params)
        return s

    def get(self, s, names=("hinge.q", "hinge.u", "tip_height")):
        return s.getReal([self.vr[n] for n in names])


def start(s, vr=None, params=None):
    """Initialized at the tolerance every instance here runs at, `params` set on the way."""
    initialize(s, 2, vr, params, tolerance=1e-8)


def steps(master, s, t0, t1, h=0.01):
    rows = []
    for k in range(int(round((t1 - t0) / h))):
        s.doStep(t0 + k * h, h)
        rows.append(master.get(s))
    return np.array(rows)


@pytest.fixture
def master(export, tmp_path):
    return Master(export(DDP), tmp_path)


def test_saved_state_continues_bit_for_bit(master):
    # A master that rolls back (a variable-step co-simulation) must get the same motion again.
    s = master.slave()
    steps(master, s, 0.0, 0.5)
    state = s.getFMUstate()
    first = steps(master, s, 0.5, 1.0)
    s.setFMUstate(state)
    again = steps(master, s, 0.5, 1.0)
    assert np.array_equal(first, again)
    # The same through the serialized form, in a second instance.
    blob = s.serializeFMUstate(state)
    s.freeFMUstate(state)
    other = master.slave("b")
    restored = other.deSerializeFMUstate(blob)
    other.setFMUstate(restored)
    assert np.array_equal(steps(master, other, 0.5, 1.0), first)
    other.freeFMUstate(restored)
    for x in (s, other):
        x.terminate()
        x.freeInstance()


def test_reset_starts_over_bit_for_bit(master):
    s = master.slave()
    first = steps(master, s, 0.0, 0.3)
    s.reset()
    start(s)
    assert np.array_equal(steps(master, s, 0.0, 0.3), first)
    s.terminate()
    s.freeInstance()


def test_two_instances_do_not_interfere(master):
    # Interleaved steps of an instance with other parameters must not change this one's motion.
    alone = master.slave("alone")
    expected = steps(master, alone, 0.0, 0.5)
    a = master.slave("a")
    b = master.slave("b", params={"L": 0.4, "amplitude": 0.0})
    rows_a, rows_b = [], []
    for k in range(50):
        a.doStep(k * 0.01, 0.01)
        b.doStep(k * 0.01, 0.01)
        rows_a.append(master.get(a))
        rows_b.append(master.get(b))
    assert np.array_equal(np.array(rows_a), expected)
    assert not np.allclose(np.array(rows_b), expected)
    for x in (alone, a, b):
        x.terminate()
        x.freeInstance()


def expect_error(master, call, text):
    master.messages.clear()
    with pytest.raises(Exception):
        call()
    assert any(text in m for m in master.messages), master.messages


def test_hostile_calls_are_errors_not_crashes(master):
    s = master.slave(initialize=False)
    expect_error(master, lambda: s.doStep(0.0, 0.01), "not allowed in instantiated")
    expect_error(master, lambda: s.setReal([master.vr["L"]], [float("nan")]), "cannot be set to nan")
    expect_error(master, lambda: s.setReal([master.vr["tip_height"]], [1.0]), "cannot be set")
    expect_error(master, lambda: s.setReal([99999], [1.0]), "not a variable")
    s.setupExperiment(startTime=0.0)
    s.enterInitializationMode()
    s.exitInitializationMode()
    s.doStep(0.0, 0.01)
    expect_error(master, lambda: s.doStep(0.0, 0.01), "the FMU is at t = 0.01")  # a step backwards
    expect_error(master, lambda: s.doStep(0.01, -0.01), "positive size")
    expect_error(master, lambda: s.doStep(0.01, float("nan")), "positive size")
    expect_error(master, lambda: s.setReal([master.vr["L"]], [1.0]), "only before initialization")
    expect_error(master, lambda: s.enterInitializationMode(), "not allowed in step mode")
    s.doStep(0.01, 0.01)  # still usable after every refused call
    s.terminate()
    s.freeInstance()


def test_a_model_exchange_instance_refuses_nan_states(export, tmp_path):
    m = Master(export(DDP), tmp_path)
    fmu = instantiate(m.dir, m.md, 2, "me", callbacks=m.callbacks())
    initialize(fmu, 2)
    fmu.enterContinuousTimeMode()
    x = np.array([np.nan, 0.0])
    expect_error(m, lambda: fmu.setContinuousStates(x.ctypes.data_as(POINTER(c_double)), 2), "cannot be nan")
    expect_error(m, lambda: fmu.setTime(float("inf")), "cannot be inf")
    fmu.terminate()
    fmu.freeInstance()


NAN_AFTER_HALF = single_pendulum("Fails", "A joint torque that is NaN after t = 0.5",
                                 equations=["hinge.tau = sqrt(0.5 - time);"])


def test_a_numerical_failure_in_do_step_is_an_error_with_its_cause(export, write_model, tmp_path):
    m = Master(export(write_model("fails.mech", NAN_AFTER_HALF), kind="cs"), tmp_path)
    s = m.slave()
    t = 0.0
    while t < 0.45:
        s.doStep(t, 0.05)
        t += 0.05
    expect_error(m, lambda: s.doStep(t, 0.2), "numerical failure at t = ")
    assert any("NaN" in msg or "nan" in msg for msg in m.messages), m.messages
    s.terminate()
    s.freeInstance()


def test_fmi3_state_continues_bit_for_bit_and_a_step_backwards_is_an_error(export, tmp_path):
    messages = []
    s, _, vr = open_instance(export(DDP, fmi=3, kind="cs"), tmp_path / "u3", 3, "cs", tolerance=1e-8,
                             logMessage=lambda env, status, category, message: messages.append(message.decode()))
    names = [vr["hinge.q"], vr["hinge.u"], vr["tip_height"], vr["time"]]

    def run(t0, n):
        out = []
        for k in range(n):
            s.doStep(t0 + k * 0.01, 0.01)
            out.append(s.getFloat64(names))
        return np.array(out)

    run(0.0, 30)
    state = s.getFMUState()
    first = run(0.3, 30)
    s.setFMUState(state)
    assert np.array_equal(run(0.3, 30), first)
    assert first[-1][3] == pytest.approx(0.6)
    s.freeFMUState(state)
    with pytest.raises(Exception):
        s.doStep(0.3, 0.01)
    assert any("the FMU is at t = 0.6" in m for m in messages), messages
    s.terminate()
    s.freeInstance()
