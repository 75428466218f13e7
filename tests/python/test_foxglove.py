"""The live Foxglove view (`node --foxglove PORT`) seen by an independent client: PyPI
`websockets` speaking the Foxglove WebSocket protocol v1 (JSON serverInfo/advertise, a
JSON subscribe, binary message frames: opcode 0x01, uint32 subscription id, uint64 log
time, payload), the payload decoded by mcap_ros2's decoder from the advertised ros2msg
schema text alone, as Foxglove decodes it. The protocol has two names: `foxglove.sdk.v1`
(the Foxglove SDK's, which the Foxglove app asks for) and `foxglove.websocket.v1` (the
ws-protocol specification's, which Lichtblick, Foxglove Studio before the rename and the
ws-protocol client libraries ask for); the node's patched SDK accepts both."""

from __future__ import annotations

import base64
import json
import math
import os
import signal
import socket
import struct
import time

import pytest
import ros_types as rt
from conftest import SCENES, SENSOR_QOS, Ros, pose_msg, reliable_qos
from mcap.reader import make_reader
from mcap.records import Schema
from mcap_ros2.decoder import DecoderFactory
from websockets.exceptions import InvalidStatus
from websockets.sync.client import connect

GRIPPER = str(SCENES / "ribbon_gripper.yaml")
SUBPROTOCOL = "foxglove.sdk.v1"
# the handle constraint is met to well under a millimetre (see test_node.py)
GRASP_TOLERANCE = 0.005


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def decoder_for(channel: dict):
    """A decoder built from what the server advertised, nothing else."""
    schema = Schema(
        id=1,
        name=channel["schemaName"],
        encoding=channel["schemaEncoding"],
        data=channel["schema"].encode(),
    )
    return DecoderFactory().decoder_for(channel["encoding"], schema)


def parse_frame(frame: bytes) -> tuple[int, int, bytes]:
    """(subscription id, log time ns, payload) of a binary MessageData frame."""
    assert frame[0] == 0x01, f"opcode {frame[0]:#x} is not MessageData"
    sub, log_time = struct.unpack_from("<IQ", frame, 1)
    return sub, log_time, frame[13:]


def connect_and_advertise(port: int, timeout: float = 20.0, subprotocol: str = SUBPROTOCOL):
    """Connect (retrying until the node listens) and collect the advertised channels."""
    deadline = time.monotonic() + timeout
    while True:
        try:
            # no message size limit (a camera frame's cloud is 4.9 MB), as Foxglove
            ws = connect(
                f"ws://127.0.0.1:{port}",
                subprotocols=[subprotocol],
                open_timeout=5,
                legacy=True,
                max_size=None,
            )
            break
        except OSError:
            if time.monotonic() > deadline:
                raise
            time.sleep(0.1)
    # the server answers with the name the client asked for (a client refuses any other)
    assert ws.subprotocol == subprotocol
    info = json.loads(ws.recv(timeout=10))
    assert info["op"] == "serverInfo", info
    channels = {}
    while time.monotonic() < deadline:
        msg = ws.recv(timeout=10)
        if isinstance(msg, str):
            m = json.loads(msg)
            if m["op"] == "advertise":
                for c in m["channels"]:
                    channels[c["topic"]] = c
                break
    return ws, info, channels


def grasp_point(markers):
    # centre of the far end (as test_node.grasp_point): the first triangle of the last
    # element is (bottom_{n-1}, bottom_n, top_n)
    surface = next(m for m in markers.markers if m.ns == "ribbon/surface")
    b, t = surface.points[-5], surface.points[-4]
    return ((b.x + t.x) / 2, (b.y + t.y) / 2, (b.z + t.z) / 2)


def bag_schemas(bag_dir) -> dict[str, bytes]:
    (mcap_file,) = list(bag_dir.glob("*.mcap"))
    with open(mcap_file, "rb") as f:
        summary = make_reader(f).get_summary()
    return {s.name: s.data for s in summary.schemas.values()}


