#!/usr/bin/env python3
"""Parses the animation files written by write_animation back, with the standard library only
(JSON + binary buffer; no assimp), and checks them against expected.json, the poses given.

What would be wrong if it failed: the file is not what kanesim promises (docs/visualization.md):
one animated node per body at identity base transform under a static node that turns the world's
up direction into +Y; key count = number of instants; times, positions and rotations equal to the
poses given (rotations up to sign); a material with the body's colour.

Usage: check_gltf.py OUTDIR
"""
import json
import math
import os
import struct
import sys

# Keys are stored as float32: a value round-trips to within half an ulp.
FLOAT_REL = 2.0 ** -23


def load(path):
    """Returns (gltf dict, binary buffer bytes)."""
    with open(path, "rb") as f:
        data = f.read()
    if path.endswith(".glb"):
        magic, version, length = struct.unpack_from("<4sII", data, 0)
        assert magic == b"glTF" and version == 2 and length == len(data), (magic, version, length, len(data))
        json_len, json_type = struct.unpack_from("<I4s", data, 12)
        assert json_type == b"JSON"
        gltf = json.loads(data[20:20 + json_len])
        offset = 20 + json_len
        bin_len, bin_type = struct.unpack_from("<I4s", data, offset)
        assert bin_type == b"BIN\x00"
        buffer = data[offset + 8:offset + 8 + bin_len]
        assert "uri" not in gltf["buffers"][0]
    else:
        gltf = json.loads(data)
        uri = gltf["buffers"][0]["uri"]
        assert "/" not in uri and not uri.startswith("data:"), uri  # a .bin beside the .gltf
        with open(os.path.join(os.path.dirname(path), uri), "rb") as f:
            buffer = f.read()
    assert gltf["asset"]["version"] == "2.0"
    assert len(buffer) >= gltf["buffers"][0]["byteLength"]
    return gltf, buffer


def read_accessor(gltf, buffer, index):
    acc = gltf["accessors"][index]
    assert acc["componentType"] == 5126, acc  # FLOAT
    width = {"SCALAR": 1, "VEC3": 3, "VEC4": 4}[acc["type"]]
    view = gltf["bufferViews"][acc["bufferView"]]
    stride = view.get("byteStride", 4 * width)
    start = view.get("byteOffset", 0) + acc.get("byteOffset", 0)
    rows = []
    for i in range(acc["count"]):
        rows.append(struct.unpack_from("<%df" % width, buffer, start + i * stride))
    return rows


def close(a, b, scale=1.0):
    return abs(a - b) <= 2 * FLOAT_REL * max(abs(b), scale)


def rotate(q, v):
    """Rotates v by the unit quaternion q = (x, y, z, w) (glTF order)."""
    x, y, z, w = q
    # v' = v + 2 w (u × v) + 2 u × (u × v), u = (x, y, z)
    ux = (y * v[2] - z * v[1], z * v[0] - x * v[2], x * v[1] - y * v[0])
    uux = (y * ux[2] - z * ux[1], z * ux[0] - x * ux[2], x * ux[1] - y * ux[0])
    return tuple(v[i] + 2 * w * ux[i] + 2 * uux[i] for i in range(3))


def check(path, node_names, expected):
    gltf, buffer = load(path)
    nodes = gltf["nodes"]
    scene = gltf["scenes"][gltf.get("scene", 0)]
    assert len(scene["nodes"]) == 1
    root = nodes[scene["nodes"][0]]
    for key in ("translation", "rotation", "scale", "matrix"):
        assert key not in root, "the root must be at identity"
    assert len(root["children"]) == 1
    world = nodes[root["children"][0]]
    # Only a rotation (assimp 5.2 also writes a zero translation: any translation but (1, 1, 1)).
    assert "matrix" not in world and world.get("scale", [1, 1, 1]) == [1, 1, 1], world
    assert world.get("translation", [0, 0, 0]) == [0, 0, 0], world
    up = rotate(world["rotation"], expected["up"])
    assert all(abs(u - e) < 1e-6 for u, e in zip(up, (0, 1, 0))), ("up must become +Y", up)

    body_nodes = [nodes[i] for i in world["children"]]
    assert [n["name"] for n in body_nodes] == node_names, ([n["name"] for n in body_nodes], node_names)
    assert len(set(node_names)) == len(node_names), "node names must be unique"
    index_of = {n["name"]: i for i, n in zip(world["children"], body_nodes)}
    for b, node in enumerate(body_nodes):
        for key in ("translation", "rotation", "scale", "matrix"):
            assert key not in node, "animated nodes must be at identity base transform"
        mesh = gltf["meshes"][node["mesh"]]
        material = gltf["materials"][mesh["primitives"][0]["material"]]
        color = material["pbrMetallicRoughness"]["baseColorFactor"]
        assert all(close(c, e) for c, e in zip(color, expected["colors"][b])), (color, expected["colors"][b])

    assert len(gltf["animations"]) == 1
    anim = gltf["animations"][0]
    times = expected["times"]
    seen = set()
    for channel in anim["channels"]:
        target = channel["target"]
        node_index, path_kind = target["node"], target["path"]
        b = node_names.index(nodes[node_index]["name"])
        assert index_of[node_names[b]] == node_index
        seen.add((b, path_kind))
        sampler = anim["samplers"][channel["sampler"]]
        assert sampler.get("interpolation", "LINEAR") == "LINEAR"
        keys_t = [r[0] for r in read_accessor(gltf, buffer, sampler["input"])]
        values = read_accessor(gltf, buffer, sampler["output"])
        assert len(keys_t) == len(times) == len(values), (len(keys_t), len(times), len(values))
        assert all(close(t, e) for t, e in zip(keys_t, times)), "times must be the instants, in seconds"
        for k, value in enumerate(values):
            pose = expected["poses"][k][b]
            if path_kind == "translation":
                assert all(close(v, e) for v, e in zip(value, pose[0:3])), (k, b, value, pose)
            else:
                assert path_kind == "rotation", path_kind
                w, x, y, z = pose[3:7]
                want = (x, y, z, w)
                same = all(close(v, e) for v, e in zip(value, want))
                flipped = all(close(v, -e) for v, e in zip(value, want))
                assert same or flipped, (k, b, value, want)
                assert abs(math.sqrt(sum(v * v for v in value)) - 1) < 1e-6
    want_channels = {(b, p) for b in range(len(node_names)) for p in ("translation", "rotation")}
    assert seen == want_channels, (seen, want_channels)
    return len(anim["channels"])


def main():
    outdir = sys.argv[1]
    checked = 0
    for json_name in sorted(os.listdir(outdir)):
        if not (json_name.startswith("expected") and json_name.endswith(".json")):
            continue
        with open(os.path.join(outdir, json_name)) as f:
            expected = json.load(f)
        for name, node_names in expected["files"].items():
            channels = check(os.path.join(outdir, name), node_names, expected)
            checked += 1
            print("%s: %d bodies, %d channels of %d keys: OK" % (name, len(node_names), channels,
                                                                 len(expected["times"])))
    assert checked == 3, "expected motion.glb, motion.gltf and decimated.glb, checked %d" % checked


if __name__ == "__main__":
    main()
