#!/usr/bin/env python3
"""`kanesim check` on models whose mesh file is no regular file or declares more than it holds:
exit 1 within a bound, with a diagnostic located at the model text that names the file
(file:line:col, the source line, a caret and a hint). Wrong if the check blocked on a FIFO,
spent minutes allocating for a PLY's claimed count, or reported the problem without a place.

usage: mesh_cli_test.py KANESIM"""
import os
import re
import subprocess
import sys
import tempfile
import time

KANESIM = sys.argv[1]
BOUND_S = 10  # each check must end within this (it ends in milliseconds; the bugs never ended)

MODEL = """model M
  parameter String f = "{f}";
  World world(g = {{0, -9.81, 0}});
  Revolute hinge(axis = {{0, 0, 1}});
  MeshBody link(file = f, density = 1000);
equation
  connect(world.frame_b, hinge.frame_a);
  connect(hinge.frame_b, link.frame_a);
end M;
"""

PLY_CLAIMS = ("ply\nformat ascii 1.0\nelement vertex 99999999\nproperty float x\nproperty float y\n"
              "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n")
PLY_BEYOND = PLY_CLAIMS.replace("99999999", "3000000")

failures = []


def check(name, mesh_path, code, message):
    d = tempfile.mkdtemp(prefix="kanesim_mesh_cli_")
    with open(os.path.join(d, "m.mech"), "w") as o:
        o.write(MODEL.format(f=mesh_path))
    start = time.time()
    try:
        p = subprocess.run([KANESIM, "check", "m.mech"], cwd=d, capture_output=True, text=True, timeout=BOUND_S,
                           )
    except subprocess.TimeoutExpired:
        failures.append(f"{name}: still running after {BOUND_S} s")
        # Unblock a reader waiting on the FIFO, so that the killed child's thread ends too.
        return d
    took = time.time() - start
    out = p.stdout + p.stderr
    expect = [(p.returncode == 1, f"exit {p.returncode}, not 1"),
              (re.search(r"m\.mech:2:24: error\[" + code + r"\]: .*" + message, out), f"no located {code} /{message}/"),
              (re.search(r'\n 2 \|   parameter String f = ".*";\n   \| +\^~+', out), "no source line with a caret"),
              ("hint: " in out, "no hint")]
    for ok, why in expect:
        if not ok:
            failures.append(f"{name}: {why} (in {took:.2f} s):\n{out}")
    print(f"{name}: exit {p.returncode} in {took:.3f} s")
    return d


def main():
    d = tempfile.mkdtemp(prefix="kanesim_mesh_files_")
    fifo = os.path.join(d, "part.stl")
    os.mkfifo(fifo)
    os.symlink(fifo, os.path.join(d, "link.stl"))
    for name, text in [("claims.ply", PLY_CLAIMS), ("beyond.ply", PLY_BEYOND)]:
        with open(os.path.join(d, name), "w") as o:
            o.write(text)
    with open(os.path.join(d, "count.stl"), "wb") as o:  # binary STL: 12 triangles held, 1e6 declared
        o.write(b"\0" * 80 + (1000000).to_bytes(4, "little") + b"\0" * 50 * 12)
    check("fifo", fifo, "E231", r"it is a named pipe \(FIFO\), not a regular file")
    check("symlink to a fifo", os.path.join(d, "link.stl"), "E231", "not a regular file")
    check("device", "/dev/zero", "E231", "it is a device, not a regular file")
    check("ply over the limit", os.path.join(d, "claims.ply"), "E232", "declares 99999999 vertex elements")
    check("ply beyond the file", os.path.join(d, "beyond.ply"), "E231", "declares 3000000 vertex, 1 face")
    check("binary stl count", os.path.join(d, "count.stl"), "E231", "declaring 1000000 triangles")
    if failures:
        print("\n".join(failures))
        sys.exit(1)


main()
