#!/usr/bin/env python3
"""A demo gripper: moves a handle of the running developable_sim node by publishing
geometry_msgs/PoseStamped over DDS, as an rclpy node on rmw_cyclonedds would, using the
PyPI `cyclonedds` package (no ROS installation needed).

    .venv/bin/python launch_scripts/demo_gripper.py                   # /handles/gripper
    .venv/bin/python launch_scripts/demo_gripper.py --topic /handles/twist_end \
        --center 1.0 0.0 0.0 --radius 0.0 --twist 1.0
    ROS_DOMAIN_ID=7 .venv/bin/python launch_scripts/demo_gripper.py --rate 200

The gripper circles around --center (m) in the y-z plane with --radius (m) every
--period (s), turning about x at --twist (rad/s), and prints what the node reports on
/<object>/status (the handle's accepted/rejected counts). Ctrl-C stops it; the node then
goes back to the scene's scripted trajectory only after a reset (the last pose holds).
"""


import argparse
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

# the message types, written once for the Python tests and the scripts
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "python"))
from ros_types import Header, Point, Pose, PoseStamped, Quaternion, SimStatus, Time  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--topic", default="/handles/gripper", help="handle pose topic")
    ap.add_argument("--status", default="/ribbon/status", help="status topic to report")
    ap.add_argument("--frame", default="world", help="header.frame_id (the scene frame)")
    ap.add_argument("--center", type=float, nargs=3, default=[0.7, 0.0, 0.3], help="m")
    ap.add_argument("--radius", type=float, default=0.12, help="m")
    ap.add_argument("--period", type=float, default=4.0, help="s per circle")
    ap.add_argument("--twist", type=float, default=0.0, help="rad/s about x")
    ap.add_argument("--rate", type=float, default=50.0, help="Hz")
    ap.add_argument("--duration", type=float, default=0.0, help="s; 0 = until Ctrl-C")
    ap.add_argument("--domain-id", type=int, default=int(os.environ.get("ROS_DOMAIN_ID", "0")))
    a = ap.parse_args()

    cdr1 = Policy.DataRepresentation(use_cdrv0_representation=True)
    dp = DomainParticipant(a.domain_id)
    writer = DataWriter(
        dp,
        Topic(dp, "rt" + a.topic, PoseStamped),
        qos=Qos(Policy.Reliability.BestEffort, Policy.History.KeepLast(5), cdr1),
    )
    status = DataReader(
        dp,
        Topic(dp, "rt" + a.status, SimStatus),
        qos=Qos(Policy.Reliability.Reliable(duration(seconds=1)), Policy.History.KeepLast(10), cdr1),
    )
    print(f"publishing on {a.topic} (domain {a.domain_id}) at {a.rate} Hz; Ctrl-C stops")
    start = time.time()
    last_print = 0.0
    try:
        while a.duration <= 0 or time.time() - start < a.duration:
            now = time.time()
            s = now - start
            phase = 2 * math.pi * s / a.period
            half = 0.5 * a.twist * s
            msg = PoseStamped(
                header=Header(
                    stamp=Time(sec=int(now), nanosec=int((now % 1) * 1e9)), frame_id=a.frame
                ),
                pose=Pose(
                    position=Point(
                        x=a.center[0],
                        y=a.center[1] + a.radius * math.cos(phase),
                        z=a.center[2] + a.radius * math.sin(phase),
                    ),
                    orientation=Quaternion(x=math.sin(half), w=math.cos(half)),
                ),
            )
            writer.write(msg)
            for st in status.take(N=100):
                if isinstance(st, SimStatus) and now - last_print > 1.0:
                    last_print = now
                    h = next((h for h in st.handles if h.topic == a.topic), None)
                    if h is not None:
                        print(
                            f"t_sim={st.sim_time:7.2f} s  external={h.external}  "
                            f"accepted={h.accepted}  rejected={st.rejected_inputs}  "
                            f"constraint={st.constraint_violation:.2e} m"
                        )
            time.sleep(max(0.0, 1.0 / a.rate - (time.time() - now)))
    except KeyboardInterrupt:
        pass


if __name__ == "__main__":
    main()
