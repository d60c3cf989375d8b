"""Every NumPy array the package returns, checked against values computed without it
(closed forms, the command line's CSV read by the csv module, NumPy's own eigvals of a
hand-built A) and for its layout: 1-D or 2-D, float64 or complex128, C-contiguous, owning
its data. A module built with a pybind11 that predates the running NumPy (2.10 under
NumPy 2) made arrays of stride 0 whose every element read as the first: the layout checks
and the package's import-time probe catch that class, whatever the NumPy.

ctest runs this file under Debian's NumPy 1.x (python.pytest, python.installed) and under
the newest NumPy 2.x from PyPI (python.installed_numpy2); KANESIM_EXPECT_NUMPY says which
major version the run must have, so a venv that quietly fell back to the other fails."""
import csv
import json
import math
import os
import pathlib
import subprocess
import sys

import numpy as np
import pytest

import kanesim

# Tolerances: the time grid is start + k * interval in doubles (a few ulps of stop_time);
# the linear model comes from finite differences (docs/linearize.md: ~1e-9 relative at the
# default step); the oscillator's closed form at rtol 1e-10.
TIME_ATOL = 1e-13
LIN_RTOL = 1e-7
NUMPY_MAJOR = int(np.__version__.split(".")[0])


def assert_plain(a, dtype, ndim):
    """What every array of the package must be: its own C-contiguous data, the right type."""
    assert isinstance(a, np.ndarray)
    assert a.dtype == dtype and a.ndim == ndim
    assert a.flags.c_contiguous and a.flags.owndata
    expected = [a.itemsize]
    for n in reversed(a.shape[1:]):
        expected.insert(0, expected[0] * n)
    assert list(a.strides) == expected, f"strides {a.strides} for shape {a.shape}"


def test_numpy_is_the_expected_major_version():
    want = os.environ.get("KANESIM_EXPECT_NUMPY")
    if not want:
        pytest.skip("KANESIM_EXPECT_NUMPY not set (ctest sets it)")
    assert str(NUMPY_MAJOR) == want, f"NumPy {np.__version__}, expected {want}.x"


def cli_rows(exe, args, tmp_path):
    out = tmp_path / "rows.csv"
    subprocess.run([exe, "run", *map(str, args), "-o", str(out)], check=True, capture_output=True)
    with open(out, newline="") as f:
        rows = list(csv.reader(f))
    return rows[0], [[float(x) for x in r] for r in rows[1:]]


def test_result_arrays(examples, kanesim_exe, tmp_path):
    """Result.time is start + k * interval; .values, .columns and r[name] are the command
    line's rows; the undamped oscillator follows 0.1 cos(sqrt(k/m) t)."""
    sets = {"F0": 0, "c": 0, "k": 50, "mass": 2}
    start, stop, dt = 0.25, 1.75, 0.05
    r = kanesim.load(examples / "spring_mass.mech", set=sets).run(
        start_time=start, stop_time=stop, interval=dt, rtol=1e-10, atol=1e-12, outputs=["slider.q", "slider.u"])
    n = round((stop - start) / dt) + 1
    assert_plain(r.time, np.float64, 1)
    assert_plain(r.values, np.float64, 2)
    assert r.time.shape == (n,) and r.values.shape == (n, 2) and len(r) == n
    grid = [start + k * dt for k in range(n)]
    assert max(abs(a - b) for a, b in zip(r.time.tolist(), grid)) < TIME_ATOL
    assert len(set(r.time.tolist())) == n  # no repeated instant (a stride-0 array has one)
    header, rows = cli_rows(kanesim_exe, [examples / "spring_mass.mech", *sum((["--set", f"{k}={v}"] for k, v in
                            sets.items()), []), "--start-time", start, "--stop-time", stop, "--interval", dt,
                            "--rtol", 1e-10, "--atol", 1e-12, "--output", "slider.q", "--output", "slider.u"], tmp_path)
    assert header == ["time", "slider.q", "slider.u"] and r.columns == header[1:]
    assert all(isinstance(c, str) for c in r.columns)
    assert r.time.tolist() == [row[0] for row in rows]  # %.17g reads back exactly
    assert r.values.tolist() == [row[1:] for row in rows]
    q = r["slider.q"]
    assert q.strides == (2 * 8,) and q.tolist() == [row[1] for row in rows]
    w = math.sqrt(50 / 2)
    # The run starts at start_time from the model's start values: x = 0.1 cos(w (t - start)).
    assert max(abs(x - 0.1 * math.cos(w * (t - start))) for t, x in zip(grid, q.tolist())) < 1e-8
    assert max(abs(v + 0.1 * w * math.sin(w * (t - start))) for t, v in zip(grid, r["slider.u"].tolist())) < 1e-7


