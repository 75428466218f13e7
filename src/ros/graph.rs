//! The node's place in a robot's ROS graph: TF in (`/tf`, `/tf_static` into a
//! [`TfBuffer`]), TF out (grasp and end frames), and an external `/clock` under
//! `use_sim_time`.
//!
//! Time bases: when the node owns time, every other node stamps poses and TF in wall
//! clock time, so lookups for a tick are at the wall clock; under `use_sim_time` the
//! node's simulated time is the graph's `/clock` time, and lookups are at the state's
//! simulated time. Never the node's own simulated time against wall-clock stamps.

use std::time::Duration;

use ros2_client::dds::rustdds::mio1::{Interest, Poll, Token};
use ros2_client::{Name, Node, Subscription};

use crate::ros::dds::{dds, qos, topic_type, NodeError};
use crate::ros::tf::{frame_name, LookupError, TfBuffer};
use crate::wire::msgs::{Clock, PoseStamped, TFMessage, Time};
use crate::wire::qos::Qos;

fn subscription<M: crate::wire::msgs::RosMessage>(
    node: &mut Node,
    topic: &str,
    q: Qos,
    poll: &Poll,
    token: Token,
) -> Result<Subscription<M>, NodeError> {
    let name = Name::parse(topic).map_err(dds("topic name"))?;
    let t = node
        .create_topic(&name, topic_type::<M>(), &qos(q))
        .map_err(dds("topic"))?;
    let mut sub = node
        .create_subscription::<M>(&t, Some(qos(q)))
        .map_err(dds("subscription"))?;
    poll.registry()
        .register(&mut sub, token, Interest::READABLE)?;
    Ok(sub)
}

/// TF in: the buffer and its two subscriptions.
pub struct TfIn {
    tf: Subscription<TFMessage>,
    tf_static: Subscription<TFMessage>,
    pub buffer: TfBuffer,
    /// A lookup this long after a chain's newest transform takes the newest.
    pub max_lag: Duration,
}

impl TfIn {
    /// Subscribe to `tf` and `tf_static` (resolved names), waking `poll` on `token` and
    /// the next token.
    pub fn new(
        node: &mut Node,
        tf: &str,
        tf_static: &str,
        poll: &Poll,
        token: usize,
        max_lag: Duration,
    ) -> Result<TfIn, NodeError> {
        Ok(TfIn {
            tf: subscription(node, tf, Qos::TF, poll, Token(token))?,
            tf_static: subscription(node, tf_static, Qos::TF_STATIC, poll, Token(token + 1))?,
            buffer: TfBuffer::default(),
            max_lag,
        })
    }

    /// Take every pending TF message into the buffer.
    pub fn drain(&mut self) {
        for (sub, is_static) in [(&self.tf, false), (&self.tf_static, true)] {
            while let Ok(Some((msg, _))) = sub.take() {
                self.buffer.insert_all(&msg.transforms, is_static);
            }
        }
    }

    /// `scene_from_frame` at `time_ns` (0: latest).
    pub fn lookup(
        &self,
        scene: &str,
        frame: &str,
        time_ns: u64,
    ) -> Result<crate::geometry::Pose, LookupError> {
        self.buffer.lookup(scene, frame, time_ns, self.max_lag)
    }

    /// A pose in another frame of the tree, expressed in the scene frame at its stamp
    /// (stamp 0: the latest transform). Ok(None): the pose needs no transform (already in
    /// the scene frame, or an empty frame id, which the input filter judges).
    pub fn to_scene(
        &self,
        scene: &str,
        msg: &PoseStamped,
    ) -> Result<Option<PoseStamped>, LookupError> {
        let frame = frame_name(&msg.header.frame_id);
        if frame.is_empty() || frame == frame_name(scene) {
            return Ok(None);
        }
        let stamp = msg.header.stamp.nanos().max(0) as u64;
        let scene_from_frame = self.lookup(scene, frame, stamp)?;
        let p = &msg.pose;
        let q = &p.orientation;
        let quaternion = nalgebra::Quaternion::new(q.w, q.x, q.y, q.z);
        // non-finite or zero quaternions are left for the input filter to reject
        let Some(rotation) = nalgebra::UnitQuaternion::try_new(quaternion, 1e-12) else {
            return Ok(None);
        };
        let frame_from_gripper = crate::geometry::Pose::from_parts(
            nalgebra::Translation3::new(p.position.x, p.position.y, p.position.z),
            rotation,
        );
        let mut out = msg.clone();
        out.header.frame_id = scene.to_string();
        out.pose = crate::wire::convert::pose(&(scene_from_frame * frame_from_gripper));
        Ok(Some(out))
    }
}

/// The scene-frame pose of TF frame `frame` at `time_ns`, as the handle input it becomes.
pub fn tf_pose(
    tf: &TfIn,
    scene: &str,
    frame: &str,
    time_ns: u64,
) -> Result<PoseStamped, LookupError> {
    let pose = tf.lookup(scene, frame, time_ns)?;
    Ok(PoseStamped {
        header: crate::wire::msgs::Header {
            stamp: Time::from_nanos(time_ns as i64),
            frame_id: scene.to_string(),
        },
        pose: crate::wire::convert::pose(&pose),
    })
}

/// An external `/clock` (use_sim_time): the newest time received, never backwards.
pub struct ClockIn {
    sub: Subscription<Clock>,
    /// Newest clock time, ns (None: nothing received yet).
    pub now_ns: Option<i64>,
    /// Clock messages older than the newest (ignored: time never runs backwards).
    pub backwards: u64,
}

impl ClockIn {
    pub fn new(
        node: &mut Node,
        clock: &str,
        poll: &Poll,
        token: usize,
    ) -> Result<ClockIn, NodeError> {
        Ok(ClockIn {
            sub: subscription(node, clock, Qos::CLOCK, poll, Token(token))?,
            now_ns: None,
            backwards: 0,
        })
    }

    /// Take pending clock messages.
    pub fn drain(&mut self) {
        while let Ok(Some((msg, _))) = self.sub.take() {
            let t = msg.clock.nanos();
            match self.now_ns {
                Some(now) if t < now => self.backwards += 1,
                _ => self.now_ns = Some(t),
            }
        }
    }
}
