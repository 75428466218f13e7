//! The scene file format. Every key: unit and default in the doc comment (and in the
//! commented YAML files under config/scenes/).

use std::path::Path;

use serde::{Deserialize, Serialize};

use super::{Outputs, Scene, SceneError};
use crate::geometry::{Point2, Pose, Vector3};
use crate::ribbon::{
    BaseMode, ClampRule, Imperfection, KineticModel, LoopKind, RibbonForce, RibbonInitialShape,
    RibbonParams, RibbonSim, SolverKind, SolverSettings,
};
use crate::sim::{HandleSpec, Motion, ObjectSim, OrientationMode, Trajectory, World};

fn d_frame() -> String {
    "world".into()
}
fn d_gravity() -> [f64; 3] {
    [0.0, 0.0, -9.81]
}
fn d_true() -> bool {
    true
}

/// A whole scene.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SceneFile {
    /// Scene name; default: the file stem.
    #[serde(default)]
    pub name: Option<String>,
    /// Simulated duration, s (> 0).
    pub duration: f64,
    /// Time step h, s (> 0).
    pub dt: f64,
    /// Fixed frame of all poses and markers. Default `world`.
    #[serde(default = "d_frame")]
    pub frame_id: String,
    /// Gravity, m/s^2. Default [0, 0, -9.81].
    #[serde(default = "d_gravity")]
    pub gravity: [f64; 3],
    /// Seed of every random choice (determinism). Default 0.
    #[serde(default)]
    pub seed: u64,
    /// Step solver (all ribbons).
    #[serde(default)]
    pub solver: SolverFile,
    /// The ribbon of a single-ribbon scene (object name `ribbon`).
    #[serde(default)]
    pub ribbon: Option<RibbonFile>,
    /// The sheet of a single-paper scene (object name `paper`, Schreck et al.); see
    /// [`super::paper_file::PaperFile`].
    #[serde(default)]
    pub paper: Option<super::paper_file::PaperFile>,
    /// Several ribbons (instead of `ribbon:`): each entry has a `name` and the keys of
    /// `ribbon:`. Optimized in parallel, then made collision-free together.
    #[serde(default)]
    pub ribbons: Vec<RibbonFile>,
    /// Rigid obstacles (see `super::contact::ColliderFile`). Default none.
    #[serde(default)]
    pub colliders: Vec<super::contact::ColliderFile>,
    /// Contact settings. A contact stage is built when the scene has colliders or this
    /// section (ribbon-ribbon and self contact only); otherwise nothing is built.
    #[serde(default)]
    pub contact: Option<super::contact::ContactFile>,
    /// Handles (grippers).
    #[serde(default)]
    pub handles: Vec<HandleFile>,
    /// Constant point forces.
    #[serde(default)]
    pub forces: Vec<ForceFile>,
    /// What is published / recorded.
    #[serde(default)]
    pub outputs: OutputsFile,
}

#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SolverFile {
    /// `gauss_newton` (ours, default), `chain` (ours, the O(n) chain sweep) or `lbfgsb`
    /// (the paper's).
    #[serde(default = "d_solver_kind")]
    pub kind: String,
    /// Inner stop: projected gradient reduced by this factor (dimensionless). 1e-6.
    #[serde(default = "d_tol")]
    pub tolerance: f64,
    /// Inner iteration limit per augmented-Lagrangian round. 200 (lbfgsb: 5000).
    #[serde(default)]
    pub max_iterations: Option<u32>,
    /// Augmented-Lagrangian penalty mu (paper 1e3).
    #[serde(default = "d_penalty")]
    pub penalty: f64,
    /// Outer stop on ||Δq||_inf (paper 1e-4).
    #[serde(default = "d_outer_tol")]
    pub outer_tolerance: f64,
    /// Outer round limit. 20.
    #[serde(default = "d_outer_max")]
    pub max_outer_iterations: u32,
    /// Outer stop when all constraints hold to this (m for positions). 1e-6.
    #[serde(default = "d_constraint_tol")]
    pub constraint_tolerance: f64,
    /// Start each step from the linear extrapolation of the last two states. false
    /// (it halves the median iteration count on smooth motion but lengthens the tail
    /// on snap-through events).
    #[serde(default)]
    pub extrapolate: bool,
}
fn d_constraint_tol() -> f64 {
    1e-6
}
fn d_solver_kind() -> String {
    "gauss_newton".into()
}
fn d_tol() -> f64 {
    1e-6
}
fn d_penalty() -> f64 {
    1e3
}
fn d_outer_tol() -> f64 {
    1e-4
}
fn d_outer_max() -> u32 {
    20
}
impl Default for SolverFile {
    fn default() -> Self {
        SolverFile {
            kind: d_solver_kind(),
            tolerance: d_tol(),
            max_iterations: None,
            penalty: d_penalty(),
            outer_tolerance: d_outer_tol(),
            max_outer_iterations: d_outer_max(),
            constraint_tolerance: d_constraint_tol(),
            extrapolate: false,
        }
    }
}

