#!/usr/bin/env python3
"""docs/cli.md against the binary: every option `kanesim <command> --help` lists has a row in
that command's option table, and every row names an option the command takes.

Usage: check_cli_docs.py KANESIM DOCS/cli.md      (exit 1 with the differences)
       check_cli_docs.py --self-test              (the checker finds planted gaps)

The page has a section "## kanesim CMD" (or "## kanesim CMD SUB") per command, each with a
table whose rows start with the option names in backticks (`-o`, `--out FILE`). `-h`/`--help`
and the top level's `--version` are in the table before the first command section.
"""
import re
import subprocess
import sys

OPTION = re.compile(r"(?<![\w-])(--?[A-Za-z][\w-]*)")


def help_text(kanesim, words):
    out = subprocess.run([kanesim, *words, "--help"], capture_output=True, text=True, check=True)
    return out.stdout


def parse_help(text):
    """(options, subcommands) of one CLI11 help page."""
    options, subcommands, section = set(), [], None
    for line in text.splitlines():
        if line and not line.startswith(" "):
            section = line.rstrip(":")
            continue
        m = re.match(r"  (\S+)", line)
        if not m:
            continue
        if section == "Options":
            options.update(name for name in m.group(1).split(",") if name.startswith("-"))
        elif section == "Subcommands":
            subcommands.append(m.group(1))
    return options, subcommands


def binary_commands(kanesim):
    """{"": top-level options, "run": its options, "sweep merge": ..., ...}."""
    top, names = parse_help(help_text(kanesim, []))
    commands = {"": top}
    for name in names:
        options, subs = parse_help(help_text(kanesim, [name]))
        commands[name] = options
        for sub in subs:
            commands[f"{name} {sub}"] = parse_help(help_text(kanesim, [name, sub]))[0]
    return commands


def parse_page(text):
    """{"": options of the table before the first command, "run": options of its table...}."""
    commands, current = {"": set()}, ""
    for line in text.splitlines():
        heading = re.match(r"## kanesim ([a-z][\w-]*(?: [a-z][\w-]*)?)\s*$", line)
        if heading:
            current = heading.group(1)
            commands[current] = set()
        elif line.startswith("## "):
            current = None  # a section that documents no command (e.g. installing)
        elif current is not None and line.startswith("| `"):
            first_cell = line.split(" | ")[0]
            commands[current].update(OPTION.findall(" ".join(re.findall(r"`([^`]*)`", first_cell))))
    return commands


def compare(binary, page):
    """The differences as lines of text; empty when the page and the binary agree."""
    problems = []
    help_options = {"-h", "--help"}
    for command in sorted(set(binary) | set(page)):
        label = f"kanesim {command}".strip()
        if command not in page:
            problems.append(f"{label}: the binary has this command; docs/cli.md has no '## {label}' section")
            continue
        if command not in binary:
            problems.append(f"{label}: documented in docs/cli.md, but the binary has no such command")
            continue
        # -h/--help is in every command's help and documented once, in the first table.
        want = binary[command] - (help_options if command else set())
        have = page[command]
        for option in sorted(want - have):
            problems.append(f"{label}: {option} is accepted by the binary but not in its table in docs/cli.md")
        for option in sorted(have - want):
            problems.append(f"{label}: docs/cli.md documents {option}, which the binary does not accept")
    return problems


def self_test():
    """The checker must see an undocumented option, a stale row and a missing command."""
    help_run = "Usage: kanesim run\n\nOptions:\n  -h,--help   Print\n  -o,--out TEXT  Out\n  --stats  S\n"
    binary = {"": {"-h", "--help"}, "run": parse_help(help_run)[0]}
    assert binary["run"] == {"-h", "--help", "-o", "--out", "--stats"}, binary
    good = "| `-h`, `--help` | x |\n## kanesim run\n| `-o`, `--out FILE` | x |\n| `--stats` | x |\n"
    assert compare(binary, parse_page(good)) == [], compare(binary, parse_page(good))
    missing = good.replace("| `--stats` | x |\n", "")
    assert any("--stats is accepted" in p for p in compare(binary, parse_page(missing)))
    stale = good + "| `--gone X` | x |\n"
    assert any("documents --gone" in p for p in compare(binary, parse_page(stale)))
    no_section = "| `-h`, `--help` | x |\n"
    assert any("no '## kanesim run' section" in p for p in compare(binary, parse_page(no_section)))
    print("self-test: the checker finds an undocumented option, a stale row and a missing command")


def main():
    if sys.argv[1:] == ["--self-test"]:
        self_test()
        return 0
    if len(sys.argv) != 3:
        print(__doc__, file=sys.stderr)
        return 2
    kanesim, page_path = sys.argv[1:]
    with open(page_path, encoding="utf-8") as f:
        page = parse_page(f.read())
    binary = binary_commands(kanesim)
    problems = compare(binary, page)
    for p in problems:
        print(p)
    if problems:
        return 1
    count = sum(len(v) for v in binary.values())
    print(f"docs/cli.md documents the {len(binary) - 1} commands and their {count} options, and no other")
    return 0


if __name__ == "__main__":
    sys.exit(main())