def test_foxglove_client_decodes_the_live_mesh_and_sees_it_follow_a_handle(
    start_node, ros, domain_id, tmp_path
):
    port = free_port()
    bag = tmp_path / "bag"
    node = start_node(domain_id, GRIPPER, "--foxglove", str(port), "--record", str(bag))
    assert f"ws://127.0.0.1:{port}" in node.log()
    ws, info, channels = connect_and_advertise(port)
    # exactly the node's outputs (gripper: no colliders, no TF; its handle's grasp
    # state and wrench; its camera's five RealSense topics and optical frame), under
    # their ROS names
    assert set(channels) == {
        "/ribbon/markers",
        "/ribbon/status",
        "/ribbon/singular_points",
        "/clock",
        "/handles/gripper/state",
        "/ribbon/gripper/wrench",
        "/tf_static",
        "/camera/color/image_raw",
        "/camera/color/camera_info",
        "/camera/aligned_depth_to_color/image_raw",
        "/camera/aligned_depth_to_color/camera_info",
        "/camera/depth/color/points",
    }
    assert channels["/ribbon/gripper/wrench"]["schemaName"] == "geometry_msgs/msg/WrenchStamped"
    markers_ch = channels["/ribbon/markers"]
    assert markers_ch["encoding"] == "cdr"
    assert markers_ch["schemaName"] == "visualization_msgs/msg/MarkerArray"
    assert markers_ch["schemaEncoding"] == "ros2msg"
    text = markers_ch["schema"]
    assert text.startswith("visualization_msgs/Marker[] markers")
    for dep in ("visualization_msgs/Marker", "std_msgs/Header", "geometry_msgs/Point"):
        assert f"\n{'=' * 80}\nMSG: {dep}\n" in text
    assert channels["/ribbon/status"]["schemaName"] == "developable_sim/msg/SimStatus"
    decode = decoder_for(markers_ch)
    decode_status = decoder_for(channels["/ribbon/status"])

    ws.send(
        json.dumps(
            {
                "op": "subscribe",
                "subscriptions": [
                    {"id": 7, "channelId": markers_ch["id"]},
                    {"id": 8, "channelId": channels["/ribbon/status"]["id"]},
                ],
            }
        )
    )
    pose = ros.writer("/handles/gripper", rt.PoseStamped, SENSOR_QOS)
    ros.wait_matched(pose)
    target = (0.7, 0.15, 0.35)  # reachable by the 1 m ribbon (test_node.py)
    first = None
    close = 0
    statuses = []
    deadline = time.monotonic() + 20.0
    sec = 1
    while time.monotonic() < deadline and close < 5:
        # no pose before the first mesh: that one must show the ribbon where the scene
        # put it (a pose written earlier could already have moved it by the time the
        # first frame reaches this client)
        if first is not None:
            pose.write(pose_msg(*target, sec=sec))
            sec += 1
        t_end = time.monotonic() + 0.02
        while time.monotonic() < t_end:
            try:
                frame = ws.recv(timeout=0.02)
            except TimeoutError:
                break
            if isinstance(frame, str):
                continue
            sub, _, payload = parse_frame(frame)
            assert payload[:4] == b"\x00\x01\x00\x00"  # CDR little endian, as on DDS
            if sub == 8:
                statuses.append(decode_status(payload))
                continue
            assert sub == 7
            ma = decode(payload)
            surface = next(m for m in ma.markers if m.ns == "ribbon/surface")
            assert surface.type == 11 and surface.header.frame_id == "world"
            # a TRIANGLE_LIST of two triangles per element: 6 * 50 vertices
            assert len(surface.points) == 6 * 50 == len(surface.colors)
            assert all(math.isfinite(p.x + p.y + p.z) for p in surface.points)
            g = grasp_point(ma)
            if first is None:
                first = g
            if math.dist(g, target) < GRASP_TOLERANCE:
                close += 1
    ws.close()
    assert first is not None, "no markers frame arrived"
    assert math.dist(first, target) > 0.1, f"the mesh started at the target already: {first}"
    assert close >= 5, f"the streamed grasp point never came within {GRASP_TOLERANCE} m of {target}"
    assert statuses and statuses[-1].object_name == "ribbon"
    assert statuses[-1].handles[0].external
    assert node.stop() == 0
    # the same schema text the bag carries (one implementation, not two)
    assert bag_schemas(bag)["visualization_msgs/msg/MarkerArray"] == text.encode()


