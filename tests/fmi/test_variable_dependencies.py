"""fmi3GetNumberOfVariableDependencies / fmi3GetVariableDependencies through FMPy: the FMU
answers with the lists of its modelDescription.xml's ModelStructure (FMI 3.0 section 2.2.10:
the initial ones before fmi3ExitInitializationMode, the runtime ones after), an unknown
without a list depending on every known of its section as the standard defines them."""
import os
from ctypes import byref, c_size_t

import pytest
from fmpy import extract, read_model_description
from fmpy.fmi3 import fmi3DependencyKind, fmi3ValueReference

from conftest import EXAMPLES, instantiate
from test_dependencies import CART, PAIR

KIND = {1: "constant", 5: "dependent"}  # fmi3Constant, fmi3Dependent


def standard_knowns(md, initial):
    """The knowns of a section (FMI 3.0 sec. 2.4.8): inputs, the independent variable, and at
    runtime the continuous states and parameters, at initialization the initial="exact" variables."""
    states = {u.variable.derivative.valueReference for u in md.derivatives}
    out = set()
    for v in md.modelVariables:
        if v.causality in ("input", "independent"):
            out.add(v.valueReference)
        elif initial and v.initial == "exact":
            out.add(v.valueReference)
        elif not initial and (v.valueReference in states or v.causality == "parameter"):
            out.add(v.valueReference)
    return out


def described(md, unknown, initial):
    """{known vr: kind} as the description lists them (no list: every known, "dependent")."""
    if unknown.dependencies is None:
        return {vr: "dependent" for vr in standard_knowns(md, initial)}
    kinds = unknown.dependenciesKind or ["dependent"] * len(unknown.dependencies)
    return {v.valueReference: k for v, k in zip(unknown.dependencies, kinds)}


def answered(m, vr):
    """{known vr: kind} as the FMU answers (each variable a scalar: element index 0)."""
    n = c_size_t()
    m.fmi3GetNumberOfVariableDependencies(m.component, fmi3ValueReference(vr), byref(n))
    k = n.value
    dep_el, ind, ind_el = (c_size_t * k)(), (fmi3ValueReference * k)(), (c_size_t * k)()
    kinds = (fmi3DependencyKind * k)()
    m.fmi3GetVariableDependencies(m.component, fmi3ValueReference(vr), dep_el, ind, ind_el, kinds, c_size_t(k))
    assert list(dep_el) == [0] * k and list(ind_el) == [0] * k
    assert list(ind) == sorted(ind)
    return {int(r): KIND[int(kd)] for r, kd in zip(ind, kinds)}


def check_api_equals_description(fmu, tmp_path):
    d = extract(fmu, unzipdir=str(tmp_path / os.path.basename(fmu)))
    md = read_model_description(d)
    m = instantiate(d, md, 3, "me")
    checked = 0
    for phase in ("instantiated", "initialization", "runtime"):
        if phase == "initialization":
            m.enterInitializationMode(startTime=0.0)
        if phase == "runtime":
            m.exitInitializationMode()
        initial = phase != "runtime"
        sections = [md.initialUnknowns] if initial else [md.outputs, md.derivatives]
        for section in sections:
            for u in section:
                vr = u.variable.valueReference
                assert answered(m, vr) == described(md, u, initial), (phase, u.variable.name)
                checked += 1
    # A state is a known after initialization, no unknown; buffers of the wrong size or none;
    # an unknown value reference: errors, not a list (nor a crash).
    state = md.derivatives[0].variable.derivative.valueReference
    der = fmi3ValueReference(md.derivatives[0].variable.valueReference)
    k = len(answered(m, der.value))
    bufs = lambda n: ((c_size_t * n)(), (fmi3ValueReference * n)(), (c_size_t * n)(), (fmi3DependencyKind * n)())
    for call in (lambda: m.fmi3GetNumberOfVariableDependencies(m.component, fmi3ValueReference(state), byref(c_size_t())),
                 lambda: m.fmi3GetNumberOfVariableDependencies(m.component, fmi3ValueReference(10**6), byref(c_size_t())),
                 lambda: m.fmi3GetNumberOfVariableDependencies(m.component, der, None),
                 lambda: m.fmi3GetVariableDependencies(m.component, der, *bufs(k + 1), c_size_t(k + 1)),
                 lambda: m.fmi3GetVariableDependencies(m.component, der, None, None, None, None, c_size_t(k))):
        with pytest.raises(Exception):
            call()
    m.terminate()
    m.freeInstance()
    return checked


EXAMPLES_SOME = ["double_pendulum.mech", "fourbar.mech", "rolling_disk.mech", "slider_crank.mech"]


@pytest.mark.parametrize("name", EXAMPLES_SOME)
def test_the_api_answers_the_description_for_examples(export, tmp_path, name):
    # Trees, a closed loop, a rolling contact: the same FMU the ModelStructure test exports.
    assert check_api_equals_description(export(os.path.join(EXAMPLES, name), fmi=3, kind="both"), tmp_path) > 0


@pytest.mark.parametrize("model", [("pair.mech", PAIR), ("cart.mech", CART)])
def test_the_api_answers_the_description_with_inputs_outputs_and_time(export, write_model, tmp_path, model):
    # Separate trees, outputs, inputs, constant factors; a prescribed motion that reads time.
    fmu = export(write_model(*model), fmi=3, kind="me")
    assert check_api_equals_description(fmu, tmp_path) > 0
