#!/usr/bin/env python3
"""Pick and place through the services: drive the `picker` gripper of
ribbon_pick_and_place.yaml by its pose topic, close it with `~/grasp` on the ribbon's
far end, lift, carry it across the box, lower it and open it with `~/release`, reading
the grasp state and the wrench on the gripper meanwhile. Written with the PyPI
`cyclonedds` package (what rclpy uses under rmw_cyclonedds: same topics, types, QoS and
service wire format), so it runs without a ROS installation; tests/python/
test_pick_and_place.py runs it against the real node.

    developable_sim node config/scenes/ribbon_pick_and_place.yaml   # one terminal
    .venv/bin/python launch_scripts/pick_and_place.py                # another

It starts the scene over (`~/reset`, unless --no-reset) while its poses arrive: from then
on they replace the gripper's script, its grasp_at and release_at too.
At the end it prints `summary: {...}` (JSON: the grasp and release answers, the grasp
states seen, the wrenches received while held and their mean force, N, in the handle
frame). Exit code 1 if the grasp or the release failed.
"""

import argparse
import json
import os
import random
import sys
import time
from pathlib import Path

from cyclonedds.core import Policy, Qos
from cyclonedds.domain import DomainParticipant
from cyclonedds.pub import DataWriter
from cyclonedds.sub import DataReader
from cyclonedds.topic import Topic
from cyclonedds.util import duration

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "python"))
import ros_types as rt  # noqa: E402

# (time s, gripper position m): down onto the far end, then (after the grasp) lift,
# carry across the box, lower beyond it
APPROACH = [(0.0, (0.6, 0.0, 0.15)), (1.0, (0.6, 0.0, 0.0012))]
CARRY = [
    (0.0, (0.6, 0.0, 0.0012)),
    (1.0, (0.6, 0.0, 0.2012)),
    (2.5, (0.6, 0.55, 0.2012)),
    (3.4, (0.6, 0.55, 0.0112)),
]


def qos(*policies):
    # ROS 2 speaks XCDR1 (encapsulation 00 01)
    return Qos(*policies, Policy.DataRepresentation(use_cdrv0_representation=True))


RELIABLE = qos(Policy.Reliability.Reliable(duration(seconds=1)), Policy.History.KeepLast(100))
LATCHED = qos(
    Policy.Reliability.Reliable(duration(seconds=1)),
    Policy.History.KeepLast(1),
    Policy.Durability.TransientLocal,
)


def along(path, t):
    """The position at time t on a piecewise-linear path."""
    for (t0, p0), (t1, p1) in zip(path, path[1:]):
        if t <= t1:
            a = max(0.0, (t - t0) / (t1 - t0))
            return tuple(x0 + a * (x1 - x0) for x0, x1 in zip(p0, p1))
    return path[-1][1]


class Client:
    """A ROS 2 service client on the rmw_cyclonedds wire format: topics rq/<name>Request
    and rr/<name>Reply, each sample led by the client's guid and a sequence number."""

    def __init__(self, dp, name, req_type, resp_type):
        self.req_type = req_type
        self.w = DataWriter(dp, Topic(dp, f"rq{name}Request", req_type), qos=RELIABLE)
        self.r = DataReader(dp, Topic(dp, f"rr{name}Reply", resp_type), qos=RELIABLE)
        self.guid = random.getrandbits(63)
        self.seq = 0

    def call(self, timeout=10.0, **fields):
        deadline = time.monotonic() + timeout
        while not (self.w.get_matched_subscriptions() and self.r.get_matched_publications()):
            if time.monotonic() > deadline:
                raise TimeoutError("the service is not there")
            time.sleep(0.02)
        self.seq += 1
        self.w.write(self.req_type(client_guid=self.guid, sequence_number=self.seq, **fields))
        while time.monotonic() < deadline:
            for s in self.r.take(N=10):
                if getattr(s, "sequence_number", None) == self.seq and s.client_guid == self.guid:
                    return s
            time.sleep(0.005)
        raise TimeoutError("no reply")


