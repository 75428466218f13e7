use rayon::prelude::*;

use crate::contact::{BodyInput, ContactReport, ContactStage};
use crate::geometry::{Point2, Point3, Pose, SurfaceMesh};
use crate::paper::PaperSim;
use crate::ribbon::RibbonSim;

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
    pub work_bound: f64,
}

/// What a whole-world step did.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct StepReport {
    /// Simulation time after the step, s.
    pub time: f64,
    pub objects: Vec<ObjectStepReport>,
    /// The contact stage, when the scene has one.
    pub contact: Option<ContactStepReport>,
}

/// What the contact stage did in a step (its wall time is measured by the caller's
/// [`PhaseClock`], see [`World::step_with_clock`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ContactStepReport {
    pub report: ContactReport,
}

/// The contact stage of a world and its per-step buffers.
#[derive(Clone, Debug)]
struct ContactState {
    stage: ContactStage,
    /// Object index of each contact body.
    objects: Vec<usize>,
    previous: Vec<Vec<Point3>>,
    predicted: Vec<Vec<Point3>>,
    corrected: Vec<Vec<Point3>>,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ObjectKind {
    Ribbon,
    Paper,
}

/// One simulated object.
#[derive(Clone, Debug)]
pub enum SimObject {
    Ribbon(Box<RibbonSim>),
    /// A sheet of paper (Schreck et al.).
    Paper(Box<PaperSim>),
}

impl SimObject {
    /// The object's energies in its current state, J.
    pub fn energies(&self) -> Energies {
        match self {
            SimObject::Ribbon(r) => r.energies(),
            SimObject::Paper(p) => p.energies(),
        }
    }

    pub fn kind(&self) -> ObjectKind {
        match self {
            SimObject::Ribbon(_) => ObjectKind::Ribbon,
            SimObject::Paper(_) => ObjectKind::Paper,
        }
    }
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

/// All objects of a scene, their handles and the clock.
#[derive(Clone, Debug)]
pub struct World {
    names: Vec<String>,
    objects: Vec<SimObject>,
    initial_objects: Vec<SimObject>,
    handles: Vec<HandleSpec>,
    dt: f64,
    time: f64,
    steps: u64,
    contact: Option<ContactState>,
    /// Handle targets at the end of the last step (the start of the next one).
    last_targets: Vec<Pose>,
}

impl World {
    /// A world at t = 0. `dt` is the time step, s.
    pub fn new(objects: Vec<(String, SimObject)>, handles: Vec<HandleSpec>, dt: f64) -> World {
        let (names, objects): (Vec<_>, Vec<_>) = objects.into_iter().unzip();
        let last_targets = handles.iter().map(|h| h.trajectory.pose_at(0.0)).collect();
        World {
            names,
            initial_objects: objects.clone(),
            objects,
            handles,
            dt,
            time: 0.0,
            steps: 0,
            contact: None,
            last_targets,
        }
    }

    /// Add a contact stage whose bodies are the ribbons of this world, in object order
    /// (build it from [`RibbonSim::contact_topology`]).
    pub fn with_contact(mut self, stage: ContactStage) -> World {
        let objects: Vec<usize> = (0..self.objects.len()).collect();
        assert_eq!(
            stage.body_count(),
            objects.len(),
            "one contact body per ribbon"
        );
        let empty = vec![Vec::new(); objects.len()];
        self.contact = Some(ContactState {
            stage,
            objects,
            previous: empty.clone(),
            predicted: empty.clone(),
            corrected: empty,
        });
        self
    }

    /// The contact stage, if the scene has one.
    pub fn contact_stage(&self) -> Option<&ContactStage> {
        self.contact.as_ref().map(|c| &c.stage)
    }

    /// Handle targets (`world_from_gripper`) at the end of the last step.
    pub fn current_targets(&self) -> &[Pose] {
        &self.last_targets
    }

    /// Simulation time, s.
    pub fn time(&self) -> f64 {
        self.time
    }
    /// Time step, s.
    pub fn dt(&self) -> f64 {
        self.dt
    }
    /// Steps taken since start or reset.
    pub fn steps_taken(&self) -> u64 {
        self.steps
    }
    pub fn handles(&self) -> &[HandleSpec] {
        &self.handles
    }
    pub fn object_names(&self) -> &[String] {
        &self.names
    }
    pub fn objects(&self) -> &[SimObject] {
        &self.objects
    }
    /// Mutable access for measurements (gradient timing); stepping goes through
    /// [`World::step`].
    pub fn objects_mut(&mut self) -> &mut [SimObject] {
        &mut self.objects
    }

    /// The scripted `world_from_gripper` of handle `handle` at time `t` (s).
    pub fn scripted_target(&self, handle: usize, t: f64) -> Pose {
        self.handles[handle].trajectory.pose_at(t)
    }

