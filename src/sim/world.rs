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
    /// Number of singular points after the step.
    pub singular_points: usize,
}

/// What a whole-world step did.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct StepReport {
    /// Simulation time after the step, s.
    pub time: f64,
    pub objects: Vec<ObjectStepReport>,
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
    pub fn kind(&self) -> ObjectKind {
        match self {
            SimObject::Ribbon(_) => ObjectKind::Ribbon,
            SimObject::Paper(_) => ObjectKind::Paper,
        }
    }
}

/// The phases of one paper frame (Schreck et al. fig. 3, table V): the FEM step, the
/// remeshing of S_G, the developable and isometric tracking.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Phase {
    Simulation,
    Remesh,
    Isometry,
}

/// Runs each phase of a step; an edge that measures wall time implements it (the core
/// never reads a clock).
pub trait PhaseClock {
    /// Run `work`, the phase `phase` of object `object`.
    fn time(&mut self, object: usize, phase: Phase, work: &mut dyn FnMut());
}

/// A [`PhaseClock`] that only runs the work.
#[derive(Clone, Copy, Debug, Default)]
pub struct NoClock;

impl PhaseClock for NoClock {
    fn time(&mut self, _object: usize, _phase: Phase, work: &mut dyn FnMut()) {
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
}

impl World {
    /// A world at t = 0. `dt` is the time step, s.
    pub fn new(objects: Vec<(String, SimObject)>, handles: Vec<HandleSpec>, dt: f64) -> World {
        let (names, objects): (Vec<_>, Vec<_>) = objects.into_iter().unzip();
        World {
            names,
            initial_objects: objects.clone(),
            objects,
            handles,
            dt,
            time: 0.0,
            steps: 0,
        }
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
        self.step_with_clock(targets, &mut NoClock)
    }

    /// [`World::step`] with the phases of each object run inside `clock` (objects
    /// without phases run as one [`Phase::Simulation`]).
    pub fn step_with_clock(
        &mut self,
        targets: &[Option<Pose>],
        clock: &mut dyn PhaseClock,
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
        let reports = self
            .objects
            .iter_mut()
            .enumerate()
            .map(|(index, object)| match object {
                SimObject::Ribbon(r) => {
                    let mut report = ObjectStepReport::default();
                    clock.time(index, Phase::Simulation, &mut || {
                        report = r.step(dt, t_next, index, handles, &resolved)
                    });
                    report
                }
                SimObject::Paper(p) => {
                    p.step_with_clock(dt, t_next, index, handles, &resolved, clock)
                }
            })
            .collect();
        self.time = t_next;
        self.steps += 1;
        StepReport {
            time: self.time,
            objects: reports,
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
    }
}
