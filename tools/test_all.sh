#!/usr/bin/env bash
# Runs every test of developable_sim: the Rust unit and integration tests, the Python
# package (python/: its wheel built by maturin, installed into the venv, pytest
# python/tests), then the Python interop tests (cyclonedds, rosbags, mcap-ros2-support)
# against the real binary. Creates the Python venv (.venv) on first use.
# Usage: bash tools/test_all.sh
set -euo pipefail
cd "$(dirname "$0")/.."

# lint first: a formatting or clippy failure stops the run within minutes instead of
# after the tests. `cargo fmt --check` takes about a second; clippy checks every
# dependency once more (check artifacts are not the release build's): 18 min cold on
# the 2-core CI machine under load on 2026-12-02, under a minute after a change to
# this crate alone.
echo "== cargo fmt --check, cargo clippy =="
cargo fmt --check
cargo clippy --release --workspace --all-targets -- -D warnings

echo "== cargo test =="
cargo test --release --workspace --lib --bins --tests -- --test-threads=2
# benchmarks and the debugging examples (examples/) must keep compiling (criterion's
# own runner does not take test flags)
cargo build --release --workspace --benches --examples
# error against run time on short scenes (issue 6): the binary `cargo test` built
echo "== report --quick =="
./target/release/developable_sim report --quick --out target/report

echo "== stress suite (quick) =="
# the binary `cargo test --release` built; exits non-zero if any run fails
./target/release/developable_sim stress --quick --out target/stress

echo "== Python package: wheel (maturin), pytest python/tests =="
bash tools/python_env.sh
# the wheel as users get it (abi3, CPython >= 3.9), installed into the venv; the
# library inside is built without its node and tools features (python/Cargo.toml), so
# this compiles developable_sim once more, without DDS (about 2 min on the 2-core CI
# machine, measured in docs/python.md)
rm -rf target/wheels
.venv/bin/maturin build --release --quiet -m python/Cargo.toml -o target/wheels
.venv/bin/pip install --quiet --force-reinstall --no-deps target/wheels/developable_sim-*.whl
# its tests compare against the binary `cargo test` built (run, render)
DEVELOPABLE_SIM_BIN="$PWD/target/release/developable_sim" .venv/bin/python -m pytest -q python/tests

if [ -d tests/python ] && ls tests/python/test_*.py >/dev/null 2>&1; then
  echo "== python interop tests =="
  bash tools/python_env.sh
  # the binary `cargo test` built for the integration tests (building it alone would
  # resolve other dependency features and recompile half the tree)
  test -x target/release/developable_sim
  # no reruns: a test that fails fails the run (tools/soak_interop.sh N measures how
  # often the suite is green)
  export DEVELOPABLE_SIM_BIN="$PWD/target/release/developable_sim"
  .venv/bin/python -m pytest -q tests/python
fi
