"""Model.linearize: the pendulum's closed form, bit-for-bit agreement with `kanesim
linearize -o`, the operating points (at=, equilibrium=, set=) and the errors."""
import json
import math
import subprocess
import threading
import warnings

import numpy as np
import pytest

import kanesim

G, L, M = 9.81, 0.7, 2.0  # tests/linearize/models/pendulum.mech


@pytest.fixture(scope="module")
def pendulum_path(source_dir):
    return source_dir / "tests" / "linearize" / "models" / "pendulum.mech"


@pytest.fixture(scope="module")
def pendulum(pendulum_path):
    return kanesim.load(pendulum_path)


def _cli_json(exe, tmp_path, *args):
    out = tmp_path / "lin.json"
    subprocess.run([exe, "linearize", *[str(a) for a in args], "-o", str(out)], check=True, capture_output=True)
    with open(out) as f:
        return json.load(f)


def _none_to_nan(rows):
    return np.array([[math.nan if x is None else x for x in row] for row in rows], dtype=float)


def _assert_same_as_cli(lm, d):
    """Every number of the JSON (17 significant digits: read back exactly) equals Python's."""
    assert lm.states == d["states"] and lm.n_coordinates == d["n_coordinates"]
    assert lm.inputs == d["inputs"] and lm.outputs == d["outputs"]
    assert lm.time == d["time"]
    for name in "ABCD":
        want = _none_to_nan(d[name]).reshape(getattr(lm, name).shape)
        np.testing.assert_array_equal(getattr(lm, name), want, err_msg=name)
    ev = np.array([complex(re, im) for re, im in d["eigenvalues"]])
    np.testing.assert_array_equal(lm.eigenvalues, ev)
    assert len(lm.modes) == len(d["modes"])
    for mine, theirs in zip(lm.modes, d["modes"]):
        assert mine["eigenvalue"] == complex(*theirs["eigenvalue"])
        assert mine["natural_frequency"] == theirs["natural_frequency"]
        assert mine["frequency_hz"] == theirs["frequency_hz"]
        assert mine["damping_ratio"] == theirs["damping_ratio"]
        assert [list(x) for x in mine["dominant"]] == theirs["dominant"]
        np.testing.assert_array_equal(mine["shape"], np.array([complex(re, im) for re, im in theirs["shape"]]))
    assert lm.ignorable == d["ignorable"]
    assert lm.held == d["held"]
    for key in ("step", "A", "BCD", "unsteady", "widened"):
        assert lm.accuracy[key] == d["accuracy"][key], key


def test_pendulum_closed_form(pendulum):
    lm = pendulum.linearize(inputs=["hinge.tau"], outputs=["tip_y"])
    assert lm.states == ["hinge.q", "hinge.u"] and lm.n_coordinates == 1
    assert lm.A.shape == (2, 2) and lm.B.shape == (2, 1) and lm.C.shape == (1, 2) and lm.D.shape == (1, 1)
    w = math.sqrt(G / L)
    np.testing.assert_allclose(lm.A, [[0, 1], [-G / L, 0]], atol=1e-9)
    assert lm.B[1, 0] == pytest.approx(1 / (M * L * L), rel=1e-12)
    assert lm.eigenvalues.dtype == np.complex128
    np.testing.assert_allclose(sorted(lm.eigenvalues.imag), [-w, w], rtol=1e-11)
    assert np.all(np.abs(lm.eigenvalues.real) < 1e-9)
    assert lm.modes[0]["dominant"][0][0] == "hinge.q"
    assert lm.modes[0]["natural_frequency"] == pytest.approx(w, rel=1e-11)
    assert lm.accuracy["A"] < 1e-9 and lm.equilibrium is None and not lm.stable
    # y = tip_y = l sin(q) - l about q = -pi/2: dy/dq = l cos(-pi/2) = 0, dy/du = 0
    np.testing.assert_allclose(lm.C, [[0, 0]], atol=1e-9)


def test_equals_cli_json(pendulum, pendulum_path, kanesim_exe, tmp_path):
    lm = pendulum.linearize(inputs=["hinge.tau", "l"], outputs=["tip_y"])
    d = _cli_json(kanesim_exe, tmp_path, pendulum_path, "--input", "hinge.tau", "--input", "l", "--output", "tip_y")
    _assert_same_as_cli(lm, d)


