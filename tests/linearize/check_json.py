"""Checks `kanesim linearize -o` JSON of tests/linearize/models/pendulum.mech against the
closed form: A = [[0, 1], [-g/l, 0]], B = [[0, 0], [1/(m l^2), dA/dl . x = 0]], lambda = +-i sqrt(g/l).
If this fails, the file's layout or its numbers are wrong."""
import json
import math
import sys

d = json.load(open(sys.argv[1]))
g, l, m = 9.81, 0.7, 2.0
assert d["states"] == ["hinge.q", "hinge.u"], d["states"]
assert d["inputs"] == ["hinge.tau", "l"], d["inputs"]
assert d["outputs"] == ["tip_y"], d["outputs"]
A = d["A"]
assert abs(A[0][0]) < 1e-12 and abs(A[0][1] - 1) < 1e-12, A
assert abs(A[1][0] + g / l) < 1e-9 and abs(A[1][1]) < 1e-12, A
assert abs(d["B"][1][0] - 1 / (m * l * l)) < 1e-12, d["B"]
assert len(d["C"]) == 1 and len(d["C"][0]) == 2 and len(d["D"][0]) == 2
w = math.sqrt(g / l)
ev = sorted(d["eigenvalues"], key=lambda e: e[1])
assert abs(ev[0][1] + w) < 1e-9 and abs(ev[1][1] - w) < 1e-9, ev
assert len(d["modes"]) == 2 and d["modes"][0]["dominant"][0][0] == "hinge.q"
assert d["accuracy"]["A"] < 1e-9
print("ok")
