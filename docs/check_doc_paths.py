#!/usr/bin/env python3
"""The docs name only what exists: every repository path, link target (and its #anchor), every
`kanesim` subcommand and every kanesim option named in README.md, tests/README.md and
docs/*.md exists, and no docs/*.md page is over 60 KB (README.md: 6 KB) — a page a reader can
finish. Dated history under docs/benchmarks/ and docs/constraints/ is kept verbatim and not
checked: it names what existed then.

Usage: check_doc_paths.py ROOT KANESIM     (exit 1, one line per problem: page:line: what)
       check_doc_paths.py --self-test      (the checker finds planted mistakes)

Paths: a word starting with a top-level folder of the repository (`runtime/runtime.h`,
`tests/viz/`) is resolved from the root; a Markdown link from its page. `<NAME>` and `*` in a
path are wildcards. Commands and options: in code (`inline` or fenced), the words after
`kanesim` or `build/cli/kanesim` (or a code span starting with a command name: `run -o`) are
checked against `kanesim <command> --help`; an option alone in a code span (`--stats`) against
every command's options. Options after another program (cmake, ctest, a script) are its own.
"""
import glob
import os
import re
import sys

PAGE_LIMIT = 60 * 1024
README_LIMIT = 6 * 1024
TOP_FOLDERS = (".ci", "lang", "runtime", "cli", "docs", "tests", "scripts", "examples", "bench",
               "stdlib", "python", "cmake")
PATH = re.compile(r"(?<![\w./~$-])((?:%s)/[\w./*<>{},-]*)" % "|".join(re.escape(t) for t in TOP_FOLDERS))
LINK = re.compile(r"\]\(([^)\s]+)\)")
OPTION = re.compile(r"^(--[A-Za-z][\w-]*|-[A-Za-z])")  # -j4 is -j
# Options of other programs the pages name alone in a code span: Chromium's, for the browser
# tests (docs/visualization.md).
FOREIGN_OPTIONS = {"--remote-debugging-pipe", "--headless", "--disable-webgl", "--disable-gpu",
                   "--disable-software-rasterizer", "--no-sandbox", "--use-angle",
                   "--enable-unsafe-swiftshader"}


# ---------------------------------------------------------------------------------------------
# What the binary accepts


# parse_help and binary_commands: shared with the docs/cli.md check (same folder).
from check_cli_docs import binary_commands  # noqa: E402


# ---------------------------------------------------------------------------------------------
# Markdown: headings (anchors), code, links


def slug(heading):
    """GitHub's anchor for a heading: lower case, punctuation dropped, spaces to hyphens."""
    text = re.sub(r"`|\*\*|\[([^\]]*)\]\([^)]*\)", r"\1", heading.strip()).lower()
    return re.sub(r"[^\w\- ]", "", text).replace(" ", "-")


def anchors(text):
    found, seen, fenced = set(), {}, False
    for line in text.splitlines():
        if line.startswith("```"):
            fenced = not fenced
        m = re.match(r"#{1,6} (.*)", line)
        if m and not fenced:
            base = slug(m.group(1))
            n = seen.get(base, 0)
            seen[base] = n + 1
            found.add(base if n == 0 else f"{base}-{n}")
        if not fenced:
            found.update(re.findall(r"<a (?:id|name)=\"([^\"]+)\"", line))  # explicit anchors
    return found


def code_pieces(text):
    """(line number, code) for each fenced or indented code line (continuations joined) and
    each inline code span."""
    pieces, fenced, pending, start = [], False, "", 0
    for number, line in enumerate(text.splitlines(), 1):
        if line.startswith("```"):
            fenced = not fenced
            continue
        if fenced or line.startswith("    "):
            if not pending:
                start = number
            pending += line.strip().rstrip("\\") + " "
            if not line.rstrip().endswith("\\"):
                pieces.append((start, pending))
                pending = ""
            continue
        for span in re.findall(r"``?([^`]+)``?", line):
            pieces.append((number, span))
    return pieces


# ---------------------------------------------------------------------------------------------
# The checks


def is_kanesim(word):
    return word == "kanesim" or word.endswith("/kanesim")


def check_command(tokens, commands, all_options):
    """Problems with the kanesim commands and options in one shell command's words."""
    problems, command, state = [], "", None
    words = [w.strip("'\"(),;.") if not w.startswith("-") else w.rstrip("'\",;.)") for w in tokens]
    i = 0
    while i < len(words):
        w = words[i]
        if is_kanesim(w):
            state, command = "kanesim", ""
            nxt = words[i + 1].rstrip(":") if i + 1 < len(words) else ""  # "kanesim run: error"
            if re.fullmatch(r"[a-z][a-z-]*", nxt):
                if nxt not in commands:
                    problems.append(f"'kanesim {nxt}': no such command")
                    state = "unknown"
                else:
                    command, i = nxt, i + 1
                    sub = words[i + 1] if i + 1 < len(words) else ""
                    if f"{command} {sub}" in commands:
                        command, i = f"{command} {sub}", i + 1
        elif i == 0 and w in commands and w:
            state, command = "kanesim", w  # `run -o`, `sweep --mpi`: a command named in prose
        elif w.startswith("-") and OPTION.match(w):
            option = OPTION.match(w).group(1)
            if state == "kanesim":
                accepted = commands[command] | (commands["sweep"] if command == "sweep merge" else set())
                if option not in accepted:
                    problems.append(f"'kanesim {command}'".replace(" '", "'") + f" takes no {option}")
            elif state is None and option.startswith("--") and option not in all_options | FOREIGN_OPTIONS:
                problems.append(f"{option}: no kanesim command takes it")
        elif state is None and not re.fullmatch(r"[A-Z_]+=\S*", w):
            state = "other"  # another program (cmake, ctest, a script): its options are its own
        i += 1
    return problems


