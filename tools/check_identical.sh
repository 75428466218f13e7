#!/usr/bin/env bash
# Bit-identity check for refactors: run scenes with `--stats` and compare the `final`
# section (every vertex of every object at the end of the run) byte for byte.
#
#   tools/check_identical.sh save    DIR [SCENE.yaml ...]   # before the change
#   tools/check_identical.sh compare DIR [SCENE.yaml ...]   # after it: exit 1 on any difference
#
# Scenes default to every config/scenes/*.yaml; the binary to ./target/release/developable_sim
# (override with DEVELOPABLE_SIM_BIN). Extra `run` options can be passed in CHECK_RUN_ARGS,
# e.g. CHECK_RUN_ARGS="--duration 0.5".
set -euo pipefail
mode=${1:?usage: check_identical.sh save|compare DIR [SCENE.yaml ...]}
dir=${2:?usage: check_identical.sh save|compare DIR [SCENE.yaml ...]}
shift 2
bin=${DEVELOPABLE_SIM_BIN:-./target/release/developable_sim}
scenes=("$@")
if [ ${#scenes[@]} -eq 0 ]; then
    scenes=(config/scenes/*.yaml)
fi
case "$mode" in
    save | compare) ;;
    *) echo "unknown mode '$mode' (save or compare)" >&2; exit 2 ;;
esac
mkdir -p "$dir"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
failed=0
for scene in "${scenes[@]}"; do
    name=$(basename "$scene" .yaml)
    # shellcheck disable=SC2086
    "$bin" run "$scene" ${CHECK_RUN_ARGS:-} --stats "$tmp/$name.json" > /dev/null
    jq -c .final "$tmp/$name.json" > "$tmp/$name.final.json"
    if [ "$mode" = save ]; then
        cp "$tmp/$name.final.json" "$dir/$name.final.json"
        echo "saved    $name"
    elif [ ! -f "$dir/$name.final.json" ]; then
        echo "MISSING  $name (no saved final in $dir)"
        failed=1
    elif cmp -s "$tmp/$name.final.json" "$dir/$name.final.json"; then
        echo "same     $name"
    else
        echo "DIFFERS  $name"
        failed=1
    fi
done
exit $failed