def test_the_camera_images_and_cloud_stream_with_the_bags_schemas(start_node, domain_id, tmp_path):
    """Foxglove's Image and PointCloud2 panels read the camera: its channels carry the
    bags' schema text, and a frame decodes from that text alone with one stamp."""
    port = free_port()
    bag = tmp_path / "bag"
    node = start_node(
        domain_id, GRIPPER, "--foxglove", str(port), "--record", str(bag), "--record-cameras"
    )
    ws, _, channels = connect_and_advertise(port)
    topics = {
        "/camera/color/image_raw": "sensor_msgs/msg/Image",
        "/camera/aligned_depth_to_color/image_raw": "sensor_msgs/msg/Image",
        "/camera/color/camera_info": "sensor_msgs/msg/CameraInfo",
        "/camera/depth/color/points": "sensor_msgs/msg/PointCloud2",
    }
    subs = []
    for k, (topic, schema) in enumerate(topics.items()):
        ch = channels[topic]
        assert (ch["schemaName"], ch["schemaEncoding"], ch["encoding"]) == (schema, "ros2msg", "cdr")
        subs.append({"id": 20 + k, "channelId": ch["id"]})
    assert channels["/tf_static"]["schemaName"] == "tf2_msgs/msg/TFMessage"
    decoders = {20 + k: decoder_for(channels[t]) for k, t in enumerate(topics)}
    ws.send(json.dumps({"op": "subscribe", "subscriptions": subs}))
    got: dict = {}
    deadline = time.monotonic() + 20.0
    while time.monotonic() < deadline:
        try:
            frame = ws.recv(timeout=0.5)
        except TimeoutError:
            continue
        if isinstance(frame, str):
            continue
        sub, _, payload = parse_frame(frame)
        m = decoders[sub](payload)
        stamp = (m.header.stamp.sec, m.header.stamp.nanosec)
        got.setdefault(stamp, {})[sub] = m
        if len(got[stamp]) == 4:
            break
    ws.close()
    complete = [f for f in got.values() if len(f) == 4]
    assert complete, {s: sorted(f) for s, f in got.items()}
    f = complete[0]
    color, depth, info, cloud = f[20], f[21], f[22], f[23]
    assert (color.encoding, color.width, color.height, len(color.data)) == ("rgb8", 640, 480, 640 * 480 * 3)
    assert (depth.encoding, len(depth.data)) == ("32FC1", 640 * 480 * 4)
    assert (info.width, info.height, info.header.frame_id) == (640, 480, "camera_color_optical_frame")
    assert (cloud.width, cloud.height, [p.name for p in cloud.fields]) == (640, 480, ["x", "y", "z", "rgb"])
    assert node.stop() == 0
    schemas = bag_schemas(bag)
    for topic, schema in topics.items():
        assert schemas[schema] == channels[topic]["schema"].encode()


def test_outputs_tf_and_colliders_are_advertised_when_the_node_publishes_them(
    start_node, domain_id
):
    port = free_port()
    start_node(
        domain_id,
        str(SCENES / "ribbon_gripper_push.yaml"),
        "--foxglove",
        str(port),
        "--set",
        "outputs.tf=true",
    )
    ws, _, channels = connect_and_advertise(port)
    ws.close()
    assert channels["/tf"]["schemaName"] == "tf2_msgs/msg/TFMessage"
    assert channels["/colliders"]["schemaName"] == "visualization_msgs/msg/MarkerArray"
    assert all(c["encoding"] == "cdr" for c in channels.values())


def test_foxglove_port_parameter_starts_the_server_and_a_bad_bind_is_refused(
    start_node, domain_id, tmp_path
):
    port = free_port()
    start_node(domain_id, GRIPPER, "--ros-args", "-p", f"foxglove_port:={port}")
    ws, _, channels = connect_and_advertise(port)
    ws.close()
    assert "/ribbon/markers" in channels
    # a subprotocol that is not Foxglove protocol v1 under either name is refused
    for unknown in ("foxglove.websocket.v2", "foxglove.websocket"):
        with pytest.raises(InvalidStatus) as refused:
            connect(f"ws://127.0.0.1:{port}", subprotocols=[unknown], open_timeout=5)
        assert refused.value.response.status_code == 400
    # the port is taken now: a second node says so and exits
    busy = start_node(domain_id, GRIPPER, "--foxglove", str(port), wait=False, name="busy")
    assert busy.wait_exit(30) != 0
    assert f"Foxglove WebSocket server on 127.0.0.1:{port}: Failed to bind port" in busy.log()
    bad = start_node(
        domain_id, GRIPPER, "--foxglove", "1", "--foxglove-bind", "localhost:x", wait=False, name="bad"
    )
    assert bad.wait_exit(20) != 0
    assert "--foxglove-bind `localhost:x` is not an IP address" in bad.log()
    high = start_node(
        domain_id, GRIPPER, "--ros-args", "-p", "foxglove_port:=70000", wait=False, name="high"
    )
    assert high.wait_exit(20) != 0
    assert "`foxglove_port`: must be a TCP port 0..=65535, got 70000" in high.log(), high.log()


