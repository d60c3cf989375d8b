"""Model.run(sensitivity=...) and Result.sensitivity: the forced oscillator's d x/d k against
its closed form, and bit for bit what `kanesim run --sensitivity` writes."""
import csv
import math
import subprocess

import numpy as np
import pytest

import kanesim


def spring_mass_x(t, k, m=2.0, c=1.0, F0=1.0, w=4.0, x0=0.1, v0=0.0):
    D = (k - m * w * w) ** 2 + (c * w) ** 2
    A, B = F0 * (k - m * w * w) / D, F0 * c * w / D
    wn = math.sqrt(k / m)
    z = c / (2 * math.sqrt(k * m))
    wd, s = wn * math.sqrt(1 - z * z), z * wn
    C1 = x0 - A
    C2 = (v0 - B * w + s * C1) / wd
    return math.exp(-s * t) * (C1 * math.cos(wd * t) + C2 * math.sin(wd * t)) + A * math.cos(w * t) + B * math.sin(w * t)


def test_stiffness_sensitivity_follows_the_closed_form(examples):
    r = kanesim.load(examples / "spring_mass.mech").run(rtol=1e-10, sensitivity=["k", "mass"])
    dx = r.sensitivity("slider.q", "k")
    assert dx.shape == r.time.shape
    h = 1e-4
    want = np.array([(spring_mass_x(t, 50 + h) - spring_mass_x(t, 50 - h)) / (2 * h) for t in r.time])
    assert np.max(np.abs(dx - want)) < 1e-6 * np.max(np.abs(want))
    assert "d(slider.u)/d(mass)" in r.columns


def test_equals_the_command_line(examples, kanesim_exe, tmp_path):
    path = examples / "double_pendulum.mech"
    r = kanesim.load(path).run(stop_time=1, sensitivity="rod1.L")
    out = tmp_path / "out.csv"
    subprocess.run([kanesim_exe, "run", str(path), "--stop-time", "1", "--sensitivity", "rod1.L", "-o", str(out)],
                   check=True, capture_output=True)
    with open(out, newline="") as f:
        rows = list(csv.reader(f))
    assert rows[0][1:] == r.columns
    cli = np.array([[float(x) for x in row[1:]] for row in rows[1:]])
    assert np.array_equal(cli, r.values)


def test_refuses_what_is_not_a_parameter(examples):
    with pytest.raises(ValueError, match="no parameter"):
        kanesim.load(examples / "double_pendulum.mech").run(sensitivity=["nosuch"])
