#!/usr/bin/env python3
"""Parses an animation written by `kanesim run --animation` back (standard library only; the
reader of tests/geometry/check_gltf.py) and checks it against the CSV of the same run.

What would be wrong if it failed: the animation does not show the simulated motion — a body
node missing or extra, a key count that is not the number of output rows, times that are not
the output instants, a body's translation that is not its frame origin p_WB or its rotation
not R_WB (as written in the CSV, `--output '*.r[*]' --output '*.R[*]'`), the world not turned
so that up (−g) is +Y, or a body drawn with the wrong size or shape.

Usage: check_animation.py FILE.glb|FILE.gltf FILE.csv --up X,Y,Z
         --body NODE=FRAME:BODY ...      node "body_NODE" has p_WB = FRAME.r[*], R_WB = BODY.R[*,*]
         [--bounds NODE=X0,X1,Y0,Y1,Z0,Z1 ...]   its drawing's bounding box in its body frame
         [--radius NODE=R ...]           its drawing's farthest vertex from the body frame's origin
         [--color NODE=R,G,B ...]        its material's base colour (linear)
         [--axes FRAME=LENGTH[:BODY] ...] (--show-frames) nodes "body_axes_FRAME_x|y|z": each a rod
                                         of LENGTH, translated to FRAME.r[*] at every key, and (with
                                         BODY, whose frame FRAME is) pointing along column x|y|z of
                                         BODY.R[*,*]; no other axes nodes
"""
import argparse
import csv
import math
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "geometry"))
from check_gltf import load, read_accessor, rotate  # noqa: E402

# Keys and vertices are stored as float32 (2^-24 relative rounding): positions of order 1 m
# agree to a few 1e-7; the CSV has 17 digits.
TOL = 1e-6


def read_csv(path):
    with open(path, newline="") as f:
        rows = [r for r in csv.reader(f) if r and not r[0].startswith("#")]
    header = rows[0]
    data = [[float(x) for x in r] for r in rows[1:]]
    return {name: [r[i] for r in data] for i, name in enumerate(header)}, len(data)


