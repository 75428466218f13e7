"""The launch scripts start the node with a params file (the ROS 2 launch file needs a
ROS installation; the shell script does the same without one and is run here), and bad
parameters fail with a message naming the file and the key."""

from __future__ import annotations

import os
import subprocess

from conftest import BIN, ROOT, SCENES


def test_shell_launcher_starts_the_node_with_a_params_file(tmp_path, domain_id):
    params = tmp_path / "params.yaml"
    params.write_text(
        "/**:\n"
        "  ros__parameters:\n"
        "    use_sim_time: false\n"
        "/**/developable_sim:\n"
        "  ros__parameters:\n"
        f"    scene: {SCENES / 'ribbon_gripper.yaml'}\n"
        "    duration: 0.3\n"
        "    as_fast_as_possible: true\n"
        "    marker:\n"
        "      line_width: 0.004\n"
    )
    env = dict(os.environ, DEVELOPABLE_SIM_BIN=str(BIN), ROS_DOMAIN_ID=str(domain_id))
    env["NAMESPACE"] = "/robot1"
    r = subprocess.run(
        ["bash", str(ROOT / "launch_scripts" / "run_node.sh"), str(params)],
        env=env,
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert r.returncode == 0, r.stdout + r.stderr
    assert "node /robot1/developable_sim" in r.stderr
    assert "/robot1/handles/gripper" in r.stderr
    assert "stopped at t = 0.3" in r.stderr


def test_bad_params_file_names_the_file_and_the_key(tmp_path):
    params = tmp_path / "bad.yaml"
    params.write_text("developable_sim:\n  ros__parameters:\n    real_time_factr: 2.0\n")
    r = subprocess.run(
        [str(BIN), "node", str(SCENES / "ribbon_gripper.yaml"), "--ros-args", "--params-file", str(params)],
        capture_output=True,
        text=True,
        timeout=30,
    )
    assert r.returncode == 2
    assert str(params) in r.stderr
    assert "developable_sim.ros__parameters.real_time_factr" in r.stderr
