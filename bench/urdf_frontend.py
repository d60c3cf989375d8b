#!/usr/bin/env python3
"""Front end of imported URDF robots in a fresh process (issue 40; docs/benchmarks/2026-11-28_front_end_issue40.md "URDF
robots"): for each robot, N runs of `kanesim run ROBOT.urdf --stats` over one output step,
each a new process, alternating with the same model already imported (`kanesim import` ->
ROBOT.mech); the medians of the phases `--stats` reports (load + elaborate includes the URDF
translation for the .urdf runs) and of the whole process's wall time.

    python3 bench/urdf_frontend.py [N] [KANESIM]      (N = 31, KANESIM = build/cli/kanesim)

Talos comes from example-robot-data in bench/.venv (sh bench/setup_venv.sh); the others
from tests/import/data/.
"""
import glob
import os
import statistics
import subprocess
import sys
import tempfile
import time

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
DATA = os.path.join(ROOT, "tests", "import", "data")


def robots():
    talos = glob.glob(os.path.join(ROOT, "bench", ".venv", "lib", "python3*", "site-packages", "cmeel.prefix", "share",
                                   "example-robot-data", "robots", "talos_data", "robots", "talos_reduced.urdf"))
    out = [("UR5", os.path.join(DATA, "ur5_robot.urdf"), []), ("Panda", os.path.join(DATA, "panda.urdf"), []),
           ("Solo12", os.path.join(DATA, "solo12.urdf"), ["--floating"])]
    if talos:
        out.append(("Talos", talos[0], ["--floating"]))
    return out


def one_run(kanesim, model, flags):
    """(load + elaborate, compile, process wall) in seconds."""
    cmd = [kanesim, "run", model, *flags, "--stats", "--stop-time", "0.001", "--interval", "0.001"]
    t0 = time.perf_counter()
    p = subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, check=True)
    wall = time.perf_counter() - t0
    phases = {}
    for line in p.stderr.splitlines():
        parts = line.split()
        if line.startswith("  load + elaborate"):
            phases["load"] = float(parts[-1])
        elif line.startswith("  compile"):
            phases["compile"] = float(parts[-1])
    return phases["load"], phases["compile"], wall


def main():
    n = int(sys.argv[1]) if len(sys.argv) > 1 else 31
    kanesim = sys.argv[2] if len(sys.argv) > 2 else os.path.join(ROOT, "build", "cli", "kanesim")
    tmp = tempfile.mkdtemp(prefix="kanesim-urdf-bench-")
    print("| robot | file | load + elaborate (ms) | compile (ms) | process wall (ms) |")
    print("|---|---|---|---|---|")
    for name, urdf, flags in robots():
        mech = os.path.join(tmp, name + ".mech")
        subprocess.run([kanesim, "import", urdf, "-o", mech, *flags], check=True, stderr=subprocess.DEVNULL)
        runs = {".urdf": [], ".mech": []}
        for _ in range(n):  # alternated, so that a change of the machine's load hits both
            runs[".urdf"].append(one_run(kanesim, urdf, flags))
            runs[".mech"].append(one_run(kanesim, mech, []))
        for kind, rs in runs.items():
            # median (fastest): on a shared machine the fastest run is the cost without interference
            cells = [f"{1000 * statistics.median(r[i] for r in rs):.2f} ({1000 * min(r[i] for r in rs):.2f})"
                     for i in range(3)]
            print(f"| {name} | {kind} | " + " | ".join(cells) + " |")
    print(f"\nmedian (fastest) of {n} fresh processes each; load average {os.getloadavg()[0]:.1f}; kanesim {subprocess.run([kanesim, '--version'], capture_output=True, text=True).stdout.strip()}")


if __name__ == "__main__":
    main()
