"""Issue 40: named frames as signals. A spatial double pendulum's tip frame (a declared
`Frame tool0`) and a leaf FixedTranslation's frame_b against closed-form kinematics of the
joint angles and speeds in the same rows."""
import warnings

import numpy as np

import kanesim

MODEL = """model Tip
  World world(g = {0, -9.81, 0});
  Revolute shoulder(axis = {0, 0, 1}, q(start = 0.7), u(start = 1.3));
  Rod rod1(L = 1, m = 1);
  Revolute elbow(axis = {0, 1, 0}, q(start = -0.4), u(start = 2.1));
  Rod rod2(L = 1, m = 1);
  Frame tool0;
  FixedTranslation off(r = {0, 0.5, 0});
equation
  connect(world.frame_b, shoulder.frame_a);
  connect(shoulder.frame_b, rod1.frame_a);
  connect(rod1.frame_b, elbow.frame_a);
  connect(elbow.frame_b, rod2.frame_a);
  connect(rod2.frame_b, tool0);
  connect(tool0, off.frame_a);
end Tip;
"""


def rot(axis, angle):
    """Rodrigues: the rotation by angle about the unit axis."""
    a = np.asarray(axis, float)
    K = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    return np.eye(3) + np.sin(angle) * K + (1 - np.cos(angle)) * K @ K


def test_frame_signals_equal_closed_form_kinematics():
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a leaf frame_b must not warn (W301 before)
        m = kanesim.loads(MODEL)
    names = m.signals
    for s in ["tool0.r[1]", "tool0.R[2,3]", "tool0.v[3]", "tool0.w[1]", "off.frame_b.r[2]", "off.frame_b.w[3]"]:
        assert s in names, s
    frame = [f"tool0.r[{k}]" for k in (1, 2, 3)] + [f"tool0.R[{i},{j}]" for i in (1, 2, 3) for j in (1, 2, 3)]
    frame += [f"tool0.v[{k}]" for k in (1, 2, 3)] + [f"tool0.w[{k}]" for k in (1, 2, 3)]
    frame += [f"off.frame_b.{x}[{k}]" for x in "rvw" for k in (1, 2, 3)]
    r = m.run(stop_time=1.5, interval=0.05, outputs=["shoulder.q", "shoulder.u", "elbow.q", "elbow.u"] + frame)
    z, y, x = np.array([0, 0, 1.0]), np.array([0, 1.0, 0]), np.array([1.0, 0, 0])
    worst = 0.0
    for i in range(len(r)):
        q1, u1, q2, u2 = (r[n][i] for n in ("shoulder.q", "shoulder.u", "elbow.q", "elbow.u"))
        R1 = rot(z, q1)
        R2 = R1 @ rot(y, q2)
        p_elbow = R1 @ x
        p_tip = p_elbow + R2 @ x
        w1 = z * u1
        w2 = w1 + (R1 @ y) * u2  # the sum of the joint rates about their (world) axes
        v_tip = np.cross(w1, p_elbow) + np.cross(w2, p_tip - p_elbow)
        p_off = p_tip + R2 @ (0.5 * y)
        v_off = v_tip + np.cross(w2, p_off - p_tip)
        R = np.array([[r[f"tool0.R[{a},{b}]"][i] for b in (1, 2, 3)] for a in (1, 2, 3)])
        got = {
            "r": np.array([r[f"tool0.r[{k}]"][i] for k in (1, 2, 3)]),
            "v": np.array([r[f"tool0.v[{k}]"][i] for k in (1, 2, 3)]),
            "w": np.array([r[f"tool0.w[{k}]"][i] for k in (1, 2, 3)]),
            "off.r": np.array([r[f"off.frame_b.r[{k}]"][i] for k in (1, 2, 3)]),
            "off.v": np.array([r[f"off.frame_b.v[{k}]"][i] for k in (1, 2, 3)]),
            "off.w": np.array([r[f"off.frame_b.w[{k}]"][i] for k in (1, 2, 3)]),
        }
        want = {"r": p_tip, "v": v_tip, "w": w2, "off.r": p_off, "off.v": v_off, "off.w": w2}
        for key in want:
            worst = max(worst, np.max(np.abs(got[key] - want[key])))
        worst = max(worst, np.max(np.abs(R - R2)), np.max(np.abs(R.T @ R - np.eye(3))), abs(np.linalg.det(R) - 1))
    assert worst < 1e-12, worst
    assert np.ptp(r["elbow.q"]) > 0.5  # it moved: the check is not at one pose


def test_frame_signals_by_any_name():
    # A frame's signals answer to each name the model gives it (rod2.frame_b is tool0 is
    # off.frame_a), not to the standard library's inner connectors.
    m = kanesim.loads(MODEL)
    r = m.run(stop_time=0.3, outputs=["tool0.w[3]", "rod2.frame_b.w[3]", "off.frame_a.R[1,1]", "tool0.R[1,1]"])
    assert np.array_equal(r["tool0.w[3]"], r["rod2.frame_b.w[3]"])
    assert np.array_equal(r["tool0.R[1,1]"], r["off.frame_a.R[1,1]"])
    assert "rod2.tip.frame_b.R[1,1]" not in m.signals
