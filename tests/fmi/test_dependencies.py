"""ModelStructure's dependencies (docs/fmi.md "Dependencies") against a numeric probe through
FMPy: every state or input whose perturbation moves a derivative or an output must be listed
(a missing one misleads a master's evaluation order and algebraic-loop detection), and the
kinematic rows der(q) = N(q) u list exactly what they read. FMI 2 and 3, Model Exchange."""
import os
from ctypes import POINTER, c_double

import numpy as np
import pytest
from fmpy import read_model_description

from conftest import EXAMPLES, open_instance
from fmu_models import link, pendulums

# Two pendulums: each one's input, states and outputs stay its own, but for the first's torque,
# which reads where the second's tip is (its joints' coordinates, not their speeds).
PAIR = pendulums("Pair", "Two pendulums, each driven by its own input",
                 [[link("ja", "ra", 1, 1, 0.3, 0.8)],
                  [link("jb", "rb", 0.7, 0.6, -0.2, 0.5), link("jc", "rc", 0.5, 0.4, 0.4, -0.3)]],
                 declarations=["input Real ta;", "input Real tb;"],
                 outputs=["output Real xa = ra.frame_b.r[1];", "output Real pb = jb.u * tb;",
                          "output Real vc = rc.frame_b.v[2];"],
                 equations=["ja.tau = ta + 0.2 * rc.frame_b.r[2];", "jc.tau = tb - 0.1 * jc.u;"])

# Rotations: a body on a free joint (quaternion) pushed by an input force, and a pendulum
# on a Cardan-angle spherical joint driven by an input torque; a spring between them
# couples the two trees.
ROTATIONS = """
model Rotations "A free body and a Cardan pendulum, joined by a spring"
  input Real f;
  input Real m3;
  World world(g = {0, -9.81, 0});
  FreeMotion fly(q(start = {0.1, 0.2, 0.3, 0.9, 0.1, 0.3, 0.2}), u(start = {0.2, -0.1, 0.3, 0.5, -0.4, 0.7}));
  Body box(m = 2, I = diagonal({0.1, 0.2, 0.3}));
  WorldForce push(force = {f, 0, 0});
  Spherical ball(coordinates = "cardan_xyz", q(start = {0.2, -0.3, 0.4}), u(start = {0.3, 0.6, -0.5}));
  Rod arm(L = 0.8, m = 1);
  Body blob(m = 0.5, I = diagonal({0.01, 0.02, 0.03}));
  Spring s(c = 5);
  output Real wz = box.frame_a.w[3];
equation
  connect(world.frame_b, fly.frame_a);
  connect(fly.frame_b, box.frame_a);
  connect(fly.frame_b, push.frame_b);
  connect(world.frame_b, ball.frame_a);
  connect(ball.frame_b, arm.frame_a);
  connect(arm.frame_b, blob.frame_a);
  connect(arm.frame_b, s.frame_a);
  connect(fly.frame_b, s.frame_b);
  ball.tau[3] = m3;
end Rotations;
"""

# A pendulum on a cart whose position is an input (a prescribed motion that reads it).
CART = """
model Cart "A pendulum hanging from a cart moved by an input"
  input Real x;
  input Real tau;
  World world(g = {0, -9.81, 0});
  Prismatic slide(axis = {1, 0, 0});
  Body cart(m = 1, I = identity(3) * 0.01);
  Revolute hinge(axis = {0, 0, 1}, q(start = 0.4), u(start = 0.2));
  Rod rod(L = 0.6, m = 0.5);
  output Real tipx = rod.frame_b.r[1];
equation
  connect(world.frame_b, slide.frame_a);
  connect(slide.frame_b, cart.frame_a);
  connect(slide.frame_b, hinge.frame_a);
  connect(hinge.frame_b, rod.frame_a);
  slide.q = x;
  hinge.tau = tau;
end Cart;
"""

TREES = {"pair.mech": PAIR, "rotations.mech": ROTATIONS, "cart.mech": CART}
H = 1e-6        # central differences: a real dependence moves by ~2 H |J|
NOISE = 1e-10   # a change above NOISE (1 + |value|) is a dependence; round-off is ~1e-16 |value|