/// One ribbon (Pan et al.).
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct RibbonFile {
    /// Object name, required in a `ribbons:` list ([A-Za-z0-9_], unique); not used by
    /// the single `ribbon:` section (its object is called `ribbon`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// Length l, m. 1.0.
    #[serde(default = "d_length")]
    pub length: f64,
    /// Width w, m (< length). 0.05.
    #[serde(default = "d_width")]
    pub width: f64,
    /// Elements n (>= 2). 50.
    #[serde(default = "d_segments")]
    pub segments: usize,
    /// Areal density rho, kg/m^2. 0.1.
    #[serde(default = "d_density")]
    pub density: f64,
    /// Bending stiffness alpha, J. 0.1.
    #[serde(default = "d_alpha")]
    pub bending_stiffness: f64,
    /// Crease regularizer beta, J (paper 0.1).
    #[serde(default = "d_beta")]
    pub crease_regularizer: f64,
    /// `full` (default), `lumped` or `quasi_static`.
    #[serde(default = "d_kinetic")]
    pub kinetic: String,
    /// How a clamp (fixed or driven base, a handle with `orientation: full`) weights the
    /// creases next to it: `moment_matched` (default, second order in n),
    /// `dual_length` (the crease next to a clamp at s_c stands for the centerline from
    /// s_c to the midpoint of its free neighbour element: second order, a ~10x larger
    /// constant at end clamps) or `paper` (every crease l/n as in Pan et al.: the clamp
    /// acts half an element away from its point, first order). See docs/accuracy.md.
    #[serde(default = "d_clamp")]
    pub clamp: String,
    /// How the first element is held.
    #[serde(default)]
    pub base: BaseFile,
    /// `none` (default), `orientable` or `non_orientable`.
    #[serde(default = "d_loop", rename = "loop")]
    pub loop_closure: String,
    /// Initial shape (in the base frame).
    #[serde(default)]
    pub initial_shape: InitialShapeFile,
    /// Settle to a static equilibrium before t = 0 (closes loops from a ring guess).
    /// Default false.
    #[serde(default)]
    pub settle: bool,
    /// Initial rigid velocity.
    #[serde(default)]
    pub initial_velocity: Option<VelocityFile>,
    /// Safety factor of the crease bound (paper 0.95), in (0, 1].
    #[serde(default = "d_bound")]
    pub crease_bound_factor: f64,
}
fn d_length() -> f64 {
    1.0
}
fn d_width() -> f64 {
    0.05
}
fn d_segments() -> usize {
    50
}
fn d_density() -> f64 {
    0.1
}
fn d_alpha() -> f64 {
    0.1
}
fn d_beta() -> f64 {
    0.1
}
fn d_kinetic() -> String {
    "full".into()
}
fn d_clamp() -> String {
    "dual_length".into()
}
fn d_loop() -> String {
    "none".into()
}
fn d_bound() -> f64 {
    0.95
}

