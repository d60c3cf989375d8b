"""Model.run against the command line (bit for bit) and against closed forms."""
import csv
import math
import subprocess

import numpy as np
import pytest

import kanesim


def cli_csv(exe, args, tmp_path):
    out = tmp_path / "out.csv"
    subprocess.run([exe, "run", *args, "-o", str(out)], check=True, capture_output=True)
    with open(out, newline="") as f:
        rows = list(csv.reader(f))
    header, body = rows[0], rows[1:]
    data = np.array([[float(x) for x in r] for r in body])  # %.17g reads back exactly
    return header, data


def same_bits(a, b):
    a = np.ascontiguousarray(a, dtype=np.float64)
    b = np.ascontiguousarray(b, dtype=np.float64)
    return a.shape == b.shape and np.array_equal(a.view(np.int64), b.view(np.int64))


@pytest.mark.parametrize(
    "model, sets, kwargs, cli_args",
    [
        ("double_pendulum.mech", {}, {}, []),
        ("double_pendulum.mech", {}, dict(stop_time=1.5, rtol=1e-10, interval=0.05, outputs=["*.q", "kinetic_energy"]),
         ["--stop-time", "1.5", "--rtol", "1e-10", "--interval", "0.05", "--output", "*.q", "--output", "kinetic_energy"]),
        ("spring_mass.mech", {"k": 80, "c": 0.25}, dict(stop_time=3, atol=1e-9),
         ["--set", "k=80", "--set", "c=0.25", "--stop-time", "3", "--atol", "1e-9"]),
        ("fourbar.mech", {}, dict(stop_time=1), ["--stop-time", "1"]),
        ("chain.mech", {}, dict(stop_time=0.5, integrator="ida"), ["--stop-time", "0.5", "--integrator", "ida"]),
    ],
)
def test_run_equals_cli_bit_for_bit(examples, kanesim_exe, tmp_path, model, sets, kwargs, cli_args):
    path = examples / model
    header, data = cli_csv(kanesim_exe, [str(path), *cli_args], tmp_path)
    r = kanesim.load(path, set=sets).run(**kwargs)
    assert header == ["time"] + r.columns
    assert same_bits(r.time, data[:, 0])
    assert same_bits(r.values, data[:, 1:])
    # run(set=...) on the plain model loads the same variant: the same numbers.
    if sets:
        r2 = kanesim.load(path).run(set=sets, **kwargs)
        assert same_bits(r2.values, r.values)


def test_undamped_oscillator_follows_the_closed_form(examples):
    # x'' = -(k/m) x, x(0) = 0.1, x'(0) = 0: x(t) = 0.1 cos(sqrt(k/m) t).
    m = kanesim.load(examples / "spring_mass.mech", set={"F0": 0, "c": 0, "k": 50, "mass": 2})
    r = m.run(stop_time=2, rtol=1e-10, atol=1e-12, interval=0.01, outputs=["slider.q"])
    exact = 0.1 * np.cos(math.sqrt(50 / 2) * r.time)
    assert np.max(np.abs(r["slider.q"] - exact)) < 1e-8
    assert r.time[0] == 0 and r.time[-1] == 2 and len(r) == 201


def test_result_columns_and_stats(examples):
    r = kanesim.load(examples / "double_pendulum.mech").run(stop_time=0.5, outputs="*.q")
    assert r.columns == ["shoulder.q", "elbow.q"]
    assert r.values.shape == (len(r.time), 2)
    assert "time" in r and "elbow.q" in r and "elbow.u" not in r
    assert r.stats["rows"] == len(r)
    assert r.stats["steps"] > 0 and r.stats["rhs_evals"] > 0
    with pytest.raises(KeyError, match="elbow.u"):
        r["elbow.u"]


def test_to_pandas(examples):
    pd = pytest.importorskip("pandas")
    r = kanesim.load(examples / "double_pendulum.mech").run(stop_time=0.2, outputs=["*.q"])
    df = r.to_pandas()
    assert isinstance(df, pd.DataFrame)
    assert list(df.columns) == ["time", "shoulder.q", "elbow.q"]
    assert np.array_equal(df["elbow.q"].to_numpy(), r["elbow.q"])


def test_check_summary(examples):
    s = kanesim.load(examples / "spring_mass.mech").check()
    assert s["model"] == "SpringMass"
    assert s["dof"] == 1 and s["nq"] == 1 and s["nu"] == 1
    assert [j["name"] for j in s["joints"]] == ["slider"]
    assert s["parameters"]["k"]["value"] == 50 and s["parameters"]["k"]["unit"] == "N/m"
    assert s["experiment"]["stop_time"] == 10
    assert s["solver"] in {"dense", "sparse", "recursive"} and s["solver_reason"]
    assert s["integrator"] in {"IDA", "CVODE", "ARKODE", "DOP853"}


