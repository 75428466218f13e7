//! The QoS of every topic the node writes or reads, as one small value that DDS
//! (`ros::dds::qos`), the bags (`offered_qos_profiles`) and Foxglove share.

/// The offered QoS of a recorded topic (what rosbag2 stores so `ros2 bag play` can
/// offer the same). Only the policies the node uses; the rest are ROS defaults.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Qos {
    /// KEEP_LAST depth.
    pub depth: u32,
    /// Reliable (true) or best effort.
    pub reliable: bool,
    /// Transient local (true) or volatile.
    pub transient_local: bool,
}

impl Qos {
    /// Sensor data: best effort, keep last 5, volatile (handle inputs).
    pub const SENSOR_DATA: Qos = Qos {
        depth: 5,
        reliable: false,
        transient_local: false,
    };
    /// Camera images, camera info and clouds: best effort, keep last 1, volatile (ROS's
    /// sensor-data profile with depth 1, as the RealSense driver offers them; a reader
    /// that falls behind gets the newest frame).
    pub const CAMERA: Qos = Qos {
        depth: 1,
        reliable: false,
        transient_local: false,
    };
    /// `/clock`: best effort, keep last 1.
    pub const CLOCK: Qos = Qos {
        depth: 1,
        reliable: false,
        transient_local: false,
    };
    /// Markers: reliable, keep last 1, transient local (late joiners get the mesh).
    pub const MARKERS: Qos = Qos {
        depth: 1,
        reliable: true,
        transient_local: true,
    };
    /// Data outputs (status, singular points): reliable, keep last 10, volatile.
    pub const DATA: Qos = Qos {
        depth: 10,
        reliable: true,
        transient_local: false,
    };
    /// A latched state (a handle's grasp; a robot description on `/robot_description`
    /// as `robot_state_publisher` latches it): reliable, keep last 1, transient local (a
    /// late joiner gets the current state).
    pub const LATCHED: Qos = Qos {
        depth: 1,
        reliable: true,
        transient_local: true,
    };
    /// `/tf` as tf2's listener reads it: reliable, volatile, keep last 100.
    pub const TF: Qos = Qos {
        depth: 100,
        reliable: true,
        transient_local: false,
    };
    /// `/tf_static`: reliable, transient local (a late joiner gets the whole static tree).
    pub const TF_STATIC: Qos = Qos {
        depth: 100,
        reliable: true,
        transient_local: true,
    };
}
