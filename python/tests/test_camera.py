"""render_depth: the scene camera's colour, depth and points as NumPy arrays. Colour is
the picture `developable_sim render --camera` writes, byte for byte; depth lies on the
mesh (checked against the triangles, not the renderer); points back-project the depth
through K; D435 noise follows the seed."""

from __future__ import annotations

import math
import struct
import subprocess
import zlib

import numpy as np
import pytest

import developable_sim as ds
from conftest import same_bits, scene_path


def read_png_rgb(path) -> np.ndarray:
    """An 8-bit RGB, non-interlaced PNG as (H, W, 3) uint8 (what `render` writes)."""
    data = path.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    at, idat, width, height = 8, b"", 0, 0
    while at < len(data):
        (n,) = struct.unpack(">I", data[at : at + 4])
        kind, body = data[at + 4 : at + 8], data[at + 8 : at + 8 + n]
        if kind == b"IHDR":
            width, height, depth, color, _, _, interlace = struct.unpack(">IIBBBBB", body)
            assert (depth, color, interlace) == (8, 2, 0)
        elif kind == b"IDAT":
            idat += body
        at += 12 + n
    raw = zlib.decompress(idat)
    stride = 3 * width
    rows, prev = [], [0] * stride
    for j in range(height):
        f = raw[j * (stride + 1)]
        line = raw[j * (stride + 1) + 1 : (j + 1) * (stride + 1)]
        if f == 0:
            cur = list(line)
        elif f == 2:
            cur = [(x + b) & 0xFF for x, b in zip(line, prev)]
        else:
            cur = [0] * stride
            for i in range(stride):
                a = cur[i - 3] if i >= 3 else 0
                if f == 1:
                    p = a
                elif f == 3:
                    p = (a + prev[i]) >> 1
                else:  # Paeth
                    b, c = prev[i], (prev[i - 3] if i >= 3 else 0)
                    pa, pb, pc = abs(b - c), abs(a - c), abs(a + b - 2 * c)
                    p = a if pa <= pb and pa <= pc else (b if pb <= pc else c)
                cur[i] = (line[i] + p) & 0xFF
        rows.append(cur)
        prev = cur
    out = np.array(rows, dtype=np.uint8)
    return out.reshape(height, width, 3)


@pytest.fixture(scope="module")
def gripper_at_1s():
    scene = ds.Scene.load(scene_path("ribbon_gripper"), overrides={"duration": 1.0})
    sim = scene.build()
    for _ in range(100):
        sim.step()
    return scene, sim


