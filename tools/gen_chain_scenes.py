#!/usr/bin/env python3
"""Generate the linked-loop chain scenes (config/scenes/ribbon_double_chain.yaml and
config/scenes/ribbon_mobius_chain.yaml).

Linked loops need interlocking initial poses. Each loop is built in its base frame
(a closed ring for orientable loops; for Moebius loops the rest shape of
config/scenes/mobius_band.yaml, baked in as an `explicit` initial shape), then placed
like chain links: link k centred k*d along the chain axis, its loop plane alternating
between two perpendicular planes, so that consecutive links pass through each other's
hole. The spacing d (and for Moebius links a spin about the loop normal) is chosen to
maximize the clearance between all surfaces while every consecutive pair keeps
linking number +-1 and every other pair 0. The simulator itself checks at load that
no two surfaces start closer than the contact thickness.

Usage: python3 tools/gen_chain_scenes.py [path/to/developable_sim]
(pure Python 3, no packages; the binary is only needed for the Moebius rest shape).
"""

import json
import math
import os
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
N = 50  # elements per loop
L = 1.0  # m, loop length
W = 0.05  # m, width


# --- small linear algebra ---------------------------------------------------------
def sub(a, b):
    return [a[i] - b[i] for i in range(3)]


def add(a, b):
    return [a[i] + b[i] for i in range(3)]


def scale(a, s):
    return [x * s for x in a]


def dot(a, b):
    return sum(a[i] * b[i] for i in range(3))


def cross(a, b):
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def norm(a):
    return math.sqrt(dot(a, a))


def unit(a):
    n = norm(a)
    return [x / n for x in a]


def matvec(m, v):
    return [dot(m[i], v) for i in range(3)]


def matmul(a, b):
    return [[sum(a[i][k] * b[k][j] for k in range(3)) for j in range(3)] for i in range(3)]


def transpose(m):
    return [[m[j][i] for j in range(3)] for i in range(3)]


def rot_axis(axis, angle):
    x, y, z = unit(axis)
    c, s = math.cos(angle), math.sin(angle)
    t = 1 - c
    return [
        [t * x * x + c, t * x * y - s * z, t * x * z + s * y],
        [t * x * y + s * z, t * y * y + c, t * y * z - s * x],
        [t * x * z - s * y, t * y * z + s * x, t * z * z + c],
    ]


def log_so3(r):
    """Rotation vector (axis * angle) of a rotation matrix."""
    cos = max(-1.0, min(1.0, (r[0][0] + r[1][1] + r[2][2] - 1) / 2))
    angle = math.acos(cos)
    if angle < 1e-12:
        return [0.0, 0.0, 0.0]
    if math.pi - angle < 1e-6:
        # axis from the diagonal
        diag = [r[i][i] for i in range(3)]
        i = diag.index(max(diag))
        v = [r[j][i] + (1 if j == i else 0) for j in range(3)]
        return scale(unit(v), angle)
    v = [r[2][1] - r[1][2], r[0][2] - r[2][0], r[1][0] - r[0][1]]
    return scale(v, angle / (2 * math.sin(angle)))


def smallest_eigvec(c):
    """Eigenvector of the smallest eigenvalue of a symmetric 3x3 (Jacobi)."""
    a = [row[:] for row in c]
    v = [[1.0 if i == j else 0.0 for j in range(3)] for i in range(3)]
    for _ in range(50):
        p, q = max(((0, 1), (0, 2), (1, 2)), key=lambda pq: abs(a[pq[0]][pq[1]]))
        if abs(a[p][q]) < 1e-15:
            break
        theta = 0.5 * math.atan2(2 * a[p][q], a[q][q] - a[p][p])
        c_, s_ = math.cos(theta), math.sin(theta)
        j = [[1.0 if i == k else 0.0 for k in range(3)] for i in range(3)]
        j[p][p] = c_
        j[q][q] = c_
        j[p][q] = s_
        j[q][p] = -s_
        a = matmul(transpose(j), matmul(a, j))
        v = matmul(v, j)
    k = min(range(3), key=lambda i: a[i][i])
    return unit([v[0][k], v[1][k], v[2][k]])