#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct BaseFile {
    /// `fixed` (default: E_0 held at `position`/`rotation`), `floating`, or `driven`
    /// (E_0 follows `handle`).
    #[serde(default = "d_base_mode")]
    pub mode: String,
    /// Position of the ribbon's material origin (start of the centerline), m.
    #[serde(default)]
    pub position: [f64; 3],
    /// Rotation vector (axis * angle), rad.
    #[serde(default)]
    pub rotation: [f64; 3],
    /// The handle driving E_0 when `mode: driven`.
    #[serde(default)]
    pub handle: Option<String>,
}
fn d_base_mode() -> String {
    "fixed".into()
}
impl Default for BaseFile {
    fn default() -> Self {
        BaseFile {
            mode: d_base_mode(),
            position: [0.0; 3],
            rotation: [0.0; 3],
            handle: None,
        }
    }
}

#[derive(Clone, Debug, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct InitialShapeFile {
    /// `flat` (default), `helix` (every crease with the values below), `ring`
    /// (square creases bent by 2 pi / n: a closed polygon, the start guess of loops) or
    /// `explicit` (every crease given: `crease_directions`, `bending_angles`).
    #[serde(default)]
    pub kind: Option<String>,
    /// Crease direction c = tan(theta) of every crease (helix). 0.
    #[serde(default)]
    pub crease_direction: f64,
    /// Bending angle psi of every crease, rad (helix). 0.
    #[serde(default)]
    pub bending_angle: f64,
    /// `explicit`: c_1 .. c_{n-1}, one per interior crease (dimensionless). Required
    /// for `explicit`, not used otherwise.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub crease_directions: Option<Vec<f64>>,
    /// `explicit`: psi_1 .. psi_{n-1}, rad. Required for `explicit`, not used otherwise.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub bending_angles: Option<Vec<f64>>,
    /// Amplitude of a seeded random perturbation of every c and psi (rad), drawn from
    /// the scene `seed`. A flat strip twisted or spun about its axis sits on a
    /// bifurcation; this breaks the symmetry as a real ribbon's imperfections do. 0.
    #[serde(default)]
    pub imperfection: f64,
}

#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct VelocityFile {
    /// Angular velocity, rad/s.
    #[serde(default)]
    pub angular: [f64; 3],
    /// Linear velocity, m/s.
    #[serde(default)]
    pub linear: [f64; 3],
    /// Centre of the rotation, m.
    #[serde(default)]
    pub center: [f64; 3],
}

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
    /// ROS topic. Default `/handles/<name>`.
    #[serde(default)]
    pub topic: Option<String>,
    /// TF frame the handle follows instead of a pose topic: looked up from `/tf` and
    /// `/tf_static` in the scene's `frame_id` at each tick. Default: none (the topic).
    #[serde(default)]
    pub tf_frame: Option<String>,
    /// Scripted target when nobody publishes.
    #[serde(default)]
    pub trajectory: TrajectoryFile,
    /// Time from which the handle lets go, s (paper objects only: unloading, fig. 18).
    /// Default: never.
    #[serde(default)]
    pub release_at: Option<f64>,
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

#[derive(Clone, Copy, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct OutputsFile {
    /// `/<obj>/markers`. Default true.
    #[serde(default = "d_true")]
    pub markers: bool,
    /// `/<obj>/singular_points`. Default true.
    #[serde(default = "d_true")]
    pub singular_points: bool,
    /// `/<obj>/status`. Default true.
    #[serde(default = "d_true")]
    pub status: bool,
    /// `/clock` when the node owns time. Default true.
    #[serde(default = "d_true")]
    pub clock: bool,
    /// `/tf`: each object's grasp frames `<object>/<handle>` and end frames
    /// `<object>/start`, `<object>/end`, parent `frame_id`. Default false.
    #[serde(default)]
    pub tf: bool,
    /// Hz, at most this many markers messages per second per object (the mesh is the
    /// largest output). Default: every tick.
    #[serde(default)]
    pub markers_rate: Option<f64>,
}
impl Default for OutputsFile {
    fn default() -> Self {
        OutputsFile {
            markers: true,
            singular_points: true,
            status: true,
            clock: true,
            tf: false,
            markers_rate: None,
        }
    }
}

