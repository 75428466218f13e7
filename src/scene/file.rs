//! The scene file format. Every key: unit and default in the doc comment (and in the
//! commented YAML files under config/scenes/).

use std::path::Path;

use serde::{Deserialize, Serialize};

use super::camera_file::{build_cameras, CameraFile};
use super::check::Check;
use super::contact::{build_contact, ColliderFile, ContactFile};
use super::handle_file::{parse_handle, ForceFile, HandleFile};
use super::paper_file::{prepare_paper, PaperFile, PaperScene, PreparedPaper};
use super::ribbon_file::{ribbon_entries, ribbon_params, RibbonFile};
use super::robot_file::RobotCollidersFile;
use super::{Outputs, Scene, SceneError};
use crate::geometry::{Point2, Pose, Vector3};
use crate::ribbon::{
    ChainVariant, Imperfection, RibbonForce, RibbonInitialShape, RibbonParams, RibbonSim,
    SolverKind, SolverSettings,
};
use crate::sim::{HandleSpec, ObjectSim, World};

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
    /// [`PaperFile`].
    #[serde(default)]
    pub paper: Option<PaperFile>,
    /// Several ribbons (instead of `ribbon:`): each entry has a `name` and the keys of
    /// `ribbon:`. Optimized in parallel, then made collision-free together.
    #[serde(default)]
    pub ribbons: Vec<RibbonFile>,
    /// Rigid obstacles (see [`ColliderFile`]). Default none.
    #[serde(default)]
    pub colliders: Vec<ColliderFile>,
    /// Contact settings. A contact stage is built when the scene has colliders, robot
    /// colliders or this section (ribbon-ribbon and self contact only); otherwise
    /// nothing is built.
    #[serde(default)]
    pub contact: Option<ContactFile>,
    /// A robot's links as colliders, from its URDF on a topic and its TF frames (see
    /// [`RobotCollidersFile`]). Default none.
    #[serde(default)]
    pub robot_colliders: Option<RobotCollidersFile>,
    /// Handles (grippers).
    #[serde(default)]
    pub handles: Vec<HandleFile>,
    /// Constant point forces.
    #[serde(default)]
    pub forces: Vec<ForceFile>,
    /// What is published / recorded.
    #[serde(default)]
    pub outputs: OutputsFile,
    /// Simulated RGB-D cameras (see [`CameraFile`]). Default none.
    #[serde(default)]
    pub cameras: Vec<CameraFile>,
}

#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SolverFile {
    /// `chain` (ours, default: projected Newton with the Newton system solved along the
    /// chain in O(n)), `trust_region` (ours: a trust-region projected Newton method on
    /// the same O(n) chain model, the end crease held exactly), `interior_point` (ours:
    /// a primal-dual interior-point method on the same chain model), `gauss_newton` (the
    /// damped method on a dense matrix, O(n^3) per iteration: a baseline) or `lbfgsb`
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
    /// Issue 47 variants of `chain` (measured, not the default; the other kinds ignore
    /// them): the end crease held exactly by a slab projection.
    #[serde(default)]
    pub end_crease_exact: bool,
    /// `chain`: pivots of the sweep that are not positive definite get their
    /// eigenvalues' absolute values (saddle-free) instead of a larger global shift.
    #[serde(default)]
    pub saddle_free: bool,
    /// `chain`: a line-search cut leaves the damping as it is (instead of x10).
    #[serde(default)]
    pub cut_keeps_shift: bool,
}
fn d_constraint_tol() -> f64 {
    1e-6
}
fn d_solver_kind() -> String {
    "chain".into()
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
            end_crease_exact: false,
            saddle_free: false,
            cut_keeps_shift: false,
        }
    }
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
    /// `/handles/<handle>/state` (developable_sim/msg/GraspState, latched): whether each
    /// handle holds an object, which and where. Default true.
    #[serde(default = "d_true")]
    pub grasp_state: bool,
    /// `/<object>/<handle>/wrench` (geometry_msgs/msg/WrenchStamped, every step while
    /// the handle holds the object): the force and torque the object exerts on the
    /// gripper. Default true.
    #[serde(default = "d_true")]
    pub wrench: bool,
    /// `/<object>/points` (sensor_msgs/msg/PointCloud2, every step): the object's mesh
    /// vertices in the scene frame with their material coordinates, fields x y z u v
    /// (float32; m): the ground truth a tracker is scored against. Default false.
    #[serde(default)]
    pub points: bool,
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
            grasp_state: true,
            wrench: true,
            points: false,
            markers_rate: None,
        }
    }
}

