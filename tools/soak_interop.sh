#!/usr/bin/env bash
# Runs the Python interop suite (tests/python, real node over Cyclone DDS) N times back
# to back, no reruns, and prints the failures per test. Not part of CI: it measures how
# often the suite is green on this machine (docs/ros2_interop.md gives the count).
# Usage: bash tools/soak_interop.sh N [pytest args, e.g. tests/python/test_node.py]
# Needs the release binary (cargo build --release) and the venv (tools/python_env.sh).
# Exit code: 0 when all N runs were green, 1 otherwise.
set -uo pipefail
cd "$(dirname "$0")/.."
n=${1:?usage: tools/soak_interop.sh N [pytest args]}
shift
targets=("$@")
[ ${#targets[@]} -eq 0 ] && targets=(tests/python)
export DEVELOPABLE_SIM_BIN="${DEVELOPABLE_SIM_BIN:-$PWD/target/release/developable_sim}"
test -x "$DEVELOPABLE_SIM_BIN" || { echo "no binary at $DEVELOPABLE_SIM_BIN" >&2; exit 2; }
out=$(mktemp -d "${TMPDIR:-/tmp}/soak_interop.XXXXXX")
green=0
for i in $(seq 1 "$n"); do
  start=$(date +%s)
  if .venv/bin/python -m pytest -q -rfE -p no:cacheprovider "${targets[@]}" >"$out/run_$i.log" 2>&1; then
    green=$((green + 1)); verdict=green
  else
    verdict=red
  fi
  # "FAILED path::test - reason" / "ERROR path::test - reason" lines of the short summary
  grep -E '^(FAILED|ERROR) ' "$out/run_$i.log" | sed -E 's/ - .*//' >>"$out/failures"
  # a crashed pytest (e.g. a segfault in the Cyclone client) prints no summary: name
  # the test from the traceback
  if [ "$verdict" = red ] && ! grep -qE '^(FAILED|ERROR) ' "$out/run_$i.log"; then
    echo "CRASHED $(grep -oE 'tests/python/[a-z_]+\.py", line [0-9]+ in test_[a-z0-9_]+' "$out/run_$i.log" \
      | head -n 1 | sed -E 's/", line [0-9]+ in /::/')" >>"$out/failures"
  fi
  echo "run $i/$n: $verdict ($(( $(date +%s) - start )) s) $(tail -n 1 "$out/run_$i.log")"
done
echo "== $green of $n runs green ($(date -u +%Y-%m-%d), commit $(git rev-parse --short HEAD)); logs in $out =="
if [ -s "$out/failures" ]; then
  echo "failures per test (of $n runs):"
  sort "$out/failures" | uniq -c | sort -rn
fi
[ "$green" -eq "$n" ]
