#!/usr/bin/env python3
"""A misbehaving DDS peer of the node, run as its own process by test_bad_subscribers.py
(each is something users do: a crashed RViz, `ros2 topic echo` with the wrong type, a
pose script that exits).

    bad_peer.py DOMAIN reader       reliable readers of /ribbon/markers and /ribbon/status
                                    that match, take one sample, then never take again
                                    (the test kills the process with -9)
    bad_peer.py DOMAIN wrong-type   reliable readers on /ribbon/markers and /ribbon/status
                                    declared with another type (std_msgs/String), until
                                    the test stops it
    bad_peer.py DOMAIN pose-script  a status reader and a pose writer on /handles/gripper:
                                    waits for a status, publishes poses for 1 s, exits 0

Prints "ready" on stdout once the node has discovered it (a sample arrived), "done" when
the pose script is about to exit.
"""


import sys
import time
from dataclasses import dataclass
from pathlib import Path

from cyclonedds.idl import IdlStruct

sys.path.insert(0, str(Path(__file__).resolve().parent))

import ros_types as rt  # noqa: E402
from conftest import SENSOR_QOS, Ros, pose_msg, reliable_qos  # noqa: E402


@dataclass
class WrongString(IdlStruct, typename="std_msgs::msg::dds_::String_"):
    data: str = ""


def say(word: str) -> None:
    print(word, flush=True)


def wait_matched(*readers, timeout: float = 20.0) -> None:
    for r in readers:
        Ros.wait_matched(r, timeout)


# What a script holds at module level: still alive when the interpreter exits (no
# orderly deletion of the DDS entities; the node learns of the exit by lease expiry).
HELD = []


def main() -> int:
    domain, mode = int(sys.argv[1]), sys.argv[2]
    ros = Ros(domain)
    HELD.append(ros)
    if mode == "reader":
        markers = ros.reader("/ribbon/markers", rt.MarkerArray, reliable_qos(1))
        status = ros.reader("/ribbon/status", rt.SimStatus, reliable_qos(1))
        wait_matched(markers, status)
        Ros.take(status, 20.0, until=lambda s: True)
        say("ready")
        while True:  # never takes again; killed by the test
            time.sleep(1.0)
    if mode == "wrong-type":
        markers = ros.reader("/ribbon/markers", WrongString, reliable_qos(1))
        status = ros.reader("/ribbon/status", WrongString, reliable_qos(1))
        # Cyclone never matches a writer of another type, but the node's writers
        # (RustDDS does not compare type names) match these readers, which then never
        # acknowledge. A /clock sample says the node has discovered this participant.
        clock = ros.reader("/clock", rt.Clock, SENSOR_QOS)
        Ros.take(clock, 20.0, until=lambda s: True)
        say("ready")
        while True:  # lives until the test stops it
            markers.take(N=16)
            status.take(N=16)
            time.sleep(0.05)
    if mode == "pose-script":
        status = ros.reader("/ribbon/status", rt.SimStatus, reliable_qos(10))
        pose = ros.writer("/handles/gripper", rt.PoseStamped, SENSOR_QOS)
        HELD.extend([status, pose])
        wait_matched(status, pose)
        Ros.take(status, 20.0, until=lambda s: True)
        say("ready")
        end = time.monotonic() + 1.0
        while time.monotonic() < end:
            pose.write(pose_msg(0.9, 0.0, 0.1))
            status.take(N=64)
            time.sleep(0.02)
        say("done")
        return 0  # a normal exit, as a script's end
    raise SystemExit(f"unknown mode {mode}")


if __name__ == "__main__":
    sys.exit(main())
