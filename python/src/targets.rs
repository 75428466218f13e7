//! Handle targets from Python: `{"gripper": (position, quaternion)}` and its short
//! forms, checked and turned into the world's `world_from_gripper` poses.
//!
//! Quaternions are (x, y, z, w), the order of ROS `geometry_msgs/Quaternion` and
//! SciPy's `Rotation.as_quat()` and PyBullet (MuJoCo writes (w, x, y, z)). A quaternion is normalized as the node normalizes one (divided by its norm); a zero
//! or non-finite one, or a non-finite position, is refused with a ValueError (the node
//! would drop such a message).

use developable_sim::geometry::{Pose, Rotation};
use developable_sim::sim::World;
use nalgebra::{Quaternion, Translation3};
use pyo3::exceptions::{PyKeyError, PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyString};

/// Quaternions shorter than this cannot be normalized (the node's bound,
/// `session::input`).
const MIN_QUATERNION_NORM: f64 = 1e-6;

/// The targets of one step, one entry per world handle (None: the handle follows its
/// script); empty when `targets` is None or empty (every handle scripted).
pub fn parse(world: &World, targets: Option<&Bound<'_, PyAny>>) -> PyResult<Vec<Option<Pose>>> {
    let Some(targets) = targets.filter(|t| !t.is_none()) else {
        return Ok(Vec::new());
    };
    let dict = targets.cast::<PyDict>().map_err(|_| {
        PyTypeError::new_err(
            "targets must be a dict {handle name: (position, quaternion)} (or position)",
        )
    })?;
    if dict.is_empty() {
        return Ok(Vec::new());
    }
    let handles = world.handles();
    let mut out = vec![None; handles.len()];
    for (name, value) in dict.iter() {
        let name: String = name
            .extract()
            .map_err(|_| PyTypeError::new_err("target keys must be handle names (str)"))?;
        let Some(i) = handles.iter().position(|h| h.name == name) else {
            let known: Vec<&str> = handles.iter().map(|h| h.name.as_str()).collect();
            return Err(PyKeyError::new_err(format!(
                "no handle `{name}` in this scene (handles: {})",
                if known.is_empty() {
                    "none".to_string()
                } else {
                    known.join(", ")
                }
            )));
        };
        let current = world.current_targets()[i];
        out[i] = Some(
            pose(&value, &current.rotation)
                .map_err(|e| PyValueError::new_err(format!("target of handle `{name}`: {e}")))?,
        );
    }
    Ok(out)
}

/// A target: `(position, quaternion)` (3 + 4 numbers), a flat 7-vector
/// `[x, y, z, qx, qy, qz, qw]`, or a position alone (3 numbers: the orientation stays
/// `keep`, the handle's current target orientation).
pub fn pose(value: &Bound<'_, PyAny>, keep: &Rotation) -> Result<Pose, String> {
    if value.is_instance_of::<PyString>() {
        return Err("expected (position, quaternion) or a position, got a string".into());
    }
    let n = value
        .len()
        .map_err(|_| "expected (position, quaternion), a position or 7 numbers".to_string())?;
    let (p, q) = match n {
        2 => {
            let p = numbers(
                &value.get_item(0).map_err(|e| e.to_string())?,
                3,
                "position",
            )?;
            let q = numbers(
                &value.get_item(1).map_err(|e| e.to_string())?,
                4,
                "quaternion",
            )?;
            (p, Some(q))
        }
        3 => (numbers(value, 3, "position")?, None),
        7 => {
            let x = numbers(value, 7, "pose")?;
            (x[..3].to_vec(), Some(x[3..].to_vec()))
        }
        n => {
            return Err(format!(
            "expected (position, quaternion), a position (3 numbers) or 7 numbers, got {n} items"
        ))
        }
    };
    if p.iter().any(|x| !x.is_finite()) {
        return Err(format!("position {p:?} is not finite"));
    }
    let rotation = match q {
        None => *keep,
        Some(q) => rotation(&q)?,
    };
    Ok(Pose::from_parts(
        Translation3::new(p[0], p[1], p[2]),
        rotation,
    ))
}

/// The unit quaternion of (x, y, z, w), divided by its norm.
fn rotation(q: &[f64]) -> Result<Rotation, String> {
    let quaternion = Quaternion::new(q[3], q[0], q[1], q[2]);
    let norm = quaternion.norm();
    if !norm.is_finite() {
        return Err(format!("quaternion {q:?} (x, y, z, w) is not finite"));
    }
    if norm < MIN_QUATERNION_NORM {
        return Err(format!(
            "quaternion {q:?} (x, y, z, w) has norm {norm:e}: no rotation"
        ));
    }
    Ok(Rotation::from_quaternion(quaternion / norm))
}

/// `count` floats from a sequence (a list, a tuple, a NumPy array).
fn numbers(value: &Bound<'_, PyAny>, count: usize, what: &str) -> Result<Vec<f64>, String> {
    let v: Vec<f64> = value
        .extract()
        .map_err(|_| format!("{what} must be {count} numbers"))?;
    if v.len() != count {
        return Err(format!("{what} must be {count} numbers, got {}", v.len()));
    }
    Ok(v)
}

/// (position, quaternion (x, y, z, w)) of a pose, as f64 arrays.
pub fn parts(pose: &Pose) -> ([f64; 3], [f64; 4]) {
    let t = pose.translation.vector;
    let q = pose.rotation.coords; // i, j, k, w
    ([t.x, t.y, t.z], [q.x, q.y, q.z, q.w])
}
