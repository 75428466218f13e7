//! The TF buffer: transforms received on `/tf` and `/tf_static`, looked up through the
//! frame tree as tf2's `BufferCore::lookupTransform(target, source, time)` does
//! (ros2/geometry2 `tf2/src/buffer_core.cpp`, `time_cache.cpp`):
//!
//! - dynamic transforms are kept for [`CACHE_TIME`] (10 s, tf2's
//!   `BUFFER_CORE_DEFAULT_CACHE_TIME`) behind each frame's newest stamp; older ones are
//!   dropped, so a lookup before the oldest kept stamp fails;
//! - between two stamps the translation is interpolated linearly and the rotation by
//!   slerp; static transforms (`/tf_static`) hold at every time;
//! - time 0 means "the latest time every hop of the chain has" (tf2's latest common
//!   time);
//! - tf2 never extrapolates. A node ticking at "now" always looks up a little after the
//!   newest stamp a broadcaster sent (transport and its publishing period), where tf2
//!   users wait with a timeout; this buffer instead takes the newest common transform
//!   when the lookup is at most `max_lag` after it, and fails beyond.
//!
//! The store is the `transforms` crate's `Registry` (tf2-like, pure Rust); this module
//! adds the ROS message conversion, tf2's frame-name rules (a leading `/` is stripped),
//! re-parenting (a frame may move to another parent, the newest parent wins) and the
//! lag rule above.

use std::time::Duration;

use transforms::errors::RegistryError;
use transforms::geometry::{Quaternion as TfQuaternion, Transform, Vector3 as TfVector3};
use transforms::time::{Stamp, Timestamp};
use transforms::Registry;

use crate::geometry::{Pose, Rotation};

use crate::wire::msgs::TransformStamped;

/// How long dynamic transforms are kept behind a frame's newest stamp (tf2's default).
const CACHE_TIME: Duration = Duration::from_secs(10);

/// Default of the `tf_max_lag` parameter, s: a lookup at most this long after the newest
/// transform of a chain takes that newest transform.
pub const DEFAULT_MAX_LAG: f64 = 0.25;

/// Why a lookup failed.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum LookupError {
    #[error("frame `{0}` does not exist in the TF tree")]
    UnknownFrame(String),
    #[error("frames `{0}` and `{1}` are not connected in the TF tree")]
    Disconnected(String, String),
    /// Requested before the oldest stamp kept for the chain (older than the buffer).
    #[error("lookup at {requested_ns} ns is before the oldest transform kept ({oldest_ns} ns)")]
    TooOld { requested_ns: u64, oldest_ns: u64 },
    /// Requested more than `max_lag` after the newest common stamp.
    #[error(
        "lookup at {requested_ns} ns is {:.3} s after the newest transform ({newest_ns} ns)",
        (*requested_ns as f64 - *newest_ns as f64) * 1e-9
    )]
    TooNew { requested_ns: u64, newest_ns: u64 },
    #[error("no transform: {0}")]
    Other(String),
}

/// Why a received transform was not stored.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum InsertError {
    #[error("empty frame id")]
    EmptyFrame,
    #[error("a NaN or infinite value")]
    NonFinite,
    #[error("a zero quaternion")]
    ZeroQuaternion,
    #[error("negative stamp")]
    NegativeStamp,
    #[error("{0}")]
    Rejected(String),
}

/// The frame tree of one node.
#[derive(Debug)]
pub struct TfBuffer {
    registry: Registry,
    /// Transforms received but not stored (bad values, cycles, a static frame sent on
    /// `/tf`), since start.
    pub rejected: u64,
    /// Transforms stored, since start.
    pub stored: u64,
}

impl Default for TfBuffer {
    fn default() -> Self {
        TfBuffer {
            registry: Registry::with_max_age(CACHE_TIME),
            rejected: 0,
            stored: 0,
        }
    }
}

/// tf2 frame ids carry no leading `/` (tf2 strips it on insertion).
pub fn frame_name(id: &str) -> &str {
    id.strip_prefix('/').unwrap_or(id)
}

impl TfBuffer {
    /// Store every transform of a `TFMessage` (from `/tf_static` when `is_static`).
    /// Bad transforms are skipped and counted in [`TfBuffer::rejected`].
    pub fn insert_all(&mut self, transforms: &[TransformStamped], is_static: bool) {
        for t in transforms {
            match self.insert(t, is_static) {
                Ok(()) => self.stored += 1,
                Err(_) => self.rejected += 1,
            }
        }
    }

