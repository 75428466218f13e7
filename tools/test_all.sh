#!/usr/bin/env bash
# Runs every test of developable_sim: the Rust unit and integration tests, then the
# Python interop tests (cyclonedds, rosbags, mcap-ros2-support) against the real binary.
# Creates the Python venv (.venv) on first use. Usage: bash tools/test_all.sh
set -euo pipefail
cd "$(dirname "$0")/.."

echo "== cargo test =="
cargo test --release --lib --bins --tests -- --test-threads=2
# benchmarks must keep compiling (criterion's own runner does not take test flags)
cargo build --release --benches

if [ -d tests/python ] && ls tests/python/test_*.py >/dev/null 2>&1; then
  echo "== python interop tests =="
  bash tools/python_env.sh
  cargo build --release --bin developable_sim
  DEVELOPABLE_SIM_BIN="$PWD/target/release/developable_sim" .venv/bin/python -m pytest -q tests/python
fi