class Picker:
    def __init__(self, dp, node):
        self.poses = DataWriter(
            dp,
            Topic(dp, "rt/handles/picker", rt.PoseStamped),
            qos=qos(Policy.Reliability.BestEffort, Policy.History.KeepLast(5)),
        )
        self.state = DataReader(dp, Topic(dp, "rt/handles/picker/state", rt.GraspState), qos=LATCHED)
        self.wrench = DataReader(dp, Topic(dp, "rt/ribbon/picker/wrench", rt.WrenchStamped), qos=RELIABLE)
        self.grasp = Client(dp, f"{node}/grasp", rt.GraspRequest, rt.GraspResponse)
        self.release = Client(dp, f"{node}/release", rt.ReleaseRequest, rt.ReleaseResponse)
        self.seen = {"states": [], "wrenches": 0, "force_sum": [0.0, 0.0, 0.0]}
        self.at = APPROACH[0][1]

    def publish(self, p):
        self.at = p
        now = time.time()
        stamp = rt.Time(sec=int(now), nanosec=int(now % 1 * 1e9))
        self.poses.write(
            rt.PoseStamped(
                header=rt.Header(stamp=stamp, frame_id="world"),
                pose=rt.Pose(position=rt.Point(x=p[0], y=p[1], z=p[2])),
            )
        )

    def follow(self, path):
        start = time.monotonic()
        while (t := time.monotonic() - start) < path[-1][0] + 0.3:
            self.publish(along(path, t))
            self.read()
            time.sleep(0.02)  # 50 Hz

    def read(self):
        for s in self.state.take(N=10):
            if isinstance(s, rt.GraspState):
                self.seen["states"].append(s.attached)
        for w in self.wrench.take(N=100):
            if isinstance(w, rt.WrenchStamped):
                self.seen["wrenches"] += 1
                f = w.wrench.force
                for i, x in enumerate((f.x, f.y, f.z)):
                    self.seen["force_sum"][i] += x


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--domain-id", type=int, default=int(os.environ.get("ROS_DOMAIN_ID", "0")))
    ap.add_argument("--node", default="/developable_sim", help="the node's full name")
    ap.add_argument("--no-reset", action="store_true", help="do not start the scene over")
    a = ap.parse_args()

    dp = DomainParticipant(a.domain_id)
    picker = Picker(dp, a.node)
    if not a.no_reset:
        # poses first, then back to t = 0: the ribbon on the table, the gripper open,
        # following its script until the next pose 20 ms later (grasp_at is at 1 s)
        reset = Client(dp, f"{a.node}/reset", rt.TriggerRequest, rt.TriggerResponse)
        for _ in range(10):
            picker.publish(APPROACH[0][1])
            time.sleep(0.02)
        if not reset.call().success:
            print("reset refused", flush=True)
            return 1
        picker.follow([(0.0, APPROACH[0][1])])  # 0.3 s: the reset's grasp state arrives
        picker.seen["states"].clear()
    picker.follow(APPROACH)
    x, y, z = picker.at
    grasp = picker.grasp.call(
        handle="picker",
        world_point=rt.Point(x=x, y=y, z=z),
        max_distance=0.01,  # m: the end is under the gripper
        hold="normal",
    )
    print(f"grasp: {grasp.success} {grasp.message}", flush=True)
    picker.follow(CARRY)
    release = picker.release.call(handle="picker")
    print(f"release: {release.success} {release.message}", flush=True)
    picker.read()
    held = picker.seen["wrenches"]
    force_sum = list(picker.seen["force_sum"])
    picker.follow([(0.0, picker.at), (0.5, (0.6, 0.55, 0.15))])
    picker.seen["wrenches_after_release"] = picker.seen["wrenches"] - held
    n = max(held, 1)
    summary = {
        "grasp": [grasp.success, grasp.message, list(grasp.material_point)],
        "release": [release.success, release.message],
        "states": picker.seen["states"],
        "wrenches": held,
        "wrenches_after_release": picker.seen["wrenches_after_release"],
        "mean_force": [s / n for s in force_sum],
    }
    print("summary: " + json.dumps(summary), flush=True)
    return 0 if grasp.success and release.success else 1


if __name__ == "__main__":
    sys.exit(main())
