"""Directional derivatives of an exported FMU (fmi2GetDirectionalDerivative,
fmi3GetDirectionalDerivative) through FMPy: the Jacobian of the derivatives and an output
with respect to the states and an input equals central differences of fmi*GetDerivatives /
the output, is linear in the seed, and equals the A, B, C and D of `kanesim linearize` at
the same point."""
import json
import os
import xml.etree.ElementTree as ET
from ctypes import POINTER, c_double

import numpy as np
import pytest

from conftest import EXAMPLES, kanesim, open_instance
from fmu_models import double_pendulum

# A double pendulum moving (velocity terms in A), driven by an input torque at its base.
DOUBLE = double_pendulum("Double", "A double pendulum with an input torque", 0.3, 0.8, 0.5, -0.4,
                         declarations=["input Real tau;"], outputs=["output Real tip = rod2.frame_b.r[2];"],
                         equations=["j1.tau = tau;"])
TAU = 0.7


def me_instance(fmu, tmp_path, fmi):
    m, md, vr = open_instance(fmu, tmp_path / f"fmu{fmi}", fmi, "me", sets={"tau": TAU})
    set_real, get_real = (m.setReal, m.getReal) if fmi == 2 else (m.setFloat64, m.getFloat64)
    set_input = lambda v: set_real([vr["tau"]], [v])
    get_out = lambda: get_real([vr["tip"]])[0]
    states = [v.name for v in md.modelVariables if v.name in ("j1.q", "j2.q", "j1.u", "j2.u")]
    return m, md, vr, states, set_input, get_out


def jacobian(m, vr, states):
    """[der(states); tip] by (states, tau), one directional derivative per column."""
    unknowns = [vr[f"der({s})"] for s in states] + [vr["tip"]]
    cols = [m.getDirectionalDerivative(unknowns, [vr[k]], [1.0]) for k in states + ["tau"]]
    return np.array(cols).T


@pytest.mark.parametrize("fmi", [2, 3])
def test_directional_derivatives_equal_differences_of_get_derivatives(export, write_model, tmp_path, fmi):
    model = write_model("double.mech", DOUBLE)
    m, md, vr, states, set_input, get_out = me_instance(export(model, fmi=fmi, kind="me"), tmp_path, fmi)
    n = len(states)
    J = jacobian(m, vr, states)
    ptr = lambda a: a.ctypes.data_as(POINTER(c_double))
    x0 = np.zeros(n)
    m.getContinuousStates(ptr(x0), n)
    get_der = m.getDerivatives if fmi == 2 else m.getContinuousStateDerivatives

    def f(x, tau):
        x = np.ascontiguousarray(x, dtype=float)
        m.setContinuousStates(ptr(x), n)
        set_input(tau)
        der = np.zeros(n)
        get_der(ptr(der), n)
        return np.append(der, get_out())

    h = 1e-5  # central differences: error ~ h^2 |f'''| ~ 1e-10
    fd = np.zeros_like(J)
    for j in range(n):
        e = np.zeros(n)
        e[j] = h
        fd[:, j] = (f(x0 + e, TAU) - f(x0 - e, TAU)) / (2 * h)
    fd[:, n] = (f(x0, TAU + h) - f(x0, TAU - h)) / (2 * h)
    assert np.max(np.abs(J - fd)) < 1e-7 * max(1.0, np.max(np.abs(J))), (J, fd)
    assert abs(J[n - 1, n]) > 0.1  # the torque accelerates the base joint: a real column

    # Linear in the seed: a combined direction is the same combination of the columns.
    f(x0, TAU)
    seed = [0.3, -1.2, 0.5, 2.0, -0.7]
    unknowns = [vr[f"der({s})"] for s in states] + [vr["tip"]]
    combined = m.getDirectionalDerivative(unknowns, [vr[k] for k in states + ["tau"]], seed)
    assert np.max(np.abs(np.array(combined) - J @ np.array(seed))) < 1e-8 * max(1.0, np.max(np.abs(J)))
    m.terminate()
    m.freeInstance()