/// Collects validation errors with their key paths.
pub(super) struct Check<'a> {
    pub(super) file: &'a Path,
}

impl Check<'_> {
    pub(super) fn fail(&self, key: &str, message: impl Into<String>) -> SceneError {
        SceneError::Invalid {
            file: self.file.to_path_buf(),
            key: key.to_string(),
            message: message.into(),
        }
    }
    pub(super) fn finite(&self, key: &str, v: f64) -> Result<f64, SceneError> {
        if v.is_finite() {
            Ok(v)
        } else {
            Err(self.fail(key, format!("must be a finite number, got {v}")))
        }
    }
    pub(super) fn positive(&self, key: &str, v: f64) -> Result<f64, SceneError> {
        self.finite(key, v)?;
        if v > 0.0 {
            Ok(v)
        } else {
            Err(self.fail(key, format!("must be > 0, got {v}")))
        }
    }
    pub(super) fn non_negative(&self, key: &str, v: f64) -> Result<f64, SceneError> {
        self.finite(key, v)?;
        if v >= 0.0 {
            Ok(v)
        } else {
            Err(self.fail(key, format!("must be >= 0, got {v}")))
        }
    }
    pub(super) fn vec3(&self, key: &str, v: [f64; 3]) -> Result<Vector3, SceneError> {
        for (i, x) in v.iter().enumerate() {
            self.finite(&format!("{key}.{i}"), *x)?;
        }
        Ok(Vector3::from(v))
    }
    pub(super) fn choice<'s>(
        &self,
        key: &str,
        v: &'s str,
        allowed: &[&str],
    ) -> Result<&'s str, SceneError> {
        if allowed.contains(&v) {
            Ok(v)
        } else {
            Err(self.fail(
                key,
                format!(
                    "unknown value `{v}`, expected one of: {}",
                    allowed.join(", ")
                ),
            ))
        }
    }
}

fn initial_kind_is_not_explicit(ribbon: &RibbonFile) -> bool {
    ribbon.initial_shape.kind.as_deref() != Some("explicit")
}

pub(super) fn pose_from(position: Vector3, rotation: Vector3) -> Pose {
    Pose::new(position, rotation)
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
    let topic = h
        .topic
        .clone()
        .unwrap_or_else(|| format!("/handles/{}", h.name));
    if !topic.starts_with('/') || topic.contains("//") || topic.ends_with('/') {
        return Err(ck.fail(
            &format!("{key}.topic"),
            format!("`{topic}` is not an absolute ROS topic name"),
        ));
    }
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
    Ok((
        HandleSpec {
            name: h.name.clone(),
            object,
            material_point: point,
            position_axes: axes,
            orientation,
            trajectory: Trajectory {
                initial: Pose::identity(),
                motions,
            },
        },
        initial,
        topic,
    ))
}

