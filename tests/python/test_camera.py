"""The simulated RGB-D camera over DDS (issue 48), as a perception pipeline sees it:
the five RealSense topics of a frame arrive with one identical header.stamp, the
optical frame is on /tf_static, Image and PointCloud2 decode as cv_bridge and
sensor_msgs_py decode them, the cloud is the depth back-projected through K, and an
independent numpy ray caster on the published mesh (the markers' TRIANGLE_LIST) and
camera_info agrees with the depth image; a camera carried by a TF frame draws from where
TF puts it, and replays."""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
import time

import numpy as np
import pytest
import ros_types as rt
from conftest import BIN, ROOT, SCENES, Ros, _cdr1, reliable_qos
from cyclonedds.core import Policy
from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory

GRIPPER = str(SCENES / "ribbon_gripper.yaml")
OPTICAL = "camera_color_optical_frame"
# the default scene's camera (config/scenes/ribbon_gripper.yaml)
POSITION = np.array([0.45, -0.95, 0.35])
LOOK_AT = np.array([0.4, 0.0, 0.0])
NEAR, FAR = 0.1, 4.0

TOPICS = {
    "color": ("/camera/color/image_raw", rt.Image),
    "color_info": ("/camera/color/camera_info", rt.CameraInfo),
    "depth": ("/camera/aligned_depth_to_color/image_raw", rt.Image),
    "depth_info": ("/camera/aligned_depth_to_color/camera_info", rt.CameraInfo),
    "points": ("/camera/depth/color/points", rt.PointCloud2),
}

# The camera topics are best effort, keep last 1 (sensor data, as the RealSense driver
# offers them); this reader keeps a few frames so that the five topics of one frame are
# all still there when the test takes them.
CAMERA_QOS = _cdr1(
    Policy.Reliability.BestEffort,
    Policy.History.KeepLast(8),
    Policy.Durability.Volatile,
)


# A 640 x 480 cloud is 4.9 MB, sent as a burst of UDP datagrams: a subscriber needs a
# socket receive buffer of a few MB (Cyclone's default is smaller; the kernel's limit
# here, net.core.rmem_max, is 4 MB), as with a RealSense driver over DDS.
RECEIVE_BUFFER = "<CycloneDDS><Domain><Internal><SocketReceiveBufferSize min=\"4MB\"/></Internal></Domain></CycloneDDS>"


@pytest.fixture(autouse=True)
def large_receive_buffer(monkeypatch):
    """Before the `ros` fixture's participant is made (autouse fixtures come first)."""
    uri = os.environ.get("CYCLONEDDS_URI")
    monkeypatch.setenv("CYCLONEDDS_URI", f"{uri},{RECEIVE_BUFFER}" if uri else RECEIVE_BUFFER)


def stamp(h) -> tuple[int, int]:
    return (h.stamp.sec, h.stamp.nanosec)


# ---- decoding as the ROS tools do -----------------------------------------------------


def buffer(data) -> np.ndarray:
    """A message's `uint8[]` as bytes (rclpy hands over an array.array of them)."""
    return np.asarray(data, dtype=np.uint8)


