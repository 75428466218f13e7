use std::sync::Arc;

use rayon::prelude::*;

use crate::contact::barrier::PairSource;
use crate::contact::{
    BarrierSettings, BodyInput, CellMesh, Collider, ContactEnv, ContactError, ContactReport,
    ContactStage, OtherMesh,
};
use crate::geometry::{Point3, Pose, SurfaceMesh};

use super::handle::{HandleSpec, ScriptedChange};
use super::object::{
    pose_is_finite, NoClock, ObjectSim, ObjectStepReport, Phase, PhaseClock, SingularPoint,
    StepContext, Wrench,
};

/// What a whole-world step did.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct StepReport {
    /// Simulation time after the step, s.
    pub time: f64,
    pub objects: Vec<ObjectStepReport>,
    /// The contact stage, when the scene has one.
    pub contact: Option<ContactStepReport>,
    /// The scripted grasps and releases applied at the start of the step.
    pub scripted: Vec<ScriptedChange>,
}

/// What the contact stage did in a step (its wall time is measured by the caller's
/// [`PhaseClock`], see [`World::step_with_clock`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ContactStepReport {
    pub report: ContactReport,
    /// With barrier contact: bodies stepped side by side with another
    /// (docs/contact_barrier.md, "Several ribbons"), and of those, bodies put back and
    /// stepped again after their class because they came within reach of another.
    pub side_by_side: usize,
    pub stepped_again: usize,
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
    /// The stage's first colliders, the scene's; kinematic colliders follow them.
    scene_colliders: usize,
}

/// All objects of a scene, their handles and the clock.
#[derive(Clone, Debug)]
pub struct World {
    names: Vec<String>,
    pub(super) objects: Vec<Box<dyn ObjectSim>>,
    initial_objects: Vec<Box<dyn ObjectSim>>,
    /// The handles now (grasps and releases edit them, `grasp`).
    pub(super) handles: Vec<HandleSpec>,
    /// The handles as the scene declared them (a reset restores them).
    pub(super) initial_handles: Vec<HandleSpec>,
    /// Per handle: its next scripted grasp or release.
    pub(super) script_next: Vec<usize>,
    dt: f64,
    time: f64,
    steps: u64,
    contact: Option<ContactState>,
    /// Contact inside the steps (`contact.method: barrier`) instead of the stage.
    barrier: Option<BarrierState>,
    /// Carrier poses at the end of the last step (the start of the next one): the
    /// handles' targets, then the kinematic bodies' poses.
    pub(super) last_targets: Vec<Pose>,
    /// The kinematic bodies' poses at the end of the next step
    /// ([`World::set_kinematic_pose`]).
    kinematic_next: Vec<Pose>,
}

/// Contact inside the objects' steps (docs/contact_barrier.md): the settings, the
/// colliders, and the contact bodies' mesh cells (for the other bodies' steps).
#[derive(Clone, Debug)]
pub(super) struct BarrierState {
    pub(super) settings: BarrierSettings,
    pub(super) colliders: Vec<Collider>,
    /// Per object: its mesh cells when it is a contact body.
    pub(super) cells: Vec<Option<Arc<CellMesh>>>,
    /// The first colliders, the scene's; kinematic colliders follow them.
    scene_colliders: usize,
    /// The guess of which bodies may meet scales their last motions by this (1: as
    /// designed); whether the check after the steps runs (tests only change them).
    pub(super) guess_scale: f64,
    pub(super) check_classes: bool,
    /// Whether a body that waited for one stepped again steps again too (tests only
    /// turn it off).
    pub(super) repeat_dependents: bool,
    /// Whether a body held back by where a later one started steps again once that one
    /// has moved off (tests only turn it off).
    pub(super) repeat_held_back: bool,
    /// Per object: its Newton iterations in the last step (which body a free thread
    /// takes first; never what a body computes).
    pub(super) last_iterations: Vec<usize>,
}

