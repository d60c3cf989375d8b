"""Fixtures of the FMU tests: the kanesim command of this build, and FMUs it exported."""
import os
import subprocess

import pytest

SOURCE = os.environ.get("KANESIM_SOURCE_DIR", os.path.join(os.path.dirname(__file__), "..", ".."))
EXE = os.environ.get("KANESIM_EXE", os.path.join(SOURCE, "build", "cli", "kanesim"))
EXAMPLES = os.path.join(SOURCE, "examples")


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