impl SceneFile {
    /// Validate and build the world.
    pub fn build(self, file: &Path) -> Result<Scene, SceneError> {
        let ck = Check { file };
        let duration = ck.positive("duration", self.duration)?;
        let dt = ck.positive("dt", self.dt)?;
        if dt > duration {
            return Err(ck.fail(
                "dt",
                format!("time step {dt} s is longer than the duration {duration} s"),
            ));
        }
        let gravity = ck.vec3("gravity", self.gravity)?;
        if self.frame_id.trim().is_empty() {
            return Err(ck.fail("frame_id", "must not be empty"));
        }
        if let Some(rate) = self.outputs.markers_rate {
            ck.positive("outputs.markers_rate", rate)?;
        }
        let solver = self.solver_settings(&ck)?;
        if self.paper.is_some() {
            if self.ribbon.is_some() || !self.ribbons.is_empty() {
                return Err(ck.fail(
                    "paper",
                    "a scene holds either ribbons (`ribbon:` or `ribbons:`) or one `paper:` sheet, not both",
                ));
            }
            return self.build_paper(file, &ck, duration, dt, gravity);
        }
        let (entries, object_names) = self.ribbon_entries(&ck)?;
        let object_of = |key: &str, name: &Option<String>| -> Result<usize, SceneError> {
            match name {
                None if object_names.len() == 1 => Ok(0),
                None => Err(ck.fail(
                    key,
                    format!(
                        "the scene has several objects: name one ({})",
                        object_names.join(", ")
                    ),
                )),
                Some(n) => object_names.iter().position(|o| o == n).ok_or_else(|| {
                    ck.fail(
                        key,
                        format!(
                            "no object named `{n}` (objects: {})",
                            object_names.join(", ")
                        ),
                    )
                }),
            }
        };

        // handles (validated before the ribbon: a driven base names one)
        let mut names = std::collections::BTreeSet::new();
        let mut specs = Vec::new();
        let mut topics = Vec::new();
        for (i, h) in self.handles.iter().enumerate() {
            let key = format!("handles.{i}");
            let object = object_of(&format!("{key}.object"), &h.object)?;
            let (spec, initial, topic) = parse_handle(&ck, &key, h, object, &mut names)?;
            let ribbon = entries[object].1;
            let point = spec.material_point;
            if point.x < 0.0
                || point.x > ribbon.length
                || point.y.abs() > 0.5 * ribbon.width + 1e-12
            {
                return Err(ck.fail(
                    &format!("{key}.point"),
                    format!(
                        "[{}, {}] is outside the ribbon [0, {}] x [-{}, {}] (m)",
                        point.x,
                        point.y,
                        ribbon.length,
                        ribbon.width / 2.0,
                        ribbon.width / 2.0
                    ),
                ));
            }
            if h.release_at.is_some() {
                return Err(ck.fail(
                    &format!("{key}.release_at"),
                    "only paper objects support releasing a handle",
                ));
            }
            topics.push(topic);
            specs.push((spec, initial));
        }

        // the ribbons: parameters first (a probe of each places default handle targets)
        let mut setups = Vec::new();
        for (rk, ribbon) in &entries {
            let (params, initial) = self.ribbon_params(&ck, rk, ribbon, gravity, solver, &specs)?;
            let imperfection = Imperfection {
                amplitude: ck.non_negative(
                    &format!("{rk}.initial_shape.imperfection"),
                    ribbon.initial_shape.imperfection,
                )?,
                seed: self.seed,
            };
            setups.push((params, initial, imperfection));
        }
        for (i, f) in self.forces.iter().enumerate() {
            let key = format!("forces.{i}");
            object_of(&format!("{key}.object"), &f.object)?;
        }

        // default handle targets: the grasp point where the initial shape puts it
        let probes: Vec<RibbonSim> = setups
            .iter()
            .map(|(params, initial, imperfection)| {
                RibbonSim::new(params.clone(), initial, *imperfection, &[], 0, &[])
            })
            .collect();
        let mut handles = Vec::new();
        for (mut spec, initial_pose) in specs {
            spec.trajectory.initial = initial_pose
                .unwrap_or_else(|| probes[spec.object].material_pose(&spec.material_point));
            handles.push(spec);
        }
        drop(probes);
        let mut objects = Vec::new();
        for (index, ((rk, ribbon), (params, initial, imperfection))) in
            entries.iter().zip(setups).enumerate()
        {
            let mut forces = Vec::new();
            for (i, f) in self.forces.iter().enumerate() {
                let key = format!("forces.{i}");
                if object_of(&format!("{key}.object"), &f.object)? != index {
                    continue;
                }
                forces.push(RibbonForce {
                    material_point: Point2::new(
                        ck.finite(&format!("{key}.point.0"), f.point[0])?,
                        ck.finite(&format!("{key}.point.1"), f.point[1])?,
                    ),
                    force: ck.vec3(&format!("{key}.force"), f.force)?,
                });
            }
            let mut sim = RibbonSim::new(params, &initial, imperfection, &forces, index, &handles);
            if let Some(v) = &ribbon.initial_velocity {
                sim.set_rigid_velocity(
                    ck.vec3(&format!("{rk}.initial_velocity.angular"), v.angular)?,
                    ck.vec3(&format!("{rk}.initial_velocity.center"), v.center)?
                        .into(),
                    ck.vec3(&format!("{rk}.initial_velocity.linear"), v.linear)?,
                );
            }
            objects.push((
                object_names[index].clone(),
                Box::new(sim) as Box<dyn ObjectSim>,
            ));
        }
        let mut world = World::new(objects, handles, dt);
        if let Some(stage) = super::contact::build_stage(&self, &ck, file, &world)? {
            world = world.with_contact(stage);
        }
        Ok(self.into_scene(file, duration, world, topics))
    }

