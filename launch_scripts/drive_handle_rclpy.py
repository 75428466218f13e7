#!/usr/bin/env python3
"""Drive a handle of the developable_sim node from rclpy: publish the gripper's pose,
read the ribbon's markers and status. Written for a ROS 2 installation (rclpy and the
developable_sim messages built from msg/ in your workspace: `colcon build
--packages-select developable_sim`); not run in CI, which runs its Cyclone DDS twin
launch_scripts/drive_handle.py against the real node instead.

    developable_sim node config/scenes/ribbon_gripper.yaml      # one terminal
    RMW_IMPLEMENTATION=rmw_cyclonedds_cpp python3 launch_scripts/drive_handle_rclpy.py
"""

import math

import rclpy
from developable_sim.msg import SimStatus
from geometry_msgs.msg import PoseStamped
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy, qos_profile_sensor_data
from visualization_msgs.msg import MarkerArray


class Gripper(Node):
    def __init__(self):
        super().__init__("my_gripper")
        # handle inputs: sensor-data QoS (best effort; a reliable publisher matches too)
        self.pose_pub = self.create_publisher(PoseStamped, "/handles/gripper", qos_profile_sensor_data)
        # markers: reliable, keep last 1, transient local (a late joiner gets the last mesh)
        latched = QoSProfile(
            depth=1,
            reliability=ReliabilityPolicy.RELIABLE,
            durability=DurabilityPolicy.TRANSIENT_LOCAL,
        )
        self.create_subscription(MarkerArray, "/ribbon/markers", self.on_markers, latched)
        self.create_subscription(SimStatus, "/ribbon/status", self.on_status, 10)
        self.start = self.get_clock().now()
        self.create_timer(0.02, self.publish_pose)  # 50 Hz

    def publish_pose(self):
        now = self.get_clock().now()
        t = (now - self.start).nanoseconds * 1e-9
        msg = PoseStamped()
        msg.header.stamp = now.to_msg()
        msg.header.frame_id = "world"  # the scene's frame_id
        msg.pose.position.x = 0.7  # m: the grasp point circles in the y-z plane
        msg.pose.position.y = 0.12 * math.cos(0.5 * math.pi * t)
        msg.pose.position.z = 0.3 + 0.12 * math.sin(0.5 * math.pi * t)
        msg.pose.orientation.w = 1.0
        self.pose_pub.publish(msg)

    def on_markers(self, msg: MarkerArray):
        surface = next(m for m in msg.markers if m.ns.endswith("/surface"))
        self.get_logger().info(f"mesh: {len(surface.points) // 3} triangles", throttle_duration_sec=1.0)

    def on_status(self, msg: SimStatus):
        self.get_logger().info(
            f"t = {msg.sim_time:.2f} s, grasp point {msg.constraint_violation:.1e} m from its target",
            throttle_duration_sec=1.0,
        )


def main():
    rclpy.init()
    rclpy.spin(Gripper())


if __name__ == "__main__":
    main()
