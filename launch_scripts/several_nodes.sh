#!/usr/bin/env bash
# N simulator nodes (one per scene) in one DDS domain with one clock owner: the first
# node owns /clock, the others run with use_sim_time:=true and follow it. Each node gets
# its own namespace /sim<i>, so topics and services stay apart.
#   launch_scripts/several_nodes.sh SCENE.yaml [SCENE.yaml ...]
#   launch_scripts/several_nodes.sh config/scenes/ribbon_gripper.yaml config/scenes/ribbon_falling.yaml
# Environment: DEVELOPABLE_SIM_BIN (default target/release/developable_sim),
# ROS_DOMAIN_ID (default 0). Ctrl-C stops every node.
set -euo pipefail
ROOT="$(cd "$(dirname "$0")/.." && pwd)"
BIN="${DEVELOPABLE_SIM_BIN:-$ROOT/target/release/developable_sim}"
if [ "$#" -lt 1 ]; then
  echo "usage: $0 SCENE.yaml [SCENE.yaml ...]" >&2
  exit 2
fi
if [ ! -x "$BIN" ]; then
  echo "no binary at $BIN: run 'cargo build --release' (or set DEVELOPABLE_SIM_BIN)" >&2
  exit 1
fi
export ROS_DOMAIN_ID="${ROS_DOMAIN_ID:-0}"
pids=()
stop() {
  for p in "${pids[@]}"; do kill -INT "$p" 2>/dev/null || true; done
  wait
}
trap stop INT TERM
i=0
for scene in "$@"; do
  args=(node "$scene" --ros-args -r "__ns:=/sim$i")
  if [ "$i" -gt 0 ]; then
    # followers: step with the owner's /clock, publish none
    args+=(-p use_sim_time:=true)
  fi
  "$BIN" "${args[@]}" &
  pids+=("$!")
  i=$((i + 1))
done
wait