    /// Store one transform: `parent_from_child` at its stamp (or for all time).
    pub fn insert(&mut self, t: &TransformStamped, is_static: bool) -> Result<(), InsertError> {
        let parent = frame_name(&t.header.frame_id);
        let child = frame_name(&t.child_frame_id);
        if parent.is_empty() || child.is_empty() {
            return Err(InsertError::EmptyFrame);
        }
        let (v, q) = (&t.transform.translation, &t.transform.rotation);
        if ![v.x, v.y, v.z, q.x, q.y, q.z, q.w]
            .iter()
            .all(|c| c.is_finite())
        {
            return Err(InsertError::NonFinite);
        }
        let norm = (q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w).sqrt();
        if !norm.is_finite() {
            return Err(InsertError::NonFinite);
        }
        if norm < crate::session::input::MIN_QUATERNION_NORM {
            return Err(InsertError::ZeroQuaternion);
        }
        let stamp = if is_static {
            Stamp::Static
        } else {
            let ns = t.header.stamp.nanos();
            if ns < 0 {
                return Err(InsertError::NegativeStamp);
            }
            Stamp::At(Timestamp::from_nanos(ns as u64))
        };
        let rotation = TfQuaternion::from_wxyz(q.w / norm, q.x / norm, q.y / norm, q.z / norm);
        let tf = Transform::new(
            parent,
            child,
            TfVector3::new(v.x, v.y, v.z),
            rotation,
            stamp,
        )
        .map_err(|e| InsertError::Rejected(e.to_string()))?;
        match self.registry.add_transform(tf.clone()) {
            Ok(()) => Ok(()),
            // tf2 keeps a parent per stamp; the newest parent wins here
            Err(RegistryError::ReparentingNotSupported { .. }) => self
                .registry
                .reparent_frame(tf)
                .map_err(|e| InsertError::Rejected(e.to_string())),
            Err(e) => Err(InsertError::Rejected(e.to_string())),
        }
    }

    /// `target_from_source` at `time_ns` (ns in the transforms' time base; 0: the latest
    /// common time). A lookup up to `max_lag` after the newest common stamp takes the
    /// newest (see the module doc).
    pub fn lookup(
        &self,
        target: &str,
        source: &str,
        time_ns: u64,
        max_lag: Duration,
    ) -> Result<Pose, LookupError> {
        let (target, source) = (frame_name(target), frame_name(source));
        if target == source {
            return Ok(Pose::identity());
        }
        let latest = || match self.registry.latest_common_time(target, source) {
            Ok(Stamp::Static) => Ok(None),
            Ok(Stamp::At(t)) => Ok(Some(t)),
            Err(e) => Err(lookup_error(e, target, source)),
        };
        let at = if time_ns == 0 {
            latest()?.unwrap_or(Timestamp::from_nanos(0))
        } else {
            Timestamp::from_nanos(time_ns)
        };
        match self.registry.get_transform(target, source, at) {
            Ok(t) => Ok(to_pose(&t)),
            Err(RegistryError::NotFoundAt { .. }) | Err(RegistryError::NoCommonTime { .. }) => {
                let Some(newest) = latest()? else {
                    return Err(LookupError::Other(format!("{target} <- {source}")));
                };
                let newest_ns = newest.as_nanos();
                if time_ns <= newest_ns {
                    return Err(LookupError::TooOld {
                        requested_ns: time_ns,
                        oldest_ns: self.oldest_ns(target, source).unwrap_or(newest_ns),
                    });
                }
                if time_ns - newest_ns > max_lag.as_nanos() as u64 {
                    return Err(LookupError::TooNew {
                        requested_ns: time_ns,
                        newest_ns,
                    });
                }
                self.registry
                    .get_transform(target, source, newest)
                    .map(|t| to_pose(&t))
                    .map_err(|e| lookup_error(e, target, source))
            }
            Err(e) => Err(lookup_error(e, target, source)),
        }
    }

    /// The oldest stamp a lookup between the two frames can use (for messages).
    fn oldest_ns(&self, target: &str, source: &str) -> Option<u64> {
        match self
            .registry
            .get_transform(target, source, Timestamp::from_nanos(0))
        {
            Err(RegistryError::NotFoundAt { covered, .. }) => covered.map(|(a, _)| a.as_nanos()),
            _ => None,
        }
    }
}

fn lookup_error(e: RegistryError, target: &str, source: &str) -> LookupError {
    match e {
        RegistryError::UnknownFrame(f) => LookupError::UnknownFrame(f),
        RegistryError::Disconnected { .. } => {
            LookupError::Disconnected(target.to_string(), source.to_string())
        }
        other => LookupError::Other(other.to_string()),
    }
}

fn to_pose(t: &Transform) -> Pose {
    let (v, q) = (t.translation(), t.rotation());
    Pose::from_parts(
        nalgebra::Translation3::new(v.x, v.y, v.z),
        Rotation::new_normalize(nalgebra::Quaternion::new(q.w, q.x, q.y, q.z)),
    )
}

#[cfg(test)]
mod tests;
