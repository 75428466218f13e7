#!/usr/bin/env bash
# Numbers of docs/paper_simulator.md ("Measured figures"), from one run of the release binary:
#   tools/paper_measure.sh [BIN]   (default ./target/release/developable_sim)
# 1. paper_cylinder_then_bend: frame times and compression (stats JSON, printed whole)
# 2. paper_first_singularity over seeds 0-19: first singular point (material u, v; time)
# 3. paper_cylinder_then_bend: singular vertices vs epsilon_c (1 %, 0.5 %, 0.2 %), seeds 0-3
# 4. paper_crumple, seeds 0-2: compression, isometry error, singular vertices
set -euo pipefail
BIN=${1:-./target/release/developable_sim}
OUT=$(mktemp -d)
num() { # num FILE KEY: the first number after "KEY": in a JSON file (no jq needed)
    python3 -c 'import json,sys; d=json.load(open(sys.argv[1]))
for k in sys.argv[2].split("."): d = d[k] if d is not None else None
print(d)' "$1" "$2"
}
echo "== paper_cylinder_then_bend"
"$BIN" run config/scenes/paper_cylinder_then_bend.yaml --stats "$OUT/c.json" >/dev/null
python3 -c 'import json,sys; d=json.load(open(sys.argv[1])); print({k: d.get(k) for k in ["step_ms","phase_ms","compression_mean_pct","compressed_edges_pct","singular_vertices","triangles_mean","finite"]})' "$OUT/c.json"
echo "== paper_first_singularity, seeds 0-19 (u v time; none = no singular point)"
for s in $(seq 0 19); do
    "$BIN" run config/scenes/paper_first_singularity.yaml --set seed=$s --stats "$OUT/f$s.json" >/dev/null
    python3 -c 'import json,sys; p=json.load(open(sys.argv[1])).get("first_singular_point")
print(sys.argv[2], *( [round(p["material"][0],4), round(p["material"][1],4), round(p["time"],3)] if p else ["none"]))' "$OUT/f$s.json" $s
done | tee "$OUT/first.txt"
python3 - "$OUT/first.txt" <<'PY'
import statistics as st, sys
rows = [l.split() for l in open(sys.argv[1]) if "none" not in l]
for name, i in (("u", 1), ("v", 2), ("time", 3)):
    xs = [float(r[i]) for r in rows]
    print(f"{name}: mean {st.mean(xs):.4f} sd {st.pstdev(xs):.4f} min {min(xs):.4f} max {max(xs):.4f} (n = {len(xs)})")
PY
echo "== singular vertices vs epsilon_c, paper_cylinder_then_bend, seeds 0-3"
for eps in 0.01 0.005 0.002; do
    n=0
    for s in 0 1 2 3; do
        "$BIN" run config/scenes/paper_cylinder_then_bend.yaml --set seed=$s --set paper.compression_threshold=$eps --stats "$OUT/e.json" >/dev/null
        n=$((n + $(num "$OUT/e.json" singular_vertices)))
    done
    echo "epsilon_c $eps: mean $(python3 -c "print($n / 4)") singular vertices"
done
echo "== paper_crumple, seeds 0-2 (the scene's seed is 0)"
for s in 0 1 2; do
    "$BIN" run config/scenes/paper_crumple.yaml --set seed=$s --stats "$OUT/k.json" >/dev/null
    python3 -c 'import json,sys; d=json.load(open(sys.argv[1])); print("seed", sys.argv[2], {k: d.get(k) for k in ["compression_mean_pct","compressed_edges_pct","isometry_error_max","singular_vertices","finite"]})' "$OUT/k.json" $s
done