def parse_map(items):
    out = {}
    for item in items or []:
        key, value = item.split("=", 1)
        out[key] = value
    return out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("gltf")
    ap.add_argument("csv")
    ap.add_argument("--up", required=True)
    ap.add_argument("--body", action="append", required=True)
    ap.add_argument("--bounds", action="append")
    ap.add_argument("--radius", action="append")
    ap.add_argument("--color", action="append")
    ap.add_argument("--axes", action="append")
    args = ap.parse_args()

    cols, n_rows = read_csv(args.csv)
    gltf, buffer = load(args.gltf)
    nodes = gltf["nodes"]
    root = nodes[gltf["scenes"][gltf.get("scene", 0)]["nodes"][0]]
    world = nodes[root["children"][0]]
    up = [float(x) for x in args.up.split(",")]
    norm = math.sqrt(sum(u * u for u in up))
    up_g = rotate(world.get("rotation", [0, 0, 0, 1]), [u / norm for u in up])
    assert all(abs(a - b) < 1e-6 for a, b in zip(up_g, (0, 1, 0))), ("up must become +Y", up_g)

    bodies = parse_map(args.body)
    body_nodes = {nodes[i]["name"]: i for i in world["children"] if not nodes[i]["name"].startswith("body_axes_")}
    axes_nodes = {nodes[i]["name"]: i for i in world["children"] if nodes[i]["name"].startswith("body_axes_")}
    axes = parse_map(args.axes)
    want_axes = sorted("body_axes_%s_%s" % (f, c) for f in axes for c in "xyz")
    assert sorted(axes_nodes) == want_axes, ("three axes nodes per frame shown", sorted(axes_nodes), want_axes)
    want = sorted("body_" + n for n in bodies)
    assert sorted(body_nodes) == want, ("one node per drawn body", sorted(body_nodes), want)

    anim = gltf["animations"][0]
    times = cols["time"]
    checked = 0
    for channel in anim["channels"]:
        node = nodes[channel["target"]["node"]]
        name = node["name"][len("body_"):]
        if node["name"] in axes_nodes:
            continue  # checked below
        frame, body = bodies[name].split(":")
        for key in ("translation", "rotation", "scale", "matrix"):
            assert key not in node, "animated nodes stay at identity base transform"
        sampler = anim["samplers"][channel["sampler"]]
        keys_t = [r[0] for r in read_accessor(gltf, buffer, sampler["input"])]
        values = read_accessor(gltf, buffer, sampler["output"])
        assert len(keys_t) == len(values) == n_rows, ("one key per output row", len(keys_t), n_rows)
        assert all(abs(a - b) <= TOL * max(1, abs(b)) for a, b in zip(keys_t, times)), "key times = output instants"
        for k, value in enumerate(values):
            if channel["target"]["path"] == "translation":
                want_p = [cols["%s.r[%d]" % (frame, i + 1)][k] for i in range(3)]
                assert all(abs(a - b) <= TOL * max(1, abs(b)) for a, b in zip(value, want_p)), (name, k, value, want_p)
            else:
                # R(q) e_j must be column j of R_WB (q up to sign).
                for j in range(3):
                    e = [1.0 if i == j else 0.0 for i in range(3)]
                    got = rotate(value, e)
                    col = [cols["%s.R[%d,%d]" % (body, i + 1, j + 1)][k] for i in range(3)]
                    assert all(abs(a - b) <= TOL for a, b in zip(got, col)), (name, k, j, got, col)
        checked += 1
    assert checked == 2 * len(bodies), ("a translation and a rotation channel per body", checked)

    # Axes: the x, y, z rods of a frame reach LENGTH from its origin (the node's), and sit at
    # the frame's origin from the CSV at every key.
    def channel_values(node_index, path):
        for channel in anim["channels"]:
            if channel["target"]["node"] == node_index and channel["target"]["path"] == path:
                sampler = anim["samplers"][channel["sampler"]]
                return read_accessor(gltf, buffer, sampler["output"])
        raise AssertionError(("no %s channel" % path, nodes[node_index]["name"]))

    for frame, spec in axes.items():
        length, _, body = spec.partition(":")
        length = float(length)
        for c in "xyz":
            i = axes_nodes["body_axes_%s_%s" % (frame, c)]
            pts = []
            for prim in gltf["meshes"][nodes[i]["mesh"]]["primitives"]:
                pts += read_accessor(gltf, buffer, prim["attributes"]["POSITION"])
            far = max(math.sqrt(sum(x * x for x in p)) for p in pts)
            assert abs(far - length) <= 0.05 * length, (frame, c, "axis length", far, length)
            values = channel_values(i, "translation")
            assert len(values) == n_rows, (frame, c, "one key per output row", len(values), n_rows)
            for k, value in enumerate(values):
                want_p = [cols["%s.r[%d]" % (frame, j + 1)][k] for j in range(3)]
                assert all(abs(a - b) <= TOL * max(1, abs(b)) for a, b in zip(value, want_p)), \
                    (frame, c, k, value, want_p)
            rotations = channel_values(i, "rotation")
            assert len(rotations) == n_rows
            if body:  # the rod (its centroid's direction) turned by the key = column c of BODY.R
                centroid = [sum(p[j] for p in pts) / len(pts) for j in range(3)]
                norm_c = math.sqrt(sum(x * x for x in centroid))
                d = [x / norm_c for x in centroid]
                col = "xyz".index(c)
                for k, q in enumerate(rotations):
                    got = rotate(q, d)
                    want_d = [cols["%s.R[%d,%d]" % (body, j + 1, col + 1)][k] for j in range(3)]
                    assert all(abs(a - b) <= 1e-5 for a, b in zip(got, want_d)), (frame, c, k, got, want_d)

    def vertices(name):
        node = nodes[body_nodes["body_" + name]]
        pts = []
        for prim in gltf["meshes"][node["mesh"]]["primitives"]:
            pts += read_accessor(gltf, buffer, prim["attributes"]["POSITION"])
        return pts

    for name, spec in parse_map(args.bounds).items():
        want_b = [float(x) for x in spec.split(",")]
        pts = vertices(name)
        got_b = []
        for i in range(3):
            got_b += [min(p[i] for p in pts), max(p[i] for p in pts)]
        assert all(abs(a - b) <= TOL for a, b in zip(got_b, want_b)), (name, "bounds", got_b, want_b)
    for name, spec in parse_map(args.radius).items():
        r = max(math.sqrt(sum(c * c for c in p)) for p in vertices(name))
        assert abs(r - float(spec)) <= TOL, (name, "radius", r, spec)

    for name, spec in parse_map(args.color).items():
        node = nodes[body_nodes["body_" + name]]
        prim = gltf["meshes"][node["mesh"]]["primitives"][0]
        got_c = gltf["materials"][prim["material"]]["pbrMetallicRoughness"]["baseColorFactor"][:3]
        want_c = [float(x) for x in spec.split(",")]
        assert all(abs(a - b) <= TOL for a, b in zip(got_c, want_c)), (name, "colour", got_c, want_c)

    print("%s: %d bodies, %d frames' axes, %d keys each, poses equal to %s: OK" % (args.gltf, len(bodies), len(axes),
                                                                                   n_rows, args.csv))


if __name__ == "__main__":
    main()
