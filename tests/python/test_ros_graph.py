"""The node in a robot's ROS graph, over Cyclone DDS as rclpy would see it: handles
driven by TF frames (/tf, /tf_static), poses in another frame of the TF tree, the grasp
and end frames it publishes on /tf, and an external /clock under use_sim_time."""

from __future__ import annotations

import math
import threading
import time

from conftest import SCENES, pose_msg, reliable_qos, _cdr1
from cyclonedds.core import Policy

import ros_types as rt

GRIPPER = str(SCENES / "ribbon_gripper.yaml")
CLOCK_QOS = _cdr1(
    Policy.Reliability.BestEffort, Policy.History.KeepLast(1), Policy.Durability.Volatile
)
TF_QOS = reliable_qos(depth=100)
TF_STATIC_QOS = reliable_qos(depth=100, transient_local=True)
SET_PAUSED = "/developable_sim/set_paused"


def tf(parent, child, xyz, yaw=0.0, stamp_ns=None):
    ns = time.time_ns() if stamp_ns is None else stamp_ns
    return rt.TransformStamped(
        header=rt.Header(
            stamp=rt.Time(sec=ns // 1_000_000_000, nanosec=ns % 1_000_000_000), frame_id=parent
        ),
        child_frame_id=child,
        transform=rt.Transform(
            translation=rt.Vector3(x=xyz[0], y=xyz[1], z=xyz[2]),
            rotation=rt.Quaternion(z=math.sin(yaw / 2), w=math.cos(yaw / 2)),
        ),
    )


def handle_status(ros, status, timeout, until):
    """The gripper's HandleStatus of the first status for which until(h) holds."""
    got = ros.take(status, timeout, until=lambda s: bool(s.handles) and until(s.handles[0]))
    return got[-1].handles[0]


def near(p, xyz, tol):
    return math.dist((p.x, p.y, p.z), xyz) <= tol


def test_a_handle_follows_a_tf_frame_through_the_tree(ros, domain_id, start_node):
    node = start_node(domain_id, GRIPPER, "--set", "handles.0.tf_frame=tool0")
    status = ros.reader("/ribbon/status", rt.SimStatus)
    static = ros.writer("/tf_static", rt.TFMessage, qos=TF_STATIC_QOS)
    dynamic = ros.writer("/tf", rt.TFMessage, qos=TF_QOS)
    ros.wait_matched(status)
    ros.wait_matched(static)
    ros.wait_matched(dynamic)
    # world -> base_link (static, yaw 90 deg, 0.1 m up), base_link -> tool0 (moving)
    static.write(rt.TFMessage(transforms=[tf("world", "base_link", (0.0, 0.0, 0.1), math.pi / 2, 0)]))
    # tool0 at (0.8, 0, 0.2) in base_link = (0, 0.8, 0.3) in world, sent at 50 Hz
    where = [(0.8, 0.0, 0.2)]
    running = threading.Event()
    running.set()

    def broadcast():
        while running.is_set():
            dynamic.write(rt.TFMessage(transforms=[tf("base_link", "tool0", where[0])]))
            time.sleep(0.02)

    sender = threading.Thread(target=broadcast, daemon=True)
    sender.start()
    try:
        h = handle_status(ros, status, 5.0, lambda h: h.external)
        assert h.tf_frame == "tool0" and h.topic == "/tf", h
        assert near(h.target.position, (0.0, 0.8, 0.3), 1e-9), h.target
        # ticks before the tree was complete were rejected; while TF flows none is
        time.sleep(0.3)
        before = handle_status(ros, status, 5.0, lambda h: True).rejected_tf_lookup
        time.sleep(1.0)
        h = handle_status(ros, status, 5.0, lambda h: True)
        assert h.rejected_tf_lookup == before and h.rejected_unknown_frame == 0, (before, h)
    finally:
        running.clear()
        sender.join()
    # TF stops: after tf_max_lag (0.25 s) each tick's lookup is a counted rejection
    # and the handle keeps its last target
    time.sleep(1.0)
    h = handle_status(ros, status, 5.0, lambda h: h.rejected_tf_lookup > before + 10)
    assert h.external and near(h.target.position, (0.0, 0.8, 0.3), 1e-9), h
    assert "TF frame tool0" in node.log()
    # TF resumes somewhere else: followed again
    for _ in range(20):
        dynamic.write(rt.TFMessage(transforms=[tf("base_link", "tool0", (0.7, 0.1, 0.2))]))
        time.sleep(0.02)
    handle_status(ros, status, 5.0, lambda h: near(h.target.position, (-0.1, 0.7, 0.3), 1e-9))
    assert "TF frame tool0 found again" in node.log()
    assert node.stop() == 0


def test_poses_in_another_frame_of_the_tree_are_transformed(ros, domain_id, start_node):
    start_node(domain_id, GRIPPER)
    status = ros.reader("/ribbon/status", rt.SimStatus)
    static = ros.writer("/tf_static", rt.TFMessage, qos=TF_STATIC_QOS)
    pose = ros.writer("/handles/gripper", rt.PoseStamped)
    for e in (status, static, pose):
        ros.wait_matched(e)
    static.write(rt.TFMessage(transforms=[tf("world", "base_link", (0.1, 0.2, 0.0), 0.0, 0)]))
    time.sleep(0.3)
    now = int(time.time())
    deadline = time.monotonic() + 3.0
    while time.monotonic() < deadline:
        pose.write(pose_msg(0.6, 0.0, 0.3, frame="base_link", sec=now))
        time.sleep(0.03)
    h = handle_status(ros, status, 5.0, lambda h: h.external)
    assert near(h.target.position, (0.7, 0.2, 0.3), 1e-9), h.target
    assert h.rejected_unknown_frame == 0, h
    # a frame the tree does not have is still rejected as unknown
    for _ in range(20):
        pose.write(pose_msg(0.0, 0.0, 0.0, frame="nowhere", sec=now + 1))
        time.sleep(0.02)
    h = handle_status(ros, status, 5.0, lambda h: h.rejected_unknown_frame > 0)
    assert near(h.target.position, (0.7, 0.2, 0.3), 1e-9), h.target


def test_grasp_and_end_frames_go_out_on_tf(ros, domain_id, start_node):
    start_node(domain_id, GRIPPER, "--set", "outputs.tf=true")
    tfr = ros.reader("/tf", rt.TFMessage, qos=TF_QOS)
    status = ros.reader("/ribbon/status", rt.SimStatus)
    ros.wait_matched(tfr)
    ros.wait_matched(status)
    # 0.5 s in: the scripted lift is under way; status and TF of one state share a stamp
    stamp = lambda h: (h.stamp.sec, h.stamp.nanosec)  # noqa: E731
    statuses = ros.take(status, 10.0, until=lambda s: s.sim_time > 0.5)
    by_stamp = {stamp(s.header): s for s in statuses}
    msgs = ros.take(
        tfr, 5.0, until=lambda m: bool(m.transforms) and stamp(m.transforms[0].header) in by_stamp
    )
    st = by_stamp[stamp(msgs[-1].transforms[0].header)]
    frames = {t.child_frame_id: t for t in msgs[-1].transforms}
    assert set(frames) == {"ribbon/gripper", "ribbon/start", "ribbon/end"}, frames.keys()
    assert all(t.header.frame_id == "world" for t in frames.values())
    # the fixed base holds the start at the origin, face up
    s = frames["ribbon/start"].transform
    assert near(s.translation, (0.0, 0.0, 0.0), 1e-9) and abs(s.rotation.w) > 1 - 1e-9, s
    # the grasp frame is where the handle holds the ribbon: at its target within the
    # step's constraint violation; the gripper holds the far end, so "end" is there too
    target = st.handles[0].target.position
    g = frames["ribbon/gripper"].transform.translation
    # (the violation is the largest residual component, m)
    tol = st.constraint_violation + 1e-9
    worst = max(abs(g.x - target.x), abs(g.y - target.y), abs(g.z - target.z))
    assert worst <= tol, (g, target, tol)
    e = frames["ribbon/end"].transform.translation
    assert near(e, (g.x, g.y, g.z), 1e-12)


def test_use_sim_time_follows_an_external_clock(ros, domain_id, start_node):
    node = start_node(domain_id, GRIPPER, "--ros-args", "-p", "use_sim_time:=true")
    status = ros.reader("/ribbon/status", rt.SimStatus)
    clock = ros.writer("/clock", rt.Clock, qos=CLOCK_QOS)
    ros.wait_matched(status)
    ros.wait_matched(clock)
    # a second participant listens on /clock: it must see our clock only
    from conftest import Ros

    other = Ros(domain_id)
    heard = other.reader("/clock", rt.Clock, qos=CLOCK_QOS)
    other.wait_matched(heard)
    sent = set()

    def tick(sec, nanosec=0):
        c = rt.Clock(clock=rt.Time(sec=sec, nanosec=nanosec))
        sent.add((sec, nanosec))
        for _ in range(3):  # best effort: say it a few times
            clock.write(c)
            time.sleep(0.01)

    def paused_at():
        # a pause reply names the time, and a fresh status follows (robust where a
        # catch-up burst of statuses may outrun a reader)
        r = ros.call(SET_PAUSED, rt.SetBoolRequest, rt.SetBoolResponse, data=True)
        st = ros.take(status, 5.0, until=lambda s: s.paused)[-1]
        assert ros.call(SET_PAUSED, rt.SetBoolRequest, rt.SetBoolResponse, data=False).success
        return r.message, st

    # nothing steps or is published without a clock (no time yet); services answer
    r = ros.call(SET_PAUSED, rt.SetBoolRequest, rt.SetBoolResponse, data=True)
    assert r.message == "paused at t = 0.000000 s", r.message
    assert ros.call(SET_PAUSED, rt.SetBoolRequest, rt.SetBoolResponse, data=False).success
    assert ros.take(status, 0.5) == []
    # the first sample starts time (at 0 here, as a developable_sim clock owner's does;
    # other starts: test_sim_time.py)
    tick(0, 0)
    tick(0, 500_000_000)
    time.sleep(1.0)
    msg, st = paused_at()
    assert msg == "paused at t = 0.500000 s", msg
    assert st.step == 50 and (st.header.stamp.sec, st.header.stamp.nanosec) == (0, 500_000_000)
    # a jump of 0.9 s (within max_clock_jump, 1 s) is caught up in dt steps (jumps
    # backwards and beyond max_clock_jump: test_sim_time.py)
    tick(1, 400_000_000)
    time.sleep(2.0)
    msg, st = paused_at()
    assert msg == "paused at t = 1.400000 s" and st.step == 140, (msg, st.step)
    assert (st.header.stamp.sec, st.header.stamp.nanosec) == (1, 400_000_000)
    heard_values = {(c.clock.sec, c.clock.nanosec) for c in other.take(heard, 0.5)}
    other.close()
    assert heard_values <= sent, heard_values - sent
    assert node.stop() == 0
