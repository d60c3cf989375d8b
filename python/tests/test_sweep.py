"""kanesim.sweep against `kanesim sweep`: the same rows, wall time aside."""
import csv
import subprocess

import numpy as np
import pytest

import kanesim


def read_summary(path):
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    return rows[0], rows[1:]


def test_sweep_equals_the_command_line(examples, kanesim_exe, tmp_path):
    model = examples / "spring_mass.mech"
    metrics = ["final:slider.q", "max:slider.q", "cross:slider.q=0", "mean:slider.u"]
    subprocess.run([kanesim_exe, "sweep", str(model), "--set", "F0=0", "--grid", "k=10:30:70", "--grid", "mass=1,2",
                    *sum((["--metric", x] for x in metrics), []), "--stop-time", "3", "-j", "2",
                    "-o", str(tmp_path / "out"), "--no-progress"], check=True, capture_output=True)
    header, rows = read_summary(tmp_path / "out" / "summary.csv")
    t = kanesim.sweep(kanesim.load(model, set={"F0": 0}), grid={"k": [10, 40, 70], "mass": [1, 2]},
                      metrics=metrics, stop_time=3, threads=2)
    assert t.columns == header
    assert len(t) == len(rows) == 6 and t.failed == 0
    assert list(t["k"]) == [10, 10, 40, 40, 70, 70] and list(t["mass"]) == [1, 2] * 3
    for j, name in enumerate(header):
        if name == "wall_time":
            continue
        column = [r[j] for r in rows]
        if name in ("status", "message", "method"):
            assert t[name] == column, name
        else:
            expected = np.array([float(c) if c else np.nan for c in column])
            assert np.array_equal(t[name], expected, equal_nan=True), name


def test_sweep_metric_follows_the_closed_form(examples):
    # Undamped, unforced: x = 0.1 cos(sqrt(k/m) t) first crosses 0 at t = (pi/2) sqrt(m/k).
    m = kanesim.load(examples / "spring_mass.mech", set={"F0": 0, "c": 0})
    t = kanesim.sweep(m, samples={"k": [20, 50, 80], "mass": [2, 2, 1]}, metrics=["cross:slider.q=0"],
                      stop_time=1.5, interval=1e-4, rtol=1e-10, threads=2)
    exact = np.pi / 2 * np.sqrt(np.array([2, 2, 1]) / np.array([20, 50, 80]))
    assert np.allclose(t["cross:slider.q=0"], exact, atol=1e-6)
    assert t["status"] == ["ok"] * 3


def test_sweep_errors(examples):
    m = kanesim.load(examples / "spring_mass.mech")
    with pytest.raises(ValueError, match="no parameter 'kk'"):
        kanesim.sweep(m, grid={"kk": [1, 2]})
    with pytest.raises(ValueError, match="no signal"):
        kanesim.sweep(m, grid={"k": [1, 2]}, metrics=["max:nothing.q"])
    with pytest.raises(ValueError, match="same length"):
        kanesim.sweep(m, samples={"k": [1, 2], "mass": [1]})
    with pytest.raises(ValueError, match="no scenarios"):
        kanesim.sweep(m)
    with pytest.raises(ValueError, match="energy_check 'sometimes': unknown \\(on, off, report\\)"):
        kanesim.sweep(m, grid={"k": [1, 2]}, energy_check="sometimes")


def test_sweep_failed_scenarios_are_rows(source_dir):
    m = kanesim.load(source_dir / "tests" / "sim" / "data" / "nan_torque.mech")
    t = kanesim.sweep(m, grid={"rod.m": [1, 2]}, metrics=["final:hinge.q"])
    assert t.failed == 2 and t["status"] == ["failed", "failed"]
    assert np.all((t["fail_time"] >= 0.5) & (t["fail_time"] <= 0.6))


def test_ctrl_c_stops_a_sweep(examples):
    import _thread
    import threading
    import time

    m = kanesim.load(examples / "spring_mass.mech")
    timer = threading.Timer(0.2, _thread.interrupt_main)
    t0 = time.perf_counter()
    timer.start()
    try:
        with pytest.raises(KeyboardInterrupt):
            kanesim.sweep(m, grid={"k": list(range(1, 20001))}, stop_time=10, threads=2)  # ~ a minute in all
    finally:
        timer.cancel()
    assert time.perf_counter() - t0 < 5