def test_loads_and_set_values_of_every_kind():
    text = """
model Drop
  parameter Real h = 1;
  parameter Integer n = 2;
  World world(g = {0, -9.81, 0});
  Prismatic fall(axis = {0, 1, 0}, q(start = h * n));
  Body ball(m = 1, I = identity(3) * 0.01);
equation
  connect(world.frame_b, fall.frame_a);
  connect(fall.frame_b, ball.frame_a);
  annotation(experiment(StopTime = 1, Interval = 0.5));
end Drop;
"""
    m = kanesim.loads(text, set={"h": 0.25, "n": 4, "world.g": np.array([0.0, -1.62, 0.0])})
    r = m.run(outputs=["fall.q"], rtol=1e-10)
    # Free fall from h*n = 1 under 1.62 m/s^2: q = 1 - 0.81 t^2.
    assert np.allclose(r["fall.q"], 1 - 0.81 * r.time**2, rtol=0, atol=1e-9)
    assert m.check()["parameters"]["n"]["value"] == 4


def test_energy_check_report_measures_what_the_rows_show(examples):
    """energy_check="report" (as `kanesim run --energy-check report`): the guard's largest
    relative energy error, recomputed here from the rows' own T and V (the motion's energy
    S = max over the rows so far of T + |V - V0|; docs/integrators.md "The energy guard");
    "off" measures nothing; a damped model is not guarded, and a bad choice is a ValueError."""
    m = kanesim.load(str(examples / "double_pendulum.mech"))
    r = m.run(stop_time=5, rtol=1e-6, outputs=["kinetic_energy", "potential_energy"], energy_check="report")
    assert r.stats["energy_guard"] == "report"
    T, V = r["kinetic_energy"], r["potential_energy"]
    E = T + V
    motion = np.maximum.accumulate(T + np.abs(V - V[0]))
    size = np.maximum.accumulate(np.abs(T) + np.abs(V))
    dE = np.abs(E - E[0])
    rel = np.where(dE > 1e-11 * size, dE / motion, 0.0)
    assert rel.max() > 0
    assert r.stats["energy_error"] == pytest.approx(rel.max(), rel=1e-9)
    assert r.stats["energy_error"] < r.stats["energy_tolerance"]
    off = m.run(stop_time=5, rtol=1e-6, outputs=["kinetic_energy"], energy_check="off")
    assert off.stats["energy_guard"] == "off" and off.stats["energy_error"] == 0.0
    assert same_bits(off["kinetic_energy"], T)  # the guard never changes a row
    damped = kanesim.load(str(examples / "spring_mass.mech")).run(stop_time=1, set={"c": 0.5})
    assert damped.stats["energy_guard"].startswith("not applied")
    with pytest.raises(ValueError, match="energy_check 'sometimes': unknown \\(on, off, report\\)"):
        m.run(stop_time=1, energy_check="sometimes")


def test_start_values_from_outside_equal_the_edited_file(examples, tmp_path):
    # set={"j.q.start": x} and start={"j.q": x} run exactly what the file edited to start=x
    # runs (before: E201); a closed loop's start (fourbar) is assembled the same way.
    text = (examples / "double_pendulum.mech").read_text()
    edited = text.replace("Revolute shoulder(axis = {0, 0, 1}, q(start = pi / 2), u(start = 0))",
                          "Revolute shoulder(axis = {0, 0, 1}, q(start = 0.3), u(start = -0.7))")
    assert edited != text
    want = kanesim.loads(edited).run(stop_time=1)
    a = kanesim.load(examples / "double_pendulum.mech", set={"shoulder.q.start": 0.3, "shoulder.u.start": -0.7})
    b = kanesim.load(examples / "double_pendulum.mech", start={"shoulder.q": 0.3, "shoulder.u": -0.7})
    for m in (a, b):
        assert same_bits(m.run(stop_time=1).values, want.values)
    four = (examples / "fourbar.mech").read_text()
    four_edited = four.replace("q(start = 1.6)", "q(start = 1.5)")
    assert four_edited != four
    want4 = kanesim.loads(four_edited).run(stop_time=0.5)
    got4 = kanesim.load(examples / "fourbar.mech", start={"rocker_pivot.q": 1.5}).run(stop_time=0.5)
    assert same_bits(got4.values, want4.values)
    with pytest.raises(kanesim.ModelError) as e:
        kanesim.load(examples / "double_pendulum.mech", start={"shoulder.qq": 1})
    assert e.value.code == "E201"
