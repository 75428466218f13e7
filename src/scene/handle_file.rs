//! The scene file's `handles:` (grippers, their scripted trajectories) and `forces:`
//! sections, shared by every object kind.

use serde::{Deserialize, Serialize};

use super::check::{pose_from, Check};
use super::SceneError;
use crate::geometry::{Point2, Pose};
use crate::sim::{GraspEvent, HandleSpec, Motion, OrientationMode, Trajectory};

/// A gripper.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct HandleFile {
    pub name: String,
    /// Object it holds. Default: the scene's only object.
    #[serde(default)]
    pub object: Option<String>,
    /// Grasp point in the flat pattern [u, v], m (u along the centerline from 0 to l,
    /// v across from -w/2 to w/2).
    pub point: [f64; 2],
    /// World axes of the grasp point held: a list of `x`, `y`, `z`. Default all three.
    #[serde(default = "d_axes")]
    pub position_axes: Vec<String>,
    /// `free` (default), `normal` (normal guiding, sec. 5.1) or `full`.
    #[serde(default = "d_orientation")]
    pub orientation: String,
    /// Normal-guiding stiffness K, J. 1.0.
    #[serde(default = "d_normal_k")]
    pub normal_stiffness: f64,
    /// ROS topic, absolute. Default `handles/<name>`, relative to the node's namespace
    /// (`/handles/<name>` in the root namespace).
    #[serde(default)]
    pub topic: Option<String>,
    /// TF frame the handle follows instead of a pose topic: looked up from `/tf` and
    /// `/tf_static` in the scene's `frame_id` at each tick. Default: none (the topic).
    #[serde(default)]
    pub tf_frame: Option<String>,
    /// Scripted target when nobody publishes.
    #[serde(default)]
    pub trajectory: TrajectoryFile,
    /// Whether the handle holds its object from t = 0. Default true; false: it grasps
    /// later (`grasp_at`, the grasp services).
    #[serde(default = "d_true")]
    pub attached: bool,
    /// Reach of a closing gripper, m: it grasps the surface point nearest its target
    /// within this distance (`grasp_at`, `/handles/<name>/grasp`). Default 0.02.
    #[serde(default = "d_grasp_radius")]
    pub grasp_radius: f64,
    /// Time at which the gripper closes, s (while it follows its script). Default:
    /// never.
    #[serde(default)]
    pub grasp_at: Option<f64>,
    /// Time from which the handle lets go, s (while it follows its script; unloading,
    /// fig. 18). Default: never.
    #[serde(default)]
    pub release_at: Option<f64>,
}
fn d_true() -> bool {
    true
}
fn d_grasp_radius() -> f64 {
    crate::sim::handle::DEFAULT_GRASP_RADIUS
}
fn d_axes() -> Vec<String> {
    vec!["x".into(), "y".into(), "z".into()]
}
fn d_orientation() -> String {
    "free".into()
}
fn d_normal_k() -> f64 {
    1.0
}

#[derive(Clone, Debug, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct TrajectoryFile {
    /// Target at t = 0. Default: where the grasp point is in the initial shape.
    #[serde(default)]
    pub initial: Option<PoseFile>,
    /// Motions, composed in order.
    #[serde(default)]
    pub motions: Vec<MotionFile>,
}

#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct PoseFile {
    /// m.
    pub position: [f64; 3],
    /// Rotation vector, rad. Default [0, 0, 0].
    #[serde(default)]
    pub rotation: [f64; 3],
}

#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct MotionFile {
    /// s.
    pub start: f64,
    /// s (> start).
    pub end: f64,
    /// m over the motion. Default 0.
    #[serde(default)]
    pub translation: [f64; 3],
    /// Rotation axis (world, through the target point). Default x.
    #[serde(default = "d_axis")]
    pub axis: [f64; 3],
    /// rad over the motion (any size: 4*pi is two full turns). Default 0.
    #[serde(default)]
    pub angle: f64,
}
fn d_axis() -> [f64; 3] {
    [1.0, 0.0, 0.0]
}

#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct ForceFile {
    /// Object. Default: the only one.
    #[serde(default)]
    pub object: Option<String>,
    /// Material point [u, v], m.
    pub point: [f64; 2],
    /// Force, N (world frame).
    pub force: [f64; 3],
}