impl World {
    /// A world at t = 0. `dt` is the time step, s.
    pub fn new(
        objects: Vec<(String, Box<dyn ObjectSim>)>,
        handles: Vec<HandleSpec>,
        dt: f64,
    ) -> World {
        let (names, objects): (Vec<_>, Vec<_>) = objects.into_iter().unzip();
        let last_targets = handles.iter().map(|h| h.trajectory.pose_at(0.0)).collect();
        World {
            names,
            initial_objects: objects.clone(),
            objects,
            initial_handles: handles.clone(),
            script_next: vec![0; handles.len()],
            handles,
            dt,
            time: 0.0,
            steps: 0,
            contact: None,
            barrier: None,
            last_targets,
            kinematic_next: Vec::new(),
        }
    }

    /// Contact inside every contact body's step (`contact.method: barrier`) against
    /// `colliders`, the other bodies and itself, instead of a contact stage after the
    /// steps. Bodies are then stepped one after the other (block Gauss-Seidel; the order
    /// alternates between steps).
    pub fn with_barrier(mut self, settings: BarrierSettings, colliders: Vec<Collider>) -> World {
        let cells = self
            .objects
            .iter()
            .map(|o| {
                o.contact_body().map(|_| {
                    let mesh = o.mesh();
                    Arc::new(CellMesh::new(&mesh.triangles, mesh.vertices.len()))
                })
            })
            .collect();
        self.barrier = Some(BarrierState {
            settings,
            scene_colliders: colliders.len(),
            colliders,
            cells,
            guess_scale: 1.0,
            check_classes: true,
            repeat_dependents: true,
            repeat_held_back: true,
            last_iterations: Vec::new(),
        });
        self
    }

    /// Test only: whether a body that waited for one put back and stepped again is
    /// stepped again too (docs/contact_barrier.md, "Several ribbons"; off: the negative
    /// control of the repeat's rule).
    #[cfg(any(test, feature = "test-hooks"))]
    pub fn set_repeat_dependents_hook(&mut self, on: bool) {
        if let Some(b) = self.barrier.as_mut() {
            b.repeat_dependents = on;
        }
    }

    /// Test only: whether a body held back by where a later body started steps again
    /// after that body moved off (docs/contact_barrier.md, "Several ribbons"; off: the
    /// negative control of that rule).
    #[cfg(any(test, feature = "test-hooks"))]
    pub fn set_repeat_held_back_hook(&mut self, on: bool) {
        if let Some(b) = self.barrier.as_mut() {
            b.repeat_held_back = on;
        }
    }

    /// Test only: the side-by-side steps' guess of which bodies may meet with their
    /// last motions scaled by `guess_scale`, and the check after each class on or off
    /// (docs/contact_barrier.md, "Several ribbons").
    #[cfg(any(test, feature = "test-hooks"))]
    pub fn set_side_by_side_hooks(&mut self, guess_scale: f64, check: bool) {
        if let Some(b) = self.barrier.as_mut() {
            b.guess_scale = guess_scale;
            b.check_classes = check;
        }
    }

    /// With barrier contact: the smallest gap (m, beyond the thickness) of any contact
    /// body against the colliders (at the current targets) and the other bodies: the
    /// gap, that body's index and what the pair is against (another body as its object
    /// index); None without barrier contact or without bodies.
    pub fn barrier_start_gap(&mut self) -> Option<(f64, usize, PairSource)> {
        let barrier = self.barrier.as_ref()?;
        let poses: Vec<Pose> = barrier
            .colliders
            .iter()
            .map(|c| c.world_pose(&self.last_targets))
            .collect();
        let mut worst: Option<(f64, usize, PairSource)> = None;
        let count = self.objects.len();
        for index in 0..count {
            let (before, rest) = self.objects.split_at_mut(index);
            let (object, after) = rest.split_first_mut().expect("index < len");
            let others: Vec<OtherMesh> = before
                .iter()
                .enumerate()
                .chain(after.iter().enumerate().map(|(j, o)| (index + 1 + j, o)))
                .filter_map(|(j, o)| {
                    barrier.cells[j].as_ref().map(|cells| OtherMesh {
                        vertices: &o.mesh().vertices,
                        start: &o.mesh().vertices,
                        cells,
                    })
                })
                .collect();
            let env = ContactEnv {
                settings: barrier.settings,
                colliders: &barrier.colliders,
                poses0: &poses,
                poses1: &poses,
                others: &others,
            };
            let bodies: Vec<usize> = (0..count)
                .filter(|&j| j != index && barrier.cells[j].is_some())
                .collect();
            if let Some(body) = object.contact_body_mut() {
                let (g, source) = body.barrier_gap(&env);
                let source = match source {
                    PairSource::Body(b) => PairSource::Body(bodies[b]),
                    s => s,
                };
                if worst.is_none_or(|(w, _, _)| g < w) {
                    worst = Some((g, index, source));
                }
            }
        }
        worst
    }

