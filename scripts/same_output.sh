#!/bin/bash
# Compares two kanesim binaries' output, for refactors that must not change it:
# `check`, `check --emit flat` and `check --emit ast` on every .mech under examples/ and
# tests/ (diagnostics included, with their exit codes), the chain at N = 1, 3, 25, 100, and
# `run` of every example (the CSV). Prints each difference; exit 1 if there is any.
#   scripts/same_output.sh OLD_BINARY NEW_BINARY
set -u
if [ $# -ne 2 ]; then
  echo "usage: $0 OLD_BINARY NEW_BINARY" >&2
  exit 2
fi
old=$(realpath "$1")
new=$(realpath "$2")
cd "$(dirname "$0")/.." || exit 2
compared=0
differ=0
compare() {
  local a b
  a=$("$old" "$@" 2>&1; echo "exit $?")
  b=$("$new" "$@" 2>&1; echo "exit $?")
  compared=$((compared + 1))
  if [ "$a" != "$b" ]; then
    differ=$((differ + 1))
    echo "differs: kanesim $*"
    diff <(echo "$a") <(echo "$b") | head -5
  fi
}
while IFS= read -r f; do
  compare check "$f"
  compare check --emit flat "$f"
  compare check --emit ast "$f"
done < <(find examples tests -name '*.mech' | sort)
for n in 1 3 25 100; do
  compare check examples/chain.mech --set "N=$n"
  compare check --emit flat examples/chain.mech --set "N=$n"
done
for f in examples/*.mech; do compare run "$f"; done
echo "$compared compared, $differ differ"
[ "$differ" -eq 0 ]
