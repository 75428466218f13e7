//! Handle inputs: which `PoseStamped` messages become handle targets.
//!
//! The same filter runs in the node (live DDS input) and in `replay` (recorded input),
//! so a replay accepts and rejects exactly what the node did.

use crate::geometry::{Pose, Rotation};

use crate::wire::msgs::{HandleStatus, PoseStamped, Time};

/// Quaternions with a norm below this are rejected (no rotation can be recovered).
pub const MIN_QUATERNION_NORM: f64 = 1e-6;
/// Accepted quaternions whose norm differs from 1 by more than this are counted as
/// normalized (all accepted quaternions are normalized).
const NORMALIZED_TOLERANCE: f64 = 1e-6;

/// What the filter accepts.
#[derive(Clone, Debug, PartialEq)]
pub struct InputPolicy {
    /// The scene's fixed frame: poses must be expressed in it.
    pub frame_id: String,
    /// Treat an empty `header.frame_id` as the scene frame (default false: rejected as
    /// an unknown frame, since an empty frame is ambiguous in tf).
    pub accept_empty_frame_id: bool,
    /// s: a pose stamped more than this after its arrival (wall clock) is rejected. One
    /// such stamp, once accepted, would make every later correctly stamped pose look
    /// stale; the margin covers clock offsets between machines.
    pub max_stamp_lead: f64,
}

/// Default of [`InputPolicy::max_stamp_lead`], s.
pub const DEFAULT_MAX_STAMP_LEAD: f64 = 10.0;

/// Why a pose was rejected.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Rejection {
    UnknownFrame,
    NonFinite,
    ZeroQuaternion,
    StaleStamp,
    FutureStamp,
}

impl std::fmt::Display for Rejection {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Rejection::UnknownFrame => "unknown frame_id",
            Rejection::NonFinite => "NaN or infinite value",
            Rejection::ZeroQuaternion => "zero quaternion",
            Rejection::StaleStamp => "stamp older than the last accepted pose",
            Rejection::FutureStamp => "stamp ahead of the wall clock by more than max_stamp_lead",
        })
    }
}

/// The input state of one handle: the latest accepted target and the counters.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct HandleInput {
    /// The latest accepted `world_from_gripper` (None: follow the script).
    pub target: Option<Pose>,
    /// Stamp of the latest accepted pose.
    pub last_stamp: Option<Time>,
    pub accepted: u64,
    pub normalized: u64,
    pub rejected_non_finite: u64,
    pub rejected_zero_quaternion: u64,
    pub rejected_stale_stamp: u64,
    pub rejected_unknown_frame: u64,
    pub rejected_future_stamp: u64,
    /// TF lookups that failed for this handle (see `ros::graph`).
    pub rejected_tf_lookup: u64,
}

impl HandleInput {
    /// Check `msg`, received at `received_ns` (wall clock, ns since the Unix epoch);
    /// when acceptable it becomes the target (latest wins).
    pub fn offer(
        &mut self,
        policy: &InputPolicy,
        msg: &PoseStamped,
        received_ns: u64,
    ) -> Result<(), Rejection> {
        let verdict = check(policy, self.last_stamp, msg, received_ns);
        match verdict {
            Ok((pose, normalized)) => {
                self.target = Some(pose);
                self.last_stamp = Some(msg.header.stamp);
                self.accepted += 1;
                self.normalized += normalized as u64;
                Ok(())
            }
            Err(r) => {
                *match r {
                    Rejection::UnknownFrame => &mut self.rejected_unknown_frame,
                    Rejection::NonFinite => &mut self.rejected_non_finite,
                    Rejection::ZeroQuaternion => &mut self.rejected_zero_quaternion,
                    Rejection::StaleStamp => &mut self.rejected_stale_stamp,
                    Rejection::FutureStamp => &mut self.rejected_future_stamp,
                } += 1;
                Err(r)
            }
        }
    }

