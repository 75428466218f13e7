"""ROS 2 launch file: start the developable_sim node (a cargo-built binary, not a ROS
package) with a params file, optionally recording a bag.

    ros2 launch launch_scripts/developable_sim.launch.py
    ros2 launch launch_scripts/developable_sim.launch.py \
        params:=config/params/developable_sim.yaml namespace:=/robot1 record:=bags/run1

The binary is taken from $DEVELOPABLE_SIM_BIN, else target/release/developable_sim
(build it with `cargo build --release`).
"""

import os

from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument, ExecuteProcess, OpaqueFunction
from launch.substitutions import LaunchConfiguration

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def _node(context):
    binary = os.environ.get(
        "DEVELOPABLE_SIM_BIN", os.path.join(ROOT, "target", "release", "developable_sim")
    )
    params = LaunchConfiguration("params").perform(context)
    namespace = LaunchConfiguration("namespace").perform(context)
    record = LaunchConfiguration("record").perform(context)
    cmd = [binary, "node"]
    if record:
        cmd += ["--record", record]
    cmd += ["--ros-args", "--params-file", params]
    if namespace:
        cmd += ["-r", f"__ns:={namespace}"]
    # SIGINT on shutdown: the node closes its bag cleanly
    return [ExecuteProcess(cmd=cmd, cwd=ROOT, output="screen", sigterm_timeout="10")]


def generate_launch_description():
    return LaunchDescription(
        [
            DeclareLaunchArgument(
                "params",
                default_value=os.path.join(ROOT, "config", "params", "developable_sim.yaml"),
                description="ROS 2 params file (developable_sim: ros__parameters: ...)",
            ),
            DeclareLaunchArgument("namespace", default_value="", description="node namespace"),
            DeclareLaunchArgument(
                "record", default_value="", description="bag folder to record into ('' = none)"
            ),
            OpaqueFunction(function=_node),
        ]
    )