    /// The colliders of the scene, whichever contact method runs them (empty without
    /// contact).
    pub fn colliders(&self) -> &[Collider] {
        match (&self.contact, &self.barrier) {
            (Some(c), _) => c.stage.colliders(),
            (None, Some(b)) => &b.colliders,
            (None, None) => &[],
        }
    }

    /// Whether the scene has contact (a stage after the steps or a barrier in them).
    pub fn has_contact(&self) -> bool {
        self.contact.is_some() || self.barrier.is_some()
    }

    /// The barrier contact's settings and colliders, if the world has it.
    pub fn barrier_contact(&self) -> Option<(&BarrierSettings, &[Collider])> {
        self.barrier
            .as_ref()
            .map(|b| (&b.settings, b.colliders.as_slice()))
    }

    /// Add a contact stage whose bodies are the objects of this world that offer one
    /// ([`ObjectSim::contact_body`]), in object order (build it from their
    /// [`super::ContactBody::contact_topology`]).
    pub fn with_contact(mut self, stage: ContactStage) -> World {
        let objects: Vec<usize> = (0..self.objects.len())
            .filter(|&o| self.objects[o].contact_body().is_some())
            .collect();
        assert_eq!(
            stage.body_count(),
            objects.len(),
            "one contact body per object that offers one"
        );
        let empty = vec![Vec::new(); objects.len()];
        self.contact = Some(ContactState {
            scene_colliders: stage.colliders().len(),
            stage,
            objects,
            previous: empty.clone(),
            predicted: empty.clone(),
            corrected: empty,
        });
        self
    }

    /// Replace the kinematic colliders: rigid bodies the caller moves by setting their
    /// poses before each step (a robot's links following TF). `poses[b]` is body b's
    /// `world_from_body` now (bodies start at rest); `colliders[i].attached_to =
    /// Some(b)` puts collider i on body b, its `pose` relative to the body. The
    /// contact stage (or the barrier's list) is rebuilt with the scene's colliders
    /// first, then these (the world's carrier index of body b is `handles().len() + b`).
    /// Errors: no contact, a collider on no body or a body out of range, a pose that is
    /// not finite, a stage that cannot be built, or, with barrier contact, a collider
    /// that would start overlapping a ribbon (the barrier cannot start from an overlap)
    /// (the world is then unchanged).
    pub fn set_kinematic_colliders(
        &mut self,
        colliders: Vec<Collider>,
        poses: Vec<Pose>,
    ) -> Result<(), ContactError> {
        let handles = self.handles.len();
        let scene: &[Collider] = match (&self.contact, &self.barrier) {
            (Some(c), _) => &c.stage.colliders()[..c.scene_colliders],
            (None, Some(b)) => &b.colliders[..b.scene_colliders],
            (None, None) => {
                return Err(ContactError::Invalid(
                    "kinematic colliders need a contact stage or barrier contact (a `contact:` section)"
                        .into(),
                ))
            }
        };
        if let Some(b) = poses.iter().position(|p| !pose_is_finite(p)) {
            return Err(ContactError::Invalid(format!(
                "kinematic body {b}: its pose is not finite"
            )));
        }
        let mut all = scene.to_vec();
        for (i, mut c) in colliders.into_iter().enumerate() {
            match c.attached_to {
                Some(b) if b < poses.len() => c.attached_to = Some(handles + b),
                _ => {
                    return Err(ContactError::Invalid(format!(
                        "kinematic collider {i}: on body {:?}, the world has {} bodies",
                        c.attached_to,
                        poses.len()
                    )))
                }
            }
            all.push(c);
        }
        if let Some(contact) = self.contact.as_mut() {
            contact.stage = contact.stage.with_colliders(all)?;
        } else {
            self.set_barrier_colliders(all, &poses)?;
        }
        self.last_targets.truncate(handles);
        self.last_targets.extend_from_slice(&poses);
        self.kinematic_next = poses;
        Ok(())
    }