class Probe:
    """An ME instance at a state and inputs; the derivatives and outputs as one vector."""

    def __init__(self, fmu, tmp_path, fmi):
        m, md, _ = open_instance(fmu, tmp_path / f"probe{fmi}_{os.path.basename(fmu)}", fmi, "me")
        self.m, self.md = m, md
        self.set_real = m.setReal if fmi == 2 else m.setFloat64
        self.get_real = m.getReal if fmi == 2 else m.getFloat64
        self.get_der = m.getDerivatives if fmi == 2 else m.getContinuousStateDerivatives
        self.states = [u.variable.derivative for u in md.derivatives]
        self.inputs = [v for v in md.modelVariables if v.causality == "input"]
        self.unknowns = [u.variable for u in md.derivatives] + [u.variable for u in md.outputs]
        self.n = len(self.states)
        self.x = np.zeros(self.n)
        m.getContinuousStates(self.x.ctypes.data_as(POINTER(c_double)), self.n)
        self.u = np.zeros(len(self.inputs))

    def __call__(self, x, u):
        x = np.ascontiguousarray(x, dtype=float)
        self.m.setContinuousStates(x.ctypes.data_as(POINTER(c_double)), self.n)
        if len(u):
            self.set_real([v.valueReference for v in self.inputs], list(u))
        der = np.zeros(self.n)
        self.get_der(der.ctypes.data_as(POINTER(c_double)), self.n)
        outs = self.get_real([u.variable.valueReference for u in self.md.outputs]) if self.md.outputs else []
        return np.concatenate([der, outs])

    def jacobian(self):
        """d(unknowns)/d(states, inputs) by central differences, and the base values."""
        f0 = self(self.x, self.u)
        knowns = self.states + self.inputs
        J = np.zeros((len(f0), len(knowns)))
        for j in range(len(knowns)):
            x, u = self.x.copy(), self.u.copy()
            dx = np.zeros_like(x)
            du = np.zeros_like(u)
            (dx if j < self.n else du)[j if j < self.n else j - self.n] = H
            J[:, j] = (self(x + dx, u + du) - self(x - dx, u - du)) / (2 * H)
        self(self.x, self.u)
        return J, f0, knowns

    def close(self):
        self.m.terminate()
        self.m.freeInstance()


def declared(md, structure_unknown):
    """The states and inputs an unknown lists (None: every known, the standard's default)."""
    if structure_unknown.dependencies is None:
        return None
    states = {u.variable.derivative.name for u in md.derivatives}
    return {v.name for v in structure_unknown.dependencies if v.causality == "input" or v.name in states}


def check_superset(probe, fmi):
    """Every numerically nonzero dependence is listed; returns the numeric pattern."""
    J, f0, knowns = probe.jacobian()
    md = probe.md
    rows = list(md.derivatives) + list(md.outputs)
    numeric = {}
    for i, unknown in enumerate(rows):
        deps = {knowns[j].name for j in range(len(knowns)) if abs(J[i, j]) * 2 * H > NOISE * (1 + abs(f0[i]))}
        numeric[unknown.variable.name] = deps
        listed = declared(md, unknown)
        if listed is not None:
            assert deps <= listed, f"FMI {fmi}: {unknown.variable.name} depends on {deps - listed}, not listed"
    return numeric, J, knowns


def check_knowns_are_allowed(md, fmi):
    """Only knowns of each section are listed, in ascending order (FMI 2.0.4 sec. 2.2.8, FMI 3.0 sec. 2.4.8)."""
    state_names = {u.variable.derivative.name for u in md.derivatives}
    index = {v.name: k for k, v in enumerate(md.modelVariables)}
    for section, initial in ((md.outputs, False), (md.derivatives, False), (md.initialUnknowns, True)):
        for u in section:
            if u.dependencies is None:
                continue
            for v in u.dependencies:
                ok = v.name in state_names or v.causality == "input"
                ok = ok or ((initial or fmi == 3) and v.causality == "parameter")
                ok = ok or (fmi == 3 and v.causality == "independent")
                assert ok, f"FMI {fmi}: {u.variable.name} lists {v.name} ({v.causality}), not a known there"
            order = [index[v.name] for v in u.dependencies]
            assert order == sorted(order) and len(set(order)) == len(order)
            kinds = set(u.dependenciesKind or [])
            assert kinds <= ({"dependent"} if initial else {"dependent", "constant"})


