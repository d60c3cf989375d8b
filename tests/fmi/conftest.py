"""Fixtures of the FMU tests: the kanesim command of this build, FMUs it exported, and their
instances through FMPy's low-level API, FMI 2 or 3."""
import os
import subprocess
from ctypes import byref

import pytest
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Model, FMU2Slave, fmi2CallbackFunctions, fmi2CallbackLoggerTYPE, printLogMessage
from fmpy.fmi3 import FMU3Model, FMU3Slave
from fmpy.logging import addLoggerProxy

SOURCE = os.environ.get("KANESIM_SOURCE_DIR", os.path.join(os.path.dirname(__file__), "..", ".."))
EXE = os.environ.get("KANESIM_EXE", os.path.join(SOURCE, "build", "cli", "kanesim"))
EXAMPLES = os.path.join(SOURCE, "examples")


# FMPy's FMI 2 logger proxy (fmpy/logging) keeps ONE Python logger for the whole process:
# simulate_fmu(logger=...) and a master's own proxied callbacks replace it, and once that
# callback is freed, every later FMU that logs through FMPy's default callbacks crashes
# the process. After each test, the default printer (kept alive here) is put back. Each
# time through a fresh struct: addLoggerProxy replaces the struct's logger by the native
# proxy, so handing it the same struct twice makes the proxy call itself.
_PRINT_LOG = fmi2CallbackLoggerTYPE(printLogMessage)


@pytest.fixture(autouse=True)
def restore_fmpy_logger():
    yield
    callbacks = fmi2CallbackFunctions()
    callbacks.logger = _PRINT_LOG
    addLoggerProxy(byref(callbacks))


def kanesim(*args, check=True):
    return subprocess.run([EXE, *args], capture_output=True, text=True, check=check)


@pytest.fixture(scope="session")
def export(tmp_path_factory):
    """export(model_path, fmi=2, kind='both', extra=()) -> path of the FMU (made once per argument set)."""
    made = {}
    out = tmp_path_factory.mktemp("fmus")

    def make(path, fmi=2, kind="both", extra=()):
        key = (path, fmi, kind, tuple(extra))
        if key not in made:
            name = f"{os.path.splitext(os.path.basename(path))[0]}_{fmi}_{kind}_{len(made)}.fmu"
            fmu = str(out / name)
            r = kanesim("export", path, "--fmi", str(fmi), "--kind", kind, "-o", fmu, *extra, check=False)
            assert r.returncode == 0, r.stderr
            made[key] = fmu
        return made[key]

    return make


@pytest.fixture
def write_model(tmp_path):
    def write(name, text):
        path = tmp_path / name
        path.write_text(text)
        return str(path)

    return write


CLASSES = {(2, "me"): FMU2Model, (2, "cs"): FMU2Slave, (3, "me"): FMU3Model, (3, "cs"): FMU3Slave}


def instantiate(unzipped, md, fmi, kind, name=None, **args):
    """An instance ("me": Model Exchange, "cs": Co-Simulation) of the FMU unzipped in `unzipped`;
    `args` go to instantiate() (callbacks, logMessage), `name` is the instance's name."""
    ident = (md.modelExchange if kind == "me" else md.coSimulation).modelIdentifier
    named = {} if name is None else {"instanceName": name}
    m = CLASSES[fmi, kind](guid=md.guid, unzipDirectory=unzipped, modelIdentifier=ident, **named)
    m.instantiate(**args)
    return m


def initialize(m, fmi, vr=None, sets=None, tolerance=None):
    """Initialized at t = 0, `sets` ({name: value}, `vr` their value references) set in
    initialization mode. FMI 2 takes the experiment in setupExperiment, FMI 3 on entering."""
    experiment = {"startTime": 0.0} if tolerance is None else {"tolerance": tolerance, "startTime": 0.0}
    if fmi == 2:
        m.setupExperiment(**experiment)
        m.enterInitializationMode()
    else:
        m.enterInitializationMode(**experiment)
    for name, value in (sets or {}).items():
        (m.setReal if fmi == 2 else m.setFloat64)([vr[name]], [value])
    m.exitInitializationMode()


def open_instance(fmu, unzipdir, fmi, kind, sets=None, tolerance=None, **args):
    """The FMU unzipped to `unzipdir`, instantiated and initialized (Model Exchange then in
    continuous-time mode): (instance, model description, {name: value reference})."""
    d = extract(fmu, unzipdir=str(unzipdir))
    md = read_model_description(d)
    vr = {v.name: v.valueReference for v in md.modelVariables}
    m = instantiate(d, md, fmi, kind, **args)
    initialize(m, fmi, vr, sets, tolerance)
    if kind == "me":
        m.enterContinuousTimeMode()
    return m, md, vr
