"""The states' start values as declared and as the FMU starts (FMI 2.0.4 section 2.2.7, FMI 3.0
section 2.4.7.4): a state whose start the FMU computes from tunable parameters (a start
expression, a closed loop's assembly) is initial="calculated", without start, an initial
unknown listing those parameters, and cannot be set; any other is initial="exact" and starts
at its start attribute or at the master's value, whatever parameters the master sets."""
import os

import pytest
from fmpy import extract, read_model_description

from conftest import EXAMPLES, initialize, instantiate
from fmu_models import double_pendulum

STARTS = double_pendulum("Starts", "A start from a parameter, literal starts, a start speed from a parameter",
                         "phi0", 0.8, 0.5, "2 * w0",
                         declarations=['parameter Real phi0(unit = "rad") = 0.3;',
                                       'parameter Real w0(unit = "rad/s") = 0.5;'])


class Master:
    """One ME instance: start(sets) sets values before initialization and returns the states after."""

    def __init__(self, fmu, tmp_path, fmi):
        d = extract(fmu, unzipdir=str(tmp_path / f"{os.path.basename(fmu)}_{fmi}"))
        self.md = md = read_model_description(d)
        self.fmi = fmi
        self.m = instantiate(d, md, fmi, "me")
        self.states = [u.variable.derivative for u in md.derivatives]
        self.vr = {v.name: v.valueReference for v in md.modelVariables}
        self.fresh = True

    def start(self, sets):
        m = self.m
        if not self.fresh:
            m.reset()
        self.fresh = False
        initialize(m, self.fmi, self.vr, sets)
        values = (m.getReal if self.fmi == 2 else m.getFloat64)([s.valueReference for s in self.states])
        return dict(zip([s.name for s in self.states], values))

    def close(self):
        self.m.freeInstance()  # allowed in every state (a refused set leaves initialization mode)


def initial_lists(md):
    return {u.variable.name: (None if u.dependencies is None else {v.name for v in u.dependencies})
            for u in md.initialUnknowns}


def check_declarations_match_behaviour(master):
    """Each tunable parameter moved alone: an exact state stays at its start attribute, a state
    that moves is calculated and lists the parameter; returns the parameters that moved some."""
    md = master.md
    lists = initial_lists(md)
    for s in master.states:
        assert s.initial in ("exact", "calculated"), s.name
        assert (s.start is None) == (s.initial == "calculated"), s.name
        assert (s.name in lists) == (s.initial == "calculated"), s.name  # initial unknowns: the calculated ones
    base = master.start({})
    for s in master.states:
        if s.initial == "exact":
            assert base[s.name] == pytest.approx(float(s.start), abs=1e-12), s.name
    moving = set()
    for p in (v for v in md.modelVariables if v.causality == "parameter"):
        value = float(p.start)
        try:
            now = master.start({p.name: value + 1e-3 * max(1.0, abs(value))})
        except Exception:  # not movable alone (an inertia's or a rotation's entry): refused at initialization
            continue
        for s in master.states:
            if abs(now[s.name] - base[s.name]) > 1e-9 * (1 + abs(base[s.name])):
                assert s.initial == "calculated", f"{s.name} is exact but moves with {p.name}"
                assert lists[s.name] is None or p.name in lists[s.name], f"{s.name} moves with {p.name}, not listed"
                moving.add(p.name)
    return moving


@pytest.mark.parametrize("fmi", [2, 3])
def test_a_start_from_a_parameter_is_calculated_and_follows_it(export, write_model, tmp_path, fmi):
    master = Master(export(write_model("starts.mech", STARTS), fmi=fmi, kind="me"), tmp_path, fmi)
    by = {s.name: s for s in master.states}
    assert {n: by[n].initial for n in by} == {"j1.q": "calculated", "j2.q": "exact", "j1.u": "exact",
                                              "j2.u": "calculated"}
    lists = initial_lists(master.md)
    assert lists["j1.q"] == {"phi0"} and lists["j2.u"] == {"w0"}
    assert check_declarations_match_behaviour(master) == {"phi0", "w0"}
    # phi0 set before initialization moves j1.q's start; an exact state is the master's to set,
    # a calculated one is not (its parameters are).
    x = master.start({"phi0": 0.7, "w0": -0.25, "j2.q": -0.4})
    assert x == {"j1.q": 0.7, "j2.q": -0.4, "j1.u": 0.8, "j2.u": -0.5}
    with pytest.raises(Exception):
        master.start({"j1.q": 0.1})
    master.close()


@pytest.mark.parametrize("name", ["double_pendulum.mech", "fourbar.mech", "slider_crank.mech"])
def test_every_declared_start_matches_what_the_fmu_does(export, tmp_path, name):
    # A tree with literal starts (exact); closed loops whose assembly follows their lengths
    # and start parameters (calculated).
    master = Master(export(os.path.join(EXAMPLES, name), fmi=2, kind="both"), tmp_path, 2)
    moving = check_declarations_match_behaviour(master)
    assert bool(moving) == (name != "double_pendulum.mech")
    master.close()


def test_every_start_of_a_closed_loop_is_calculated_by_its_assembly(export, write_model, tmp_path):
    # The four-bar with its crank's start a literal held by `fixed = true`: the assembly still
    # computes every start together, so none is the master's to set (it would not be assembled
    # with the others).
    with open(os.path.join(EXAMPLES, "fourbar.mech")) as f:
        text = f.read().replace("q(start = theta0, fixed = true), u(start = omega0)",
                                "q(start = 0.3, fixed = true), u(start = 6)")
    master = Master(export(write_model("fourbar_literal.mech", text), fmi=3, kind="me"), tmp_path, 3)
    assert {s.initial for s in master.states} == {"calculated"}
    assert not initial_lists(master.md)["crank_pivot.q"] & {"a", "b", "c", "d"}  # held: the lengths do not move it
    assert master.start({})["crank_pivot.q"] == 0.3
    with pytest.raises(Exception):
        master.start({"crank_pivot.q": 0.5})
    master.close()