    /// The ribbons declared (`ribbon:` or `ribbons:`) with their key prefixes, and the
    /// object names.
    #[allow(clippy::type_complexity)]
    fn ribbon_entries(
        &self,
        ck: &Check,
    ) -> Result<(Vec<(String, &RibbonFile)>, Vec<String>), SceneError> {
        match (&self.ribbon, self.ribbons.is_empty()) {
            (Some(_), false) => Err(ck.fail(
                "ribbons",
                "declare either one `ribbon:` section or a `ribbons:` list, not both",
            )),
            (None, true) => Err(ck.fail(
                "ribbon",
                "the scene declares no object (add a `ribbon:` section or a `ribbons:` list)",
            )),
            (Some(r), true) => {
                if r.name.is_some() {
                    return Err(ck.fail(
                        "ribbon.name",
                        "the single `ribbon:` object is called `ribbon`; use a `ribbons:` list to name objects",
                    ));
                }
                Ok((vec![("ribbon".to_string(), r)], vec!["ribbon".to_string()]))
            }
            (None, false) => {
                let mut entries = Vec::new();
                let mut names: Vec<String> = Vec::new();
                for (i, r) in self.ribbons.iter().enumerate() {
                    let key = format!("ribbons.{i}");
                    let Some(name) = &r.name else {
                        return Err(
                            ck.fail(&format!("{key}.name"), "every listed ribbon needs a name")
                        );
                    };
                    if name.is_empty()
                        || !name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
                    {
                        return Err(ck.fail(
                            &format!("{key}.name"),
                            format!("`{name}` must be non-empty [A-Za-z0-9_]"),
                        ));
                    }
                    if names.contains(name) {
                        return Err(ck.fail(
                            &format!("{key}.name"),
                            format!("duplicate object name `{name}`"),
                        ));
                    }
                    names.push(name.clone());
                    entries.push((key, r));
                }
                Ok((entries, names))
            }
        }
    }