    /// Advance every object by `dt`. `targets[i]`, when `Some`, overrides the scripted
    /// target of handle `i` (`world_from_gripper` at the end of the step); missing entries
    /// follow the script.
    pub fn step(&mut self, targets: &[Option<Pose>]) -> StepReport {
        self.step_with_clock(targets, &NoClock)
    }

    /// [`World::step`] with every phase run inside `clock` (a ribbon's step is one
    /// [`Phase::Simulation`]; only the phases the scene has run).
    pub fn step_with_clock(
        &mut self,
        targets: &[Option<Pose>],
        clock: &dyn PhaseClock,
    ) -> StepReport {
        let t_next = self.time + self.dt;
        let resolved: Vec<Pose> = (0..self.handles.len())
            .map(|i| {
                targets
                    .get(i)
                    .copied()
                    .flatten()
                    .unwrap_or_else(|| self.scripted_target(i, t_next))
            })
            .collect();
        let dt = self.dt;
        let handles = &self.handles;
        // Every object's optimization in parallel: each is independent and sequential
        // inside, so the results do not depend on the thread count.
        let mut reports: Vec<ObjectStepReport> = self
            .objects
            .par_iter_mut()
            .enumerate()
            .map(|(index, object)| match object {
                SimObject::Ribbon(r) => {
                    let mut report = ObjectStepReport::default();
                    clock.time(Some(index), Phase::Simulation, &mut || {
                        report = r.step(dt, t_next, index, handles, &resolved)
                    });
                    report
                }
                SimObject::Paper(p) => {
                    p.step_with_clock(dt, t_next, index, handles, &resolved, clock)
                }
            })
            .collect();
        let objects = &mut self.objects;
        let last_targets = &self.last_targets;
        let contact = self.contact.as_mut().map(|c| {
            let mut report = None;
            clock.time(None, Phase::Contact, &mut || {
                report = Some(c.run(objects, &mut reports, last_targets, &resolved, dt))
            });
            report.expect("the clock runs the contact stage")
        });
        self.last_targets = resolved;
        self.time = t_next;
        self.steps += 1;
        StepReport {
            time: self.time,
            objects: reports,
            contact,
        }
    }

    /// The current surface mesh of object `object`.
    pub fn mesh(&self, object: usize) -> &SurfaceMesh {
        match &self.objects[object] {
            SimObject::Ribbon(r) => r.mesh(),
            SimObject::Paper(p) => p.mesh(),
        }
    }

    /// The current singular points of object `object`.
    pub fn singular_points(&self, object: usize) -> &[SingularPoint] {
        match &self.objects[object] {
            SimObject::Ribbon(r) => r.singular_points(),
            SimObject::Paper(p) => p.singular_points(),
        }
    }

    /// Back to the state at t = 0.
    pub fn reset(&mut self) {
        self.objects = self.initial_objects.clone();
        self.time = 0.0;
        self.steps = 0;
        self.last_targets = self
            .handles
            .iter()
            .map(|h| h.trajectory.pose_at(0.0))
            .collect();
    }
}

impl ContactState {
    /// The contact stage on all ribbon meshes together (Pan et al. algorithm 1, line 5);
    /// the corrected meshes become the ribbons' X^{n+1}.
    fn run(
        &mut self,
        objects: &mut [SimObject],
        reports: &mut [ObjectStepReport],
        targets0: &[Pose],
        targets1: &[Pose],
        dt: f64,
    ) -> ContactStepReport {
        for (b, &o) in self.objects.iter().enumerate() {
            match &objects[o] {
                SimObject::Ribbon(r) => {
                    r.previous_mesh_vertices(&mut self.previous[b]);
                    self.predicted[b].clear();
                    self.predicted[b].extend_from_slice(&r.mesh().vertices);
                }
                SimObject::Paper(_) => unreachable!(
                    "contact bodies are ribbons: the scene builder rejects a contact stage with a paper sheet"
                ),
            }
        }
        let inputs: Vec<BodyInput> = self
            .previous
            .iter()
            .zip(&self.predicted)
            .map(|(p, q)| BodyInput {
                previous: p,
                predicted: q,
            })
            .collect();
        let report = self
            .stage
            .resolve(&inputs, targets0, targets1, &mut self.corrected);
        for (b, &o) in self.objects.iter().enumerate() {
            match &mut objects[o] {
                SimObject::Ribbon(r) => {
                    r.apply_contact_correction(&self.corrected[b], dt);
                    reports[o].isometry_error = r.mesh().isometry_error();
                    reports[o].energies = r.energies();
                }
                SimObject::Paper(_) => unreachable!(
                    "contact bodies are ribbons: the scene builder rejects a contact stage with a paper sheet"
                ),
            }
        }
        ContactStepReport { report }
    }
}
