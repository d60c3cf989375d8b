#!/usr/bin/env python3
"""`kanesim linearize` of a model with `input Real tau;` (issue 42): the input's value comes
from --set or --input-file, and the input is a column of B and D.

A uniform rod (mass m, length L) on a revolute joint about its end, driven by the input
torque tau against gravity: I q'' = tau - m g (L/2) cos q, I = m L^2 / 3. Its equilibrium under
tau0 is cos q* = 2 tau0 / (m g L) (the hanging branch, q* < 0), and about it

    A = [[0, 1], [m g (L/2) sin q* / I, 0]],   B = [[0], [1 / I]],   D = [[2]] for out = 2 tau.

With tau read as 0 the equilibrium would be q* = -pi/2; with --set making tau a constant
there would be no column of B.

    model_inputs_test.py KANESIM WORKDIR
"""
import json
import math
import os
import subprocess
import sys

M, L, G, TAU0 = 1.5, 0.8, 9.81, 2.0  # the rod and gravity of MODEL
# The driven rod, shared with python/tests/test_linearize.py.
MODEL = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "data", "driven_pendulum.mech")


def linearize(exe, work, name, *args):
    out = os.path.join(work, name + ".json")
    r = subprocess.run([exe, "linearize", MODEL, "--equilibrium", "--output", "twice",
                        "-o", out, *args], capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit(f"{name}: exit {r.returncode}\n{r.stderr}")
    with open(out) as f:
        return json.load(f)


def check(name, lin, failures):
    inertia = M * L * L / 3
    q = -math.acos(2 * TAU0 / (M * G * L))
    want = {"A": [[0, 1], [M * G * L / 2 * math.sin(q) / inertia, 0]], "B": [[0], [1 / inertia]], "D": [[2]]}
    if lin["states"] != ["j.q", "j.u"] or lin["inputs"] != ["tau"]:
        failures.append(f"{name}: states {lin['states']}, inputs {lin['inputs']}")
        return
    for key, m in want.items():
        for i, row in enumerate(m):
            for j, v in enumerate(row):
                got = lin[key][i][j]
                if not abs(got - v) <= 1e-7 * max(1.0, abs(v)):
                    failures.append(f"{name}: {key}[{i}][{j}] = {got!r}, closed form {v!r}")


def main():
    exe, work = sys.argv[1], sys.argv[2]
    os.makedirs(work, exist_ok=True)
    with open(os.path.join(work, "tau.csv"), "w") as f:
        f.write(f"time,tau\n0,{TAU0}\n5,{TAU0}\n")
    failures = []
    check("--set", linearize(exe, work, "set", "--set", f"tau={TAU0}"), failures)
    check("--input-file", linearize(exe, work, "table", "--input-file", os.path.join(work, "tau.csv")), failures)
    # Named again with --input: the same single column.
    check("--input tau", linearize(exe, work, "named", "--set", f"tau={TAU0}", "--input", "tau"), failures)
    # Nothing gives it: E239 at the declaration, exit 1.
    r = subprocess.run([exe, "linearize", MODEL], capture_output=True, text=True)
    if r.returncode != 1 or "driven_pendulum.mech:2:14: error[E239]: input 'tau' is not connected" not in r.stderr:
        failures.append(f"no value: exit {r.returncode}, stderr {r.stderr!r}")
    if failures:
        sys.exit("\n".join(failures))
    print("ok")


if __name__ == "__main__":
    main()