@pytest.mark.parametrize("fmi", [2, 3])
def test_directional_derivatives_equal_linearize(export, write_model, tmp_path, fmi):
    model = write_model("double.mech", DOUBLE)
    m, md, vr, states, _, _ = me_instance(export(model, fmi=fmi, kind="me"), tmp_path, fmi)
    J = jacobian(m, vr, states)
    m.terminate()
    m.freeInstance()
    out = tmp_path / "lin.json"
    kanesim("linearize", model, "--set", f"tau={TAU}", "--frozen", "--output", "tip", "-o", str(out))
    lin = json.loads(out.read_text())
    assert lin["inputs"] == ["tau"]
    order = [states.index(s) for s in lin["states"]]  # linearize's states in the FMU's order
    n = len(states)
    A = np.array(lin["A"])
    assert np.max(np.abs(J[:n, :n][np.ix_(order, order)] - A)) < 1e-8 * max(1.0, np.max(np.abs(A)))
    # The input's column is B's; tip's row is C and D.
    assert np.max(np.abs(J[:n, n][order] - np.array(lin["B"])[:, 0])) < 1e-8
    assert np.max(np.abs(J[n, :n][order] - np.array(lin["C"])[0])) < 1e-8
    assert abs(J[n, n] - lin["D"][0][0]) < 1e-8


@pytest.mark.parametrize("fmi", [2, 3])
@pytest.mark.parametrize("name", ["double_pendulum.mech", "fourbar.mech"])
def test_directional_derivatives_of_a_tree_and_a_closed_loop_equal_central_differences(export, tmp_path, fmi, name):
    # The examples as exported (a tree; a four-bar whose derivative projects onto its loop):
    # every column d der(y) / d y_j against central differences of fmi*GetDerivatives.
    fmu = export(os.path.join(EXAMPLES, name), fmi=fmi, kind="both")
    m, md, _ = open_instance(fmu, tmp_path / f"ex{fmi}", fmi, "me")
    caps = ET.parse(tmp_path / f"ex{fmi}" / "modelDescription.xml").getroot().find("ModelExchange").attrib
    assert caps["providesDirectionalDerivative" if fmi == 2 else "providesDirectionalDerivatives"] == "true"
    assert fmi == 2 or caps["providesAdjointDerivatives"] == "true"
    ptr = lambda a: a.ctypes.data_as(POINTER(c_double))
    n = len(md.derivatives)
    x0 = np.zeros(n)
    m.getContinuousStates(ptr(x0), n)
    get_der = m.getDerivatives if fmi == 2 else m.getContinuousStateDerivatives

    def f(x):
        x = np.ascontiguousarray(x, dtype=float)
        m.setContinuousStates(ptr(x), n)
        der = np.zeros(n)
        get_der(ptr(der), n)
        return der

    states = [u.variable.derivative.valueReference for u in md.derivatives]
    ders = [u.variable.valueReference for u in md.derivatives]
    h = 1e-5
    fd = np.zeros((n, n))
    for j in range(n):
        e = np.zeros(n)
        e[j] = h * max(1.0, abs(x0[j]))
        fd[:, j] = (f(x0 + e) - f(x0 - e)) / (2 * e[j])
    f(x0)
    J = np.array([m.getDirectionalDerivative(ders, [states[j]], [1.0]) for j in range(n)]).T
    scale = max(1.0, np.max(np.abs(J)))
    assert np.max(np.abs(J - fd)) < 1e-6 * scale, (J, fd)
    assert np.count_nonzero(np.abs(J) > 1e-3 * scale) > n  # more than der(q) = u: real columns
    m.terminate()
    m.freeInstance()


def test_fmi3_adjoint_derivatives_are_the_transposed_jacobian(export, write_model, tmp_path):
    # fmi3GetAdjointDerivative (providesAdjointDerivatives="true"): v^T J for the unknowns'
    # seeds v, J the directional derivatives' (checked against differences above).
    model = write_model("double.mech", DOUBLE)
    m, md, vr, states, _, _ = me_instance(export(model, fmi=3, kind="me"), tmp_path, 3)
    J = jacobian(m, vr, states)
    unknowns = [vr[f"der({s})"] for s in states] + [vr["tip"]]
    knowns = [vr[k] for k in states + ["tau"]]
    for v in (np.array([0.3, -1.2, 0.5, 2.0, -0.7]), np.eye(5)[4]):
        adj = m.getAdjointDerivative(unknowns, knowns, list(v), nSensitivity=len(knowns))
        assert np.max(np.abs(np.array(adj) - v @ J)) < 1e-9 * max(1.0, np.max(np.abs(J)))
    with pytest.raises(Exception):  # one seed per unknown
        m.getAdjointDerivative(unknowns, knowns, [1.0], nSensitivity=len(knowns))
    m.terminate()
    m.freeInstance()
