#!/usr/bin/env python3
"""S_P triangle quality and area error on the final frame of paper runs.

    developable_sim run config/scenes/paper_crumple.yaml --stats s.json
    python3 tools/paper_triangle_quality.py s.json [more.json ...]

For each file: the number of triangles of `final.objects[0]`, the share with an angle
over 160 deg in the pattern (caps: their area is ill-conditioned in the edge lengths),
the range of area / pattern area, and the share of triangles whose area is off by more
than 1 %. Edge strains alone do not see a cap's area error (docs/paper_simulator.md,
"S_P triangle quality").
"""
import json
import math
import sys


def largest_angle_deg(m):
    lengths = [math.dist(m[i], m[(i + 1) % 3]) for i in range(3)]
    worst = 0.0
    for i in range(3):
        a, b, c = lengths[i], lengths[(i + 1) % 3], lengths[(i + 2) % 3]
        if b == 0 or c == 0:
            return 180.0
        worst = max(worst, math.degrees(math.acos(max(-1.0, min(1.0, (b * b + c * c - a * a) / (2 * b * c))))))
    return worst


def area_ratio(m, x):
    a0 = 0.5 * abs((m[1][0] - m[0][0]) * (m[2][1] - m[0][1]) - (m[1][1] - m[0][1]) * (m[2][0] - m[0][0]))
    u = [x[1][k] - x[0][k] for k in range(3)]
    v = [x[2][k] - x[0][k] for k in range(3)]
    c = [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]]
    return 0.5 * math.sqrt(sum(q * q for q in c)) / a0 if a0 > 0 else math.inf


def main(paths):
    if not paths:
        sys.exit(__doc__)
    for path in paths:
        o = json.load(open(path))["final"]["objects"][0]
        X, M, T = o["vertices"], o["material_vertices"], o["triangles"]
        caps = sum(largest_angle_deg([M[i] for i in t]) > 160 for t in T)
        ratios = [area_ratio([M[i] for i in t], [X[i] for i in t]) for t in T]
        off = sum(abs(r - 1) > 0.01 for r in ratios)
        print(f"{path}: {len(T)} triangles, {100 * caps / len(T):.1f} % with an angle > 160 deg, "
              f"area ratio {min(ratios):.2f}..{max(ratios):.2f}, {100 * off / len(T):.1f} % off by > 1 %")


if __name__ == "__main__":
    main(sys.argv[1:])
