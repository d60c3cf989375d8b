"""kanesim export --fmi 2, checked by the real client (FMPy): the FMU validates, and FMPy's
own simulation of it (Co-Simulation: kanesim's integrator in doStep; Model Exchange: FMPy's
CVODE on the exposed states and derivatives) equals `kanesim run` of the same model."""
import functools
import io
import os
import shutil
import subprocess
import zipfile

import numpy as np
import pytest
from fmpy import read_model_description, simulate_fmu
from fmpy.validation import validate_fmu

from conftest import EXAMPLES, kanesim
from fmu_models import single_pendulum

DDP = os.path.join(EXAMPLES, "damped_driven_pendulum.mech")
DOUBLE = os.path.join(EXAMPLES, "double_pendulum.mech")


def run_csv(path, *args):
    out = kanesim("run", path, *args).stdout
    return np.genfromtxt(io.StringIO(out), delimiter=",", names=True, deletechars="")


@pytest.mark.parametrize("fmi,kind,model", [(2, "cs", DDP), (2, "me", DDP), (2, "both", DOUBLE),
                                             (3, "cs", DDP), (3, "me", DDP), (3, "both", DOUBLE)])
def test_fmpy_validates_the_fmu(export, fmi, kind, model):
    # A problem here: a modelDescription.xml FMPy (and so most masters) would reject.
    assert validate_fmu(export(model, fmi=fmi, kind=kind)) == []


EVERY_EXAMPLE = sorted(f for f in os.listdir(EXAMPLES) if f.endswith(".mech"))


@pytest.mark.parametrize("fmi", [2, 3])
@pytest.mark.parametrize("name", EVERY_EXAMPLE)
def test_fmpy_validates_every_example_as_co_simulation_and_model_exchange(export, fmi, name):
    # The bar: no example (closed loops and rolling contacts included) exports a
    # description FMPy rejects; one FMU carries both kinds, so both are validated.
    assert validate_fmu(export(os.path.join(EXAMPLES, name), fmi=fmi, kind="both")) == []


def test_the_description_lists_states_derivatives_outputs_parameters_and_units(export):
    md = read_model_description(export(DDP))
    v = {x.name: x for x in md.modelVariables}
    assert float(v["hinge.q"].start) == pytest.approx(-np.pi / 2 + 0.3) and v["hinge.q"].unit == "rad"
    assert v["der(hinge.u)"].derivative is v["hinge.u"] and v["der(hinge.u)"].unit == "rad/s2"
    assert [o.variable.name for o in md.outputs] == ["tip_height", "energy_like"]
    assert v["L"].causality == "parameter" and v["L"].unit == "m" and float(v["L"].start) == 0.8
    # withDamper gates a component: structural, so fixed at export and listed as a constant.
    assert v["withDamper"].variability == "constant" and v["withDamper"].type == "Boolean"
    assert md.modelExchange and md.coSimulation and md.modelExchange.modelIdentifier == "DampedDrivenPendulum"


def test_the_fmu_loads_nothing_from_outside_it_but_the_c_and_cxx_runtime(export, tmp_path):
    # A library found outside the FMU would make it work only on machines like this one.
    with zipfile.ZipFile(export(DDP)) as z:
        z.extractall(tmp_path)
    lib = tmp_path / "binaries" / "linux64" / "DampedDrivenPendulum.so"
    dynamic = subprocess.run(["readelf", "-d", str(lib)], capture_output=True, text=True, check=True).stdout
    assert "Library rpath: [$ORIGIN]" in dynamic
    for line in subprocess.run(["ldd", str(lib)], capture_output=True, text=True, check=True).stdout.splitlines():
        if "=>" not in line:
            continue
        name, path = line.split("=>")[0].strip(), line.split("=>")[1].split()[0]
        system = name.split(".so")[0] in ("libc", "libm", "libstdc++", "libgcc_s", "libpthread", "libdl")
        assert system or path.startswith(str(lib.parent)), line


# Every example (closed loops, rolling contacts, regularized friction, meshes) over a short
# window at rtol 1e-9 on both sides, on the example's own output grid: the FMU's states and
# outputs against `kanesim run`'s columns of the same names. Bounds per kind, on
# max|fmu - run| / (1 + max|run|): Co-Simulation steps kanesim's own integrator, so only the
# communication points differ (measured <= 4.1e-9, spring_mass); Model Exchange integrates
# with FMPy's CVODE, a second method (measured <= 4.6e-8, chain's j[7].u). The examples with
# events (bouncing_ball, stick_slip, pendulum_stop) are compared on the output grid only: an
# event's two rows (left and right limits) are written by the run and by FMPy differently;
# test_events.py and test_cosimulation_events.py compare the events themselves.
WINDOW = 0.4
BOUND = {"CoSimulation": 1e-7, "ModelExchange": 1e-6}


@functools.lru_cache(maxsize=None)
def window_run(path, interval):
    return run_csv(path, "--stop-time", str(WINDOW), "--rtol", "1e-9", "--interval", str(interval))


