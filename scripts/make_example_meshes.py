#!/usr/bin/env python3
"""Writes the mesh parts of examples/slider_crank_meshes.mech (ASCII STL, in millimetres, as a
CAD tool would export them) into examples/meshes/ or the folder given.

  crank.stl   a crank arm 100 mm between its pin centres: a plate 20 mm wide, 10 mm thick
              with half-hexagon ends, its first pin at the file's origin, along +x
  rod.stl     the connecting rod, 350 mm between pins, 15 x 10 mm, rounded the same way
  slider.stl  the slider block, 60 x 40 x 40 mm, centred on the file's origin

Each is a closed, outward-oriented solid (kanesim computes its mass properties from it).
The committed files are this script's output; tests compare them (examples/CMakeLists.txt).
Usage: make_example_meshes.py [OUTDIR]
       make_example_meshes.py --check      (exit 1 if examples/meshes/ is not this script's output)
"""
import filecmp
import math
import os
import sys
import tempfile


def prism(outline, thickness):
    """A prism over a convex polygon in the x-y plane (counter-clockwise), from z = -t/2 to
    z = t/2: its triangles, outward (counter-clockwise seen from outside)."""
    lo = [(x, y, -thickness / 2) for x, y in outline]
    hi = [(x, y, thickness / 2) for x, y in outline]
    n = len(outline)
    tris = []
    for i in range(1, n - 1):
        tris.append((hi[0], hi[i], hi[i + 1]))  # top, facing +z
        tris.append((lo[0], lo[i + 1], lo[i]))  # bottom, facing -z
    for i in range(n):
        j = (i + 1) % n
        tris.append((lo[i], lo[j], hi[j]))
        tris.append((lo[i], hi[j], hi[i]))
    return tris


def link(length, width, thickness):
    """Outline of a link between pins at x = 0 and x = length: half-hexagon ends."""
    h = width / 2
    d = h * math.tan(math.pi / 6)  # how far each end pokes out past its pin
    return [(-d, -h / 2), (0, -h), (length, -h), (length + d, -h / 2), (length + d, h / 2), (length, h),
            (0, h), (-d, h / 2)]


def box(lx, ly, lz):
    return prism([(-lx / 2, -ly / 2), (lx / 2, -ly / 2), (lx / 2, ly / 2), (-lx / 2, ly / 2)], lz)


def normal(a, b, c):
    u = [b[i] - a[i] for i in range(3)]
    v = [c[i] - a[i] for i in range(3)]
    n = [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]]
    s = math.sqrt(sum(x * x for x in n))
    return [x / s for x in n]


def write_stl(path, name, tris):
    def fmt(x):
        s = ("%.6f" % x).rstrip("0").rstrip(".")
        return "0" if s in ("-0", "") else s

    with open(path, "w", newline="\n") as f:
        f.write("solid %s\n" % name)
        for t in tris:
            f.write("  facet normal %s\n    outer loop\n" % " ".join(fmt(x) for x in normal(*t)))
            for p in t:
                f.write("      vertex %s\n" % " ".join(fmt(x) for x in p))
            f.write("    endloop\n  endfacet\n")
        f.write("endsolid %s\n" % name)


PARTS = {
    "crank.stl": lambda: prism(link(100, 20, 10), 10),
    "rod.stl": lambda: prism(link(350, 15, 10), 10),
    "slider.stl": lambda: box(60, 40, 40),
}


def write_all(out):
    os.makedirs(out, exist_ok=True)
    for name, make in PARTS.items():
        write_stl(os.path.join(out, name), name[:-4], make())


def main():
    committed = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "examples", "meshes")
    if sys.argv[1:] == ["--check"]:
        with tempfile.TemporaryDirectory() as tmp:
            write_all(tmp)
            differ = [n for n in PARTS if not filecmp.cmp(os.path.join(tmp, n), os.path.join(committed, n), False)]
        print("examples/meshes: " + ("differ from the script's output: " + ", ".join(differ) if differ else "OK"))
        return 1 if differ else 0
    write_all(sys.argv[1] if len(sys.argv) > 1 else committed)
    return 0


if __name__ == "__main__":
    sys.exit(main())