    /// Validate one ribbon's keys (under `rk`) into its parameters and initial shape.
    fn ribbon_params(
        &self,
        ck: &Check,
        rk: &str,
        ribbon: &RibbonFile,
        gravity: Vector3,
        solver: SolverSettings,
        specs: &[(HandleSpec, Option<Pose>)],
    ) -> Result<(RibbonParams, RibbonInitialShape), SceneError> {
        let length = ck.positive(&format!("{rk}.length"), ribbon.length)?;
        let width = ck.positive(&format!("{rk}.width"), ribbon.width)?;
        if width >= length {
            return Err(ck.fail(&format!("{rk}.width"), format!("must be smaller than ribbon.length ({width} >= {length}): a ribbon is long and narrow")));
        }
        if ribbon.segments < 2 {
            return Err(ck.fail(
                &format!("{rk}.segments"),
                format!("must be at least 2, got {}", ribbon.segments),
            ));
        }
        if ribbon.segments > 20_000 {
            return Err(ck.fail(
                &format!("{rk}.segments"),
                format!("{} is more than the supported 20000", ribbon.segments),
            ));
        }
        let density = ck.positive(&format!("{rk}.density"), ribbon.density)?;
        let alpha =
            ck.non_negative(&format!("{rk}.bending_stiffness"), ribbon.bending_stiffness)?;
        let beta = ck.non_negative(
            &format!("{rk}.crease_regularizer"),
            ribbon.crease_regularizer,
        )?;
        let factor = ck.positive(
            &format!("{rk}.crease_bound_factor"),
            ribbon.crease_bound_factor,
        )?;
        if factor > 1.0 {
            return Err(ck.fail(
                &format!("{rk}.crease_bound_factor"),
                format!("must be in (0, 1], got {factor}"),
            ));
        }
        let kinetic = match ck.choice(
            &format!("{rk}.kinetic"),
            &ribbon.kinetic,
            &["full", "lumped", "quasi_static"],
        )? {
            "full" => KineticModel::Full,
            "lumped" => KineticModel::Lumped,
            _ => KineticModel::QuasiStatic,
        };
        let clamp = match ck.choice(
            &format!("{rk}.clamp"),
            &ribbon.clamp,
            &["moment_matched", "dual_length", "paper"],
        )? {
            "paper" => ClampRule::Paper,
            "dual_length" => ClampRule::DualLength,
            _ => ClampRule::MomentMatched,
        };
        let loop_closure = match ck.choice(
            &format!("{rk}.loop"),
            &ribbon.loop_closure,
            &["none", "orientable", "non_orientable"],
        )? {
            "orientable" => Some(LoopKind::Orientable),
            "non_orientable" => Some(LoopKind::NonOrientable),
            _ => None,
        };
        let base_pose = pose_from(
            ck.vec3(&format!("{rk}.base.position"), ribbon.base.position)?,
            ck.vec3(&format!("{rk}.base.rotation"), ribbon.base.rotation)?,
        );
        let base = match ck.choice(
            &format!("{rk}.base.mode"),
            &ribbon.base.mode,
            &["fixed", "floating", "driven"],
        )? {
            "fixed" => BaseMode::Prescribed {
                pose: base_pose,
                driven_by: None,
            },
            "floating" => BaseMode::Floating { initial: base_pose },
            _ => {
                let Some(name) = &ribbon.base.handle else {
                    return Err(ck.fail(
                        &format!("{rk}.base.handle"),
                        "a driven base names the handle that drives it",
                    ));
                };
                let h = specs
                    .iter()
                    .position(|(s, _)| &s.name == name)
                    .ok_or_else(|| {
                        ck.fail(
                            &format!("{rk}.base.handle"),
                            format!("no handle named `{name}`"),
                        )
                    })?;
                BaseMode::Prescribed {
                    pose: base_pose,
                    driven_by: Some(h),
                }
            }
        };
        if let Some(v) = &ribbon.base.handle {
            if ribbon.base.mode != "driven" {
                return Err(ck.fail(
                    &format!("{rk}.base.handle"),
                    format!("`{v}` is only used with mode: driven"),
                ));
            }
        }
        let initial = match ribbon.initial_shape.kind.as_deref().unwrap_or("flat") {
            "flat" => RibbonInitialShape::Flat,
            "ring" => RibbonInitialShape::Ring,
            "helix" => RibbonInitialShape::Helix {
                crease_direction: ck.finite(
                    &format!("{rk}.initial_shape.crease_direction"),
                    ribbon.initial_shape.crease_direction,
                )?,
                bending_angle: ck.finite(
                    &format!("{rk}.initial_shape.bending_angle"),
                    ribbon.initial_shape.bending_angle,
                )?,
            },
            "explicit" => {
                let n = ribbon.segments;
                let list = |name: &str, v: &Option<Vec<f64>>| -> Result<Vec<f64>, SceneError> {
                    let key = format!("{rk}.initial_shape.{name}");
                    let v = v.as_ref().ok_or_else(|| {
                        ck.fail(&key, "required for kind `explicit` (n - 1 values)")
                    })?;
                    if v.len() + 1 != n {
                        return Err(ck.fail(
                            &key,
                            format!(
                                "{} values for {n} segments: expected n - 1 = {}",
                                v.len(),
                                n.saturating_sub(1)
                            ),
                        ));
                    }
                    for (i, x) in v.iter().enumerate() {
                        ck.finite(&format!("{key}.{i}"), *x)?;
                    }
                    Ok(v.clone())
                };
                RibbonInitialShape::Explicit {
                    crease_direction: list(
                        "crease_directions",
                        &ribbon.initial_shape.crease_directions,
                    )?,
                    bending_angle: list("bending_angles", &ribbon.initial_shape.bending_angles)?,
                }
            }
            other => {
                return Err(ck.fail(
                    &format!("{rk}.initial_shape.kind"),
                    format!(
                        "unknown value `{other}`, expected one of: flat, helix, ring, explicit"
                    ),
                ))
            }
        };
        if initial_kind_is_not_explicit(ribbon) {
            for (name, present) in [
                (
                    "crease_directions",
                    ribbon.initial_shape.crease_directions.is_some(),
                ),
                (
                    "bending_angles",
                    ribbon.initial_shape.bending_angles.is_some(),
                ),
            ] {
                if present {
                    return Err(ck.fail(
                        &format!("{rk}.initial_shape.{name}"),
                        "only used with kind: explicit",
                    ));
                }
            }
        }
        let params = RibbonParams {
            length,
            width,
            segments: ribbon.segments,
            density,
            bending_stiffness: alpha,
            crease_regularizer: beta,
            clamp,
            gravity: gravity.into(),
            kinetic,
            base,
            loop_closure,
            crease_bound_factor: factor,
            solver,
        };
        if let RibbonInitialShape::Helix {
            crease_direction, ..
        } = initial
        {
            if crease_direction.abs() > params.crease_bound() {
                return Err(ck.fail(
                    &format!("{rk}.initial_shape.crease_direction"),
                    format!(
                        "|c| = {} exceeds the crease bound 0.95*2l/(wn) = {}",
                        crease_direction.abs(),
                        params.crease_bound()
                    ),
                ));
            }
        }
        Ok((params, initial))
    }