    /// The barrier's colliders replaced by `all` with the kinematic bodies at `poses`,
    /// unless a ribbon would then start overlapping one (the world unchanged).
    fn set_barrier_colliders(
        &mut self,
        all: Vec<Collider>,
        poses: &[Pose],
    ) -> Result<(), ContactError> {
        let handles = self.handles.len();
        let barrier = self.barrier.as_mut().expect("called with barrier contact");
        let kept = std::mem::replace(&mut barrier.colliders, all);
        let kept_targets = self.last_targets.split_off(handles);
        self.last_targets.extend_from_slice(poses);
        let start = self.barrier_start_gap();
        self.last_targets.truncate(handles);
        self.last_targets.extend(kept_targets);
        match start {
            Some((gap, o, PairSource::Collider(k))) if gap <= 0.0 => {
                let barrier = self.barrier.as_mut().expect("barrier contact");
                barrier.colliders = kept;
                Err(ContactError::Invalid(format!(
                    "collider {k} would start {:.4} m closer than the thickness to `{}`: contact.method barrier cannot start from an overlap",
                    -gap, self.names[o]
                )))
            }
            _ => Ok(()),
        }
    }

    /// Kinematic body `body`'s pose (`world_from_body`) at the end of the next step:
    /// over that step its colliders move there from where they are, and friction takes
    /// their velocity from the two poses. A pose that is not finite is ignored (the
    /// body stays), as is a body out of range.
    pub fn set_kinematic_pose(&mut self, body: usize, pose: Pose) {
        if let Some(next) = self.kinematic_next.get_mut(body) {
            if pose_is_finite(&pose) {
                *next = pose;
            }
        }
    }

    /// The kinematic bodies' poses (`world_from_body`) at the end of the last step.
    pub fn kinematic_poses(&self) -> &[Pose] {
        &self.last_targets[self.handles.len()..]
    }

    /// The contact stage, if the scene has one.
    pub fn contact_stage(&self) -> Option<&ContactStage> {
        self.contact.as_ref().map(|c| &c.stage)
    }