def test_colour_is_the_picture_render_writes(cli, tmp_path, gripper_at_1s):
    scene, sim = gripper_at_1s
    frame = sim.render_depth("camera")
    assert frame.color.shape == (480, 640, 3) and frame.color.dtype == np.uint8
    assert frame.depth.shape == (480, 640) and frame.depth.dtype == np.float32
    assert frame.points.shape == (480, 640, 3) and frame.points.dtype == np.float32
    assert frame.index == 15  # floor(1.0 s * 15 Hz)
    out = tmp_path / "c.png"
    args = [str(cli), "render", str(scene_path("ribbon_gripper")), "--camera", "camera"]
    done = subprocess.run(args + ["--time", "1.0", "--out", str(out)], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    png = read_png_rgb(out)
    assert same_bits(png, frame.color)
    # the comparison sees a change of one pixel
    png[240, 320, 0] ^= 1
    assert not same_bits(png, frame.color)


def triangle_distance(points: np.ndarray, v: np.ndarray, tris: np.ndarray) -> np.ndarray:
    """Distance of each point to the nearest triangle whose interior (with its edges)
    its projection onto the triangle's plane falls in; inf when none."""
    a, b, c = v[tris[:, 0]], v[tris[:, 1]], v[tris[:, 2]]
    n = np.cross(b - a, c - a)
    area2 = np.linalg.norm(n, axis=1)
    n = n / area2[:, None]
    d = points[:, None, :] - a[None]  # (P, T, 3)
    h = np.einsum("ptk,tk->pt", d, n)
    q = points[:, None, :] - h[..., None] * n[None]
    best = np.full(len(points), np.inf)
    inside = np.ones(h.shape, dtype=bool)
    for p0, p1 in ((a, b), (b, c), (c, a)):
        w = np.einsum("ptk,tk->pt", np.cross(p1 - p0, q - p0[None]), n)
        inside &= w >= -1e-9 * area2[None]
    best = np.where(inside, np.abs(h), np.inf).min(axis=1)
    return best


def test_depth_lies_on_the_mesh_and_points_back_project_it(gripper_at_1s):
    _, sim = gripper_at_1s
    frame = sim.render_depth("camera")
    z = frame.depth
    hit = np.isfinite(z)
    assert 2000 < hit.sum() < 0.5 * z.size  # the ribbon, nothing behind it
    near, far = 0.1, 4.0
    assert z[hit].min() >= near and z[hit].max() <= far
    # points: z is the depth; x, y back-project it through K, computed in float64
    # from the float32 depth and rounded once (docs/camera.md)
    k = frame.k
    f, cx, cy = k[0, 0], k[0, 2], k[1, 2]
    assert k[1, 1] == f and cx == 319.5 and cy == 239.5
    jj, ii = np.mgrid[0:480, 0:640]
    z64 = z.astype(np.float64)
    assert same_bits(frame.points[..., 2], z)
    assert same_bits(frame.points[..., 0], (z64 * (ii - cx) / f).astype(np.float32))
    assert same_bits(frame.points[..., 1], (z64 * (jj - cy) / f).astype(np.float32))
    # every hit pixel's point, in the world, lies on a triangle of the ribbon: within
    # the float32 rounding of a depth of ~1 m (2^-24 * 1 m = 6e-8 m), 1e-6 m allowed
    m = frame.world_from_optical
    p = frame.points[hit].astype(np.float64) @ m[:3, :3].T + m[:3, 3]
    rng = np.random.default_rng(0)
    sample = p[rng.choice(len(p), size=600, replace=False)]
    s = sim.state()
    dist = triangle_distance(sample, s.vertices, s.triangles.astype(np.int64))
    assert np.all(dist < 1e-6), np.sort(dist)[-5:]
    # the check's negative side: points 1 mm off the surface are seen
    off = triangle_distance(sample + [0.0, 0.0, 1e-3], s.vertices, s.triangles.astype(np.int64))
    assert np.mean(off > 1e-6) > 0.9


def test_cameras_on_a_tf_frame_need_a_pose_and_unknown_cameras_are_refused():
    text = scene_path("ribbon_gripper").read_text()
    text = text.replace("    position: [0.45, -0.95, 0.35]", "    tf_frame: camera_link")
    text = "\n".join(l for l in text.splitlines() if "look_at:" not in l)
    sim = ds.Scene.from_yaml(text, name="tf_camera.yaml").build()
    with pytest.raises(KeyError, match="rides on the TF frame `camera_link`"):
        sim.render_depth("camera")
    with pytest.raises(KeyError, match="no camera `eye`"):
        sim.render_depth("eye")
    # the body frame 1 m behind the origin looking along +x (x forward, z up):
    # the optical frame looks along +x with its x (right) along world -y, y (down) -z
    frame = sim.render_depth("camera", pose=([-1.0, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0]))
    r = frame.world_from_optical[:3, :3]
    assert np.allclose(r, [[0, 0, 1], [-1, 0, 0], [0, -1, 0]], atol=1e-15)
    assert same_bits(frame.world_from_optical[:3, 3], np.array([-1.0, 0.0, 0.0]))


def test_d435_noise_is_deterministic_and_follows_the_seed():
    scene = ds.Scene.load(scene_path("ribbon_gripper_push"))
    a, b, c = scene.build(seed=0), scene.build(seed=0), scene.build(seed=1)
    for s in (a, b, c):
        for _ in range(20):
            s.step()
    fa, fb, fc = (s.render_depth("camera") for s in (a, b, c))
    assert same_bits(fa.depth, fb.depth) and same_bits(fa.color, fb.color)
    assert not same_bits(fa.depth, fc.depth)
    assert math.isclose(np.nanmedian(fa.depth), np.nanmedian(fc.depth), rel_tol=1e-2)