def test_tiny_step_is_widened_and_said(pendulum, pendulum_path, kanesim_exe, tmp_path):
    """A step that rounding would swallow is widened, said in accuracy["widened"] (as in the
    CLI's JSON), and the eigenvalues still have the closed form +-i sqrt(g/l)."""
    lm = pendulum.linearize(step=1e-16)
    assert set(lm.accuracy["widened"]) == {"hinge.q", "hinge.u"}
    assert all(used > 1e-16 for used in lm.accuracy["widened"].values())
    np.testing.assert_allclose(sorted(lm.eigenvalues.imag), [-math.sqrt(G / L), math.sqrt(G / L)], rtol=1e-5)
    assert lm.accuracy["A"] <= 1e-5
    _assert_same_as_cli(lm, _cli_json(kanesim_exe, tmp_path, pendulum_path, "--step", "1e-16"))
    assert pendulum.linearize().accuracy["widened"] == {}


def test_equilibrium_and_set_equal_cli(examples, kanesim_exe, tmp_path):
    m = kanesim.load(examples / "fourbar.mech")
    lm = m.linearize(equilibrium=True)
    assert lm.equilibrium["residual"] < 1e-10 and lm.equilibrium["iterations"] > 0
    assert [name for name, _ in lm.equilibrium["moved"]][0] == "crank_pivot.q"
    _assert_same_as_cli(lm, _cli_json(kanesim_exe, tmp_path, examples / "fourbar.mech", "--equilibrium"))
    # set= and at= as --set and --at
    disk = kanesim.load(examples / "rolling_disk_upright.mech")
    lm = disk.linearize(set={"v": 0.5}, at=0.25)
    assert lm.time == pytest.approx(0.25, abs=0)
    _assert_same_as_cli(lm, _cli_json(kanesim_exe, tmp_path, examples / "rolling_disk_upright.mech",
                                      "--set", "v=0.5", "--at", "0.25"))


def test_rolling_disk_lean_mode(examples):
    # Upright disk at v = 0.5 m/s (below sqrt(g a / 3)): lambda^2 = (4 g / a - 12 v^2 / a^2) / 5
    m = kanesim.load(examples / "rolling_disk_upright.mech")
    a = m.check()["parameters"]["a"]["value"]
    v = 0.5
    lam2 = (4 * 9.81 / a - 12 * v * v / (a * a)) / 5
    lm = m.linearize(set={"v": v})
    assert max(lm.eigenvalues.real) == pytest.approx(math.sqrt(lam2), rel=1e-8)
    assert set(lm.ignorable) >= {"px.q", "pz.q"}


def test_bad_input_is_model_error(pendulum):
    with pytest.raises(kanesim.ModelError) as e:
        pendulum.linearize(inputs=["nosuch.tau"])
    assert "nosuch.tau" in str(e.value)
    with pytest.raises(kanesim.ModelError):
        pendulum.linearize(outputs=["nosuch.q"])


def test_no_equilibrium_is_simulation_error(pendulum_path):
    m = kanesim.load(pendulum_path, set={"tau0": 20})  # more than m g l = 13.73 N.m
    with pytest.raises(kanesim.SimulationError) as e:
        m.linearize(equilibrium=True)
    assert "equilibrium" in str(e.value) and e.value.result is None
    # without equilibrium=True the motion at t = 0.3 is no equilibrium nor steady motion
    # ("A changes by 2.7e-02"): refused like the command line's exit 2, with the time ...
    with pytest.raises(kanesim.SimulationError, match="neither an equilibrium") as e:
        m.linearize(at=0.3)
    assert e.value.time == pytest.approx(0.3) and "frozen=True" in str(e.value) and e.value.result is None
    # ... unless frozen=True accepts the frozen instant (the command line's --frozen)
    with pytest.warns(kanesim.KanesimWarning, match="neither an equilibrium"):
        lm = m.linearize(at=0.3, frozen=True)
    assert lm.A.shape == (2, 2) and lm.accuracy["unsteady"] > 1e-3
    with pytest.warns(kanesim.KanesimWarning, match="neither an equilibrium"):
        m.linearize(at=0.3, set={"tau0": 1}, frozen=True)  # through with_set
    with pytest.raises(kanesim.SimulationError, match="neither an equilibrium"):
        m.linearize(at=0.3, set={"tau0": 1})


def test_bad_settings(pendulum):
    with pytest.raises(ValueError):
        pendulum.linearize(step=0)
    with pytest.raises(ValueError):
        pendulum.linearize(step=0.5)
    with pytest.raises(ValueError):
        pendulum.linearize(at=float("nan"))
    with pytest.raises(TypeError):
        pendulum.linearize(at="soon")


