#!/usr/bin/env bash
# Behaviour identity check for refactors: the same scene gives bit-identical results
# before and after a change that must not change physics.
#
#   bash tools/check_identical.sh baseline DIR [BIN]   results of BIN (default the
#                                                      release binary) into DIR
#   bash tools/check_identical.sh from COMMIT DIR      build COMMIT in a scratch
#                                                      worktree, then `baseline` with it
#   bash tools/check_identical.sh check DIR [BIN]      rerun with BIN, compare with DIR
#   bash tools/check_identical.sh selftest DIR [BIN]   the check's negative test: a
#                                                      perturbed run and a perturbed
#                                                      replay must be reported different
#
# For every scene in config/scenes/ it runs `developable_sim run SCENE --stats` (the
# scene's own duration, or the one in DURATIONS below: the same before and after) and
# records the run into a bag (`run --record`). `check` compares, per scene,
#   - the `final` section of the stats JSON (every mesh vertex, pattern coordinate,
#     ribbon coordinate and singular point) byte for byte (serde_json writes the
#     shortest decimal that round-trips, so equal text = equal bits), and
#   - every other key except the wall-time ones (step_ms, gradient_us, contact_ms,
#     phase_ms, wall_s): energies, iterations, errors, counts;
# and replays the baseline's bag with BIN (`replay`), which re-simulates the recorded
# inputs and compares every recorded output bit for bit: it must reproduce all of them,
# or, where the baseline binary does not reproduce its own bag either, differ exactly
# as that binary's replay does (stored by `baseline`). Exit status 1 if anything
# differs. Compare against your own branch point, not a moving main.
set -euo pipefail
cd "$(dirname "$0")/.."

# Simulated time per scene, s (scenes not listed run their own `duration`).
declare -A DURATIONS=(
  [ribbon_mobius_chain]=0.5
  [ribbon_double_chain]=0.5
  [ribbon_gripper]=4.0
)
TIMING_KEYS='del(.step_ms, .gradient_us, .contact_ms, .phase_ms, .wall_s, .final)'