def first_markers(ws, channel: dict, timeout: float = 20.0):
    """Subscribe to `channel` and decode the first message that arrives on it."""
    ws.send(json.dumps({"op": "subscribe", "subscriptions": [{"id": 3, "channelId": channel["id"]}]}))
    decode = decoder_for(channel)
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        try:
            frame = ws.recv(timeout=1.0)
        except TimeoutError:
            continue
        if isinstance(frame, str):
            continue
        sub, _, payload = parse_frame(frame)
        assert sub == 3
        return decode(payload)
    raise AssertionError(f"no message on {channel['topic']} in {timeout} s")


@pytest.mark.parametrize("subprotocol", ["foxglove.websocket.v1", "foxglove.sdk.v1"])
def test_clients_asking_for_either_name_of_protocol_v1_receive_the_markers(
    start_node, domain_id, subprotocol
):
    """Lichtblick, Foxglove Studio before the rename and the ws-protocol client libraries
    ask for `foxglove.websocket.v1`, the Foxglove app for `foxglove.sdk.v1`: both are
    answered with their own name and stream the markers channel."""
    port = free_port()
    start_node(domain_id, GRIPPER, "--foxglove", str(port))
    ws, info, channels = connect_and_advertise(port, subprotocol=subprotocol)
    assert info["op"] == "serverInfo"
    markers_ch = channels["/ribbon/markers"]
    assert markers_ch["schemaName"] == "visualization_msgs/msg/MarkerArray"
    ma = first_markers(ws, markers_ch)
    ws.close()
    surface = next(m for m in ma.markers if m.ns == "ribbon/surface")
    assert surface.type == 11 and len(surface.points) == 6 * 50
    assert all(math.isfinite(p.x + p.y + p.z) for p in surface.points)


def raw_ws_client(port: int, rcvbuf: int = 4096) -> socket.socket:
    """A WebSocket client on a bare socket with a small receive buffer: after the
    handshake it reads only when told to (the `websockets` client reads in a thread)."""
    s = socket.socket()
    s.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, rcvbuf)
    s.connect(("127.0.0.1", port))
    key = base64.b64encode(os.urandom(16)).decode()
    s.sendall(
        (
            f"GET / HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\nUpgrade: websocket\r\n"
            f"Connection: Upgrade\r\nSec-WebSocket-Key: {key}\r\n"
            f"Sec-WebSocket-Version: 13\r\nSec-WebSocket-Protocol: {SUBPROTOCOL}\r\n\r\n"
        ).encode()
    )
    head = b""
    while b"\r\n\r\n" not in head:
        head += s.recv(1)
    assert head.startswith(b"HTTP/1.1 101"), head
    return s


class FrameReader:
    """Unmasked server frames from a raw socket (RFC 6455 section 5.2)."""

    def __init__(self, s: socket.socket):
        self.s = s
        self.buf = b""

    def _need(self, n: int, deadline: float) -> bool:
        while len(self.buf) < n:
            self.s.settimeout(max(0.01, deadline - time.monotonic()))
            try:
                chunk = self.s.recv(1 << 16)
            except TimeoutError:
                return False
            if not chunk:
                return False
            self.buf += chunk
        return True

    def next(self, timeout: float):
        deadline = time.monotonic() + timeout
        if not self._need(2, deadline):
            return None
        op, n = self.buf[0] & 0x0F, self.buf[1] & 0x7F
        h = 2
        if n == 126:
            if not self._need(4, deadline):
                return None
            n, h = struct.unpack_from(">H", self.buf, 2)[0], 4
        elif n == 127:
            if not self._need(10, deadline):
                return None
            n, h = struct.unpack_from(">Q", self.buf, 2)[0], 10
        if not self._need(h + n, deadline):
            return None
        data, self.buf = self.buf[h : h + n], self.buf[h + n :]
        return op, data


