//! The contract every simulated object meets ([`ObjectSim`]) and the types it speaks in.
//!
//! A leaf of the core: it knows geometry and the contact stage's body description, not
//! the world, the ribbon or the paper. The [`super::World`] steps its objects through
//! this trait and never asks what they are; a simulator (ribbon, paper, the next one)
//! implements it in its own module.

use std::any::Any;
use std::fmt::Debug;

use crate::contact::BodyTopology;
use crate::geometry::{EdgeStrain, Point2, Point3, Pose, SurfaceMesh, SurfacePoint, Vector3};

use super::handle::HandleSpec;

/// A point where the surface is not smooth (rulings meet), reported with a stable id.
#[derive(Clone, Debug, PartialEq)]
pub struct SingularPoint {
    /// Stable while the point persists (ribbons: derived from the crease pair; paper:
    /// assigned at creation and never reused).
    pub id: u64,
    /// World position, m.
    pub position: Point3,
    /// Flat-pattern position, m.
    pub material: Point2,
}

/// Energies of one object after a step, J.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Energies {
    /// Kinetic energy 1/2 v^T M v of the new velocities.
    pub kinetic: f64,
    /// Bending (and crease regularizer for ribbons; stretching for paper FEM).
    pub elastic: f64,
    /// Gravitational potential -m g.x (zero at the world origin).
    pub gravity: f64,
    /// Handle terms (normal guiding, constraint penalties) and external forces.
    pub external: f64,
}

impl Energies {
    pub fn total(&self) -> f64 {
        self.kinetic + self.elastic + self.gravity + self.external
    }
}

/// The force and torque a handle and the object it holds exert on each other, from
/// the last step's constraint reaction.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Wrench {
    /// The force the object exerts on the gripper, N, world frame.
    pub force: Vector3,
    /// The torque the object exerts on the gripper about the grasp point, N m, world
    /// frame.
    pub torque: Vector3,
}

/// What one object's step did.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ObjectStepReport {
    /// Inner solver iterations summed over augmented-Lagrangian rounds.
    pub iterations: u32,
    /// Augmented-Lagrangian (outer) rounds.
    pub outer_iterations: u32,
    /// False when the solver stopped on its iteration limit; the state is still the best
    /// finite one found (or the previous one, see `kept_previous_state`).
    pub converged: bool,
    /// True when the new state was rejected (not finite) and the previous one kept.
    pub kept_previous_state: bool,
    pub energies: Energies,
    /// Max over mesh edges of |length - material length| / material length.
    pub isometry_error: f64,
    /// Largest handle / loop constraint violation, m.
    pub constraint_violation: f64,
    /// The world handle whose grasp point is that far from its target (None when the
    /// largest violation is a loop closure's, or the object does not say).
    pub violation_handle: Option<usize>,
    /// Number of singular points after the step.
    pub singular_points: usize,
    /// Upper bound on the work the handles and point forces did on the object during
    /// the step, J: per held point |F| |Δx| (F the constraint force after the step, Δx
    /// the target's displacement over the step), per normal guide K |n - n_target|
    /// |Δn_target|, per point force |F . Δx|. Gravity is not included: its potential is
    /// part of [`Energies`]. Implicit Euler is dissipative, so the total energy cannot
    /// rise by more than the sum of these over the steps (the stress suite checks it).
    /// With contact inside the step, moving colliders' work is included.
    pub work_bound: f64,
    /// What contact inside the step did (`contact.method: barrier`), if it ran.
    pub contact: Option<crate::contact::barrier::BarrierOutcome>,
}

/// The phases of a world step: each object's optimization (a ribbon's implicit step,
/// a paper frame's FEM step, Schreck et al. fig. 3, table V), the paper's remeshing of
/// S_G and its developable and isometric tracking, then the world's contact stage.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Phase {
    Simulation,
    Remesh,
    Isometry,
    Contact,
}

/// Runs each phase of a step; an edge that measures wall time implements it (the core
/// never reads a clock). Objects step in parallel, so a clock is shared between threads
/// (`&self`, `Sync`): a timer sums the phases over objects.
pub trait PhaseClock: Sync {
    /// Run `work`, the phase `phase` of object `object` (`None` for the world's stages).
    fn time(&self, object: Option<usize>, phase: Phase, work: &mut dyn FnMut());
}