def test_result_to_pandas(examples):
    pd = pytest.importorskip("pandas")
    r = kanesim.load(examples / "double_pendulum.mech").run(stop_time=0.3, interval=0.1, outputs=["*.q"])
    df = r.to_pandas()
    assert isinstance(df, pd.DataFrame) and list(df.columns) == ["time", "shoulder.q", "elbow.q"]
    assert df["time"].tolist() == pytest.approx([0.0, 0.1, 0.2, 0.3], abs=TIME_ATOL)
    for j, name in enumerate(r.columns):
        assert df[name].tolist() == r.values[:, j].tolist()


# Two carts in series on prismatic joints (q1 the first's, q2 the second's relative to the
# first), springs k1 (world-cart 1) and k2 (cart 1-cart 2), dampers d1, d2, at rest at
# the springs' unstretched lengths. In the joint coordinates
#   M q'' + Dd q' + K q = tau,  M = [[m1 + m2, m2], [m2, m2]],  Dd = diag(d1, d2),  K = diag(k1, k2)
# so A = [[0, I], [-M^-1 K, -M^-1 Dd]], B = [[0], [M^-1]] (inputs s1.tau, s2.tau), and for
# the outputs (s1.q, s2.q, s2.u) C picks those states and D = 0.
TWO_CARTS = """
model TwoCarts
  parameter Real m1 = 2, m2 = 0.5, k1 = 40, k2 = 15, d1 = 0.8, d2 = 0.3;
  World world(g = {0, 0, 0});
  Prismatic s1(axis = {1, 0, 0}, q(start = 1));
  Prismatic s2(axis = {1, 0, 0}, q(start = 1));
  Body cart1(m = m1, I = identity(3) * 0.01);
  Body cart2(m = m2, I = identity(3) * 0.01);
  SpringDamper sd1(c = k1, d = d1, s_unstretched = 1);
  SpringDamper sd2(c = k2, d = d2, s_unstretched = 1);
equation
  connect(world.frame_b, s1.frame_a);
  connect(s1.frame_b, cart1.frame_a);
  connect(s1.frame_b, s2.frame_a);
  connect(s2.frame_b, cart2.frame_a);
  connect(world.frame_b, sd1.frame_a);
  connect(s1.frame_b, sd1.frame_b);
  connect(s1.frame_b, sd2.frame_a);
  connect(s2.frame_b, sd2.frame_b);
end TwoCarts;
"""


def two_carts_by_hand(m1=2.0, m2=0.5, k1=40.0, k2=15.0, d1=0.8, d2=0.3):
    M = np.array([[m1 + m2, m2], [m2, m2]])
    Mi = np.linalg.inv(M)
    A = np.block([[np.zeros((2, 2)), np.eye(2)], [-Mi @ np.diag([k1, k2]), -Mi @ np.diag([d1, d2])]])
    B = np.vstack([np.zeros((2, 2)), Mi])
    C = np.array([[1.0, 0, 0, 0], [0, 1, 0, 0], [0, 0, 0, 1]])
    return A, B, C, np.zeros((3, 2))


