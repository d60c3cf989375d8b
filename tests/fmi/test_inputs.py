"""The model's inputs through the FMU: an input table given by FMPy (CS and ME, FMI 2 and 3)
equals `kanesim run --input-file` of the same table, and a PD controller in a Python master stepping the FMU at
1 kHz reproduces the same controller written in the .mech file, its difference shrinking
with the sampling period as a zero-order hold's must (first order)."""
import io

import numpy as np
import pytest
from fmpy import simulate_fmu

from conftest import kanesim, open_instance
from fmu_models import single_pendulum

def driven(name, torque, parameters=()):
    """The pendulum driven by the input tau, its torque `torque`."""
    return single_pendulum(name, "A pendulum driven by an input torque", declarations=["input Real tau;", *parameters],
                           outputs=["output Real tip = rod.frame_b.r[2];"], equations=[f"hinge.tau = {torque};"],
                           annotation="StopTime = 2, Tolerance = 1e-9, Interval = 0.01")


DRIVEN = driven("Driven", "tau")

# The same pendulum under a PD law toward q = 1 written in the model.
PD = driven("DrivenPD", "tau + KP * (1 - hinge.q) - KD * hinge.u", ["parameter Real KP = 40;", "parameter Real KD = 8;"])
KP, KD = 40.0, 8.0


def run_csv(*args):
    out = kanesim("run", *args).stdout
    return np.genfromtxt(io.StringIO(out), delimiter=",", names=True, deletechars="")


@pytest.mark.parametrize("fmi", [2, 3])
@pytest.mark.parametrize("fmi_type", ["CoSimulation", "ModelExchange"])
def test_an_input_table_through_fmpy_equals_run_input_file(export, write_model, tmp_path, fmi, fmi_type):
    # FMPy sets an input at its communication points (and at a table's steps: time events),
    # holding it in between, so the table is held between rows: `# interpolation = hold`.
    model = write_model("driven.mech", DRIVEN)
    table = tmp_path / "tau.csv"
    table.write_text("# interpolation = hold\ntime,tau\n0,0\n0.5,3\n1,-2\n1.5,1\n2,1\n")
    ref = run_csv(model, "--input-file", str(table))
    signal = np.array([(0, 0), (0.5, 0), (0.5, 3), (1, 3), (1, -2), (1.5, -2), (1.5, 1), (2, 1)],
                      dtype=[("time", float), ("tau", float)])
    r = simulate_fmu(export(model, fmi=fmi), fmi_type=fmi_type, input=signal, output=["hinge.q", "hinge.u", "tip"],
                     output_interval=0.01, relative_tolerance=1e-9, record_events=False)
    for name in ["hinge.q", "hinge.u", "tip"]:
        assert np.max(np.abs(r[name] - ref[name])) < 2e-5, name


def pd_master(fmu, tmp_path, rate):
    """The PD law in Python, sampled at `rate` Hz, its torque held over each step."""
    s, _, vr = open_instance(fmu, tmp_path / f"pd{rate}", 2, "cs", tolerance=1e-9)
    h, n = 1.0 / rate, int(round(2.0 * rate))
    q = []
    for k in range(n):
        qk, uk = s.getReal([vr["hinge.q"], vr["hinge.u"]])
        s.setReal([vr["tau"]], [KP * (1 - qk) - KD * uk])
        s.doStep(k * h, h)
        q.append(s.getReal([vr["hinge.q"]])[0])
    s.terminate()
    s.freeInstance()
    return np.array(q)[int(rate * 0.01) - 1::int(rate * 0.01)]  # every 10 ms, as the run's rows


def test_a_pd_controller_in_a_python_master_reproduces_the_same_controller_in_the_model(export, write_model,
                                                                                      tmp_path):
    ref = run_csv(write_model("pd.mech", PD), "--set", "tau=0")["hinge.q"][1:]
    fmu = export(write_model("driven.mech", DRIVEN), kind="cs")
    e1 = np.max(np.abs(pd_master(fmu, tmp_path, 1000) - ref))
    e2 = np.max(np.abs(pd_master(fmu, tmp_path, 2000) - ref))
    # The zero-order hold lags the law by h/2: a first-order difference, halved with h.
    assert e1 < 5e-3 and 1.6 < e1 / e2 < 2.4, (e1, e2)