def expand_braces(path):
    """sim/newton_krylov.{h,cpp} -> both paths."""
    m = re.search(r"\{([^{}]*)\}", path)
    if not m:
        return [path]
    return [p for alt in m.group(1).split(",") for p in expand_braces(path[:m.start()] + alt + path[m.end():])]


def path_exists(root, path):
    """A path, a glob (<NAME> and * are wildcards) or a build target named after its source
    (bench/rhs_chain for bench/rhs_chain.cpp)."""
    for alternative in expand_braces(path):
        pattern = os.path.join(root, re.sub(r"<[^>]*>", "*", alternative))
        if not (glob.glob(pattern) or glob.glob(pattern + ".*")):
            return False
    return True


def check_page(root, page, commands):
    problems = []
    with open(page, encoding="utf-8") as f:
        text = f.read()
    rel = os.path.relpath(page, root)
    size = len(text.encode("utf-8"))
    limit = README_LIMIT if rel == "README.md" else PAGE_LIMIT
    if size > limit:
        problems.append(f"{rel}: {size} bytes, over the {limit // 1024} KB a reader can finish")
    all_options = set().union(*commands.values())
    here = os.path.dirname(page)
    for number, line in enumerate(text.splitlines(), 1):
        for target in LINK.findall(re.sub(r"`[^`]*`", "", line)):  # `a[N](...)` is code
            if re.match(r"[a-z]+:", target):
                continue  # http:, https:, mailto:
            path, _, anchor = target.partition("#")
            full = os.path.normpath(os.path.join(here, path)) if path else page
            if not os.path.exists(full):
                problems.append(f"{rel}:{number}: link to {target}: no such file")
            elif anchor and full.endswith(".md"):
                with open(full, encoding="utf-8") as f:
                    if anchor not in anchors(f.read()):
                        problems.append(f"{rel}:{number}: link to {target}: no such heading")
        for path in PATH.findall(line):
            path = path.rstrip(".,")
            if not path_exists(root, path):
                problems.append(f"{rel}:{number}: {path}: no such file or folder")
    for number, code in code_pieces(text):
        code = re.sub(r"(^|\s)#.*", "", code)  # a shell comment
        for command in re.split(r"\|\||&&|[|;]|\$\(|\)", code):
            problems += [f"{rel}:{number}: {p}" for p in check_command(command.split(), commands, all_options)]
    return problems


def pages(root):
    found = [os.path.join(root, "README.md"), os.path.join(root, "tests", "README.md")]
    return found + sorted(glob.glob(os.path.join(root, "docs", "*.md")))


def self_test():
    import tempfile

    commands = {"": {"-h", "--help", "--version"}, "run": {"-h", "--help", "-o", "--out", "--stats"},
                "sweep": {"-h", "--help", "--grid"}, "sweep merge": {"-h", "--help", "-o"}}
    with tempfile.TemporaryDirectory() as root:
        os.makedirs(os.path.join(root, "docs"))
        os.makedirs(os.path.join(root, "cli"))
        open(os.path.join(root, "cli", "main.cpp"), "w").close()
        good = ("# Page\n## A `run` heading\nSee cli/main.cpp, [here](#a-run-heading), `--stats`,\n"
                "**Bold.** <a id=\"bold\"></a> [there](#bold)\n"
                "`kanesim run -o x.csv --stats`, cli/main.{cpp}, cli/main, `a[N](...)`, `kanesim sweep merge -o s.csv`, `cmake --build b`,\n"
                "```sh\nbuild/cli/kanesim run m.mech \\\n  --stats   # a comment --bad\nctest --output-on-failure\n```\n")
        bad = {"cli/gone.cpp": "no such file", "[x](nothere.md)": "no such file",
               "[x](#nowhere)": "no such heading", "`kanesim walk`": "no such command",
               "`kanesim run --fast`": "takes no --fast", "`--fast`": "no kanesim command",
               "`run --grid`": "takes no --grid", "cli/{main,gone}.cpp": "no such file", "x" * (PAGE_LIMIT + 1): "over the 60 KB"}
        page = os.path.join(root, "docs", "page.md")
        with open(page, "w") as f:
            f.write(good)
        assert check_page(root, page, commands) == [], check_page(root, page, commands)
        for mistake, expected in bad.items():
            with open(page, "w") as f:
                f.write(good + mistake + "\n")
            found = check_page(root, page, commands)
            assert len(found) == 1 and expected in found[0], (mistake, found)
    print(f"self-test: the checker finds each of {len(bad)} planted mistakes and nothing in a good page")


def main():
    if sys.argv[1:] == ["--self-test"]:
        self_test()
        return 0
    if len(sys.argv) != 3:
        print(__doc__, file=sys.stderr)
        return 2
    root, kanesim = sys.argv[1:]
    commands = binary_commands(kanesim)
    problems = []
    checked = pages(root)
    for page in checked:
        problems += check_page(root, page, commands)
    for p in problems:
        print(p)
    if problems:
        print(f"{len(problems)} problems in {len(checked)} pages")
        return 1
    print(f"{len(checked)} pages: every path, link, command and option named exists; no page too long")
    return 0


if __name__ == "__main__":
    sys.exit(main())
