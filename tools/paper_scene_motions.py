#!/usr/bin/env python3
"""Handle motions of the paper scenes (config/scenes/paper_*.yaml), printed as YAML.

The scene format moves a handle by piecewise-linear translations and rotations about
world axes through the handle point. This script samples the isometric paths used by
the scenes (a sheet rolled into a cylinder, a cylinder bent about an orthogonal axis)
into such pieces, so that the numbers in the YAML files can be regenerated:

  python3 tools/paper_scene_motions.py roll --phi 1.0 --t0 0 --t1 1.5 --pieces 3
  python3 tools/paper_scene_motions.py bend --psi 0.6 --t0 1.5 --t1 3 --pieces 3
  python3 tools/paper_scene_motions.py mobius --length 0.2 --t0 0 --t1 4 --pieces 8
"""
import argparse
import math

L = 0.1  # m, side of the sheet


def roll(phi, side):
    """Position (x, z) of the left (side=-1) or right (side=+1) edge of an L-wide sheet
    rolled so that each edge has turned by phi, its middle kept at z = 0."""
    if phi == 0.0:
        return (L / 2 + side * L / 2, 0.0)
    r = (L / 2) / phi
    return (L / 2 + side * r * math.sin(phi), r * (1.0 - math.cos(phi)))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("kind", choices=["roll", "bend", "mobius"])
    ap.add_argument("--length", type=float, default=0.2, help="m, strip length (mobius)")
    ap.add_argument("--closure", type=float, default=0.9, help="share of the loop closed (mobius)")
    ap.add_argument("--phi", type=float, default=1.0, help="rad, final edge turn (roll)")
    ap.add_argument("--psi", type=float, default=0.6, help="rad, final turn (bend)")
    ap.add_argument("--t0", type=float, default=0.0)
    ap.add_argument("--t1", type=float, default=1.0)
    ap.add_argument("--pieces", type=int, default=3)
    a = ap.parse_args()
    n = a.pieces
    if a.kind == "mobius":
        mobius(a)
        return
    ts = [a.t0 + (a.t1 - a.t0) * k / n for k in range(n + 1)]
    total = a.phi if a.kind == "roll" else a.psi
    angles = [total * k / n for k in range(n + 1)]
    for side, name in [(-1, "left / bottom"), (1, "right / top")]:
        print(f"# {a.kind}, {name} side")
        prev = roll(0.0, side)
        for k in range(1, n + 1):
            p = roll(angles[k], side)
            d_in, d_z = p[0] - prev[0], p[1] - prev[1]
            dang = angles[k] - angles[k - 1]
            if a.kind == "roll":
                # left edge turns +phi about y, right edge -phi
                print(f"- {{start: {ts[k-1]:.4g}, end: {ts[k]:.4g}, translation: [{d_in:.6f}, 0.0, {d_z:.6f}], "
                      f"axis: [0, 1, 0], angle: {-side * dang:.6f}}}")
            else:
                # bottom edge (v = 0) turns +psi about x, top edge -psi; both go down
                print(f"- {{start: {ts[k-1]:.4g}, end: {ts[k]:.4g}, translation: [0.0, {d_in:.6f}, {-d_z:.6f}], "
                      f"axis: [1, 0, 0], angle: {-side * dang:.6f}}}")
            prev = p


def matmul(a, b):
    return [[sum(a[i][k] * b[k][j] for k in range(3)) for j in range(3)] for i in range(3)]


def transpose(a):
    return [[a[j][i] for j in range(3)] for i in range(3)]


def rot_x(t):
    c, s = math.cos(t), math.sin(t)
    return [[1, 0, 0], [0, c, -s], [0, s, c]]


def rot_y(t):
    c, s = math.cos(t), math.sin(t)
    return [[c, 0, s], [0, 1, 0], [-s, 0, c]]


def axis_angle(r):
    """Axis and angle of a rotation matrix (angle in [0, pi))."""
    angle = math.acos(max(-1.0, min(1.0, (r[0][0] + r[1][1] + r[2][2] - 1) / 2)))
    if angle < 1e-12:
        return [1.0, 0.0, 0.0], 0.0
    v = [r[2][1] - r[1][2], r[0][2] - r[2][0], r[1][0] - r[0][1]]
    n = math.sqrt(sum(x * x for x in v))
    return [x / n for x in v], angle


def mobius(a):
    """The far end of a strip of length `length` (held at its start, material axis
    along +x) bent into a loop closing `closure` of a turn while twisting by
    pi * closure: the end follows the arc of radius length / theta and turns by
    R_y(-theta) R_x(pi tau)."""
    n = a.pieces
    prev_p = (a.length, 0.0)
    prev_r = [[1, 0, 0], [0, 1, 0], [0, 0, 1]]
    for k in range(1, n + 1):
        tau = a.closure * k / n
        theta = 2 * math.pi * tau
        r = a.length / theta
        p = (r * math.sin(theta), r * (1 - math.cos(theta)))
        rot = matmul(rot_y(-theta), rot_x(math.pi * tau))
        d = matmul(rot, transpose(prev_r))
        axis, angle = axis_angle(d)
        t0 = a.t0 + (a.t1 - a.t0) * (k - 1) / n
        t1 = a.t0 + (a.t1 - a.t0) * k / n
        print(f"- {{start: {t0:.4g}, end: {t1:.4g}, translation: [{p[0]-prev_p[0]:.6f}, 0.0, {p[1]-prev_p[1]:.6f}], "
              f"axis: [{axis[0]:.6f}, {axis[1]:.6f}, {axis[2]:.6f}], angle: {angle:.6f}}}")
        prev_p, prev_r = p, rot


if __name__ == "__main__":
    main()