/// A [`PhaseClock`] that only runs the work.
#[derive(Clone, Copy, Debug, Default)]
pub struct NoClock;

impl PhaseClock for NoClock {
    fn time(&self, _object: Option<usize>, _phase: Phase, work: &mut dyn FnMut()) {
        work()
    }
}

/// What an object's step is given.
#[derive(Clone, Copy)]
pub struct StepContext<'a> {
    /// Time step, s.
    pub dt: f64,
    /// Simulation time at the end of the step, s.
    pub time: f64,
    /// This object's index in the world (handles name their object by it).
    pub index: usize,
    /// Every handle of the world; those with `object == index` act on this object.
    pub handles: &'a [HandleSpec],
    /// Target `world_from_gripper` of each world handle at the end of the step. Always
    /// finite: the world replaces a non-finite target by the handle's last one.
    pub targets: &'a [Pose],
    /// Runs each phase of the step (an edge times them).
    pub clock: &'a dyn PhaseClock,
    /// Contact inside the step (`contact.method: barrier`): the colliders and the
    /// other bodies this object must not cross; None without it.
    pub contact: Option<&'a crate::contact::ContactEnv<'a>>,
}

/// Edge strains of an object's physical mesh in its last frame (Schreck et al. table
/// IV, V: compression; stretch as well), for objects that measure them (the paper).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CompressionStats {
    /// Compression (table IV) and stretch of the mesh's edges, %.
    pub edges: EdgeStrain,
    /// Triangles of the physical mesh (N_t).
    pub triangles: usize,
}

/// An object as a body of the world's contact stage (Pan et al. sec. 5.2): the stage
/// sees its mesh before and after the step and hands back a collision-free mesh.
pub trait ContactBody {
    /// The contact mesh (which mesh vertices weld, triangles, stations).
    fn contact_topology(&self) -> BodyTopology;
    /// Mesh vertices of the state before the last step (X^n), m, in mesh order.
    fn previous_mesh_vertices(&self, out: &mut Vec<Point3>);
    /// Take the collision-free mesh `corrected` (mesh order, m) as the state after the
    /// last step of `dt` s.
    fn apply_contact_correction(&mut self, corrected: &[Point3], dt: f64);
    /// With contact inside the step: the smallest gap (m, beyond the thickness) of the
    /// current state against `env` and what it is against; +∞ when nothing is within
    /// the barrier's reach.
    fn barrier_gap(
        &mut self,
        _env: &crate::contact::ContactEnv,
    ) -> (f64, crate::contact::barrier::PairSource) {
        (f64::INFINITY, Default::default())
    }
    /// With contact inside the step: boxes (m) covering every position the mesh took
    /// during the last step, the path between its iterates included; empty when the
    /// body does not record them (then it never steps beside another body).
    fn swept_boxes(&self) -> &[(crate::geometry::Vector3, crate::geometry::Vector3)] {
        &[]
    }
}

