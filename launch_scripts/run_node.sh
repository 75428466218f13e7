#!/usr/bin/env bash
# Start the developable_sim node with a params file, as the ROS 2 launch file does, but
# without ROS installed.
#   launch_scripts/run_node.sh [PARAMS.yaml] [extra node arguments...]
#   launch_scripts/run_node.sh config/params/developable_sim.yaml --record bags/run1
# Environment: DEVELOPABLE_SIM_BIN (default target/release/developable_sim),
# ROS_DOMAIN_ID (default 0), NAMESPACE (e.g. /robot1).
set -euo pipefail
ROOT="$(cd "$(dirname "$0")/.." && pwd)"
BIN="${DEVELOPABLE_SIM_BIN:-$ROOT/target/release/developable_sim}"
PARAMS="${1:-$ROOT/config/params/developable_sim.yaml}"
shift || true
if [ ! -x "$BIN" ]; then
  echo "no binary at $BIN: run 'cargo build --release' (or set DEVELOPABLE_SIM_BIN)" >&2
  exit 1
fi
ROS_ARGS=(--ros-args --params-file "$PARAMS")
if [ -n "${NAMESPACE:-}" ]; then
  ROS_ARGS+=(-r "__ns:=$NAMESPACE")
fi
cd "$ROOT"
# exec: Ctrl-C and SIGTERM reach the node directly, which closes its bag cleanly
exec "$BIN" node "$@" "${ROS_ARGS[@]}"