# --- loop shapes in their base frame -------------------------------------------------
def ring_shape():
    """Rim vertices (bottom, top interleaved) of the closed ring: every crease bent by
    2 pi / n about the crease line (the core's `ring`)."""
    verts = []
    p = [0.0, 0.0, 0.0]
    d = [1.0, 0.0, 0.0]
    psi = 2 * math.pi / N
    for j in range(N + 1):
        verts.append(add(p, [0, -W / 2, 0]))
        verts.append(add(p, [0, W / 2, 0]))
        p = add(p, scale(d, L / N))
        d = matvec(rot_axis([0, 1, 0], psi), d)
    return verts, None


def mobius_shape(binary):
    """Rest shape of the Moebius band (quasi-static, fixed base at the origin)."""
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "mobius.json")
        subprocess.run(
            [binary, "run", os.path.join(ROOT, "config/scenes/mobius_band.yaml"),
             "--set", f"ribbon.segments={N}", "--stats", out],
            check=True, stdout=subprocess.DEVNULL)
        with open(out) as f:
            obj = json.load(f)["final"]["objects"][0]
    c = obj["crease_direction"][1:N]
    psi = obj["bending_angle"][1:N]
    return obj["vertices"], (c, psi)


def frame_of(verts):
    """Centre, unit normal of the best-fit plane, and an in-plane axis of a loop."""
    mids = [scale(add(verts[2 * j], verts[2 * j + 1]), 0.5) for j in range(N)]
    cen = scale([sum(m[i] for m in mids) for i in range(3)], 1.0 / N)
    cov = [[sum((m[i] - cen[i]) * (m[j] - cen[j]) for m in mids) for j in range(3)] for i in range(3)]
    nrm = smallest_eigvec(cov)
    u = sub(mids[0], cen)
    u = unit(sub(u, scale(nrm, dot(u, nrm))))
    v = cross(nrm, u)
    radius = sum(norm(sub(m, cen)) for m in mids) / N
    return cen, [u, v, nrm], radius, mids


def place(verts, cen, axes, rot, pos):
    """Vertices after mapping the loop frame (cen, axes) to world rotation `rot` at
    `pos`; returns (world vertices, base rotation matrix, base position)."""
    # base_from_link: columns u, v, n; world_from_base = world_from_link * link_from_base
    b_from_l = transpose(axes)  # rows -> columns
    l_from_b = transpose(b_from_l)
    r = matmul(rot, l_from_b)
    t = sub(pos, matvec(r, cen))
    return [add(matvec(r, p), t) for p in verts], r, t


def linking_number(a, b):
    """Gauss linking integral of two closed polylines (midpoint rule)."""
    total = 0.0
    na, nb = len(a), len(b)
    for i in range(na):
        p0, p1 = a[i], a[(i + 1) % na]
        dp = sub(p1, p0)
        pm = scale(add(p0, p1), 0.5)
        for j in range(nb):
            q0, q1 = b[j], b[(j + 1) % nb]
            dq = sub(q1, q0)
            qm = scale(add(q0, q1), 0.5)
            r = sub(pm, qm)
            d = norm(r)
            total += dot(cross(dp, dq), r) / (d ** 3)
    return total / (4 * math.pi)


def min_distance(va, vb):
    return min(math.sqrt((p[0] - q[0]) ** 2 + (p[1] - q[1]) ** 2 + (p[2] - q[2]) ** 2)
               for p in va for q in vb)


