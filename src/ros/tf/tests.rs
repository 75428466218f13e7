//! The buffer against tf2's documented semantics (ros2/geometry2 `tf2/src/buffer_core.cpp`
//! and `time_cache.cpp`): chains through the tree in both directions, linear + slerp
//! interpolation between stamps, exact stamps, time 0 as the latest common time,
//! static frames at every time, no extrapolation before the oldest kept stamp, pruning
//! 10 s behind the newest stamp, plus our `max_lag` rule after the newest stamp.

use std::time::Duration;

use super::*;
use crate::wire::msgs::{Header, Quaternion, Time, Transform, Vector3};

const S: u64 = 1_000_000_000;
const LAG: Duration = Duration::from_millis(250);

fn tf(parent: &str, child: &str, ns: u64, xyz: [f64; 3], yaw: f64) -> TransformStamped {
    TransformStamped {
        header: Header {
            stamp: Time::from_nanos(ns as i64),
            frame_id: parent.into(),
        },
        child_frame_id: child.into(),
        transform: Transform {
            translation: Vector3 {
                x: xyz[0],
                y: xyz[1],
                z: xyz[2],
            },
            rotation: Quaternion {
                x: 0.0,
                y: 0.0,
                z: (yaw / 2.0).sin(),
                w: (yaw / 2.0).cos(),
            },
        },
    }
}

fn yaw(p: &Pose) -> f64 {
    p.rotation.euler_angles().2
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() < 1e-12
}

/// world -> base (static, x + 1), base -> gripper (dynamic: x from 0 to 1 and yaw from 0
/// to pi/2 between t = 100 s and t = 101 s).
fn tree() -> TfBuffer {
    let mut b = TfBuffer::default();
    b.insert_all(&[tf("world", "base", 0, [1.0, 0.0, 0.0], 0.0)], true);
    b.insert_all(
        &[
            tf("base", "gripper", 100 * S, [0.0, 0.0, 0.0], 0.0),
            tf(
                "/base",
                "/gripper",
                101 * S,
                [1.0, 0.0, 0.0],
                std::f64::consts::FRAC_PI_2,
            ),
        ],
        false,
    );
    assert_eq!((b.stored, b.rejected), (3, 0));
    b
}

#[test]
fn chains_and_interpolates_between_stamps() {
    let b = tree();
    // exactly at a stamp
    let p = b.lookup("world", "gripper", 100 * S, LAG).unwrap();
    assert!(close(p.translation.vector.x, 1.0) && close(yaw(&p), 0.0));
    // a quarter of the way: translation linear, rotation by slerp (yaw pi/8)
    let p = b.lookup("world", "gripper", 100 * S + S / 4, LAG).unwrap();
    assert!(close(p.translation.vector.x, 1.25), "{p}");
    assert!(close(yaw(&p), std::f64::consts::FRAC_PI_8), "{}", yaw(&p));
    // the inverse direction is the inverse transform
    let q = b.lookup("gripper", "world", 100 * S + S / 4, LAG).unwrap();
    assert!((q * p).translation.vector.norm() < 1e-12);
    assert!((q * p).rotation.angle() < 1e-12);
    // a frame to itself is the identity, even unknown
    assert_eq!(b.lookup("x", "x", 5, LAG).unwrap(), Pose::identity());
}

#[test]
fn time_zero_is_the_latest_common_time_and_statics_hold_always() {
    let b = tree();
    let p = b.lookup("world", "gripper", 0, LAG).unwrap();
    assert!(close(p.translation.vector.x, 2.0) && close(yaw(&p), std::f64::consts::FRAC_PI_2));
    // an all-static chain answers at any time, also long before and after
    for t in [0, 1, 100 * S, 10_000 * S] {
        let p = b.lookup("world", "base", t, LAG).unwrap();
        assert!(close(p.translation.vector.x, 1.0));
    }
}

#[test]
fn no_extrapolation_before_the_buffer_or_far_after_it() {
    let b = tree();
    assert!(matches!(
        b.lookup("world", "gripper", 100 * S - 1, LAG),
        Err(LookupError::TooOld { .. })
    ));
    // within max_lag after the newest stamp: the newest transform (no extrapolation)
    let p = b.lookup("world", "gripper", 101 * S + S / 5, LAG).unwrap();
    assert!(close(p.translation.vector.x, 2.0));
    let e = b
        .lookup("world", "gripper", 101 * S + S / 2, LAG)
        .unwrap_err();
    assert_eq!(
        e,
        LookupError::TooNew {
            requested_ns: 101 * S + S / 2,
            newest_ns: 101 * S
        }
    );
    assert!(matches!(
        b.lookup("world", "camera", 100 * S, LAG),
        Err(LookupError::UnknownFrame(f)) if f == "camera"
    ));
}

#[test]
fn keeps_ten_seconds_behind_the_newest_stamp() {
    let mut b = tree();
    b.insert_all(
        &[tf("base", "gripper", 111 * S, [3.0, 0.0, 0.0], 0.0)],
        false,
    );
    // 111 - 10 = 101: the sample at 100 s is gone, the one at 101 s stays
    assert!(matches!(
        b.lookup("world", "gripper", 100 * S + S / 2, LAG),
        Err(LookupError::TooOld { .. })
    ));
    let p = b.lookup("world", "gripper", 106 * S, LAG).unwrap();
    assert!(close(p.translation.vector.x, 3.0), "{p}");
}

#[test]
fn bad_transforms_are_counted_not_stored_and_frames_may_change_parent() {
    let mut b = tree();
    let mut nan = tf("base", "tool", S, [f64::NAN, 0.0, 0.0], 0.0);
    b.insert_all(std::slice::from_ref(&nan), false);
    nan.transform.translation.x = 0.0;
    nan.transform.rotation.w = 0.0;
    b.insert_all(&[nan], false);
    b.insert_all(&[tf("", "tool", S, [0.0; 3], 0.0)], false);
    // a cycle: world under gripper
    b.insert_all(&[tf("gripper", "world", 101 * S, [0.0; 3], 0.0)], false);
    // base is static: a dynamic base is a conflict
    b.insert_all(&[tf("world", "base", 101 * S, [0.0; 3], 0.0)], false);
    assert_eq!(b.rejected, 5);
    // a non-unit quaternion is normalized, as our pose filter does
    let mut t = tf("world", "table", 0, [0.0; 3], 0.0);
    t.transform.rotation.w = 2.0;
    b.insert_all(&[t], true);
    assert_eq!(b.rejected, 5);
    // the gripper moves from base to table (the newest parent wins)
    b.insert_all(
        &[tf("table", "gripper", 102 * S, [0.0, 5.0, 0.0], 0.0)],
        false,
    );
    let p = b.lookup("world", "gripper", 102 * S, LAG).unwrap();
    assert!(close(p.translation.vector.y, 5.0), "{p}");
}