def on_grid(rows, interval):
    """The rows at the multiples of `interval` (the last of several at one time: an event's
    right limit)."""
    k = np.round(rows["time"] / interval)
    at = np.abs(rows["time"] - k * interval) <= 1e-12 * np.maximum(1.0, np.abs(rows["time"]))
    keep = at & np.append(rows["time"][1:] != rows["time"][:-1], True)
    return rows[keep]


def assert_fmpy_equals_run(fmu, fmi_type, ref, stop, interval):
    """The FMU's states and outputs, simulated by FMPy, against the run's columns `ref`."""
    md = read_model_description(fmu)
    states = {v.derivative.name for v in md.modelVariables if v.derivative is not None}
    names = [v.name for v in md.modelVariables if v.name in states or v.causality == "output"]
    assert names and set(names) <= set(ref.dtype.names), names
    r = simulate_fmu(fmu, fmi_type=fmi_type, stop_time=stop, output_interval=interval, relative_tolerance=1e-9,
                     output=names)
    r, ref = on_grid(r, interval), on_grid(ref, interval)
    assert len(r) == len(ref) and np.allclose(r["time"], ref["time"], atol=1e-12)
    for n in names:
        err = np.max(np.abs(r[n] - ref[n])) / (1 + np.max(np.abs(ref[n])))
        assert err < BOUND[fmi_type], (n, err)


@pytest.mark.parametrize("fmi_type", ["CoSimulation", "ModelExchange"])
@pytest.mark.parametrize("fmi", [2, 3])
@pytest.mark.parametrize("name", EVERY_EXAMPLE)
def test_fmpy_simulation_of_every_example_equals_kanesim_run(export, name, fmi, fmi_type):
    path = os.path.join(EXAMPLES, name)
    fmu = export(path, fmi=fmi, kind="both")
    interval = float(read_model_description(fmu).defaultExperiment.stepSize)
    assert_fmpy_equals_run(fmu, fmi_type, window_run(path, interval), WINDOW, interval)


def test_parameters_set_by_the_master_equal_set_on_the_command_line(export):
    # A tunable parameter set through the FMU must change the model as --set does.
    ref = run_csv(DDP, "--stop-time", "2", "--rtol", "1e-9", "--set", "L=0.5", "--set", "d=0.2")
    r = simulate_fmu(export(DDP), fmi_type="CoSimulation", stop_time=2, output_interval=0.02,
                     relative_tolerance=1e-9, start_values={"L": 0.5, "d": 0.2}, output=["hinge.q", "tip_height"])
    for name in ["hinge.q", "tip_height"]:
        assert np.max(np.abs(r[name] - ref[name])) < 2e-5, name


def test_fmi3_lists_time_as_the_independent_variable_and_derivatives_by_value_reference(export):
    md = read_model_description(export(DDP, fmi=3))
    v = {x.name: x for x in md.modelVariables}
    assert md.fmiVersion == "3.0" and v["time"].causality == "independent"
    assert v["der(hinge.q)"].derivative is v["hinge.q"]
    with zipfile.ZipFile(export(DDP, fmi=3)) as z:
        assert "binaries/x86_64-linux/DampedDrivenPendulum.so" in z.namelist()


STOPPED = single_pendulum("Stopped", "A pendulum that hits an end stop", q_min=-0.5, q_max=0.5)


def test_end_stops_are_handled_in_co_simulation(export, write_model, tmp_path):
    # (Model Exchange: test_events.py.)
    model = write_model("stopped.mech", STOPPED)
    # Co-Simulation steps with the run's event handling: the impacts as `kanesim run` has them.
    ref = run_csv(model, "--stop-time", "2", "--rtol", "1e-9")
    res = simulate_fmu(export(model, kind="cs"), stop_time=2, output_interval=0.002, relative_tolerance=1e-9,
                       output=["hinge.q", "hinge.u"])
    assert np.min(res["hinge.q"]) > -0.5 - 1e-6 and np.max(res["hinge.q"]) < 0.5 + 1e-6
    # The run's rows on its grid (every 4 ms; the two rows of each impact left out) against
    # the FMU's rows at the same instants.
    k = np.round(ref["time"] / 0.002).astype(int)
    on_grid = np.abs(k * 0.002 - ref["time"]) < 1e-12
    assert np.max(np.abs(res["hinge.q"][k[on_grid]] - ref["hinge.q"][on_grid])) < 1e-4


def test_kanesim_export_rejects_what_it_cannot_export(tmp_path):
    r = kanesim("export", DDP, "--fmi", "4", "-o", str(tmp_path / "x.fmu"), check=False)
    assert r.returncode == 1
    r = kanesim("export", str(tmp_path / "missing.mech"), "--fmi", "2", "-o", str(tmp_path / "x.fmu"), check=False)
    assert r.returncode == 1 and not (tmp_path / "x.fmu").exists()