def chain(verts, shape_info, links, axis, plane_normals, spacing, spin, origin, beta=None):
    """World vertices, centrelines and base poses of a chain of `links` loops. Loop
    planes alternate between the two `plane_normals`, or (with `beta`) turn by `beta`
    rad per link about the chain axis starting from the first; odd links are spun by
    `spin` about their normal."""
    cen, axes, radius, mids = frame_of(verts)
    out = []
    ax = unit(axis)
    for k in range(links):
        if beta is None:
            nrm = plane_normals[k % 2]
        else:
            nrm = matvec(rot_axis(ax, k * beta), plane_normals[0])
        # link frame: u along the chain axis, the normal as given, spun about it
        u = ax
        v = cross(nrm, u)
        rot = transpose([u, v, nrm])  # columns u, v, n
        if spin and k % 2 == 1:
            rot = matmul(rot_axis(nrm, spin), rot)
        pos = add(origin, scale(ax, k * spacing))
        wv, r, t = place(verts, cen, axes, rot, pos)
        wm = [add(matvec(r, m), t) for m in mids]
        out.append((wv, wm, r, t))
    return out, radius


def check_chain(links):
    worst = float("inf")
    for i in range(len(links)):
        for j in range(i + 1, len(links)):
            lk = linking_number(links[i][1], links[j][1])
            want = 1 if j == i + 1 else 0
            if abs(abs(lk) - want) > 0.1:
                return None
            if j - i <= 2:
                worst = min(worst, min_distance(links[i][0], links[j][0]))
    return worst


def candidates(verts, shape, axis, normals, spins, origin, betas=(None,)):
    """Interlocking placements (vertex clearance, spacing, spin, beta), best first."""
    cen, axes, radius, mids = frame_of(verts)
    found = []
    for beta in betas:
        for f in [0.80 + 0.05 * i for i in range(15)]:
            for spin in spins:
                links, _ = chain(verts, shape, 4, axis, normals, f * radius, spin, origin,
                                 beta)
                clearance = check_chain(links)
                if clearance is not None:
                    found.append((clearance, f * radius, spin, beta))
    found.sort(key=lambda c: -c[0])
    return found, radius


def best_spacing(verts, shape, axis, normals, spins, origin):
    found, radius = candidates(verts, shape, axis, normals, spins, origin)
    return (found[0][:3] if found else None), radius


def fmt(v):
    return "[" + ", ".join(f"{x:.6f}" for x in v) + "]"


def ribbon_entry(name, r, t, loop, shape, velocity=None, extra=""):
    w = log_so3(r)
    lines = [
        f"  - name: {name}",
        f"    length: {L}            # m",
        f"    width: {W}            # m",
        f"    segments: {N}",
        f"    loop: {loop}",
        f"    base: {{mode: floating, position: {fmt(t)}, rotation: {fmt(w)}}}",
    ]
    if shape is None:
        lines.append("    initial_shape: {kind: ring}")
        lines.append("    settle: true          # close the ring exactly before t = 0")
    elif extra == "anchor":
        c, psi = shape
        lines.append("    initial_shape: &mobius   # the Moebius rest shape (mobius_band.yaml); reused below")
        lines.append("      kind: explicit")
        lines.append(f"      crease_directions: [{', '.join(repr(x) for x in c)}]")
        lines.append(f"      bending_angles: [{', '.join(repr(x) for x in psi)}]")
        extra = ""
    else:
        lines.append("    initial_shape: *mobius")
    if velocity:
        lines.append(f"    initial_velocity: {{linear: {fmt(velocity)}}}   # m/s")
    if extra:
        lines.append(extra)
    return "\n".join(lines)


