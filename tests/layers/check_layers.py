#!/usr/bin/env python3
"""The layers of kanesim: each top-level source folder is one layer (docs/architecture.md,
"The map"), and this checks the graph on both the #include lines and the CMake link lines.

    check_layers.py ROOT          exit 1 and one line per problem
    check_layers.py --self-test   the checker finds planted violations in a scratch tree

For every layer: a CMakeLists.txt building its target, and one public header (PUBLIC) saying
what the layer offers. A file of layer A may include a header of layer B only when B is
below A (USES[A]) and the header is B's public header, one of the headers that public
header includes from B, or one it names on a `// kanesim-public: PATH` line. FRIENDS lists the
exceptions, each with its reason. Inside the runtime, its sub-folders are ordered too
(RUNTIME_ORDER). A source folder missing from USES is an error (a new folder needs a place).
"""
import os
import re
import sys
import tempfile

# Bottom up: layer -> the layers its files and its target may use.
USES = {
    "util": [],
    "flat": [],
    "stdlib": [],
    "geometry": ["util"],
    "lang": ["flat", "geometry"],
    "import": ["flat", "lang"],
    "runtime": ["flat"],
    "compiler": ["flat", "runtime"],
    "sim": ["runtime"],
    "linearize": ["flat", "runtime", "compiler", "sim"],
    "batch": ["util", "flat", "runtime", "compiler", "sim"],
    "pipeline": ["flat", "lang", "stdlib", "import", "runtime", "compiler", "sim"],
    "viz": ["util", "geometry"],
    "fmi": ["flat", "lang", "runtime", "compiler", "sim", "linearize", "pipeline"],
    "cli": ["util", "flat", "geometry", "lang", "stdlib", "import", "runtime", "compiler", "sim", "linearize", "batch",
            "pipeline", "viz", "fmi"],
    "python": ["flat", "lang", "stdlib", "import", "runtime", "compiler", "sim", "linearize", "batch", "pipeline"],
}
# The CMake target of each layer (cli's is the kanesim command, python's the module).
TARGET = {name: "kanesim_" + name for name in USES}
TARGET.update({"util": "kanesim_dynamic_module", "cli": "kanesim", "python": "_kanesim"})
# The public header of each layer.
PUBLIC = {name: f"{name}/{name}.h" for name in USES}
PUBLIC.update({"util": "util/dynamic_module.h", "cli": None, "python": None})
# Layers that may see another's internal headers, and why.
FRIENDS = {
    # The compiler writes the runtime's Program: its tapes, kinematics and constraint rows.
    ("compiler", "runtime"): "the compiler emits the runtime's internal data",
    # Linearization differentiates the loop closures and the kinematics it reads from them.
    ("linearize", "runtime"): "linearization reads the constraint rows and kinematics",
}
# The dynamics core's sub-layers, bottom up: each folder may include those before it.
RUNTIME_ORDER = ["runtime/program", "runtime/kinematics", "runtime/constraints", "runtime/kane", "runtime/engine"]

INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"]+)"')
PUBLIC_LINE = re.compile(r"//\s*kanesim-public:\s*(\S+)")
SOURCE = (".h", ".hpp", ".cpp", ".cc", ".inc")
LINK = re.compile(r"target_link_libraries\(\s*(\S+)(.*?)\)", re.S)
SKIP_DIRS = {"node_modules", "page", "__pycache__", "kanesim"}


def public_headers(root, layer):
    """The headers of `layer` other layers may include."""
    main = PUBLIC.get(layer)
    if main is None:
        return set()
    found = {main}
    path = os.path.join(root, main)
    if os.path.exists(path):
        with open(path, encoding="utf-8", errors="replace") as f:
            for line in f:
                m = INCLUDE.match(line)
                if m and m.group(1).startswith(layer + "/"):
                    found.add(m.group(1))
                m = PUBLIC_LINE.search(line)
                if m:
                    found.add(m.group(1))
    return found


def runtime_rank(path):
    for i, folder in enumerate(RUNTIME_ORDER):
        if path.startswith(folder + "/"):
            return i
    return None  # runtime/runtime.h: the engine's public face, rank of runtime/engine


def check_include(own_layer, rel, target, root, cache):
    layer = target.split("/")[0]
    if layer not in USES:
        return None  # not one of ours (a system or third-party header)
    if layer == own_layer:
        if layer != "runtime":
            return None
        mine, theirs = runtime_rank(rel), runtime_rank(target)
        mine = len(RUNTIME_ORDER) - 1 if mine is None else mine
        theirs = len(RUNTIME_ORDER) - 1 if theirs is None else theirs
        if theirs > mine:
            return f"{rel}: includes {target}, a runtime folder above its own (RUNTIME_ORDER)"
        return None
    if layer not in USES[own_layer]:
        return f"{rel}: layer {own_layer} includes {target} from {layer}, not a layer below it"
    if (own_layer, layer) in FRIENDS:
        return None
    if layer not in cache:
        cache[layer] = public_headers(root, layer)
    if target not in cache[layer]:
        return f"{rel}: includes {target}, internal to {layer} (its public header is {PUBLIC[layer]})"
    return None


def check_links(root, layer, problems):
    path = os.path.join(root, layer, "CMakeLists.txt")
    if not os.path.exists(path):
        problems.append(f"{layer}/: no CMakeLists.txt (each layer builds its own target)")
        return
    text = open(path, encoding="utf-8").read()
    ours = {TARGET[name]: name for name in USES}
    for m in LINK.finditer(text):
        if m.group(1) != TARGET[layer]:
            continue
        for word in m.group(2).split():
            other = ours.get(word)
            if other is not None and other != layer and other not in USES[layer]:
                problems.append(f"{layer}/CMakeLists.txt: {TARGET[layer]} links {word}, not a layer below it")


