"""Shared fixtures: the source tree (for examples/) and the kanesim command (for the
bit-for-bit comparisons). ctest passes KANESIM_SOURCE_DIR and KANESIM_EXE."""
import os
import pathlib
import shutil

import pytest

SOURCE_DIR = pathlib.Path(os.environ.get("KANESIM_SOURCE_DIR", pathlib.Path(__file__).resolve().parents[2]))


def _kanesim_exe():
    exe = os.environ.get("KANESIM_EXE")
    if exe and os.path.exists(exe):
        return exe
    built = SOURCE_DIR / "build" / "cli" / "kanesim"
    if built.exists():
        return str(built)
    return shutil.which("kanesim")


@pytest.fixture(scope="session")
def source_dir():
    return SOURCE_DIR


@pytest.fixture(scope="session")
def examples():
    return SOURCE_DIR / "examples"


@pytest.fixture(scope="session")
def kanesim_exe():
    exe = _kanesim_exe()
    if exe is None:
        pytest.skip("the kanesim command is not built (KANESIM_EXE)")
    return exe