/// A handle as parsed: its spec (initial target still to place) and the initial pose
/// the file gives, if any.
type ParsedHandle = (HandleSpec, Option<Pose>);

/// An object section of a scene file.
enum ObjectEntry<'a> {
    /// A ribbon (keys under `key`: `ribbon` or `ribbons.<i>`).
    Ribbon {
        key: String,
        file: &'a RibbonFile,
    },
    Paper(&'a PaperFile),
}

/// An object validated together with the handles on it, waiting for the scene's whole
/// handle list (a ribbon's handle terms, a sheet's held vertices are built from it).
enum Prepared {
    Ribbon(RibbonSetup, Vec<RibbonForce>),
    Paper(PreparedPaper),
}

impl SceneFile {
    /// Validate and build the scene: the world, then the cameras.
    pub fn build(self, file: &Path) -> Result<Scene, SceneError> {
        let cameras = build_cameras(&Check { file }, &self.cameras)?;
        let mut scene = self.build_world(file)?;
        scene.cameras = cameras;
        Ok(scene)
    }

    /// Validate and build the world: the objects (each kind validates its section and
    /// the handles on it, then is built with the scene's handle list), then the contact
    /// stage if the scene declares one.
    fn build_world(self, file: &Path) -> Result<Scene, SceneError> {
        let ck = Check { file };
        let (duration, dt, gravity) = self.time_and_frame(&ck)?;
        let solver = self.solver_settings(&ck)?;
        let entries = self.object_entries(&ck)?;
        let object_names: Vec<String> = entries.iter().map(|(n, _)| n.clone()).collect();
        let names = ObjectNames {
            ck: &ck,
            names: &object_names,
        };
        let (mut specs, topics) = self.parse_handles(&ck, &names)?;
        let mut prepared = Vec::new();
        for (index, (_, entry)) in entries.iter().enumerate() {
            prepared.push(match entry {
                ObjectEntry::Ribbon { key, file } => {
                    let setup = self.prepare_ribbon(&ck, (key, file), (gravity, solver), &specs)?;
                    let forces = self.ribbon_forces(&ck, &names, index)?;
                    place_on_ribbon(&setup, index, &mut specs);
                    Prepared::Ribbon(setup, forces)
                }
                ObjectEntry::Paper(paper) => {
                    let scene = self.paper_scene(paper);
                    Prepared::Paper(prepare_paper(scene, &ck, gravity, &mut specs)?)
                }
            });
        }
        self.check_forces(&names)?;
        let handles: Vec<HandleSpec> = specs.into_iter().map(|(spec, _)| spec).collect();
        let mut objects = Vec::new();
        for (index, (p, (name, entry))) in prepared.into_iter().zip(&entries).enumerate() {
            let sim: Box<dyn ObjectSim> = match (p, entry) {
                (Prepared::Ribbon(setup, forces), ObjectEntry::Ribbon { key, file }) => Box::new(
                    ribbon_sim(&ck, (key, file), setup, &forces, index, &handles)?,
                ),
                (Prepared::Paper(paper), _) => Box::new(paper.build(&ck, index, &handles)?),
                (Prepared::Ribbon(..), ObjectEntry::Paper(_)) => {
                    unreachable!("prepared in the entries' order")
                }
            };
            objects.push((name.clone(), sim));
        }
        let world = World::new(objects, handles, dt);
        let robot = self
            .robot_colliders
            .as_ref()
            .map(|r| r.check(&ck, file))
            .transpose()?;
        let sections = (&self.colliders[..], self.contact.as_ref(), robot.is_some());
        let world = build_contact(sections, &ck, file, world)?;
        let mut scene = self.into_scene(file, duration, world, topics);
        scene.robot = robot;
        Ok(scene)
    }