def double_chain():
    verts, shape = ring_shape()
    best, radius = best_spacing(verts, shape, [1, 0, 0], [[0, 1, 0], [0, 0, 1]], [0.0],
                                [0, 0, 0])
    clearance, spacing, spin = best
    entries = []
    half = 4 * spacing
    # chain A along x, 0.27 m up, moving down; chain B along y, 0.27 m down, moving up
    a, _ = chain(verts, shape, 9, [1, 0, 0], [[0, 1, 0], [0, 0, 1]], spacing, spin,
                 [-half, 0.0, 0.27])
    b, _ = chain(verts, shape, 9, [0, 1, 0], [[1, 0, 0], [0, 0, 1]], spacing, spin,
                 [0.0, -half, -0.27])
    for k, (_, _, r, t) in enumerate(a):
        entries.append(ribbon_entry(f"a{k}", r, t, "orientable", None, [0, 0, -1.0]))
    for k, (_, _, r, t) in enumerate(b):
        entries.append(ribbon_entry(f"b{k}", r, t, "orientable", None, [0, 0, 1.0]))
    head = f"""# Two chains of 9 linked orientable loops impacting (Pan et al. sec. 6, fig. 12 bottom,
# table 1). Each loop: 1 m x 0.05 m, 50 elements, closed by the orientable loop
# constraint (sec. 5.1) from a ring settled before t = 0. Consecutive links interlock
# (their loop planes alternate, spacing {spacing:.4f} m = {spacing / radius:.2f} loop radii, smallest
# surface clearance {clearance:.3f} m at rest). No gravity: chain A (along x, 0.27 m up)
# and chain B (along y, 0.27 m down) fly into each other at 1 m/s each. Contact is part
# of every loop's step (contact.method: barrier, docs/contact_barrier.md): the loops are
# stepped one after the other, each against the others' meshes, every frame isometric
# and intersection free; contact.method: projection optimizes them in parallel, then
# makes them collision-free together (impact-zone QP with edge stiffness K, Pan et al.).
# Generated by tools/gen_chain_scenes.py (edit that, not this file).
name: ribbon_double_chain
duration: 1.0            # s
dt: 0.01                 # s, time step h (the paper's)
frame_id: world
seed: 0
gravity: [0.0, 0.0, 0.0] # m/s^2: free flight, the impact only

solver:
  kind: chain          # chain (ours, O(n) per Newton iteration) | gauss_newton (the same method, dense; baseline) | lbfgsb (the paper's); default chain
  max_outer_iterations: 50   # augmented-Lagrangian rounds (loop constraints); default 20

contact:
  method: barrier        # barrier (inside the step) | projection (Pan et al. sec. 5.2); default barrier
  thickness: 0.002       # m, h; default 0.001
  stiffness: 100.0       # projection: K (the paper's 1e2); default 100
  closeness: stiff       # stiff | plain (set plain for the paper's fig. 6 comparison)
  max_iterations: 50     # detection/response rounds per step; default 50
  tolerance: 1.0e-6      # m; default 1e-6
  self_contact: true     # default true

# Each entry takes every key of a `ribbon:` section (defaults: density 0.1 kg/m^2,
# bending_stiffness 0.1 J, crease_regularizer 0.1 J, kinetic full).
ribbons:
"""
    return head + "\n".join(entries) + "\n"