def test_threads_give_the_same_model(examples):
    m = kanesim.load(examples / "fourbar.mech")
    results = [None] * 3

    def work(i):
        results[i] = m.linearize(equilibrium=True)

    threads = [threading.Thread(target=work, args=(i,)) for i in range(3)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for r in results[1:]:
        np.testing.assert_array_equal(r.A, results[0].A)
        np.testing.assert_array_equal(r.eigenvalues, results[0].eigenvalues)


def test_model_inputs_take_their_operating_values(kanesim_exe, tmp_path, source_dir):
    # A rod held by the input torque tau0: the equilibrium cos q* = 2 tau0 / (m g L) and
    # A, B, D there (closed form); bit for bit `kanesim linearize --set tau=2`. With tau
    # read as 0 the rod would hang at q* = -pi/2 (another A).
    path = source_dir / "tests" / "data" / "driven_pendulum.mech"  # shared with tests/linearize/model_inputs_test.py
    model = kanesim.load(path)
    lm = model.linearize(equilibrium=True, inputs={"tau": 2.0}, outputs=["twice"])
    m, length, g, tau0 = 1.5, 0.8, 9.81, 2.0
    inertia = m * length**2 / 3
    q = -math.acos(2 * tau0 / (m * g * length))
    assert lm.inputs == ["tau"]
    np.testing.assert_allclose(lm.A, [[0, 1], [m * g * length / 2 * math.sin(q) / inertia, 0]], rtol=1e-7, atol=1e-9)
    np.testing.assert_allclose(lm.B, [[0], [1 / inertia]], rtol=1e-7)
    np.testing.assert_allclose(lm.D, [[2]], rtol=1e-7)
    _assert_same_as_cli(lm, _cli_json(kanesim_exe, tmp_path, path, "--equilibrium", "--set", "tau=2",
                                      "--output", "twice"))
    # At a time, the motion to it under the held input, as --at with --set.
    with warnings.catch_warnings():  # a moving rod: the frozen instant's warning
        warnings.simplefilter("ignore")
        lm = model.linearize(at=0.3, inputs={"tau": 2.0, "j.tau": None}, frozen=True)
    d = _cli_json(kanesim_exe, tmp_path, path, "--at", "0.3", "--set", "tau=2", "--input", "j.tau", "--frozen")
    _assert_same_as_cli(lm, d)


def test_a_model_input_without_a_value_or_an_unknown_one_is_a_model_error(source_dir):
    model = kanesim.load(source_dir / "tests" / "data" / "driven_pendulum.mech")
    with pytest.raises(kanesim.ModelError, match="input 'tau' has no value"):
        model.linearize(equilibrium=True)
    with pytest.raises(kanesim.ModelError, match="'nosuch' is not one of the model's inputs"):
        model.linearize(equilibrium=True, inputs={"tau": 1.0, "nosuch": 2.0})


# Two rods, the first resting on its stop (gravity presses it onto q_min = 0), the second
# hanging: the held joint is no state, and the second rod swings alone about the first's tip,
# omega^2 = m g (L2 / 2) / (m L2^2 / 3) = 3 g / (2 L2) (tests/linearize/hybrid_test.cpp's model).
HELD = """model Held
  World world(g = {0, -9.81, 0});
  Revolute j1(axis = {0, 0, 1}, q(start = 0), q_min = 0);
  Rod r1(L = 1, m = 1);
  Revolute j2(axis = {0, 0, 1}, q(start = -1.5707963267948966));
  Rod r2(L = 0.8, m = 0.7);
equation
  connect(world.frame_b, j1.frame_a);
  connect(j1.frame_b, r1.frame_a);
  connect(r1.frame_b, j2.frame_a);
  connect(j2.frame_b, r2.frame_a);
end Held;
"""


def test_a_joint_resting_on_its_stop_is_held_and_no_state(kanesim_exe, tmp_path):
    path = tmp_path / "held.mech"
    path.write_text(HELD)
    lm = kanesim.load(path).linearize()
    assert lm.held == ["j1 on q_min"]
    assert lm.states == ["j2.q", "j2.u"]
    w = math.sqrt(3 * 9.81 / (2 * 0.8))
    assert sorted(lm.eigenvalues.imag) == pytest.approx([-w, w], rel=1e-7)
    assert np.all(np.abs(lm.eigenvalues.real) < 1e-7 * w)
    _assert_same_as_cli(lm, _cli_json(kanesim_exe, tmp_path, path))