def check(root):
    problems = []
    cache = {}
    # Every top-level folder holding C++ sources is a layer with a place in USES.
    for entry in sorted(os.listdir(root)):
        full = os.path.join(root, entry)
        if not os.path.isdir(full) or entry.startswith(".") or entry in ("tests", "bench", "build", "docs", "examples",
                                                                          "scripts", "cmake"):
            continue
        if entry.startswith("build"):
            continue
        has_source = any(n.endswith(SOURCE) for _, _, names in os.walk(full) for n in names)
        if has_source and entry not in USES:
            problems.append(f"{entry}/: a source folder with no place in the layers (tests/layers/check_layers.py USES)")
    for layer in USES:
        base = os.path.join(root, layer)
        if not os.path.isdir(base):
            continue
        if PUBLIC.get(layer) and not os.path.exists(os.path.join(root, PUBLIC[layer])):
            problems.append(f"{layer}/: no public header {PUBLIC[layer]}")
        if layer != "python":
            check_links(root, layer, problems)
        for dirpath, dirnames, filenames in os.walk(base):
            dirnames[:] = sorted(d for d in dirnames if d not in SKIP_DIRS)
            for name in sorted(filenames):
                if not name.endswith(SOURCE):
                    continue
                path = os.path.join(dirpath, name)
                rel = os.path.relpath(path, root).replace(os.sep, "/")
                if layer == "runtime" and rel != "runtime/runtime.h" and runtime_rank(rel) is None:
                    problems.append(f"{rel}: a runtime folder with no place in RUNTIME_ORDER")
                    continue
                with open(path, encoding="utf-8", errors="replace") as f:
                    for line_no, line in enumerate(f, 1):
                        m = INCLUDE.match(line)
                        if not m:
                            continue
                        p = check_include(layer, rel, m.group(1), root, cache)
                        if p:
                            problems.append(p.replace(f"{rel}:", f"{rel}:{line_no}:", 1))
    return problems


def self_test():
    with tempfile.TemporaryDirectory() as d:
        def put(rel, text):
            p = os.path.join(d, rel)
            os.makedirs(os.path.dirname(p), exist_ok=True)
            with open(p, "w") as f:
                f.write(text)
        put("flat/flat.h", '#include "flat/mechanism.h"\n')
        put("flat/CMakeLists.txt", "add_library(kanesim_flat STATIC m.cpp)\n")
        put("runtime/runtime.h", "// kanesim-public: runtime/program/program.h\n")
        put("runtime/CMakeLists.txt", "target_link_libraries(kanesim_runtime PUBLIC kanesim_flat)\n")
        put("runtime/constraints/c.cpp", '#include "runtime/kinematics/k.h"\n')  # down: fine
        put("sim/sim.h", "\n")
        put("sim/CMakeLists.txt", "target_link_libraries(kanesim_sim PUBLIC kanesim_runtime)\n")
        put("sim/s.cpp", '#include "runtime/runtime.h"\n#include "runtime/program/program.h"\n')  # public
        put("lang/lang.h", "\n")
        put("lang/CMakeLists.txt", "target_link_libraries(kanesim_lang PUBLIC kanesim_flat)\n")
        put("lang/l.cpp", '#include <vector>\n#include "flat/mechanism.h"\n')  # a part of flat/flat.h
        put("compiler/compiler.h", '#include "runtime/kane/kane.h"\n')  # a friend of the runtime
        put("compiler/CMakeLists.txt", "target_link_libraries(kanesim_compiler PUBLIC kanesim_runtime)\n")
        clean = check(d)
        if clean:
            print("self-test: a clean tree was reported:", clean)
            return 1
        put("runtime/kinematics/bad.cpp", '#include "runtime/kane/kane.h"\n')  # up inside the runtime
        put("sim/bad.cpp", '#include "runtime/kane/kane.h"\n')                 # past the public face
        put("lang/bad.cpp", '  #  include "runtime/runtime.h"\n')             # lang into the runtime
        put("lang/bad2.cpp", '#include "flat/expr.h"\n')                       # not listed by flat/flat.h
        put("newlayer/x.cpp", "\n")                                             # no place
        put("runtime/newfolder/x.cpp", "\n")                                    # no place in the runtime
        put("lang/CMakeLists.txt", "target_link_libraries(kanesim_lang PUBLIC kanesim_flat kanesim_sim)\n")  # links up
        os.remove(os.path.join(d, "sim/sim.h"))                                 # no public header
        found = check(d)
        want = ["runtime/kinematics/bad.cpp:1", "sim/bad.cpp:1", "lang/bad.cpp:1", "lang/bad2.cpp:1", "newlayer/",
                "runtime/newfolder/x.cpp", "lang/CMakeLists.txt", "sim/: no public header"]
        missing = [w for w in want if not any(p.startswith(w) for p in found)]
        if missing or len(found) != len(want):
            print("self-test: expected", want, "found", found)
            return 1
    print(f"self-test: {len(want)} planted violations found, a clean tree passes")
    return 0


def main(argv):
    if len(argv) == 2 and argv[1] == "--self-test":
        return self_test()
    if len(argv) != 2:
        print(__doc__)
        return 2
    problems = check(argv[1])
    for p in problems:
        print(p)
    if problems:
        print(f"{len(problems)} problem(s) against the layers (docs/architecture.md)")
        return 1
    print("every layer has its target and public header; every include and link points down")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