    fn solver_settings(&self, ck: &Check) -> Result<SolverSettings, SceneError> {
        let s = &self.solver;
        let kind = match ck.choice("solver.kind", &s.kind, &["gauss_newton", "lbfgsb", "chain"])? {
            "lbfgsb" => SolverKind::Lbfgsb,
            "chain" => SolverKind::Chain,
            _ => SolverKind::GaussNewton,
        };
        let tolerance = ck.positive("solver.tolerance", s.tolerance)?;
        if tolerance >= 1.0 {
            return Err(ck.fail(
                "solver.tolerance",
                format!("must be < 1 (a relative reduction), got {tolerance}"),
            ));
        }
        let max_iterations = s.max_iterations.unwrap_or(match kind {
            SolverKind::GaussNewton | SolverKind::Chain => 200,
            SolverKind::Lbfgsb => 5000,
        });
        if max_iterations == 0 {
            return Err(ck.fail("solver.max_iterations", "must be at least 1"));
        }
        if s.max_outer_iterations == 0 {
            return Err(ck.fail("solver.max_outer_iterations", "must be at least 1"));
        }
        Ok(SolverSettings {
            kind,
            tolerance,
            max_iterations,
            penalty: ck.positive("solver.penalty", s.penalty)?,
            outer_tolerance: ck.positive("solver.outer_tolerance", s.outer_tolerance)?,
            max_outer_iterations: s.max_outer_iterations,
            constraint_tolerance: ck
                .positive("solver.constraint_tolerance", s.constraint_tolerance)?,
            extrapolate: s.extrapolate,
        })
    }
}

impl SceneFile {
    /// The built scene: `world` with the file's name (or its stem), frame and outputs.
    pub(super) fn into_scene(
        self,
        file: &Path,
        duration: f64,
        world: World,
        handle_topics: Vec<String>,
    ) -> Scene {
        let name = self.name.clone().unwrap_or_else(|| {
            file.file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_else(|| "scene".into())
        });
        Scene {
            name,
            file: file.to_path_buf(),
            duration,
            world,
            frame_id: self.frame_id.clone(),
            handle_topics,
            outputs: Outputs {
                markers: self.outputs.markers,
                singular_points: self.outputs.singular_points,
                status: self.outputs.status,
                clock: self.outputs.clock,
                tf: self.outputs.tf,
                markers_rate: self.outputs.markers_rate,
            },
            handle_tf_frames: self.handles.iter().map(|h| h.tf_frame.clone()).collect(),
            source: self,
        }
    }
}
