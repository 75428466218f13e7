"""launch_scripts/several_nodes.sh: two nodes in one domain, one clock owner; the
follower (use_sim_time) steps with the owner's /clock."""

from __future__ import annotations

import os
import signal
import subprocess
import time

from conftest import BIN, ROOT, SCENES

import ros_types as rt


def stamp(s) -> float:
    return s.header.stamp.sec + 1e-9 * s.header.stamp.nanosec


def test_two_nodes_share_one_clock(ros, domain_id, tmp_path):
    scene = str(SCENES / "ribbon_gripper.yaml")
    log = open(tmp_path / "nodes.log", "w")
    proc = subprocess.Popen(
        ["bash", str(ROOT / "launch_scripts" / "several_nodes.sh"), scene, scene],
        env=dict(os.environ, ROS_DOMAIN_ID=str(domain_id), DEVELOPABLE_SIM_BIN=str(BIN)),
        stdout=log, stderr=subprocess.STDOUT, start_new_session=True,
    )
    try:
        owner = ros.reader("/sim0/ribbon/status", rt.SimStatus)
        follower = ros.reader("/sim1/ribbon/status", rt.SimStatus)
        ros.wait_matched(owner, 20.0)
        ros.wait_matched(follower, 20.0)
        f = ros.take(follower, 20.0, until=lambda s: s.sim_time > 1.0)[-1]
        o = max(ros.take(owner, 0.5), key=lambda s: stamp(s))
        # the follower's simulated time started at the first clock sample it heard, so
        # the nodes agree on stamps (the clock's time), not on sim_time: the follower is
        # never stamped ahead of the owner's clock, and keeps up with it: its state read
        # right after the owner's (0.3 s of real time later, 1x real time) is within
        # that window of the owner's time
        assert stamp(f) <= stamp(o) + 1e-9, (stamp(f), stamp(o))
        f2 = max(ros.take(follower, 0.3), key=lambda s: stamp(s))
        assert stamp(o) - 0.2 <= stamp(f2) <= stamp(o) + 0.3 + 0.2, (stamp(o), stamp(f2))
        # its stamps are the clock's: its first sample plus its own simulated time
        assert f2.sim_time <= stamp(f2) + 1e-9
    finally:
        os.killpg(proc.pid, signal.SIGINT)
        proc.wait(timeout=20)
        log.close()
    text = (tmp_path / "nodes.log").read_text()
    assert text.count("[developable_sim] ready") == 2, text
