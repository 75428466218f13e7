#!/usr/bin/env python3
"""Print the `step_vs_n` criterion benchmark (benches/ribbon.rs) as JSON.

One step of ribbon_extreme_torsion against the number of elements n, per solver
(chain, gauss_newton = dense projected Newton, lbfgsb): criterion's median (its
`median.point_estimate`) in ms, and the ratios the issue asks about (chain at n over
chain at 50; dense over chain at the same n), all from one `cargo bench` run.

    cargo bench --bench ribbon -- step_vs_n
    python3 tools/step_vs_n.py [target/criterion]
"""

import json
import pathlib
import subprocess
import sys


def main() -> int:
    root = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else "target/criterion")
    group = root / "step_vs_n"
    if not group.is_dir():
        print(f"no {group}: run `cargo bench --bench ribbon -- step_vs_n` first", file=sys.stderr)
        return 1
    medians: dict[str, dict[int, float]] = {}
    for estimates in sorted(group.glob("*/*/new/estimates.json")):
        kind, n = estimates.parts[-4], estimates.parts[-3]
        if not n.isdigit():
            continue
        median_ns = json.loads(estimates.read_text())["median"]["point_estimate"]
        medians.setdefault(kind, {})[int(n)] = median_ns * 1e-6
    if not medians:
        print(f"no estimates under {group}", file=sys.stderr)
        return 1
    chain = medians.get("chain", {})
    dense = medians.get("gauss_newton", {})
    ratios = {}
    if 50 in chain:
        ratios["chain_over_chain_at_50"] = {n: t / chain[50] for n, t in sorted(chain.items())}
    ratios["dense_over_chain"] = {n: dense[n] / chain[n] for n in sorted(dense) if n in chain}
    try:
        commit = subprocess.run(
            ["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True, check=True
        ).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        commit = None
    table = {
        "scene": "ribbon_extreme_torsion",
        "commit": commit,
        "median_ms": {k: dict(sorted(v.items())) for k, v in sorted(medians.items())},
        "ratios": ratios,
    }
    print(json.dumps(table, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
