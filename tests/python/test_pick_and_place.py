"""launch_scripts/pick_and_place.py, run as a user would against the real node on
ribbon_pick_and_place.yaml: it drives the picker by poses, grasps the ribbon's end with
`~/grasp` by the nearest point, carries it and lets go with `~/release`; the grasp
state closes and opens once and the wrench flows only while it holds."""

from __future__ import annotations

import json
import os
import subprocess
import sys

from conftest import ROOT, SCENES

# 0.6 m x 0.04 m at 0.1 kg/m^2
WEIGHT = 0.6 * 0.04 * 0.1 * 9.81


def test_the_pick_and_place_script_grasps_carries_and_releases(start_node, domain_id):
    node = start_node(domain_id, str(SCENES / "ribbon_pick_and_place.yaml"))
    env = dict(os.environ, ROS_DOMAIN_ID=str(domain_id))
    r = subprocess.run(
        [sys.executable, str(ROOT / "launch_scripts" / "pick_and_place.py")],
        env=env,
        capture_output=True,
        text=True,
        timeout=90,
    )
    assert r.returncode == 0, r.stdout + r.stderr + node.log()
    line = next(x for x in r.stdout.splitlines() if x.startswith("summary: "))
    got = json.loads(line[len("summary: "):])
    ok, message, point = got["grasp"]
    assert ok and message.startswith("grasped `ribbon`"), got
    # the far end, under the gripper
    assert abs(point[0] - 0.6) < 0.01 and abs(point[1]) <= 0.02, got
    assert got["release"] == [True, "handle `picker` released"], got
    # after the script's reset: the grasp, the release
    assert got["states"] == [True, False], got
    # 3.4 s carried at 100 Hz, whatever the script's reader keeps up with
    assert got["wrenches"] >= 100, got
    # queued before the release at most: none is published after it
    assert got["wrenches_after_release"] <= 10, got
    # the ribbon pulls the gripper down (its z is up: the normal hold keeps the face up),
    # by less than its whole weight (part lies on the table or the box)
    fz = got["mean_force"][2]
    assert -WEIGHT < fz < 0.0, got