# Units of every kind of variable, from the model's unit check: a spherical joint's quaternion
# ("1") and rates, a prismatic joint, parameters in N.m/rad and mm (a factor), an output
# whose unit is inferred (m), an input's unit attribute (N); and, declaring none, a parameter
# whose unit is inferred from its binding (half_gap: mm), a parameter and an input inferred
# from their use beside a force (preload, nudge: N).
UNITS = """
model Units
  input Real push(unit = "N");
  input Real nudge;
  parameter Real k(unit = "N/m") = 2;
  parameter Real c(unit = "N.m/rad") = 0.5;
  parameter Real gap(unit = "mm") = 5;
  parameter Real half_gap = gap / 2;
  parameter Real preload = 0.1;
  World world;
  Spherical ball;
  Rod rod(L = 1, m = 1);
  Body hub(m = 0.1, I = diagonal({0.01, 0.01, 0.01}));
  Prismatic slide(axis = {1, 0, 0});
  Body b(m = 1);
  output Real height = rod.frame_b.r[2];
equation
  connect(world.frame_b, ball.frame_a);
  connect(ball.frame_b, rod.frame_a);
  connect(ball.frame_b, hub.frame_a);
  connect(world.frame_b, slide.frame_a);
  connect(slide.frame_b, b.frame_a);
  slide.tau = -k * slide.q + push + preload + nudge;
end Units;
"""


@pytest.mark.parametrize("fmi", [2, 3])
def test_units_and_their_definitions_come_from_the_unit_check(export, write_model, fmi):
    fmu = export(write_model("units.mech", UNITS), fmi=fmi)
    assert validate_fmu(fmu) == []
    md = read_model_description(fmu)
    unit = {x.name: x.unit for x in md.modelVariables}
    assert unit["ball.q[1]"] == "1" and unit["der(ball.q[1])"] == "1/s"
    assert unit["ball.u[2]"] == "rad/s" and unit["der(ball.u[2])"] == "rad/s2"
    assert unit["slide.q"] == "m" and unit["der(slide.u)"] == "m/s2"
    assert unit["c"] == "N.m/rad" and unit["gap"] == "mm" and unit["height"] == "m" and unit["push"] == "N"
    # Declared nowhere, inferred by the check (without it an FMI tool shows them unitless).
    assert unit["half_gap"] == "mm" and unit["preload"] == "N" and unit["nudge"] == "N"
    base = {u.name: u.baseUnit for u in md.unitDefinitions}
    exps = lambda b: {a: int(getattr(b, a)) for a in ("kg", "m", "s", "A", "K", "mol", "cd", "rad")
                      if getattr(b, a) not in (None, 0, "0")}
    assert exps(base["N.m/rad"]) == {"kg": 1, "m": 2, "s": -2, "rad": -1}
    assert exps(base["mm"]) == {"m": 1} and float(base["mm"].factor) == pytest.approx(1e-3)
    assert exps(base["rad/s2"]) == {"rad": 1, "s": -2} and exps(base["1"]) == {}
    assert exps(base["N"]) == {"kg": 1, "m": 1, "s": -2}


def test_an_input_in_the_wrong_unit_is_refused_by_the_unit_check(write_model, tmp_path):
    # The unit check reads an input's declared unit as any variable's: N.m added to a force.
    path = write_model("units.mech", UNITS.replace('push(unit = "N")', 'push(unit = "N.m")'))
    r = kanesim("export", path, "--fmi", "2", "-o", str(tmp_path / "u.fmu"), check=False)
    assert r.returncode == 1 and "units.mech:" in r.stderr and "N.m" in r.stderr, r.stderr


MESHES = os.path.join(EXAMPLES, "slider_crank_meshes.mech")


@pytest.mark.parametrize("fmi", [2, 3])
def test_an_fmu_of_a_mesh_model_carries_its_meshes_and_runs_where_the_sources_are_gone(fmi, tmp_path):
    # The example with its crank let go (falling under gravity: the motion depends on the
    # meshes' mass properties), exported from a copy that is then deleted, and simulated
    # from another folder: the meshes can only come from inside the FMU.
    src = tmp_path / "src"
    shutil.copytree(os.path.join(EXAMPLES, "meshes"), src / "meshes")
    with open(MESHES) as f:
        text = f.read()
    assert "  crank_pivot.q = omega * time;\n" in text
    (src / "free.mech").write_text(text.replace("  crank_pivot.q = omega * time;\n", ""))
    ref = run_csv(str(src / "free.mech"), "--stop-time", "0.2", "--rtol", "1e-9", "--interval", "0.002")
    fmu = tmp_path / "made.fmu"
    kanesim("export", str(src / "free.mech"), "--fmi", str(fmi), "-o", str(fmu))
    shutil.rmtree(src)
    (tmp_path / "elsewhere").mkdir()
    fmu = shutil.move(str(fmu), tmp_path / "elsewhere" / "slider.fmu")
    with zipfile.ZipFile(fmu) as z:
        assert sorted(n for n in z.namelist() if n.endswith(".stl")) == [
            "resources/files/1-crank.stl", "resources/files/2-rod.stl", "resources/files/3-slider.stl"]
    assert validate_fmu(fmu) == []
    for fmi_type in ["CoSimulation", "ModelExchange"]:
        assert_fmpy_equals_run(fmu, fmi_type, ref, 0.2, 0.002)