    /// Back to following the script (after a reset); counters are kept.
    pub fn clear_target(&mut self) {
        self.target = None;
        self.last_stamp = None;
    }

    /// Copy the counters into a status entry.
    pub fn fill_status(&self, s: &mut HandleStatus) {
        s.external = self.target.is_some();
        s.last_stamp = self.last_stamp.unwrap_or_default();
        s.accepted = self.accepted;
        s.normalized = self.normalized;
        s.rejected_non_finite = self.rejected_non_finite;
        s.rejected_zero_quaternion = self.rejected_zero_quaternion;
        s.rejected_stale_stamp = self.rejected_stale_stamp;
        s.rejected_unknown_frame = self.rejected_unknown_frame;
        s.rejected_future_stamp = self.rejected_future_stamp;
        s.rejected_tf_lookup = self.rejected_tf_lookup;
    }

    pub fn rejected(&self) -> u64 {
        self.rejected_non_finite
            + self.rejected_zero_quaternion
            + self.rejected_stale_stamp
            + self.rejected_unknown_frame
            + self.rejected_future_stamp
            + self.rejected_tf_lookup
    }
}

/// Validate one pose received at `received_ns` (wall clock, ns since the Unix epoch):
/// frame, finiteness, quaternion, stamp not ahead of the clock, stamp order (in that
/// order). Returns the pose (unit quaternion) and whether it had to be normalized.
pub fn check(
    policy: &InputPolicy,
    last_stamp: Option<Time>,
    msg: &PoseStamped,
    received_ns: u64,
) -> Result<(Pose, bool), Rejection> {
    let frame = msg
        .header
        .frame_id
        .strip_prefix('/')
        .unwrap_or(&msg.header.frame_id);
    let scene_frame = policy
        .frame_id
        .strip_prefix('/')
        .unwrap_or(&policy.frame_id);
    let frame_ok = frame == scene_frame || (frame.is_empty() && policy.accept_empty_frame_id);
    if !frame_ok {
        return Err(Rejection::UnknownFrame);
    }
    let p = &msg.pose.position;
    let q = &msg.pose.orientation;
    if ![p.x, p.y, p.z, q.x, q.y, q.z, q.w]
        .iter()
        .all(|v| v.is_finite())
    {
        return Err(Rejection::NonFinite);
    }
    let quaternion = nalgebra::Quaternion::new(q.w, q.x, q.y, q.z);
    let norm = quaternion.norm();
    // norm() of finite components can still overflow to inf
    if !norm.is_finite() {
        return Err(Rejection::NonFinite);
    }
    if norm < MIN_QUATERNION_NORM {
        return Err(Rejection::ZeroQuaternion);
    }
    let stamp = msg.header.stamp;
    let stamp_ns = i128::from(stamp.sec) * 1_000_000_000 + i128::from(stamp.nanosec);
    let lead_ns = (policy.max_stamp_lead * 1e9) as i128;
    if stamp_ns > i128::from(received_ns) + lead_ns {
        return Err(Rejection::FutureStamp);
    }
    if let Some(last) = last_stamp {
        if msg.header.stamp < last {
            return Err(Rejection::StaleStamp);
        }
    }
    let rotation = Rotation::from_quaternion(quaternion / norm);
    let pose = Pose::from_parts(nalgebra::Translation3::new(p.x, p.y, p.z), rotation);
    Ok((pose, (norm - 1.0).abs() > NORMALIZED_TOLERANCE))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::wire::msgs::{Header, Point, Pose as PoseMsg, Quaternion};

    fn msg(frame: &str, sec: i32, p: [f64; 3], q: [f64; 4]) -> PoseStamped {
        PoseStamped {
            header: Header {
                stamp: Time { sec, nanosec: 0 },
                frame_id: frame.into(),
            },
            pose: PoseMsg {
                position: Point {
                    x: p[0],
                    y: p[1],
                    z: p[2],
                },
                orientation: Quaternion {
                    x: q[0],
                    y: q[1],
                    z: q[2],
                    w: q[3],
                },
            },
        }
    }

    /// Arrival time of every pose in these tests: 1000 s after the epoch, ns.
    const AT: u64 = 1_000_000_000_000;

    #[test]
    fn rejects_bad_poses_and_counts_them() {
        let policy = InputPolicy {
            frame_id: "world".into(),
            accept_empty_frame_id: false,
            max_stamp_lead: DEFAULT_MAX_STAMP_LEAD,
        };
        let mut h = HandleInput::default();
        let id = [0.0, 0.0, 0.0, 1.0];
        assert_eq!(
            h.offer(&policy, &msg("world", 5, [1.0, 0.0, 0.0], id), AT),
            Ok(())
        );
        assert_eq!(
            h.offer(&policy, &msg("map", 6, [0.0; 3], id), AT),
            Err(Rejection::UnknownFrame)
        );
        assert_eq!(
            h.offer(&policy, &msg("", 6, [0.0; 3], id), AT),
            Err(Rejection::UnknownFrame)
        );
        assert_eq!(
            h.offer(&policy, &msg("world", 6, [f64::NAN, 0.0, 0.0], id), AT),
            Err(Rejection::NonFinite)
        );
        assert_eq!(
            h.offer(
                &policy,
                &msg("world", 6, [0.0; 3], [0.0, f64::INFINITY, 0.0, 1.0]),
                AT
            ),
            Err(Rejection::NonFinite)
        );
        assert_eq!(
            h.offer(
                &policy,
                &msg("world", 6, [0.0; 3], [1e300, 1e300, 0.0, 0.0]),
                AT
            ),
            Err(Rejection::NonFinite)
        );
        assert_eq!(
            h.offer(&policy, &msg("world", 6, [0.0; 3], [0.0; 4]), AT),
            Err(Rejection::ZeroQuaternion)
        );
        assert_eq!(
            h.offer(&policy, &msg("world", 4, [0.0; 3], id), AT),
            Err(Rejection::StaleStamp)
        );
        // the target is still the first pose
        assert!((h.target.unwrap().translation.vector.x - 1.0).abs() < 1e-15);
        // same stamp is not older: accepted; a leading slash is ignored; normalized
        assert_eq!(
            h.offer(
                &policy,
                &msg("/world", 5, [2.0, 0.0, 0.0], [0.0, 0.0, 0.0, 2.0]),
                AT
            ),
            Ok(())
        );
        assert_eq!(h.normalized, 1);
        assert!((h.target.unwrap().rotation.quaternion().norm() - 1.0).abs() < 1e-15);
        assert_eq!((h.accepted, h.rejected(), h.rejected_non_finite), (2, 7, 3));
        h.clear_target();
        assert!(h.target.is_none());
        assert_eq!(h.offer(&policy, &msg("world", 1, [0.0; 3], id), AT), Ok(()));
        let lenient = InputPolicy {
            accept_empty_frame_id: true,
            ..policy.clone()
        };
        assert_eq!(h.offer(&lenient, &msg("", 2, [0.0; 3], id), AT), Ok(()));
        // a stamp more than max_stamp_lead (10 s) after arrival would make every later
        // pose stale: rejected, and the target stays; exactly at the lead is accepted
        let future = 1000 + DEFAULT_MAX_STAMP_LEAD as i32;
        assert_eq!(
            h.offer(&policy, &msg("world", future + 1, [5.0, 0.0, 0.0], id), AT),
            Err(Rejection::FutureStamp)
        );
        assert_eq!(h.rejected_future_stamp, 1);
        assert!(h.target.unwrap().translation.vector.x.abs() < 1e-15);
        assert_eq!(
            h.offer(&policy, &msg("world", future, [0.0; 3], id), AT),
            Ok(())
        );
        assert_eq!(
            h.offer(&policy, &msg("world", 3, [0.0; 3], id), AT),
            Err(Rejection::StaleStamp)
        );
    }
}
