#!/usr/bin/env python3
"""Drive a handle of the developable_sim node: publish the gripper's pose, read the
ribbon's markers and status. The twin of drive_handle_rclpy.py written with the PyPI
`cyclonedds` package (what rclpy uses under rmw_cyclonedds: same topics, types and QoS),
so it runs without a ROS installation; tests/python/test_drive_handle.py runs it against
the real node.

    developable_sim node config/scenes/ribbon_gripper.yaml      # one terminal
    .venv/bin/python launch_scripts/drive_handle.py --duration 5  # another

It prints one line a second and, at the end, a summary line `summary: {...}` (JSON:
markers and status messages received, the last mesh's triangle count, the handle's
accepted poses, the last constraint violation in m). Exit code 1 if nothing arrived.
"""

import argparse
import json
import math
import os
import sys
import time
from pathlib import Path

from cyclonedds.core import Policy, Qos
from cyclonedds.domain import DomainParticipant
from cyclonedds.pub import DataWriter
from cyclonedds.sub import DataReader
from cyclonedds.topic import Topic
from cyclonedds.util import duration

# The ROS 2 message types as cyclonedds dataclasses (rclpy imports them from the ROS
# packages instead): geometry_msgs, visualization_msgs, developable_sim.
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "python"))
from ros_types import Header, MarkerArray, Point, Pose, PoseStamped, SimStatus, Time  # noqa: E402


def qos(*policies):
    # ROS 2 speaks XCDR1 (encapsulation 00 01)
    return Qos(*policies, Policy.DataRepresentation(use_cdrv0_representation=True))


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--duration", type=float, default=10.0, help="s of driving")
    ap.add_argument("--domain-id", type=int, default=int(os.environ.get("ROS_DOMAIN_ID", "0")))
    a = ap.parse_args()

    dp = DomainParticipant(a.domain_id)
    # handle inputs: sensor-data QoS (best effort, keep last 5, volatile)
    pose_pub = DataWriter(
        dp,
        Topic(dp, "rt/handles/gripper", PoseStamped),
        qos=qos(Policy.Reliability.BestEffort, Policy.History.KeepLast(5)),
    )
    # markers: reliable, keep last 1, transient local (a late joiner gets the last mesh)
    markers = DataReader(
        dp,
        Topic(dp, "rt/ribbon/markers", MarkerArray),
        qos=qos(
            Policy.Reliability.Reliable(duration(seconds=1)),
            Policy.History.KeepLast(1),
            Policy.Durability.TransientLocal,
        ),
    )
    status = DataReader(
        dp,
        Topic(dp, "rt/ribbon/status", SimStatus),
        qos=qos(Policy.Reliability.Reliable(duration(seconds=1)), Policy.History.KeepLast(10)),
    )

    got = {"markers": 0, "status": 0, "triangles": 0, "accepted": 0, "constraint_violation": None}
    start = time.monotonic()
    last_print = start
    while time.monotonic() - start < a.duration:
        t = time.monotonic() - start
        now = time.time()
        pose_pub.write(
            PoseStamped(
                header=Header(stamp=Time(sec=int(now), nanosec=int(now % 1 * 1e9)), frame_id="world"),
                pose=Pose(  # m: the grasp point circles in the y-z plane; identity orientation
                    position=Point(
                        x=0.7,
                        y=0.12 * math.cos(0.5 * math.pi * t),
                        z=0.3 + 0.12 * math.sin(0.5 * math.pi * t),
                    )
                ),
            )
        )
        for m in markers.take(N=10):
            if isinstance(m, MarkerArray):
                got["markers"] += 1
                surface = next(k for k in m.markers if k.ns.endswith("/surface"))
                got["triangles"] = len(surface.points) // 3
        for s in status.take(N=100):
            if isinstance(s, SimStatus):
                got["status"] += 1
                got["constraint_violation"] = s.constraint_violation
                h = next((h for h in s.handles if h.name == "gripper"), None)
                got["accepted"] = h.accepted if h else 0
        if time.monotonic() - last_print >= 1.0:
            last_print = time.monotonic()
            print(f"t = {t:4.1f} s: {got}", flush=True)
        time.sleep(0.02)  # 50 Hz
    print("summary: " + json.dumps(got), flush=True)
    return 0 if got["markers"] and got["status"] else 1


if __name__ == "__main__":
    sys.exit(main())