def test_linear_model_arrays():
    lm = kanesim.loads(TWO_CARTS).linearize(inputs=["s1.tau", "s2.tau"], outputs=["s1.q", "s2.q", "s2.u"])
    A, B, C, D = two_carts_by_hand()
    assert lm.states == ["s1.q", "s2.q", "s1.u", "s2.u"] and lm.n_coordinates == 2
    for name, want in zip("ABCD", (A, B, C, D)):
        got = getattr(lm, name)
        assert_plain(got, np.float64, 2)
        assert got.shape == want.shape, name
        np.testing.assert_allclose(got, want, rtol=LIN_RTOL, atol=LIN_RTOL * np.abs(want).max(), err_msg=name)
    # Eigenvalues: NumPy's of the hand-built A; two damped pairs, all four distinct.
    assert_plain(lm.eigenvalues, np.complex128, 1)
    want = np.linalg.eigvals(A)
    assert len(lm.eigenvalues) == 4 and len(set(lm.eigenvalues.tolist())) == 4
    for lam in want:
        assert np.min(np.abs(lm.eigenvalues - lam)) < LIN_RTOL * np.abs(want).max()
    assert np.all(lm.eigenvalues.real < 0) and lm.stable
    # Each mode: its eigenvalue, |lambda|, -Re/|lambda|, Im/(2 pi), and a shape v with
    # A v = lambda v and largest entry 1 (docs/linearize.md).
    assert len(lm.modes) == 4
    for k, mode in enumerate(lm.modes):
        lam = mode["eigenvalue"]
        assert lam == lm.eigenvalues[k]
        assert mode["natural_frequency"] == pytest.approx(abs(lam), rel=1e-12)
        assert mode["damping_ratio"] == pytest.approx(-lam.real / abs(lam), rel=1e-12)
        assert mode["frequency_hz"] == pytest.approx(abs(lam.imag) / (2 * math.pi), rel=1e-12)
        v = mode["shape"]
        assert_plain(v, np.complex128, 1)
        assert v.shape == (4,) and np.max(np.abs(v)) == pytest.approx(1.0, rel=1e-12)
        assert np.linalg.norm(A @ v - lam * v) < 1e-6 * np.abs(lam)


def test_pendulum_eigenvalues_are_distinct(source_dir):
    """The reproducer's case: +-i sqrt(g/l), not the first value twice."""
    lm = kanesim.load(source_dir / "tests" / "linearize" / "models" / "pendulum.mech").linearize()
    w = math.sqrt(9.81 / 0.7)
    assert_plain(lm.eigenvalues, np.complex128, 1)
    assert sorted(x.imag for x in lm.eigenvalues.tolist()) == pytest.approx([-w, w], rel=1e-9)
    for mode in lm.modes:
        s = mode["shape"].tolist()
        # v = (1, lambda) scaled to its largest entry (|lambda| = w > 1): (1 / lambda, 1)
        assert s[1] == pytest.approx(1) and s[0] == pytest.approx(1 / mode["eigenvalue"], rel=1e-9)


def test_sweep_table_arrays(examples, kanesim_exe, tmp_path):
    """Table columns: id 0..n-1 (int64), the grid's values, closed-form metrics, the command
    line's summary.csv read by the csv module; Table.to_pandas the same columns."""
    model = examples / "spring_mass.mech"
    ks = [20.0, 50.0, 80.0]
    metrics = ["max:slider.q", "cross:slider.q=0"]
    t = kanesim.sweep(kanesim.load(model, set={"F0": 0, "c": 0}), grid={"k": ks}, metrics=metrics, stop_time=1.5,
                      interval=1e-4, rtol=1e-10, threads=2)
    assert_plain(t["id"], np.int64, 1)
    assert t["id"].tolist() == [0, 1, 2]
    for name in t.columns:
        if name not in ("id", "status", "message", "method"):
            assert_plain(t[name], np.float64, 1)
            assert t[name].shape == (3,), name
    assert t["k"].tolist() == ks
    assert t["max:slider.q"].tolist() == pytest.approx([0.1] * 3, abs=1e-9)  # the start value
    # x = 0.1 cos(sqrt(k/m) t) first crosses 0 at (pi/2) sqrt(m/k), m = 2
    assert t["cross:slider.q=0"].tolist() == pytest.approx([math.pi / 2 * math.sqrt(2 / k) for k in ks], abs=1e-6)
    subprocess.run([kanesim_exe, "sweep", str(model), "--set", "F0=0", "--set", "c=0", "--grid", "k=20,50,80",
                    *sum((["--metric", m] for m in metrics), []), "--stop-time", "1.5", "--interval", "1e-4",
                    "--rtol", "1e-10", "-j", "2", "-o", str(tmp_path / "s"), "--no-progress"],
                   check=True, capture_output=True)
    with open(tmp_path / "s" / "summary.csv", newline="") as f:
        rows = list(csv.reader(f))
    assert rows[0] == t.columns
    for j, name in enumerate(t.columns):
        if name in ("id", "status", "message", "method", "wall_time"):
            continue
        cells = [r[j] for r in rows[1:]]
        assert [math.nan if c == "" else float(c) for c in cells] == pytest.approx(t[name].tolist(), nan_ok=True)


