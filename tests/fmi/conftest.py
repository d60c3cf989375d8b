"""Fixtures of the FMU tests: the kanesim command of this build, and FMUs it exported."""
import os
import subprocess
from ctypes import byref

import pytest
from fmpy.fmi2 import fmi2CallbackFunctions, fmi2CallbackLoggerTYPE, printLogMessage
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