usage() { sed -n '2,26p' "$0" | sed 's/^# \{0,1\}//'; exit 2; }
[ $# -ge 2 ] || usage
mode=$1 dir=$2
bin=${3:-$PWD/target/release/developable_sim}

duration_args() {
  local name=$1
  if [ -n "${DURATIONS[$name]:-}" ]; then echo "--duration ${DURATIONS[$name]}"; fi
}

# run_scene BIN SCENE OUTDIR [extra run args...]: OUTDIR/NAME.{final,rest}.json (+ bag)
run_scene() {
  local bin=$1 scene=$2 out=$3; shift 3
  local name; name=$(basename "$scene" .yaml)
  rm -rf "$out/$name.bag"
  # shellcheck disable=SC2046
  "$bin" run "$scene" $(duration_args "$name") "$@" --stats "$out/$name.stats.json" \
    --record "$out/$name.bag" >"$out/$name.log" 2>&1 || {
    echo "FAILED: $bin run $scene (see $out/$name.log)"; return 1; }
  jq -c '.final' "$out/$name.stats.json" >"$out/$name.final.json"
  jq -S -c "$TIMING_KEYS" "$out/$name.stats.json" >"$out/$name.rest.json"
}

# compare BASE NEW NAME: prints one line, returns 1 on a difference
compare() {
  local base=$1 new=$2 name=$3 ok=0 what=""
  if ! cmp -s "$base/$name.final.json" "$new/$name.final.json"; then
    ok=1 what="final differs"
  fi
  if ! cmp -s "$base/$name.rest.json" "$new/$name.rest.json"; then
    ok=1
    local keys
    keys=$(jq -n --slurpfile a "$base/$name.rest.json" --slurpfile b "$new/$name.rest.json" \
      '[$a[0] | paths(scalars)] | map(select(. as $p | ($a[0] | getpath($p)) != ($b[0] | getpath($p)))) | map(map(tostring) | join(".")) | join(", ")' -r)
    what="${what:+$what; }stats differ: ${keys:-structure}"
  fi
  if [ $ok = 0 ]; then
    printf '  %-28s final identical (%s bytes), stats identical\n' "$name" \
      "$(wc -c <"$new/$name.final.json")"
  else
    printf '  %-28s DIFFERENT: %s\n' "$name" "$what"
  fi
  return $ok
}

# replay_json BIN BAG OUT [--scene FILE]: the replay's comparison without wall time
# (`replay` exits 1 when the outputs differ, 2 when it cannot replay the bag)
replay_json() {
  local bin=$1 bag=$2 out=$3; shift 3
  local json; json=$(mktemp)
  local rc=0
  "$bin" replay "$bag" "$@" --stats "$json" >/dev/null 2>&1 || rc=$?
  if [ "$rc" -ne 0 ] && [ "$rc" -ne 1 ]; then
    rm -f "$json"; return 1
  fi
  jq -S -c 'del(.wall_s, .bag)' "$json" >"$out"
  rm -f "$json"
}

# replay_bag BIN BAG BASE_JSON [--scene FILE]: replays BAG with BIN; prints one line;
# returns 1 unless every output is reproduced, or (for a bag the baseline binary itself
# did not reproduce) the comparison is the same as the baseline binary's own replay.
replay_bag() {
  local bin=$1 bag=$2 base=$3; shift 3
  local name; name=$(basename "$bag" .bag)
  local json; json=$(mktemp)
  if ! replay_json "$bin" "$bag" "$json" "$@"; then
    printf '  %-28s replay FAILED\n' "$name"; rm -f "$json"; return 1
  fi
  local identical steps status=0
  identical=$(jq -r '.identical' "$json")
  steps=$(jq -r '.steps' "$json")
  if [ "$identical" = true ]; then
    printf '  %-28s replay identical (%s steps)\n' "$name" "$steps"
  elif [ -f "$base" ] && cmp -s "$json" "$base"; then
    printf '  %-28s replay as the baseline binary replays it (%s steps; it differs there too: %s)\n' \
      "$name" "$steps" "$(jq -r '[.topics[] | select(.differing > 0) | "\(.topic) \(.differing) at \(.max_at)"] | join(", ")' "$json")"
  else
    printf '  %-28s replay DIFFERENT: %s\n' "$name" \
      "$(jq -r '[.topics[] | select(.differing > 0) | "\(.topic) \(.differing) at \(.max_at)"] | join(", ")' "$json")"
    status=1
  fi
  rm -f "$json"
  return $status
}

scenes() { ls config/scenes/*.yaml; }

case $mode in
  baseline)
    mkdir -p "$dir"
    git rev-parse HEAD >"$dir/commit" 2>/dev/null || true
    "$bin" --version >"$dir/version"
    for s in $(scenes); do
      name=$(basename "$s" .yaml)
      run_scene "$bin" "$s" "$dir"
      replay_json "$bin" "$dir/$name.bag" "$dir/$name.replay.json"
      echo "  $name: $(jq -r 'if .identical then "replays identically" else "its own replay differs: \([.topics[] | select(.differing > 0) | .topic] | join(", "))" end' "$dir/$name.replay.json")"
    done
    echo "baseline of $(cat "$dir/version") in $dir"
    ;;
  from)
    commit=$2 dir=$3
    tree=$(mktemp -d /tmp/check_identical.XXXXXX)
    git worktree add --detach "$tree/src" "$commit" >/dev/null
    # its own target folder, seeded from ours so that only the crate recompiles
    target=$PWD/target/identity/target
    if [ ! -d "$target/release" ] && [ -d target/release ]; then
      mkdir -p "$target" && cp -a target/release "$target/"
    fi
    (cd "$tree/src" && CARGO_TARGET_DIR=$target cargo build --release --bin developable_sim)
    cp "$target/release/developable_sim" "$tree/developable_sim"
    git worktree remove --force "$tree/src"
    bash "$0" baseline "$dir" "$tree/developable_sim"
    git rev-parse "$commit" >"$dir/commit"
    ;;
  check)
    [ -d "$dir" ] || { echo "no baseline in $dir"; exit 2; }
    new=$(mktemp -d /tmp/check_identical.XXXXXX)
    status=0
    echo "identity check of $("$bin" --version) against $(cat "$dir/version") ($(cat "$dir/commit" 2>/dev/null || echo '?'))"
    for s in $(scenes); do
      name=$(basename "$s" .yaml)
      if [ ! -f "$dir/$name.final.json" ]; then
        printf '  %-28s not in the baseline (skipped)\n' "$name"; continue
      fi
      run_scene "$bin" "$s" "$new" || { status=1; continue; }
      compare "$dir" "$new" "$name" || status=1
      replay_bag "$bin" "$dir/$name.bag" "$dir/$name.replay.json" || status=1
    done
    rm -rf "$new"
    if [ $status = 0 ]; then echo "IDENTICAL"; else echo "DIFFERENT"; fi
    exit $status
    ;;
  selftest)
    # A change of one part in 1e9 of a physical parameter must be caught both by the
    # stats comparison and by the replay (so a check that passes means something).
    [ -d "$dir" ] || { echo "no baseline in $dir"; exit 2; }
    name=ribbon_extreme_torsion
    new=$(mktemp -d /tmp/check_identical.XXXXXX)
    status=0
    run_scene "$bin" "config/scenes/$name.yaml" "$new" --set ribbon.density=0.1000000001
    if compare "$dir" "$new" "$name" >/dev/null; then
      echo "selftest FAILED: a perturbed run compared identical"; status=1
    else
      echo "selftest: the perturbed run is reported: $(compare "$dir" "$new" "$name" || true)"
    fi
    sed 's/^  density: 0.1 /  density: 0.1000000001 /' "config/scenes/$name.yaml" >"$new/perturbed.yaml"
    if cmp -s "$new/perturbed.yaml" "config/scenes/$name.yaml"; then
      echo "selftest FAILED: could not perturb the scene"; status=1
    elif replay_bag "$bin" "$dir/$name.bag" /dev/null --scene "$new/perturbed.yaml" >/dev/null; then
      echo "selftest FAILED: a perturbed replay compared identical"; status=1
    else
      echo "selftest: the perturbed replay is reported: $(replay_bag "$bin" "$dir/$name.bag" /dev/null --scene "$new/perturbed.yaml" || true)"
    fi
    rm -rf "$new"
    exit $status
    ;;
  *) usage ;;
esac
