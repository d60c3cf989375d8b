#!/usr/bin/env python3
"""The layers of kanesim, checked on the #include lines (docs/architecture.md, "Which target
may include which" and "The layers of the runtime").

    check_layers.py ROOT          exit 1 and one line per include that points up
    check_layers.py --self-test   the checker finds planted violations in a scratch tree

Each source folder may include its own headers and those of the folders RULES lists for
it; a folder missing from RULES is an error too (a new folder must be given its place).
"""
import os
import re
import sys
import tempfile

CORE = ["runtime/flat", "runtime/program", "runtime/kinematics", "runtime/constraints",
        "runtime/kane", "runtime/engine"]

# folder -> the folders (or exact headers) its files may include, bottom up.
RULES = {
    "runtime/util": [],
    "runtime/flat": [],
    "stdlib": [],
    "runtime/geometry": ["runtime/util"],
    "runtime/viz": ["runtime/geometry", "runtime/util"],
    "lang": ["runtime/flat", "runtime/geometry"],
    # The dynamics core, folder by folder (kanesim_dynamics).
    "runtime/program": CORE[:1],
    "runtime/kinematics": CORE[:2],
    "runtime/constraints": CORE[:3],
    "runtime/kane": CORE[:4],
    "runtime/engine": CORE[:5],
    # kanesim_compile and kanesim_sim on top of it; sim sees only the facade.
    "runtime/compile": CORE,
    "runtime/sim": ["runtime/engine/engine.h"],
    # The layers above the runtime.
    "runtime/linearize": CORE + ["runtime/compile", "runtime/sim"],
    "runtime/batch": CORE + ["runtime/compile", "runtime/sim", "runtime/util"],
    "runtime/pipeline": CORE + ["runtime/compile", "runtime/sim", "lang", "stdlib"],
}
INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"]+)"')
SOURCE = (".h", ".hpp", ".cpp", ".cc", ".inc")


def folder_of(rel):
    """The RULES key a file (relative path) belongs to, the longest match."""
    best = None
    for key in RULES:
        if rel == key or rel.startswith(key + "/"):
            if best is None or len(key) > len(best):
                best = key
    return best


def allowed(own, target, rules):
    if target.startswith(own + "/"):
        return True
    for a in rules:
        if target == a or target.startswith(a + "/"):
            return True
    return False


def check(root):
    problems = []
    for sub in ["lang", "runtime", "stdlib"]:
        for dirpath, dirnames, filenames in os.walk(os.path.join(root, sub)):
            dirnames[:] = [d for d in dirnames if d not in ("node_modules",)]
            for name in sorted(filenames):
                if not name.endswith(SOURCE):
                    continue
                path = os.path.join(dirpath, name)
                rel = os.path.relpath(path, root).replace(os.sep, "/")
                own = folder_of(rel)
                if own is None:
                    problems.append(f"{rel}: folder has no place in the layers (tests/layers/check_layers.py RULES)")
                    continue
                with open(path, encoding="utf-8", errors="replace") as f:
                    for line_no, line in enumerate(f, 1):
                        m = INCLUDE.match(line)
                        if not m:
                            continue
                        target = m.group(1)
                        # Only the project's own headers (a folder of the tree) are ruled.
                        top = target.split("/")[0]
                        if top not in ("lang", "runtime", "stdlib", "cli", "python"):
                            continue
                        if not allowed(own, target, RULES[own]):
                            problems.append(f"{rel}:{line_no}: {own} includes {target}, a layer above or beside it")
    return problems


def self_test():
    with tempfile.TemporaryDirectory() as d:
        def put(rel, text):
            p = os.path.join(d, rel)
            os.makedirs(os.path.dirname(p), exist_ok=True)
            with open(p, "w") as f:
                f.write(text)
        put("runtime/constraints/c.cpp", '#include "runtime/kinematics/k.h"\n')  # down: fine
        put("runtime/kane/k.cpp", '#include "runtime/constraints/c.h"\n')        # down: fine
        put("runtime/sim/s.cpp", '#include "runtime/engine/engine.h"\n')         # the facade: fine
        put("lang/l.cpp", '#include <vector>\n#include "runtime/flat/m.h"\n')      # fine
        if check(d):
            print("self-test: a clean tree was reported:", check(d))
            return 1
        put("runtime/constraints/bad.cpp", '#include "runtime/kane/kane.h"\n')   # up
        put("runtime/sim/bad.cpp", '#include "runtime/program/program.h"\n')     # past the facade
        put("lang/bad.cpp", '  #  include "runtime/engine/engine.h"\n')          # lang into the runtime
        put("runtime/newfolder/x.cpp", "\n")                                       # no place
        found = check(d)
        want = ["runtime/constraints/bad.cpp:1", "runtime/sim/bad.cpp:1", "lang/bad.cpp:1", "runtime/newfolder/x.cpp"]
        missing = [w for w in want if not any(p.startswith(w) for p in found)]
        if missing or len(found) != len(want):
            print("self-test: expected", want, "found", found)
            return 1
    print("self-test: 4 planted violations found, a clean tree passes")
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
        print(f"{len(problems)} include(s) against the layers (docs/architecture.md)")
        return 1
    print("every include points down the layers")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