/// One simulated object: what the world, the edges (statistics, runner, report, ROS
/// session) and the contact stage need of it. `Clone` through [`ObjectSim::clone_box`]
/// (the world keeps its initial objects for a reset).
pub trait ObjectSim: AsAny + Send + Sync + Debug {
    /// The scene-file section that declares this kind of object (`ribbon`, `paper`).
    fn kind(&self) -> &'static str;
    /// The solver that steps it, as `--stats` names it (`gauss_newton`, `lbfgsb`,
    /// `paper_newton`).
    fn solver_name(&self) -> &'static str;
    /// Advance by `ctx.dt` to `ctx.time`.
    fn step(&mut self, ctx: &StepContext<'_>) -> ObjectStepReport;
    /// The current surface mesh (world positions, pattern coordinates).
    fn mesh(&self) -> &SurfaceMesh;
    /// The current singular points.
    fn singular_points(&self) -> &[SingularPoint];
    /// Energies of the current state, J.
    fn energies(&self) -> Energies;
    /// `world_from_material_point`: the frame at pattern point `m` (m) in the current
    /// state (the default target of a handle grasping there).
    fn material_pose(&self, m: &Point2) -> Pose;
    /// The world's handles changed at a step boundary (a grasp or a release): rebuild
    /// what they hold on this object, object `index` of the world (those with
    /// [`HandleSpec::holds`]`(index)` act on it from the next step on).
    fn handles_changed(&mut self, index: usize, handles: &[HandleSpec]);
    /// The material point a handle grasping at `m` (m, flat pattern) holds: `m` itself
    /// where the object can be held there, or why it cannot (off the pattern; a sheet of
    /// paper is held on its boundary, Schreck et al. sec. 3.3).
    fn graspable(&self, m: &Point2) -> Result<Point2, String>;
    /// `world_from_material_point` at pattern point `m` (m) in the current state: the
    /// frame a grasp there holds where it is. By default read off the mesh
    /// ([`SurfaceMesh::frame_at`]); None off the pattern.
    fn grasp_pose(&self, m: &Point2) -> Option<Pose> {
        self.mesh().frame_at(*m)
    }
    /// The point a handle can grasp nearest the world point `p` (m): on the surface by
    /// default.
    fn nearest_graspable(&self, p: &Point3) -> Option<SurfacePoint> {
        self.mesh().nearest_surface_point(p)
    }
    /// Whether world handle `handle` drives this object's prescribed base (it cannot
    /// let go: the base would have no pose).
    fn drives_base(&self, _handle: usize) -> bool {
        false
    }
    /// What the object exerts on world handle `handle` in the last step's final state
    /// (None when the handle holds nothing on this object, or before the first step).
    fn handle_wrench(&self, _handle: usize) -> Option<Wrench> {
        None
    }
    /// Named reduced coordinates of the current state (ribbons: `crease_direction`,
    /// `bending_angle`), in the order the statistics write them; none by default.
    fn coordinates(&self) -> Vec<(&'static str, &[f64])> {
        Vec::new()
    }
    /// One evaluation of the step objective and its gradient at the current state (the
    /// cost of one solver iteration, for `--stats`' `gradient_us`); returns the
    /// objective, J, or None for an object without one.
    fn evaluate_gradient(&mut self, _gradient: &mut Vec<f64>) -> Option<f64> {
        None
    }
    /// The compression of the last frame, for objects that measure it.
    fn compression_stats(&self) -> Option<CompressionStats> {
        None
    }
    /// The object as a contact body, when it takes part in the contact stage.
    fn contact_body(&self) -> Option<&dyn ContactBody> {
        None
    }
    fn contact_body_mut(&mut self) -> Option<&mut dyn ContactBody> {
        None
    }
    /// A boxed copy.
    fn clone_box(&self) -> Box<dyn ObjectSim>;
}

/// Access to the concrete simulator behind a `dyn ObjectSim` (tests, benchmarks, the
/// report's per-kind sweeps); implemented for every `'static` type.
pub trait AsAny {
    fn as_any(&self) -> &dyn Any;
    fn as_any_mut(&mut self) -> &mut dyn Any;
}

impl<T: Any> AsAny for T {
    fn as_any(&self) -> &dyn Any {
        self
    }
    fn as_any_mut(&mut self) -> &mut dyn Any {
        self
    }
}

impl dyn ObjectSim {
    /// The object as a `T`, if it is one.
    pub fn downcast_ref<T: ObjectSim + 'static>(&self) -> Option<&T> {
        self.as_any().downcast_ref()
    }
    pub fn downcast_mut<T: ObjectSim + 'static>(&mut self) -> Option<&mut T> {
        self.as_any_mut().downcast_mut()
    }
}

impl Clone for Box<dyn ObjectSim> {
    fn clone(&self) -> Self {
        self.clone_box()
    }
}

/// Whether every component of `pose` is finite.
pub fn pose_is_finite(pose: &Pose) -> bool {
    pose.translation.vector.iter().all(|x| x.is_finite())
        && pose.rotation.coords.iter().all(|x| x.is_finite())
}
