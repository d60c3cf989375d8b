"""kanesim.load("robot.urdf"): the URDF translated in memory as `kanesim import` writes it
(docs/import.md). If these fail, Python loads a URDF differently from the command line, or
its mistakes arrive without their code and line."""
import os
import subprocess

import numpy as np
import pytest

import kanesim

ROOT = os.environ.get("KANESIM_SOURCE_DIR", os.path.join(os.path.dirname(__file__), "..", ".."))
URDF = os.path.join(ROOT, "tests", "import", "data", "ur5_robot.urdf")


def test_urdf_loads_and_runs_as_its_imported_text():
    kanesim_exe = os.environ.get("KANESIM_EXE")
    if not kanesim_exe:
        pytest.skip("KANESIM_EXE not set")
    text = subprocess.run([kanesim_exe, "import", URDF], capture_output=True, text=True, check=True).stdout
    direct = kanesim.load(URDF).run(stop_time=0.1, interval=0.05)
    imported = kanesim.loads(text, name=URDF + ".mech").run(stop_time=0.1, interval=0.05)
    assert direct.columns == imported.columns and "shoulder_pan_joint.q" in direct.columns
    # The same text, the same arithmetic: equal to the last bit.
    assert np.array_equal(direct.values, imported.values)


def test_urdf_error_has_code_and_line(tmp_path):
    bad = tmp_path / "bad.urdf"
    bad.write_text('<robot name="r">\n  <link name="a"/>\n  <joint name="j" type="hinge"/>\n</robot>\n')
    with pytest.raises(kanesim.ModelError) as e:
        kanesim.load(bad)
    assert "bad.urdf:3:" in str(e.value) and "error[U408]" in str(e.value)


def test_floating_gives_the_root_a_free_base():
    solo = os.path.join(ROOT, "tests", "import", "data", "solo12.urdf")
    fixed = kanesim.load(solo)
    free = kanesim.load(solo, floating=True, package_path=[ROOT])
    assert "root_joint.q[1]" not in fixed.signals
    assert "root_joint.q[7]" in free.signals
    # Released from rest, the free quadruped falls: z'' = -g at the start (no contact).
    r = free.run(stop_time=0.1, interval=0.1, outputs=["root_joint.q[3]"])
    assert r["root_joint.q[3]"][-1] == pytest.approx(-9.81 * 0.1**2 / 2, rel=1e-6)


def test_limits_are_end_stops_unless_ignored(tmp_path):
    # A slider falling from q = 0 rests on its lower limit -0.5 (reached at sqrt(2 h / g));
    # limits="ignore" (as Pinocchio reads the file) lets it fall freely: q(1) = -g / 2.
    urdf = tmp_path / "slider.urdf"
    urdf.write_text(
        '<robot name="s">\n  <link name="base"/>\n'
        '  <link name="m"><inertial><mass value="2"/><inertia ixx="1" iyy="1" izz="1"/></inertial></link>\n'
        '  <joint name="j" type="prismatic"><parent link="base"/><child link="m"/><axis xyz="0 0 1"/>'
        '<limit lower="-0.5" upper="1" effort="1" velocity="1"/></joint>\n</robot>\n')
    stopped = kanesim.load(urdf).run(stop_time=1, interval=0.01, outputs=["j.q"])
    assert min(stopped["j.q"]) == -0.5 and stopped["j.q"][-1] == -0.5
    free = kanesim.load(urdf, limits="ignore").run(stop_time=1, interval=0.01, outputs=["j.q"])
    assert free["j.q"][-1] == pytest.approx(-9.81 / 2, rel=1e-6)
    with pytest.raises(ValueError):
        kanesim.load(urdf, limits="soft")
