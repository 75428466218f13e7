"""A robot's links as colliders (`robot_colliders:`), against the real node over Cyclone
DDS as a robot cell drives it: the test plays robot_state_publisher (the URDF of a
two-link arm latched on /robot_description, the base on /tf_static, the joints on /tf)
and the simulator clock (use_sim_time, so each state's TF lookup time is known
exactly), and sweeps the arm through the hanging ribbon of ribbon_robot_arm.yaml.

Checked from the bag (every state recorded) with geometry recomputed here from the URDF
and the TF this test sent, nothing taken from the node: no ribbon triangle intersects a
link's box in any state (an exact triangle/box separating-axis test), the ribbon is
pushed aside, /colliders draws each link where this test put it, and the run replays
bit for bit. With the forearm's collision a mesh file that does not exist, the node
names the link on stderr and keeps running, and the same check finds the forearm
crossing the ribbon (the checker's negative)."""

from __future__ import annotations

import math
import time
from pathlib import Path

import numpy as np
import pytest
from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory

import ros_types as rt
from conftest import SCENES, reliable_qos
from test_bags import replay
from test_ros_graph import CLOCK_QOS, TF_QOS, TF_STATIC_QOS

SCENE = str(SCENES / "ribbon_robot_arm.yaml")
DT = 0.01
STEPS = 250  # 2 s of sweep, 0.5 s at rest
LEAD = 10  # TF is sent this many steps ahead of the clock (it must be there first)
SWEEP_T = 2.0  # s
AMPLITUDE = 0.35  # rad, shoulder swing each side of +y
BASE = np.array([0.0, -0.45, 0.75])  # m, world -> base_link (static)
LINK_LENGTH = 0.3  # m, both links
BOX = np.array([0.3, 0.04, 0.04])  # m, each link's collision box
ORIGIN = np.array([0.15, 0.0, 0.0])  # m, the boxes' <origin> in their links


def urdf(forearm_geometry: str) -> str:
    return f"""<?xml version="1.0"?>
<robot name="two_link_arm">
  <link name="base_link"/>
  <link name="upper_arm">
    <collision><origin xyz="0.15 0 0" rpy="0 0 0"/><geometry><box size="0.3 0.04 0.04"/></geometry></collision>
  </link>
  <link name="forearm">
    <visual><geometry><box size="0.3 0.04 0.04"/></geometry></visual>
    <collision><origin xyz="0.15 0 0" rpy="0 0 0"/><geometry>{forearm_geometry}</geometry></collision>
  </link>
  <joint name="shoulder" type="revolute">
    <parent link="base_link"/><child link="upper_arm"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="1" velocity="1"/>
  </joint>
  <joint name="elbow" type="revolute">
    <origin xyz="0.3 0 0"/><parent link="upper_arm"/><child link="forearm"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="1" velocity="1"/>
  </joint>
</robot>
"""


def joints(t: float) -> tuple[float, float]:
    """Shoulder and elbow angles (rad) at time t (s): a smooth swing of the shoulder
    from +y - 0.35 rad to +y + 0.35 rad in 2 s, the elbow bending a little meanwhile."""
    s = min(t, SWEEP_T) / SWEEP_T
    return math.pi / 2 - AMPLITUDE * math.cos(math.pi * s), 0.15 * math.sin(math.pi * s)


