"""Runs pytest on this directory for ctest; exit 77 (ctest's skip) when the interpreter
has no pytest or NumPy, so that a machine without them says "skipped", not "passed"."""
import os
import sys

try:
    import numpy  # noqa: F401
    import pytest
except ImportError as e:
    print(f"python.pytest skipped: {e} (scripts/setup.sh installs python3-pytest and python3-numpy)")
    sys.exit(77)

# python.installed: the package pip installed into that venv, not a copy from the tree.
venv = os.environ.get("KANESIM_EXPECT_INSTALLED")
if venv and os.path.realpath(sys.prefix) != os.path.realpath(venv):
    venv_python = os.path.join(venv, "bin", "python")
    if not os.path.exists(venv_python):
        print(f"python.installed skipped: no {venv_python} (scripts/pip_install.sh makes it)")
        sys.exit(77)
    os.execv(venv_python, [venv_python, *sys.argv])
if venv:
    try:
        import kanesim
    except ImportError as e:
        print(f"python.installed skipped: {e} (scripts/pip_install.sh installs it)")
        sys.exit(77)
    where = os.path.realpath(kanesim.__file__)
    if not where.startswith(os.path.realpath(venv) + os.sep):
        print(f"python.installed: kanesim imported from {where}, not from {venv}")
        sys.exit(1)
    print(f"testing the installed package {os.path.dirname(where)}")

sys.exit(pytest.main(["-q", "-p", "no:cacheprovider", *sys.argv[1:]]))