    /// The scene's objects in order: its ribbons (`ribbon:` or `ribbons:`) or one
    /// `paper:` sheet (a scene with both kinds is not supported yet).
    fn object_entries(&self, ck: &Check) -> Result<Vec<(String, ObjectEntry<'_>)>, SceneError> {
        if let Some(paper) = &self.paper {
            if self.ribbon.is_some() || !self.ribbons.is_empty() {
                return Err(ck.fail(
                    "paper",
                    "a scene holds either ribbons (`ribbon:` or `ribbons:`) or one `paper:` sheet, not both",
                ));
            }
            if self.robot_colliders.is_some() {
                return Err(ck.fail(
                    "robot_colliders",
                    "a robot's links collide with ribbons (the contact stage); a paper sheet does not take them",
                ));
            }
            return Ok(vec![("paper".into(), ObjectEntry::Paper(paper))]);
        }
        let (entries, names) = ribbon_entries(ck, &self.ribbon, &self.ribbons)?;
        Ok(names
            .into_iter()
            .zip(entries)
            .map(|(name, (key, file))| (name, ObjectEntry::Ribbon { key, file }))
            .collect())
    }

    /// Every handle's common keys (name, object, axes, orientation, trajectory, topic),
    /// each on the object it names; returns the specs with their explicit initial poses,
    /// and the topics (same order).
    fn parse_handles(
        &self,
        ck: &Check,
        names: &ObjectNames,
    ) -> Result<(Vec<ParsedHandle>, Vec<String>), SceneError> {
        let mut handle_names = std::collections::BTreeSet::new();
        let mut specs = Vec::new();
        let mut topics = Vec::new();
        for (i, h) in self.handles.iter().enumerate() {
            let key = format!("handles.{i}");
            let object = names.index(&format!("{key}.object"), &h.object)?;
            let (spec, initial, topic) = parse_handle(ck, &key, h, object, &mut handle_names)?;
            specs.push((spec, initial));
            topics.push(topic);
        }
        Ok((specs, topics))
    }

    /// A ribbon's parameters and initial shape, checked with the handles on it (their
    /// grasp points lie on its strip; only paper handles release).
    fn prepare_ribbon(
        &self,
        ck: &Check,
        (rk, ribbon): (&str, &RibbonFile),
        (gravity, solver): (Vector3, SolverSettings),
        specs: &[ParsedHandle],
    ) -> Result<RibbonSetup, SceneError> {
        let index = self.ribbon_index(rk);
        for (i, (spec, _)) in specs.iter().enumerate() {
            if spec.object != index {
                continue;
            }
            let key = format!("handles.{i}");
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
        }
        let (params, initial) = ribbon_params(ck, rk, ribbon, gravity, solver, specs)?;
        let imperfection = Imperfection {
            amplitude: ck.non_negative(
                &format!("{rk}.initial_shape.imperfection"),
                ribbon.initial_shape.imperfection,
            )?,
            seed: self.seed,
        };
        Ok(RibbonSetup {
            params,
            initial,
            imperfection,
        })
    }

    /// The index of the ribbon whose keys are under `rk` (`ribbon` or `ribbons.<i>`).
    fn ribbon_index(&self, rk: &str) -> usize {
        rk.strip_prefix("ribbons.")
            .and_then(|i| i.parse().ok())
            .unwrap_or(0)
    }

    /// Every force names an object of the scene.
    fn check_forces(&self, names: &ObjectNames) -> Result<(), SceneError> {
        for (i, f) in self.forces.iter().enumerate() {
            names.index(&format!("forces.{i}.object"), &f.object)?;
        }
        Ok(())
    }

    /// The duration and the time step h (s, h <= duration), gravity (m/s^2), and the
    /// frame and marker rate checked.
    fn time_and_frame(&self, ck: &Check) -> Result<(f64, f64, Vector3), SceneError> {
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
        Ok((duration, dt, gravity))
    }