def accepted(binary, text, clearance):
    """True when the simulator loads the scene with contact thickness `clearance` (its
    exact detection finds no two surfaces closer)."""
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "chain.yaml")
        with open(path, "w") as f:
            f.write(text)
        r = subprocess.run([binary, "run", path, "--duration", "0.01", "--set",
                            f"contact.thickness={clearance}"],
                           stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        return r.returncode == 0


def exact_clearance(binary, verts, shape, spacing, spin, beta):
    """Largest contact thickness (m, to 0.5 mm) at which the simulator accepts three
    consecutive links: their exact smallest surface distance."""
    head, anchor, body = mobius_text(verts, shape, 0.0, spacing, spin, beta, links=4)
    text = head + anchor + body
    lo, hi = 0.0, 0.04
    if not accepted(binary, text, 0.0005):
        return 0.0
    lo = 0.0005
    while hi - lo > 0.0005:
        mid = 0.5 * (lo + hi)
        if accepted(binary, text, mid):
            lo = mid
        else:
            hi = mid
    return lo


def mobius_chain(binary):
    verts, shape = mobius_shape(binary)
    spins = [i * math.pi / 6 for i in range(12)]
    betas = (None, math.pi / 3, 2 * math.pi / 3, math.pi / 4, 3 * math.pi / 4)
    found, radius = candidates(verts, shape, [1, 0, 0], [[0, 1, 0], [0, 0, 1]], spins,
                               [0, 0, 0], betas)
    best = None
    for _, spacing, spin, beta in found[:25]:
        c = exact_clearance(binary, verts, shape, spacing, spin, beta)
        if best is None or c > best[0]:
            best = (c, spacing, spin, beta)
    if best is None or best[0] < 0.003:
        raise SystemExit(f"no interlocking placement with 3 mm clearance found: {best}")
    clearance, spacing, spin, beta = best
    return mobius_text(verts, shape, clearance, spacing, spin, beta)


def mobius_text(verts, shape, clearance, spacing, spin, beta, links=9):
    half = 4 * spacing
    count = links
    links, _ = chain(verts, shape, count, [1, 0, 0], [[0, 1, 0], [0, 0, 1]], spacing, spin,
                     [-half, 0.0, 0.0], beta)
    zmin = min(p[2] for l in links for p in l[0])
    lift = 0.15 - zmin  # lowest point 0.15 m above the ground
    entries = []
    for k, (_, _, r, t) in enumerate(links):
        t = add(t, [0, 0, lift])
        entries.append(ribbon_entry(f"m{k}", r, t, "non_orientable", shape,
                                    extra="anchor" if k == 0 else ""))
    head = f"""# A chain of 9 linked Moebius loops falling on the ground (Pan et al. sec. 6, table 1).
# Each loop: 1 m x 0.05 m, 50 elements, closed by the non-orientable loop constraint
# (x_0 = y_n, y_0 = x_n, n_0 = -n_(n-1), sec. 5.1), starting from the band's rest shape.
# Consecutive links interlock (spacing {spacing:.4f} m; loop planes {"alternate" if beta is None else f"turn by {beta:.3f} rad per link"},
# odd links spun by {spin:.3f} rad; smallest surface distance {clearance:.4f} m at rest); the chain is
# released 0.15 m above the ground and lands. Generated by tools/gen_chain_scenes.py
# (edit that, not this file).
name: ribbon_mobius_chain
duration: 1.0            # s
dt: 0.01                 # s, time step h
frame_id: world
seed: 0
gravity: [0.0, 0.0, -9.81]   # m/s^2

solver:
  kind: chain          # chain (ours, O(n) per Newton iteration) | gauss_newton (the same method, dense; baseline) | lbfgsb (the paper's); default chain
  max_outer_iterations: 50   # augmented-Lagrangian rounds (loop constraints); default 20

colliders:
  - name: ground
    kind: plane          # half-space z <= 0
    friction: 0.5        # Coulomb mu; default 0.5

contact:
  method: barrier        # barrier (inside the step) | projection (Pan et al. sec. 5.2); default barrier
  thickness: 0.002       # m, h; default 0.001
  stiffness: 100.0       # projection: K; default 100
  closeness: stiff       # stiff | plain; default stiff
  max_iterations: 50     # default 50
  tolerance: 1.0e-6      # m; default 1e-6
  self_contact: true     # default true

# Each entry takes every key of a `ribbon:` section; the first link's initial shape is a
# YAML anchor (&mobius) the others reuse (*mobius).
"""
    return head, "", "ribbons:\n" + "\n".join(entries) + "\n"


def main():
    binary = sys.argv[1] if len(sys.argv) > 1 else os.path.join(ROOT, "target/release/developable_sim")
    with open(os.path.join(ROOT, "config/scenes/ribbon_double_chain.yaml"), "w") as f:
        f.write(double_chain())
    head, anchor, body = mobius_chain(binary)
    with open(os.path.join(ROOT, "config/scenes/ribbon_mobius_chain.yaml"), "w") as f:
        f.write(head + anchor + body)
    print("wrote config/scenes/ribbon_double_chain.yaml and ribbon_mobius_chain.yaml")


if __name__ == "__main__":
    main()