def imgmsg_to_array(msg) -> np.ndarray:
    """cv_bridge's CvBridge.imgmsg_to_cv2(msg, "passthrough") (cv_bridge/core.py, ROS 2
    Jazzy): the dtype and channels of the encoding, the byte order of is_bigendian, rows
    of `step` bytes cut to `width`."""
    dtype, channels = {"rgb8": (np.uint8, 3), "32FC1": (np.float32, 1)}[msg.encoding]
    dtype = np.dtype(dtype).newbyteorder(">" if msg.is_bigendian else "<")
    if channels == 1:
        im = np.ndarray(
            shape=(msg.height, msg.step // dtype.itemsize), dtype=dtype, buffer=buffer(msg.data)
        )
        return np.ascontiguousarray(im[: msg.height, : msg.width])
    im = np.ndarray(
        shape=(msg.height, msg.step // dtype.itemsize // channels, channels),
        dtype=dtype,
        buffer=buffer(msg.data),
    )
    return np.ascontiguousarray(im[: msg.height, : msg.width, :])


# sensor_msgs/PointField datatypes (sensor_msgs_py.point_cloud2._DATATYPES)
POINT_FIELD_TYPES = {1: "i1", 2: "u1", 3: "i2", 4: "u2", 5: "i4", 6: "u4", 7: "f4", 8: "f8"}


def read_points(cloud) -> np.ndarray:
    """sensor_msgs_py.point_cloud2.read_points(cloud) (ROS 2 Jazzy): a structured array
    whose dtype is built from the fields (name, datatype, offset) with itemsize
    point_step, over the whole buffer, byte-swapped if the cloud's byte order is not
    the machine's; then the organized shape (height, width)."""
    names = [f.name for f in cloud.fields]
    formats = [POINT_FIELD_TYPES[f.datatype] for f in cloud.fields]
    offsets = [f.offset for f in cloud.fields]
    dtype = np.dtype(
        {"names": names, "formats": formats, "offsets": offsets, "itemsize": cloud.point_step}
    )
    points = np.ndarray(
        shape=(cloud.width * cloud.height,), dtype=dtype, buffer=buffer(cloud.data)
    )
    if (sys.byteorder != "little") != bool(cloud.is_bigendian):
        points = points.byteswap()
    return points.reshape(cloud.height, cloud.width)


# ---- the geometry -----------------------------------------------------------------------


def rotation(q) -> np.ndarray:
    x, y, z, w = q.x, q.y, q.z, q.w
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )


def optical_transform(ros):
    """The camera's optical frame from the latched /tf_static."""
    tf = ros.reader("/tf_static", rt.TFMessage, reliable_qos(100, transient_local=True))
    found = []

    def has(msg) -> bool:
        found.extend(t for t in msg.transforms if t.child_frame_id == OPTICAL)
        return bool(found)

    Ros.take(tf, 10.0, until=has)
    return found[-1]


def optical_frame(ros) -> tuple[np.ndarray, np.ndarray]:
    """(R, t) of world_from_optical from the latched /tf_static."""
    t = optical_transform(ros)
    assert t.header.frame_id == "world"
    tr = t.transform.translation
    return rotation(t.transform.rotation), np.array([tr.x, tr.y, tr.z])


def ray_cast(origin, dirs, tris) -> np.ndarray:
    """Möller-Trumbore on every (ray, triangle) pair, both sides: per ray the nearest
    parameter t >= NEAR along `dirs` (inf: none). Independent of the renderer (which
    scans triangles in the image plane with edge functions)."""
    v0 = tris[:, 0]
    e1, e2 = tris[:, 1] - v0, tris[:, 2] - v0
    p = np.cross(dirs[:, None, :], e2[None, :, :])
    det = np.einsum("nmk,mk->nm", p, e1)
    ok = np.abs(det) > 1e-18
    inv = np.where(ok, 1.0 / np.where(ok, det, 1.0), 0.0)
    s = origin[None, :] - v0
    u = np.einsum("mk,nmk->nm", s, p) * inv
    q = np.cross(s, e1)
    v = np.einsum("nk,mk->nm", dirs, q) * inv
    t = np.einsum("mk,mk->m", e2, q)[None, :] * inv
    hit = ok & (u >= 0) & (v >= 0) & (u + v <= 1) & (t >= NEAR)
    return np.where(hit, t, np.inf).min(axis=1)


def take_frames(readers, seconds: float, until=None) -> dict:
    """Everything the five readers get for `seconds`, or until `until(frames)` holds:
    {stamp: {name: message}}."""
    frames: dict = {}
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline and not (until and until(frames)):
        for name, r in readers.items():
            for s in r.take(N=16):
                if s is None or not hasattr(s, "__dataclass_fields__"):
                    continue
                frames.setdefault(stamp(s.header), {})[name] = s
        time.sleep(0.005)
    return frames


def camera_readers(ros) -> dict:
    readers = {name: ros.reader(topic, typ, CAMERA_QOS) for name, (topic, typ) in TOPICS.items()}
    for r in readers.values():
        ros.wait_matched(r)
    return readers


def check_frame(f: dict) -> None:
    """One frame's five messages decoded as the ROS tools decode them; the cloud is the
    depth back-projected through K, its rgb the colour image."""
    for m in f.values():
        assert m.header.frame_id == OPTICAL
    info = f["color_info"]
    assert info == f["depth_info"], "the depth is aligned to the colour: one pinhole"
    assert (info.width, info.height, info.distortion_model) == (640, 480, "plumb_bob")
    assert list(info.d) == [0.0] * 5
    fx, cx, fy, cy = info.k[0], info.k[2], info.k[4], info.k[5]
    assert fx == fy and (cx, cy) == (319.5, 239.5)
    # fov_y 0.75 rad: f = (h / 2) / tan(fov_y / 2)
    assert math.isclose(fx, 240 / math.tan(0.375), rel_tol=1e-15)
    assert list(info.p) == [fx, 0, cx, 0, 0, fy, cy, 0, 0, 0, 1, 0]
    color = imgmsg_to_array(f["color"])
    depth = imgmsg_to_array(f["depth"])
    assert color.shape == (480, 640, 3) and color.dtype == np.uint8
    assert depth.shape == (480, 640) and depth.dtype == np.float32
    assert (f["color"].encoding, f["depth"].encoding) == ("rgb8", "32FC1")
    hit = np.isfinite(depth)
    assert 0.005 < hit.mean() < 0.9, f"the ribbon covers {hit.mean():.1%} of the image"
    assert np.all(depth[hit] >= NEAR) and np.all(depth[hit] <= FAR)
    cloud = f["points"]
    assert (cloud.height, cloud.width, cloud.point_step) == (480, 640, 16)
    assert [(p.name, p.offset, p.datatype, p.count) for p in cloud.fields] == [
        ("x", 0, 7, 1),
        ("y", 4, 7, 1),
        ("z", 8, 7, 1),
        ("rgb", 12, 7, 1),
    ]
    assert not cloud.is_dense
    pts = read_points(cloud)
    # x = z (i - cx) / f, y = z (j - cy) / f from the float32 depth, in float64, rounded
    # once: bit for bit
    j, i = np.mgrid[0:480, 0:640]
    z = depth.astype(np.float64)
    want_x = (z * (i - cx) / fx).astype(np.float32)
    want_y = (z * (j - cy) / fy).astype(np.float32)
    assert np.array_equal(pts["z"], depth, equal_nan=True)
    assert np.array_equal(pts["x"], want_x, equal_nan=True)
    assert np.array_equal(pts["y"], want_y, equal_nan=True)
    assert np.all(np.isnan(pts["x"][~hit]))
    rgb = pts["rgb"].view(np.uint32)
    unpacked = np.stack([(rgb >> 16) & 0xFF, (rgb >> 8) & 0xFF, rgb & 0xFF], axis=-1)
    assert np.array_equal(unpacked, color)


def test_five_topics_one_stamp_the_optical_frame_and_the_cloud(
    start_node, ros, domain_id, tmp_path
):
    stats = tmp_path / "stats.json"
    node = start_node(domain_id, GRIPPER, "--stats", str(stats))
    readers = camera_readers(ros)
    r, t = optical_frame(ros)
    # the frame of the scene's camera: at its position, z forward at its target, x
    # right (horizontal: the image's up is the scene's +z)
    assert np.allclose(t, POSITION, atol=1e-12)
    forward = (LOOK_AT - POSITION) / np.linalg.norm(LOOK_AT - POSITION)
    assert np.allclose(r[:, 2], forward, atol=1e-12)
    assert abs(r[2, 0]) < 1e-12 and r[2, 1] < 0, "x horizontal, y down"
    # 15 Hz: 60 frames in 4 s; this Python reader decodes ~7 MB a frame into lists and
    # keeps the newest 8 per topic, so it takes a fraction of them, fewer the slower the
    # machine (4 complete in 4 s on a slow afternoon, 2026-12-07): it reads until it has
    # five, within 20 s
    def five_complete(frames):
        return sum(len(f) == 5 for f in frames.values()) >= 5

    frames = take_frames(readers, 20.0, until=five_complete)
    complete = {s: f for s, f in frames.items() if len(f) == 5}
    assert len(complete) >= 5, {s: sorted(f) for s, f in frames.items()}
    # every stamp any topic carried is a tick's state: k / 15 s to within half a step
    for sec, ns in frames:
        t = sec + ns * 1e-9
        assert abs(t - round(t * 15) / 15) <= 0.005 + 1e-9, t
    stamps = sorted(complete)
    for s in stamps[-3:]:
        check_frame(complete[s])
    status = ros.reader("/ribbon/status", rt.SimStatus)
    Ros.take(status, 5.0, until=lambda s: True)
    assert node.stop() == 0
    # every tick is drawn or skipped (a tick that finds the camera still drawing; on a
    # loaded machine the drawing thread, at a lower priority than the simulation, falls
    # behind): the last state's tick may be neither yet
    s = json.loads(stats.read_text())
    ticks = math.floor((s["sim_time"] + 0.005) * 15) + 1
    drawn, skipped = s["camera_frames"], s["camera_frames_skipped"]
    assert drawn + skipped in (ticks - 1, ticks), (drawn, skipped, ticks)
    assert drawn >= len(complete)
    assert s["camera_draw"]["samples"] == drawn


def step(ros, n: int) -> None:
    for _ in range(n):
        reply = ros.call("/developable_sim/step", rt.TriggerRequest, rt.TriggerResponse)
        assert reply.success, reply.message


def test_an_independent_ray_caster_agrees_with_the_depth_image(start_node, ros, domain_id):
    """At t = 2.0 s (lifted: the gripper's script), lock-step so the mesh of the frame's
    state is the one the markers carry: 2000 random pixels hit or miss alike (>= 99.5 %:
    a pixel centre within rounding of a triangle's edge may go either way; measured
    100 %, 846 hits) and the depth agrees within 1e-4 m where both hit."""
    start_node(domain_id, GRIPPER, "--lockstep", "service")
    readers = camera_readers(ros)
    markers = ros.reader("/ribbon/markers", rt.MarkerArray, reliable_qos(1, True))
    r, t = optical_frame(ros)
    step(ros, 200)  # tick 30 falls on step 200 (t = 2.0 s)
    want = (2, 0)
    frame = {}
    deadline = time.monotonic() + 15.0
    while len(frame) < 5 and time.monotonic() < deadline:
        for s, f in take_frames(readers, 0.2).items():
            if s == want:
                frame.update(f)
    assert len(frame) == 5, sorted(frame)
    ma = Ros.take(markers, 10.0, until=lambda m: stamp(m.markers[0].header) == want)[-1]
    surface = next(m for m in ma.markers if m.ns == "ribbon/surface")
    assert surface.type == 11 and surface.header.frame_id == "world"
    p = surface.pose
    assert (p.position.x, p.position.y, p.position.z, p.orientation.w) == (0, 0, 0, 1)
    tris = np.array([[q.x, q.y, q.z] for q in surface.points]).reshape(-1, 3, 3)
    info = frame["color_info"]
    fx, cx, fy, cy = info.k[0], info.k[2], info.k[4], info.k[5]
    depth = imgmsg_to_array(frame["depth"])
    # 2000 random pixels: 1000 anywhere, 1000 near the ribbon (random points of random
    # triangles projected through K, jittered by up to 3 px: the ribbon covers ~2 % of
    # the image, and its edges are where hit or miss can go either way)
    rng = np.random.default_rng(48)
    tri = tris[rng.integers(0, len(tris), 1000)]
    a, b = rng.random(1000), rng.random(1000)
    flip = a + b > 1
    a, b = np.where(flip, 1 - a, a), np.where(flip, 1 - b, b)
    on_mesh = tri[:, 0] + a[:, None] * (tri[:, 1] - tri[:, 0]) + b[:, None] * (tri[:, 2] - tri[:, 0])
    opt = (on_mesh - t) @ r  # optical frame, R^T (p - t) as rows
    u = fx * opt[:, 0] / opt[:, 2] + cx + rng.uniform(-3, 3, 1000)
    v = fy * opt[:, 1] / opt[:, 2] + cy + rng.uniform(-3, 3, 1000)
    i = np.concatenate([rng.integers(0, 640, 1000), np.clip(np.rint(u), 0, 639).astype(int)])
    j = np.concatenate([rng.integers(0, 480, 1000), np.clip(np.rint(v), 0, 479).astype(int)])
    rays = np.stack([(i - cx) / fx, (j - cy) / fy, np.ones(2000)], axis=1)  # optical, z = 1
    t_hit = ray_cast(t, rays @ r.T, tris)  # along a ray with z = 1, t is the depth
    ref_hit = np.isfinite(t_hit) & (t_hit <= FAR)
    assert ref_hit.sum() >= 500, f"only {ref_hit.sum()} of 2000 pixels see the ribbon"

    def compare(image):
        ours = image[j, i].astype(np.float64)
        our_hit = np.isfinite(ours)
        both = ref_hit & our_hit
        return np.mean(ref_hit == our_hit), np.abs(ours[both] - t_hit[both]), t_hit[both]

    agree, err, z = compare(depth)
    assert agree >= 0.995, f"hit or miss agree at {agree:.2%}"
    assert err.max() <= 1e-4, f"depth differs by {err.max()} m"
    # and closer: the renderer reads the depth off the pixel's own ray in float64 and
    # rounds it once to float32 (half an ulp, 2^-24 relative); one ulp bounds it
    # (measured: 5.9e-8 m at ~1 m, 2026-12-07)
    assert np.all(err <= 2.0**-23 * z), err.max()
    # the check can fail: the same image one pixel off, or 1 mm deeper, does
    agree, err, _ = compare(np.roll(depth, 1, axis=1))
    assert agree < 0.995 or err.max() > 1e-4
    _, err, z = compare(depth + np.float32(1e-3))
    assert err.max() > 1e-4
    check_frame(frame)


def quaternion(m: np.ndarray) -> rt.Quaternion:
    """The unit quaternion of a rotation matrix (Shepperd: the largest diagonal term)."""
    t = np.trace(m)
    if t > 0:
        s = 2 * math.sqrt(1 + t)
        x, y, z = (m[2, 1] - m[1, 2]) / s, (m[0, 2] - m[2, 0]) / s, (m[1, 0] - m[0, 1]) / s
        return rt.Quaternion(x=x, y=y, z=z, w=s / 4)
    k = int(np.argmax(np.diag(m)))
    i, j = (k + 1) % 3, (k + 2) % 3
    s = 2 * math.sqrt(1 + m[k, k] - m[i, i] - m[j, j])
    q = [0.0] * 3
    q[k] = s / 4
    q[i] = (m[i, k] + m[k, i]) / s
    q[j] = (m[j, k] + m[k, j]) / s
    return rt.Quaternion(x=q[0], y=q[1], z=q[2], w=(m[j, i] - m[i, j]) / s)


def test_a_camera_on_a_tf_frame_draws_from_where_tf_puts_it(start_node, ros, domain_id, tmp_path):
    """`tf_frame: cam_link` instead of a position: until TF has the frame the camera's
    ticks are skipped (said once); then it draws from the looked-up pose, its optical
    frame hangs under cam_link on /tf_static, and the bag's captures carry the pose drawn
    from, so the replay is identical."""
    bag = tmp_path / "bag"
    sets = ["cameras.0.position=null", "cameras.0.look_at=null", "cameras.0.tf_frame=cam_link"]
    args = [GRIPPER, "--record", str(bag), "--record-cameras"]
    for s in sets:
        args += ["--set", s]
    node = start_node(domain_id, *args)
    info = ros.reader("/camera/color/camera_info", rt.CameraInfo, CAMERA_QOS)
    ros.wait_matched(info)
    deadline = time.monotonic() + 10
    while "camera camera: TF frame cam_link" not in node.log():
        assert time.monotonic() < deadline, node.log()
        time.sleep(0.05)
    assert not [m for m in info.take(N=16) if hasattr(m, "header")], "drawn without a pose"
    # cam_link, a REP 103 body frame (x forward, z up), where the fixed camera is:
    # world_from_body = world_from_optical * optical_from_body
    z = (LOOK_AT - POSITION) / np.linalg.norm(LOOK_AT - POSITION)
    up = np.array([0.0, 0.0, 1.0]) - z * z[2]
    y = -up / np.linalg.norm(up)
    world_from_optical = np.column_stack([np.cross(y, z), y, z])
    body_from_optical = np.array([[0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]])
    world_from_body = world_from_optical @ body_from_optical.T
    static = ros.writer("/tf_static", rt.TFMessage, reliable_qos(100, transient_local=True))
    link = rt.TransformStamped(
        header=rt.Header(frame_id="world"),
        child_frame_id="cam_link",
        transform=rt.Transform(
            translation=rt.Vector3(x=POSITION[0], y=POSITION[1], z=POSITION[2]),
            rotation=quaternion(world_from_body),
        ),
    )
    static.write(rt.TFMessage(transforms=[link]))
    Ros.take(info, 10.0, until=lambda m: m.header.frame_id == OPTICAL)
    assert "camera camera: TF frame cam_link found again" in node.log()
    # the optical frame hangs under cam_link (the node's own /tf_static)
    mounted = optical_transform(ros)
    assert mounted.header.frame_id == "cam_link"
    assert np.allclose(rotation(mounted.transform.rotation), body_from_optical, atol=1e-15)
    assert node.stop() == 0
    # the captures carry the pose drawn from: where the fixed camera is
    poses = []
    with open(next(bag.glob("*.mcap")), "rb") as fh:
        reader = make_reader(fh, decoder_factories=[DecoderFactory()])
        for _s, _c, _m, msg in reader.iter_decoded_messages(topics=["/developable_sim/commands"]):
            if msg.kind == 9:  # CAPTURE
                assert msg.camera == "camera"
                poses.append(msg.pose)
    assert poses
    for p in poses:
        assert np.allclose([p.position.x, p.position.y, p.position.z], POSITION, atol=1e-12)
        assert np.allclose(rotation(p.orientation), world_from_optical, atol=1e-12)
    out = tmp_path / "replay.json"
    r = subprocess.run(
        [str(BIN), "replay", str(bag), "--stats", str(out)],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert r.returncode == 0, r.stdout + r.stderr
    rep = json.loads(out.read_text())
    color = next(t for t in rep["topics"] if t["topic"] == "/camera/color/image_raw")
    assert color["compared"] == len(poses) and color["differing"] == 0, color