def rot_z(a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def boxes(t: float) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Each link's collision box at time t: (centre, rotation), world frame."""
    shoulder, elbow = joints(t)
    r_upper = rot_z(shoulder)
    r_fore = r_upper @ rot_z(elbow)
    elbow_at = BASE + r_upper @ np.array([LINK_LENGTH, 0.0, 0.0])
    return {
        "upper_arm": (BASE + r_upper @ ORIGIN, r_upper),
        "forearm": (elbow_at + r_fore @ ORIGIN, r_fore),
    }


def triangles_cross_box(tris: np.ndarray, centre, rot, half) -> np.ndarray:
    """Which triangles (k x 3 x 3, world) intersect the box (Akenine-Moeller's separating
    axis test: the box's 3 axes, the triangle's normal, the 9 edge cross products)."""
    v = (tris - centre) @ rot  # in the box frame
    edges = [v[:, 1] - v[:, 0], v[:, 2] - v[:, 1], v[:, 0] - v[:, 2]]
    axes = [np.broadcast_to(np.eye(3)[i], v[:, 0].shape) for i in range(3)]
    axes.append(np.cross(edges[0], edges[1]))
    for i in range(3):
        for e in edges:
            axes.append(np.cross(np.eye(3)[i], e))
    separated = np.zeros(len(v), dtype=bool)
    for a in axes:
        p = np.einsum("kj,kij->ki", a, v)  # the three vertices on the axis
        r = np.abs(a) @ half  # the box's radius on it
        degenerate = np.einsum("kj,kj->k", a, a) < 1e-24
        separated |= ~degenerate & ((p.min(axis=1) > r) | (p.max(axis=1) < -r))
    return ~separated


def test_the_triangle_box_check_sees_crossings_and_clearances():
    half = BOX / 2
    centre, rot = np.zeros(3), rot_z(0.3)
    through = np.array([[[-1.0, -1.0, 0.0], [1.0, -1.0, 0.0], [0.0, 1.0, 0.0]]])  # a big one
    beside = through + np.array([0.0, 0.0, 0.021])  # 1 mm above the box's top face
    upright = np.array([[[0.0, -1.0, -1.0], [0.0, 1.0, -1.0], [0.0, 0.0, 1.0]]])
    # a small triangle off the box's end, separated only along a box axis (x)
    off_end = np.array([[[0.2, 0.0, 0.0], [0.25, 0.01, 0.0], [0.2, 0.01, 0.01]]]) @ rot.T
    cases = np.concatenate([through, beside, upright, off_end])
    assert triangles_cross_box(cases, centre, rot, half).tolist() == [True, False, True, False]


def send_tf(writer, k: int) -> None:
    ns = k * 10_000_000  # k * DT exactly
    shoulder, elbow = joints(k * DT)
    stamp = rt.Time(sec=ns // 1_000_000_000, nanosec=ns % 1_000_000_000)

    def joint(parent, child, x, angle):
        return rt.TransformStamped(
            header=rt.Header(stamp=stamp, frame_id=parent),
            child_frame_id=child,
            transform=rt.Transform(
                translation=rt.Vector3(x=x),
                rotation=rt.Quaternion(z=math.sin(angle / 2), w=math.cos(angle / 2)),
            ),
        )

    writer.write(
        rt.TFMessage(
            transforms=[
                joint("base_link", "upper_arm", 0.0, shoulder),
                joint("upper_arm", "forearm", LINK_LENGTH, elbow),
            ]
        )
    )


def sweep(
    start_node, ros, domain_id, tmp_path: Path, forearm_geometry: str, latched_first: bool
):
    """Run the sweep with this forearm geometry; returns (bag, node). latched_first:
    the description is published before the node starts (as robot_state_publisher,
    started first, latches it: the node must get it as a late joiner), else after the
    node is up."""
    bag = tmp_path / "bag"
    description = ros.writer("/robot_description", rt.String, reliable_qos(1, True))
    if latched_first:
        description.write(rt.String(data=urdf(forearm_geometry)))
    node = start_node(
        domain_id, SCENE, "--record", str(bag), "--ros-args", "-p", "use_sim_time:=true"
    )
    static = ros.writer("/tf_static", rt.TFMessage, qos=TF_STATIC_QOS)
    dynamic = ros.writer("/tf", rt.TFMessage, qos=TF_QOS)
    clock = ros.writer("/clock", rt.Clock, qos=CLOCK_QOS)
    status = ros.reader("/ribbon/status", rt.SimStatus)
    for e in (description, static, dynamic, clock, status):
        ros.wait_matched(e)
    if not latched_first:
        description.write(rt.String(data=urdf(forearm_geometry)))
    static.write(
        rt.TFMessage(
            transforms=[
                rt.TransformStamped(
                    header=rt.Header(frame_id="world"),
                    child_frame_id="base_link",
                    transform=rt.Transform(
                        translation=rt.Vector3(x=BASE[0], y=BASE[1], z=BASE[2])
                    ),
                )
            ]
        )
    )
    deadline = time.monotonic() + 10
    while "robot `two_link_arm`" not in node.log():
        assert time.monotonic() < deadline, node.log()
        time.sleep(0.05)
    for k in range(LEAD + 1):
        send_tf(dynamic, k)
    time.sleep(0.3)
    for k in range(STEPS + 1):
        if k > 0:
            send_tf(dynamic, k + LEAD)
        ns = k * 10_000_000
        clock.write(rt.Clock(clock=rt.Time(sec=ns // 1_000_000_000, nanosec=ns % 1_000_000_000)))
        time.sleep(0.012)
    for _ in range(5):  # best effort: the last clock must arrive
        clock.write(rt.Clock(clock=rt.Time(sec=ns // 1_000_000_000, nanosec=ns % 1_000_000_000)))
        time.sleep(0.02)
    last = ros.take(status, 30.0, until=lambda s: s.step >= STEPS)[-1]
    assert last.step == STEPS
    assert node.stop() == 0, node.log()
    return bag, node


def bag_messages(bag: Path, topics: list[str]):
    (mcap,) = list(bag.glob("*.mcap"))
    with open(mcap, "rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        for _, channel, _, msg in reader.iter_decoded_messages(topics=topics):
            yield channel.topic, msg


def stamp_of(msg) -> float:
    h = msg.markers[0].header.stamp
    return h.sec + 1e-9 * h.nanosec


def ribbon_states(bag: Path):
    """(t, triangles k x 3 x 3) of every recorded ribbon state."""
    for _, ma in bag_messages(bag, ["/ribbon/markers"]):
        surface = next(m for m in ma.markers if m.ns == "ribbon/surface")
        pts = np.array([(p.x, p.y, p.z) for p in surface.points])
        yield stamp_of(ma), pts.reshape(-1, 3, 3)


def crossings(bag: Path) -> dict[str, int]:
    """Per link: how many recorded states have a ribbon triangle inside its box."""
    out = {"upper_arm": 0, "forearm": 0}
    states = 0
    for t, tris in ribbon_states(bag):
        states += 1
        for link, (centre, rot) in boxes(t).items():
            if triangles_cross_box(tris, centre, rot, BOX / 2).any():
                out[link] += 1
    assert states == STEPS + 1, f"{states} ribbon states in the bag"
    return out


def vertex_box_distance(tris: np.ndarray, t: float) -> float:
    """The smallest distance of a ribbon vertex to a link's box at time t, m (for the
    log: the stage keeps the mid-surface contact.thickness / 2 = 1 mm away)."""
    v = tris.reshape(-1, 3)
    best = math.inf
    for centre, rot in boxes(t).values():
        local = np.abs((v - centre) @ rot) - BOX / 2
        best = min(best, float(np.linalg.norm(np.maximum(local, 0.0), axis=1).min()))
    return best


def drawn_boxes(bag: Path) -> list[tuple[float, list]]:
    """(t, the CUBE markers' centres) of every /colliders message."""
    out = []
    for _, ma in bag_messages(bag, ["/colliders"]):
        cubes = [m for m in ma.markers if m.type == 1]
        assert ma.markers[0].action == 3  # DELETEALL first: links may come and go
        out.append((stamp_of(ma), [(m.pose.position.x, m.pose.position.y, m.pose.position.z) for m in cubes]))
    return out


def test_a_two_link_arm_sweeping_through_the_ribbon_pushes_it_aside_never_across(
    start_node, ros, domain_id, tmp_path
):
    # the URDF latched before the node starts, as robot_state_publisher does
    bag, node = sweep(
        start_node, ros, domain_id, tmp_path, '<box size="0.3 0.04 0.04"/>', True
    )
    assert "2 colliding links (upper_arm, forearm)" in node.log()
    assert "skipped" not in node.log()
    assert crossings(bag) == {"upper_arm": 0, "forearm": 0}
    # pushed aside: the forearm swept from x = +0.16 to -0.16 m across the ribbon's
    # plane x = 0 and took the ribbon along
    pushed = max(-tris[:, :, 0].min() for _, tris in ribbon_states(bag))
    assert pushed > 0.1, f"the ribbon moved only {pushed} m in -x"
    closest = min(vertex_box_distance(tris, t) for t, tris in ribbon_states(bag))
    print(f"ribbon pushed {pushed:.4f} m in -x; closest ribbon vertex to a link box {closest * 1e3:.3f} mm")
    # /colliders draws both links where this test's TF puts them, state by state
    drawn = drawn_boxes(bag)
    assert len(drawn) == STEPS + 1
    moving = 0
    for t, centres in drawn:
        if not centres:
            continue  # before the links' first lookup
        want = [boxes(t)[link][0] for link in ("upper_arm", "forearm")]
        assert np.abs(np.array(centres) - np.array(want)).max() < 1e-9, (t, centres, want)
        moving += 1
    assert moving >= STEPS - 1
    r = replay(bag, tmp_path)
    assert r["identical"], r
    assert r["steps"] == STEPS


def test_a_missing_mesh_is_named_and_skipped_and_the_node_runs_on(
    start_node, ros, domain_id, tmp_path
):
    missing = tmp_path / "meshes" / "forearm.stl"
    bag, node = sweep(
        start_node, ros, domain_id, tmp_path, f'<mesh filename="file://{missing}"/>', False
    )
    log = node.log()
    assert f"link `forearm`: collision 0 (mesh `file://{missing}`): cannot read {missing}" in log
    assert "1 colliding links (upper_arm)" in log
    crossed = crossings(bag)
    # the upper arm never reaches the ribbon; the forearm, without its collider, goes
    # through it: the check above sees it (its negative)
    assert crossed["upper_arm"] == 0
    assert crossed["forearm"] > 10, crossed
    print(f"without the forearm's collider: {crossed['forearm']} of {STEPS + 1} states cross its box")
    assert all(len(c) == 1 for t, c in drawn_boxes(bag)[2:])
    assert replay(bag, tmp_path)["identical"]
