"""Runs pytest on this directory for ctest; exit 77 (ctest's skip) when the interpreter
has no pytest or NumPy, so that a machine without them says "skipped", not "passed"."""
import os
import sys

try:
    import numpy  # noqa: F401
    import pytest
except ImportError as e:
    print(f"python.pytest skipped: {e} (scripts/setup.sh test installs python3-pytest and python3-numpy)")
    sys.exit(77)

# python.installed*: the package pip installed into that venv, not a copy from the tree.
# Under CI (CI=true) a missing or stale install fails instead of skipping: CI must test
# the installed package under both NumPy majors (scripts/pip_install.sh makes the venvs).
venv = os.environ.get("KANESIM_EXPECT_INSTALLED")
SKIP = 1 if venv and os.environ.get("CI") == "true" else 77


def not_installed(why):
    print(f"python.installed {'failed (CI=true)' if SKIP == 1 else 'skipped'}: {why}")
    sys.exit(SKIP)


if venv and os.path.realpath(sys.prefix) != os.path.realpath(venv):
    venv_python = os.path.join(venv, "bin", "python")
    if not os.path.exists(venv_python):
        not_installed(f"no {venv_python} (scripts/pip_install.sh makes it)")
    os.execv(venv_python, [venv_python, *sys.argv])
if venv:
    try:
        import kanesim
    except ModuleNotFoundError as e:
        not_installed(f"{e} (scripts/pip_install.sh installs it)")
    except ImportError as e:  # installed, and refused (e.g. its arrays would be wrong): a failure
        print(f"python.installed: import kanesim failed: {e}")
        sys.exit(1)
    where = os.path.realpath(kanesim.__file__)
    if not where.startswith(os.path.realpath(venv) + os.sep):
        print(f"python.installed: kanesim imported from {where}, not from {venv}")
        sys.exit(1)
    # Older than this tree's package or build/'s module: the install is stale (rerun
    # scripts/pip_install.sh; scripts/test.sh always does) and is not what to test.
    here = os.path.dirname(os.path.abspath(__file__))
    newer = [os.path.join(here, "..", "kanesim", "__init__.py")]
    build_pkg = os.path.join(os.path.dirname(venv), "python", "kanesim")
    if os.path.isdir(build_pkg):
        newer += [os.path.join(build_pkg, f) for f in os.listdir(build_pkg) if f.startswith("_kanesim")]
    if any(os.path.getmtime(f) > os.path.getmtime(where) for f in newer if os.path.exists(f)):
        not_installed(f"{where} is older than the tree's package (scripts/pip_install.sh)")
    print(f"testing the installed package {os.path.dirname(where)} with NumPy {numpy.__version__}")

sys.exit(pytest.main(["-q", "-p", "no:cacheprovider", *sys.argv[1:]]))