    /// Carrier poses at the end of the last step: the handle targets
    /// (`world_from_gripper`, one per handle, in order), then the kinematic bodies'
    /// poses ([`World::set_kinematic_colliders`]). Colliders index it
    /// ([`Collider::world_pose`]).
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
    /// The handles now (what each holds changes with grasps and releases).
    pub fn handles(&self) -> &[HandleSpec] {
        &self.handles
    }
    /// The handles as the scene declared them.
    pub fn scene_handles(&self) -> &[HandleSpec] {
        &self.initial_handles
    }
    pub fn object_names(&self) -> &[String] {
        &self.names
    }
    pub fn objects(&self) -> &[Box<dyn ObjectSim>] {
        &self.objects
    }
    /// Mutable access for measurements (gradient timing); stepping goes through
    /// [`World::step`].
    pub fn objects_mut(&mut self) -> &mut [Box<dyn ObjectSim>] {
        &mut self.objects
    }
    /// Object `object`.
    pub fn object(&self, object: usize) -> &dyn ObjectSim {
        self.objects[object].as_ref()
    }
    /// Object `object` as the simulator `T`, if it is one.
    pub fn object_as<T: ObjectSim + 'static>(&self, object: usize) -> Option<&T> {
        self.objects.get(object)?.downcast_ref()
    }
    pub fn object_as_mut<T: ObjectSim + 'static>(&mut self, object: usize) -> Option<&mut T> {
        self.objects.get_mut(object)?.downcast_mut()
    }

    /// The scripted `world_from_gripper` of handle `handle` at time `t` (s).
    pub fn scripted_target(&self, handle: usize, t: f64) -> Pose {
        self.handles[handle].trajectory.pose_at(t)
    }

    /// Advance every object by `dt`. `targets[i]`, when `Some`, overrides the scripted
    /// target of handle `i` (`world_from_gripper` at the end of the step); missing entries
    /// follow the script. A target that is not finite is ignored: the handle keeps its
    /// last target (for the objects and for the colliders it carries).
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
        let scripted = self.apply_script(t_next, targets);
        let resolved: Vec<Pose> = (0..self.handles.len())
            .map(|i| {
                let target = targets
                    .get(i)
                    .copied()
                    .flatten()
                    .unwrap_or_else(|| self.scripted_target(i, t_next));
                if pose_is_finite(&target) {
                    target
                } else {
                    self.last_targets[i]
                }
            })
            .collect();
        let n_handles = self.handles.len();
        // the carriers at the end of the step: the handles, then the kinematic bodies
        let mut resolved = resolved;
        resolved.extend_from_slice(&self.kinematic_next);
        let dt = self.dt;
        let handles = &self.handles;
        if let Some(barrier) = &mut self.barrier {
            let (reports, contact) = barrier.step(
                &mut self.objects,
                self.steps,
                (&self.last_targets, &resolved),
                (dt, t_next, handles),
                clock,
            );
            self.last_targets = resolved;
            self.time = t_next;
            self.steps += 1;
            return StepReport {
                time: self.time,
                objects: reports,
                contact: Some(contact),
                scripted,
            };
        }
        // Every object's optimization in parallel: each is independent and sequential
        // inside, so the results do not depend on the thread count.
        let mut reports: Vec<ObjectStepReport> = self
            .objects
            .par_iter_mut()
            .enumerate()
            .map(|(index, object)| {
                object.step(&StepContext {
                    dt,
                    time: t_next,
                    index,
                    handles,
                    targets: &resolved[..n_handles],
                    clock,
                    contact: None,
                })
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
            scripted,
        }
    }

    /// What handle `handle` feels from the object it holds, from the last step (None:
    /// it holds nothing, or no step was taken since it grasped).
    pub fn handle_wrench(&self, handle: usize) -> Option<Wrench> {
        let spec = self.handles.get(handle)?;
        if !spec.attached {
            return None;
        }
        self.objects.get(spec.object)?.handle_wrench(handle)
    }

    /// The current surface mesh of object `object`.
    pub fn mesh(&self, object: usize) -> &SurfaceMesh {
        self.objects[object].mesh()
    }

    /// The current singular points of object `object`.
    pub fn singular_points(&self, object: usize) -> &[SingularPoint] {
        self.objects[object].singular_points()
    }

    /// Back to the state at t = 0.
    pub fn reset(&mut self) {
        self.objects = self.initial_objects.clone();
        self.handles = self.initial_handles.clone();
        self.script_next.iter_mut().for_each(|k| *k = 0);
        self.time = 0.0;
        self.steps = 0;
        // the kinematic bodies stay where they are (a robot is not reset with the world)
        let kinematic = self.last_targets.split_off(self.handles.len());
        self.last_targets = self
            .handles
            .iter()
            .map(|h| h.trajectory.pose_at(0.0))
            .chain(kinematic)
            .collect();
    }
}

impl ContactState {
    /// The contact stage on all contact bodies together (Pan et al. algorithm 1, line
    /// 5); the corrected meshes become the bodies' X^{n+1}.
    fn run(
        &mut self,
        objects: &mut [Box<dyn ObjectSim>],
        reports: &mut [ObjectStepReport],
        targets0: &[Pose],
        targets1: &[Pose],
        dt: f64,
    ) -> ContactStepReport {
        for (b, &o) in self.objects.iter().enumerate() {
            let object = &objects[o];
            if let Some(body) = object.contact_body() {
                body.previous_mesh_vertices(&mut self.previous[b]);
            }
            self.predicted[b].clear();
            self.predicted[b].extend_from_slice(&object.mesh().vertices);
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
            let object = &mut objects[o];
            if let Some(body) = object.contact_body_mut() {
                body.apply_contact_correction(&self.corrected[b], dt);
            }
            reports[o].isometry_error = object.mesh().isometry_error();
            reports[o].energies = object.energies();
        }
        ContactStepReport {
            report,
            ..Default::default()
        }
    }
}