    /// The point forces on ribbon `index`: material point (m) and force (N).
    fn ribbon_forces(
        &self,
        ck: &Check,
        names: &ObjectNames,
        index: usize,
    ) -> Result<Vec<RibbonForce>, SceneError> {
        let mut forces = Vec::new();
        for (i, f) in self.forces.iter().enumerate() {
            let key = format!("forces.{i}");
            if names.index(&format!("{key}.object"), &f.object)? != index {
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
        Ok(forces)
    }

    fn solver_settings(&self, ck: &Check) -> Result<SolverSettings, SceneError> {
        let s = &self.solver;
        let kind = match ck.choice(
            "solver.kind",
            &s.kind,
            &[
                "gauss_newton",
                "lbfgsb",
                "chain",
                "trust_region",
                "interior_point",
            ],
        )? {
            "lbfgsb" => SolverKind::Lbfgsb,
            "chain" => SolverKind::Chain,
            "trust_region" => SolverKind::TrustRegion,
            "interior_point" => SolverKind::InteriorPoint,
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
            SolverKind::GaussNewton
            | SolverKind::Chain
            | SolverKind::TrustRegion
            | SolverKind::InteriorPoint => 200,
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
            chain_variant: ChainVariant {
                end_crease_exact: s.end_crease_exact,
                saddle_free: s.saddle_free,
                cut_keeps_shift: s.cut_keeps_shift,
            },
        })
    }
}

impl SceneFile {
    /// What a paper object reads besides its `paper:` section.
    fn paper_scene<'a>(&'a self, paper: &'a PaperFile) -> PaperScene<'a> {
        PaperScene {
            paper,
            has_colliders: !self.colliders.is_empty(),
            has_contact: self.contact.is_some(),
            has_forces: !self.forces.is_empty(),
            seed: self.seed,
        }
    }

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
                grasp_state: self.outputs.grasp_state,
                wrench: self.outputs.wrench,
                points: self.outputs.points,
                markers_rate: self.outputs.markers_rate,
            },
            handle_tf_frames: self.handles.iter().map(|h| h.tf_frame.clone()).collect(),
            cameras: Vec::new(),
            robot: None,
            source: self,
        }
    }
}

/// The object names of a ribbon scene, for the `object:` keys of handles and forces.
struct ObjectNames<'a> {
    ck: &'a Check<'a>,
    names: &'a [String],
}

impl ObjectNames<'_> {
    /// The object `name` (under `key`) refers to: required when the scene has several.
    fn index(&self, key: &str, name: &Option<String>) -> Result<usize, SceneError> {
        let (ck, object_names) = (self.ck, self.names);
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
    }
}

/// One ribbon's validated parameters, initial shape and imperfection.
struct RibbonSetup {
    params: RibbonParams,
    initial: RibbonInitialShape,
    imperfection: Imperfection,
}

/// The handles on ribbon `index` without an initial pose get the grasp point where the
/// initial shape puts it (a probe of the ribbon, built without handles).
fn place_on_ribbon(setup: &RibbonSetup, index: usize, specs: &mut [ParsedHandle]) {
    let needs_probe = specs.iter().any(|(s, p)| s.object == index && p.is_none());
    let probe = needs_probe.then(|| {
        RibbonSim::new(
            setup.params.clone(),
            &setup.initial,
            setup.imperfection,
            &[],
            0,
            &[],
        )
    });
    for (spec, initial) in specs.iter_mut().filter(|(s, _)| s.object == index) {
        spec.trajectory.initial = match (initial, &probe) {
            (Some(pose), _) => *pose,
            (None, Some(probe)) => probe.material_pose(&spec.material_point),
            (None, None) => unreachable!("a probe is built when a handle needs one"),
        };
    }
}

/// Build ribbon `index` (keys under `rk`) with its forces and handles, and give it its
/// initial rigid velocity (rad/s about a centre m, m/s) if the file sets one.
fn ribbon_sim(
    ck: &Check,
    (rk, ribbon): (&str, &RibbonFile),
    setup: RibbonSetup,
    forces: &[RibbonForce],
    index: usize,
    handles: &[HandleSpec],
) -> Result<RibbonSim, SceneError> {
    let mut sim = RibbonSim::new(
        setup.params,
        &setup.initial,
        setup.imperfection,
        forces,
        index,
        handles,
    );
    if let Some(v) = &ribbon.initial_velocity {
        sim.set_rigid_velocity(
            ck.vec3(&format!("{rk}.initial_velocity.angular"), v.angular)?,
            ck.vec3(&format!("{rk}.initial_velocity.center"), v.center)?
                .into(),
            ck.vec3(&format!("{rk}.initial_velocity.linear"), v.linear)?,
        );
    }
    Ok(sim)
}
