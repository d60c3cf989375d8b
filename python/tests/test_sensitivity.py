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


PENDULUM = """
model Pendulum "A uniform rod hanging from a pivot, released 1 mrad off the vertical"
  World world(g = {0, -9.81, 0});
  Revolute pivot(axis = {0, 0, 1}, q(start = -pi / 2 + 1e-3), u(start = 0));
  Rod rod(L = 1, m = 1);
equation
  connect(world.frame_b, pivot.frame_a);
  connect(pivot.frame_b, rod.frame_a);
end Pendulum;
"""


def test_start_value_sensitivity_of_a_pendulum_is_cos_omega_t():
    # Small amplitude a: q = -pi/2 + a cos(w t), w^2 = m g (L/2) / (m L^2/3) = 3 g / (2 L);
    # dq/dq0 = cos(w t) and du/dq0 = -w sin(w t), up to the anharmonic a^2 w t / 8 ~ 2e-6.
    r = kanesim.loads(PENDULUM).run(stop_time=3, rtol=1e-10, sensitivity="pivot.q.start")
    w = math.sqrt(3 * 9.81 / 2)
    # s(t0) = 1 by a difference of starts at q0 +/- delta: round-off eps |q0| / delta ~ 4e-11.
    assert r.sensitivity("pivot.q", "pivot.q.start")[0] == pytest.approx(1.0, abs=1e-9)
    assert np.max(np.abs(r.sensitivity("pivot.q", "pivot.q.start") - np.cos(w * r.time))) < 1e-5
    assert np.max(np.abs(r.sensitivity("pivot.u", "pivot.q.start") + w * np.sin(w * r.time))) < 1e-5 * w


def test_stats_report_the_differences_error_estimate(examples, kanesim_exe, tmp_path):
    # The forced oscillator's acceleration is proportional to 1/mass, whose central difference
    # at delta = cbrt(eps) mass is off by exactly delta^2 / (mass^2 - delta^2) ~ eps^(2/3)
    # relative: the estimate (truncation plus round-off, each about that) must cover it
    # without overstating it tenfold. And it is what `kanesim run --stats` prints.
    path = examples / "spring_mass.mech"
    r = kanesim.load(path).run(rtol=1e-10, sensitivity=["mass", "k"])
    est = r.stats["sensitivity"]
    assert list(est) == ["mass", "k"]
    e = est["mass"]
    truncation = np.finfo(float).eps ** (2 / 3)
    assert truncation <= e["dfdp_error"] / e["dfdp_scale"] < 10 * truncation
    assert e["start_scale"] == 0.0  # the start does not depend on the mass
    p = subprocess.run([kanesim_exe, "run", str(path), "--rtol", "1e-10", "--sensitivity", "mass,k", "--stats",
                        "-o", str(tmp_path / "out.csv")], check=True, capture_output=True, text=True)
    for name, e in est.items():
        line = next(x for x in p.stderr.splitlines() if x.split()[:1] == [name])
        want = (f"df/dp {e['dfdp_error']:.2g} / {e['dfdp_scale']:.2g}, (df/dy) s {e['dfdy_error']:.2g} / "
                f"{e['dfdy_scale']:.2g}, start {e['start_error']:.2g} / {e['start_scale']:.2g}")
        assert line.split(None, 1)[1] == want