def test_sweep_table_to_pandas(examples):
    pd = pytest.importorskip("pandas")
    ks = [20.0, 50.0, 80.0]
    t = kanesim.sweep(kanesim.load(examples / "spring_mass.mech", set={"F0": 0, "c": 0}), grid={"k": ks},
                      metrics=["cross:slider.q=0"], stop_time=1.5, interval=1e-4, rtol=1e-10, threads=2)
    df = t.to_pandas()
    assert isinstance(df, pd.DataFrame) and list(df.columns) == t.columns
    assert df["k"].tolist() == ks and df["id"].tolist() == [0, 1, 2]
    assert df["status"].tolist() == ["ok"] * 3
    assert df["cross:slider.q=0"].tolist() == pytest.approx([math.pi / 2 * math.sqrt(2 / k) for k in ks], abs=1e-6)


def test_layout_probe_reads_back():
    """The import-time probe (python/src/module.cpp LayoutProbe): known values through each
    way the module makes an array."""
    vector, rows, matrix, complexes = kanesim._kanesim._layout_probe()
    assert_plain(vector, np.float64, 1)
    assert_plain(rows, np.float64, 2)
    assert_plain(matrix, np.float64, 2)
    assert_plain(complexes, np.complex128, 1)
    assert vector.tolist() == [1, 2, 3]
    assert rows.tolist() == matrix.tolist() == [[1, 2, 3], [4, 5, 6]]
    assert complexes.tolist() == [1 + 2j, 3 - 4j]
    if NUMPY_MAJOR >= 2:
        assert tuple(kanesim._kanesim._pybind11_version[:2]) >= (2, 12)


def test_no_module_with_wrong_arrays_imports():
    """The module of the tree's build (KANESIM_TREE_MODULE: build/python, Debian's pybind11)
    under this NumPy: either its arrays read back and the package imports, or the package
    refuses with an ImportError that names pybind11; never a package whose arrays are wrong."""
    tree = os.environ.get("KANESIM_TREE_MODULE")
    if not tree:
        pytest.skip("KANESIM_TREE_MODULE not set (ctest sets it)")
    so = sorted(pathlib.Path(tree, "kanesim").glob("_kanesim*.so"))
    if not so:
        pytest.skip(f"no module built in {tree}")
    # The bare extension, without the package's check (in a child: a second pybind11 module
    # of the same build in this process would register its types twice): what its arrays
    # really hold, and which pybind11 made it.
    probe = ("import importlib.util, json, sys; s = importlib.util.spec_from_file_location('_kanesim', sys.argv[1]); "
             "m = importlib.util.module_from_spec(s); s.loader.exec_module(m); v = m._layout_probe()[0]; "
             "print(json.dumps([v.tolist(), list(v.strides), list(m._pybind11_version)]))")
    raw = subprocess.run([sys.executable, "-c", probe, str(so[0])], capture_output=True, text=True, check=True)
    values, strides, built = json.loads(raw.stdout)
    reads_back = values == [1.0, 2.0, 3.0] and strides == [8]
    env = dict(os.environ, PYTHONPATH=tree)
    p = subprocess.run([sys.executable, "-c", "import kanesim; print(kanesim.__file__)"], env=env,
                       capture_output=True, text=True)
    if reads_back:
        assert p.returncode == 0, p.stderr
        assert os.path.realpath(p.stdout.strip()).startswith(os.path.realpath(os.path.join(tree, "kanesim")))
    else:
        version = ".".join(map(str, built))
        assert p.returncode != 0 and "ImportError" in p.stderr and f"pybind11 {version}" in p.stderr, p.stderr
    if NUMPY_MAJOR >= 2 and tuple(built[:2]) < (2, 12):
        assert p.returncode != 0, "a pre-2.12 pybind11 module imported under NumPy 2"