/// One handle's keys except its grasp point's range (checked per object kind): name,
/// axes, orientation, trajectory, topic. Returns the spec (trajectory initial pose
/// still to be defaulted), the explicit initial pose if any, and the ROS topic.
pub(super) fn parse_handle(
    ck: &Check,
    key: &str,
    h: &HandleFile,
    object: usize,
    names: &mut std::collections::BTreeSet<String>,
) -> Result<(HandleSpec, Option<Pose>, String), SceneError> {
    if h.name.is_empty()
        || !h
            .name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '_')
    {
        return Err(ck.fail(
            &format!("{key}.name"),
            format!("`{}` must be non-empty [A-Za-z0-9_]", h.name),
        ));
    }
    if !names.insert(h.name.clone()) {
        return Err(ck.fail(
            &format!("{key}.name"),
            format!("duplicate handle name `{}`", h.name),
        ));
    }
    let point = Point2::new(
        ck.finite(&format!("{key}.point.0"), h.point[0])?,
        ck.finite(&format!("{key}.point.1"), h.point[1])?,
    );
    let mut axes = [false; 3];
    for a in &h.position_axes {
        match a.as_str() {
            "x" => axes[0] = true,
            "y" => axes[1] = true,
            "z" => axes[2] = true,
            other => {
                return Err(ck.fail(
                    &format!("{key}.position_axes"),
                    format!("unknown axis `{other}`, expected x, y or z"),
                ))
            }
        }
    }
    let orientation = match ck.choice(
        &format!("{key}.orientation"),
        &h.orientation,
        &["free", "normal", "full"],
    )? {
        "free" => OrientationMode::Free,
        "normal" => OrientationMode::Normal {
            stiffness: ck.non_negative(&format!("{key}.normal_stiffness"), h.normal_stiffness)?,
        },
        _ => OrientationMode::Full,
    };
    let mut motions = Vec::new();
    for (m_i, m) in h.trajectory.motions.iter().enumerate() {
        let mk = format!("{key}.trajectory.motions.{m_i}");
        let start = ck.non_negative(&format!("{mk}.start"), m.start)?;
        let end = ck.finite(&format!("{mk}.end"), m.end)?;
        if end <= start {
            return Err(ck.fail(
                &format!("{mk}.end"),
                format!("must be after start ({end} <= {start})"),
            ));
        }
        let axis = ck.vec3(&format!("{mk}.axis"), m.axis)?;
        let angle = ck.finite(&format!("{mk}.angle"), m.angle)?;
        if angle != 0.0 && axis.norm() == 0.0 {
            return Err(ck.fail(&format!("{mk}.axis"), "must be non-zero when angle is"));
        }
        motions.push(Motion {
            start,
            end,
            translation: ck.vec3(&format!("{mk}.translation"), m.translation)?,
            axis,
            angle,
        });
    }
    let initial = match &h.trajectory.initial {
        Some(p) => Some(pose_from(
            ck.vec3(&format!("{key}.trajectory.initial.position"), p.position)?,
            ck.vec3(&format!("{key}.trajectory.initial.rotation"), p.rotation)?,
        )),
        None => None,
    };
    let topic = input_topic(ck, key, h)?;
    let trajectory = Trajectory {
        initial: Pose::identity(),
        motions,
    };
    Ok((
        HandleSpec {
            position_axes: axes,
            orientation,
            attached: h.attached,
            grasp_radius: ck.non_negative(&format!("{key}.grasp_radius"), h.grasp_radius)?,
            script: grasp_script(ck, key, h)?,
            ..HandleSpec::new(&h.name, object, point, trajectory)
        },
        initial,
        topic,
    ))
}

/// The handle's input topic before name resolution: the absolute `topic:` given, or
/// `handles/<name>`, relative to the node's namespace so that `-r __ns:=/robot1` moves
/// it (the node resolves both, `session::names`); a `tf_frame:` instead of a topic is
/// checked too.
fn input_topic(ck: &Check, key: &str, h: &HandleFile) -> Result<String, SceneError> {
    let topic = match &h.topic {
        Some(t) if !t.starts_with('/') || t.contains("//") || t.ends_with('/') => {
            return Err(ck.fail(
                &format!("{key}.topic"),
                format!("`{t}` is not an absolute ROS topic name"),
            ));
        }
        Some(t) => t.clone(),
        None => format!("handles/{}", h.name),
    };
    if let Some(f) = &h.tf_frame {
        let k = format!("{key}.tf_frame");
        if h.topic.is_some() {
            return Err(ck.fail(&k, "a handle follows either a `topic` or a `tf_frame`"));
        }
        let bare = f.strip_prefix('/').unwrap_or(f);
        if bare.is_empty() || f.chars().any(char::is_whitespace) {
            return Err(ck.fail(&k, format!("`{f}` is not a TF frame id")));
        }
    }
    Ok(topic)
}

/// The handle's scripted grasp and release (`grasp_at`, `release_at`, s), in time order.
fn grasp_script(ck: &Check, key: &str, h: &HandleFile) -> Result<Vec<GraspEvent>, SceneError> {
    let mut script = Vec::new();
    if let Some(t) = h.grasp_at {
        let time = ck.non_negative(&format!("{key}.grasp_at"), t)?;
        script.push(GraspEvent { time, grasp: true });
    }
    if let Some(t) = h.release_at {
        let time = ck.non_negative(&format!("{key}.release_at"), t)?;
        script.push(GraspEvent { time, grasp: false });
    }
    script.sort_by(|a, b| a.time.total_cmp(&b.time));
    Ok(script)
}