@pytest.mark.parametrize("fmi", [2, 3])
@pytest.mark.parametrize("name", sorted(TREES))
def test_listed_dependencies_cover_the_numeric_ones_and_kinematic_rows_are_exact(export, write_model, tmp_path,
                                                                               fmi, name):
    probe = Probe(export(write_model(name, TREES[name]), fmi=fmi, kind="me"), tmp_path, fmi)
    rng = np.random.default_rng(42)
    probe.x = probe.x + 0.2 * rng.standard_normal(probe.n)  # a generic state: no accidental zeros
    probe.u = rng.standard_normal(len(probe.inputs))
    numeric, J, knowns = check_superset(probe, fmi)
    md = probe.md
    check_knowns_are_allowed(md, fmi)
    for k, unknown in enumerate(md.derivatives):
        if ".q" not in unknown.variable.derivative.name:
            continue
        # der(q): the kinematic differential equations, listed exactly; qdot = u with factor 1.
        listed = declared(md, unknown)
        assert listed == numeric[unknown.variable.name], unknown.variable.name
        kinds = unknown.dependenciesKind or ["dependent"] * len(unknown.dependencies)  # none: all dependent
        for v, kind in zip(unknown.dependencies, kinds):
            if kind == "constant":
                assert J[k, knowns.index(v)] == pytest.approx(1.0, abs=1e-9)
    probe.close()


@pytest.mark.parametrize("fmi", [2, 3])
def test_separate_trees_and_inputs_stay_apart(export, write_model, tmp_path, fmi):
    # ja's pendulum reads neither tb nor the other tree's speeds; the output pb reads jb.u and tb only.
    probe = Probe(export(write_model("pair.mech", PAIR), fmi=fmi, kind="me"), tmp_path, fmi)
    md = probe.md
    by_name = {u.variable.name: declared(md, u) for u in list(md.derivatives) + list(md.outputs)}
    assert by_name["der(ja.u)"] == {"ja.q", "ja.u", "ta", "jb.q", "jc.q"}
    assert by_name["der(jb.u)"] == {"jb.q", "jb.u", "jc.q", "jc.u", "tb"}
    assert by_name["der(ja.q)"] == {"ja.u"}
    assert by_name["xa"] == {"ja.q"}
    assert by_name["pb"] == {"jb.u", "tb"}
    assert by_name["vc"] == {"jb.q", "jb.u", "jc.q", "jc.u"}
    kinds = {u.variable.name: u.dependenciesKind for u in md.derivatives}
    assert kinds["der(ja.q)"] == ["constant"]
    if fmi == 3:  # FMI 3 counts time and the parameters among the knowns
        der_q = next(u for u in md.derivatives if u.variable.name == "der(ja.q)")
        assert [v.name for v in der_q.dependencies] == ["ja.u"]
        der_u = next(u for u in md.derivatives if u.variable.name == "der(ja.u)")
        assert any(v.causality == "parameter" for v in der_u.dependencies)
    probe.close()


@pytest.mark.parametrize("fmi", [2, 3])
def test_a_prescribed_motion_that_reads_an_input_and_time(export, write_model, tmp_path, fmi):
    # The cart's position is the input x: the pendulum's outputs read x; in FMI 3 a
    # prescribed motion reads time, which FMI 3 lists as a known.
    md = read_model_description(export(write_model("cart.mech", CART), fmi=fmi, kind="me"))
    by = {u.variable.name: u for u in list(md.derivatives) + list(md.outputs)}
    assert {v.name for v in by["tipx"].dependencies} >= {"hinge.q", "x"}
    if fmi == 3:
        deps = by["der(hinge.u)"].dependencies  # None: every known, time too
        assert deps is None or "time" in {v.name for v in deps}


# Those an FMU can load (one that reads meshes cannot yet: docs/fmi.md).
EXAMPLES_ALL = sorted(f for f in os.listdir(EXAMPLES) if f.endswith(".mech") and "meshes" not in f)


@pytest.mark.parametrize("name", EXAMPLES_ALL)
def test_every_example_lists_every_numeric_dependence(export, tmp_path, name):
    # Closed loops, rolling contacts, end stops: at the example's start state, whatever moves
    # a derivative or an output is listed (probed in FMI 2: both versions list the same
    # analysis), and only knowns are listed, in both versions.
    path = os.path.join(EXAMPLES, name)
    probe = Probe(export(path, fmi=2, kind="both"), tmp_path, 2)
    check_superset(probe, 2)
    check_knowns_are_allowed(probe.md, 2)
    probe.close()
    check_knowns_are_allowed(read_model_description(export(path, fmi=3, kind="both")), 3)