def send_text(s: socket.socket, text: str) -> None:
    data, mask = text.encode(), os.urandom(4)
    n = len(data)
    head = bytes([0x81]) + (
        bytes([0x80 | n]) if n < 126 else bytes([0x80 | 126]) + struct.pack(">H", n)
    )
    s.sendall(head + mask + bytes(b ^ mask[i % 4] for i, b in enumerate(data)))


def test_a_client_that_never_reads_stalls_neither_the_node_nor_a_dds_reader(
    start_node, ros, domain_id
):
    """One step per ~/step call (lockstep: service), 400 steps of a 150-element ribbon
    (~45 kB per mesh, ~18 MB in all, far beyond the stalled client's socket buffers and
    the server's 64-message queue). A node that waited for the client would stop
    answering; it must answer every call, the DDS reader must get the last step's mesh,
    and the stalled client, once it reads, must find the newest mesh with older ones
    dropped (the SDK's drop-oldest queue), not all 400."""
    steps = 400
    port = free_port()
    start_node(
        domain_id,
        GRIPPER,
        "--foxglove",
        str(port),
        "--lockstep",
        "service",
        "--set",
        "ribbon.segments=150",
    )
    stalled = raw_ws_client(port)
    reader = FrameReader(stalled)
    channels = {}
    while "/ribbon/markers" not in channels:
        frame = reader.next(timeout=10)
        assert frame is not None, "no advertise from the server"
        op, data = frame
        m = json.loads(data)
        if m["op"] == "advertise":
            channels.update({c["topic"]: c for c in m["channels"]})
    ch = channels["/ribbon/markers"]
    send_text(stalled, json.dumps({"op": "subscribe", "subscriptions": [{"id": 1, "channelId": ch["id"]}]}))

    markers = ros.reader("/ribbon/markers", rt.MarkerArray, reliable_qos(1, True))
    status = ros.reader("/ribbon/status", rt.SimStatus)
    ros.wait_matched(markers)
    w, r = ros.service("/developable_sim/step", rt.TriggerRequest, rt.TriggerResponse)

    def step(seq: int) -> None:
        w.write(rt.TriggerRequest(client_guid=ros.guid, sequence_number=seq))
        reply = Ros.take(
            r, 10.0, until=lambda s: s.client_guid == ros.guid and s.sequence_number == seq
        )[-1]
        assert reply.success, reply.message

    # the subscription is in effect once a stepped mesh reaches the client (the server
    # takes it asynchronously); from then on the client reads nothing
    seq = 0
    while True:
        seq += 1
        assert seq <= 20, "no mesh reached the subscribed client in 20 steps"
        step(seq)
        frame = reader.next(timeout=0.5)
        if frame is not None and frame[0] == 0x02:
            break
    for seq in range(seq + 1, steps + 1):
        step(seq)
    last_step = Ros.take(status, 10.0, until=lambda s: s.step >= steps)[-1]
    assert last_step.step == steps
    dt = last_step.dt
    end = steps * dt
    got = Ros.take(
        markers,
        10.0,
        until=lambda m: abs(m.markers[0].header.stamp.sec + 1e-9 * m.markers[0].header.stamp.nanosec - end) < 1e-6,
    )
    assert got

    # now the stalled client reads what the server kept for it
    decode = decoder_for(ch)
    stamps = []
    while True:
        frame = reader.next(timeout=3.0)
        if frame is None:
            break
        op, data = frame
        if op != 0x02:
            continue
        sub, _, payload = parse_frame(data)
        assert sub == 1
        h = decode(payload).markers[0].header.stamp
        stamps.append(h.sec + 1e-9 * h.nanosec)
    stalled.close()
    print(f"stalled client: {len(stamps)} of {steps} meshes kept, newest t = {stamps[-1]} s")
    assert stamps, "the stalled client got nothing at all"
    assert abs(stamps[-1] - end) < 1e-6, f"the newest mesh (t = {end} s) was not kept: {stamps[-5:]}"
    assert len(stamps) < steps, "nothing was dropped: the server buffered every mesh"
    assert stamps == sorted(stamps)
