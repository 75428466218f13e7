//! The session: a scene, its handle inputs and counters, and the outputs it produces.
//! Commands change it ([`Session::apply`], the one way in); each new state is turned
//! into a [`Frame`] of encoded messages ([`Session::frame`]).

use std::time::Instant;

use crate::geometry::Pose;
use crate::scene::Scene;
use crate::sim::{GraspAt, GraspError, Grasped, StepReport};
use crate::wire::cdr::CdrError;
use crate::wire::msgs::{PoseStamped, Time};

use super::camera::Cameras;
use super::command::Command;
use super::input::{HandleInput, InputPolicy, Rejection};
use super::outputs::{Frame, OutputTable};
use super::params::ParamValue;
use super::produce::{stamp_at, Counters, Produce};
use super::robot::RobotLinks;
use super::style::MarkerStyle;

/// What applying a command did.
#[derive(Clone, Debug, PartialEq)]
pub enum Applied {
    /// A pose became its handle's target, or the input filter rejected it.
    Input(Result<(), Rejection>),
    /// A failed TF lookup was counted (the handle keeps its target).
    TfLookupFailed,
    /// A new state: after a step, or the initial state after a reset.
    NewState,
    /// The same state with a new stamp (the time origin moved).
    TimeOrigin,
    /// A robot description or the links' poses were taken (Err: why the description or
    /// the links could not be used; the robot stays as it was).
    Robot(Result<(), String>),
    /// Paused or resumed; `changed`: the flag differs from before.
    Paused { changed: bool },
    /// A parameter took effect in the session, or concerns only the node (its pacing,
    /// its TF buffer, the markers' rate): `in_session` says which.
    Parameter { in_session: bool },
    /// A grasp happened (`changed` false: the handle already held exactly that), or was
    /// refused.
    Grasp(Result<Grasped, GraspError>),
    /// A release happened (true), found the handle open (false), or was refused.
    Release(Result<bool, GraspError>),
    /// Camera `camera` captured the frame of tick `frame` (None: no tick of it was due,
    /// nothing captured).
    Captured { camera: usize, frame: Option<u64> },
}

/// Which rows a frame makes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Content {
    /// Every row of the table.
    All,
    /// The statuses and the rows that changed (the same state published again: paused,
    /// a handle grasped or released).
    Statuses,
}

/// A scene with its handle inputs, counters and outputs.
pub struct Session {
    pub scene: Scene,
    pub policy: InputPolicy,
    pub style: MarkerStyle,
    /// The input topic each handle's status reports (`/tf` for a TF-driven handle).
    pub handle_topics: Vec<String>,
    /// The outputs this session produces.
    pub table: OutputTable,
    pub counters: Counters,
    pub paused: bool,
    /// ns on the stamping clock where simulated time 0 is: 0 when the node owns time;
    /// under use_sim_time set by [`Command::SetTimeOrigin`] and [`Command::ResetAt`].
    pub origin_ns: i64,
    inputs: Vec<HandleInput>,
    /// The robot's links in the world (`robot_colliders:`).
    robot: RobotLinks,
    /// Per handle: when it last grasped or released (simulated time; zero: the scene's
    /// own hold) and whether that is not in a frame yet.
    grasp_changed: Vec<Time>,
    grasp_dirty: Vec<bool>,
    /// The step that made the current state and its wall time, s (None: step 0).
    last_step: Option<(StepReport, f64)>,
    targets: Vec<Option<Pose>>,
    /// The cameras' due ticks and captured frames.
    pub cameras: Cameras,
}

impl Session {
    pub fn new(
        scene: Scene,
        policy: InputPolicy,
        handle_topics: Vec<String>,
        table: OutputTable,
    ) -> Session {
        let handles = scene.world.handles().len();
        let objects = scene.world.objects().len();
        let mut cameras = Cameras::new(&scene, &table.rows);
        cameras.on_state(&scene);
        Session {
            scene,
            policy,
            style: MarkerStyle::default(),
            handle_topics,
            table,
            counters: Counters {
                unconverged_steps: vec![0; objects],
                rejected_steps: vec![0; objects],
                ..Counters::default()
            },
            paused: false,
            origin_ns: 0,
            inputs: vec![HandleInput::default(); handles],
            robot: RobotLinks::default(),
            grasp_changed: vec![Time::default(); handles],
            grasp_dirty: vec![false; handles],
            last_step: None,
            targets: vec![None; handles],
            cameras,
        }
    }

    /// Apply one command (see [`Command`]).
    pub fn apply(&mut self, command: &Command) -> Applied {
        match command {
            Command::Pose {
                handle,
                pose,
                arrival_ns,
                ..
            } => Applied::Input(self.offer(*handle, pose, *arrival_ns)),
            Command::TfLookupFailed { handle, .. } => {
                if let Some(input) = self.inputs.get_mut(*handle) {
                    input.rejected_tf_lookup += 1;
                }
                Applied::TfLookupFailed
            }
            Command::RobotDescription { loaded, .. } => {
                let friction = self.robot_friction();
                let world = &mut self.scene.world;
                Applied::Robot(self.robot.set_description(loaded, world, friction))
            }
            Command::LinkPoses { transforms, .. } => {
                let friction = self.robot_friction();
                let world = &mut self.scene.world;
                Applied::Robot(self.robot.set_poses(transforms, world, friction))
            }
            Command::Step => {
                self.step();
                Applied::NewState
            }
            Command::Reset => {
                self.reset();
                Applied::NewState
            }
            Command::ResetAt {
                origin_ns,
                clock_jump,
            } => {
                self.reset();
                self.origin_ns = *origin_ns;
                self.counters.clock_resets += u32::from(*clock_jump);
                Applied::NewState
            }
            Command::SetTimeOrigin { origin_ns } => {
                self.origin_ns = *origin_ns;
                Applied::TimeOrigin
            }
            Command::SetPaused(p) => {
                let changed = self.paused != *p;
                self.paused = *p;
                Applied::Paused { changed }
            }
            Command::SetParameter { name, value } => self.set_parameter(name, value),
            Command::Grasp {
                handle,
                object,
                material_point,
                hold,
            } => {
                let at = GraspAt::Material(*material_point);
                let r = self.scene.world.grasp(*handle, *object, at, *hold);
                if matches!(r, Ok(Grasped { changed: true, .. })) {
                    self.note_grasp_change(*handle);
                }
                Applied::Grasp(r)
            }
            Command::Release { handle } => {
                let r = self.scene.world.release(*handle);
                if r == Ok(true) {
                    self.note_grasp_change(*handle);
                }
                Applied::Release(r)
            }
            Command::Capture {
                camera,
                world_from_optical,
            } => Applied::Captured {
                camera: *camera,
                frame: {
                    let stamp = self.stamp();
                    self.cameras
                        .capture(&self.scene, *camera, world_from_optical, stamp)
                },
            },
        }
    }

    /// Handle `h` grasped or released now: its state goes out with the next frame.
    fn note_grasp_change(&mut self, h: usize) {
        self.grasp_changed[h] = self.stamp();
        self.grasp_dirty[h] = true;
    }

    /// The messages a command's outcome publishes: a new state's whole frame; a pause
    /// toggled, a grasp or a release: the statuses again (subscribers see `paused`,
    /// the handles' hold) and what changed; otherwise none.
    pub fn frame_after(&mut self, applied: &Applied) -> Option<Result<Frame, CdrError>> {
        match applied {
            Applied::NewState | Applied::TimeOrigin => Some(self.frame(Content::All)),
            Applied::Paused { changed: true }
            | Applied::Grasp(Ok(Grasped { changed: true, .. }))
            | Applied::Release(Ok(true)) => Some(self.frame(Content::Statuses)),
            _ => None,
        }
    }

    /// The robot's links in the world (`robot_colliders:`).
    pub fn robot(&self) -> &RobotLinks {
        &self.robot
    }

    /// Coulomb μ of the robot's links (`robot_colliders.friction`).
    fn robot_friction(&self) -> f64 {
        self.scene.robot.as_ref().map_or(0.0, |r| r.friction)
    }

    /// The parameters that change the session; the others concern the node only.
    fn set_parameter(&mut self, name: &str, value: &ParamValue) -> Applied {
        let (b, x) = match value {
            ParamValue::Bool(b) => (*b, 0.0),
            ParamValue::Double(x) => (false, *x),
            _ => (false, 0.0),
        };
        match name {
            "accept_empty_frame_id" => self.policy.accept_empty_frame_id = b,
            "max_stamp_lead" => self.policy.max_stamp_lead = x,
            "marker.line_width" => self.style.line_width = x,
            "marker.sphere_diameter" => self.style.sphere_diameter = x,
            _ => return Applied::Parameter { in_session: false },
        }
        Applied::Parameter { in_session: true }
    }

    /// Offer a pose received for handle `handle` at `received_ns` (wall clock, ns since
    /// the Unix epoch) to its input filter.
    fn offer(
        &mut self,
        handle: usize,
        msg: &PoseStamped,
        received_ns: u64,
    ) -> Result<(), Rejection> {
        self.inputs[handle].offer(&self.policy, msg, received_ns)
    }

    /// Advance the world one step with the newest targets. Returns the report and the
    /// wall time of the step, s (also kept for the frame).
    pub fn step(&mut self) -> (StepReport, f64) {
        for (t, input) in self.targets.iter_mut().zip(&self.inputs) {
            *t = input.target;
        }
        let start = Instant::now();
        let from = self.stamp();
        let report = self.scene.world.step(&self.targets);
        let elapsed = start.elapsed().as_secs_f64();
        // the script's grasps and releases happened at the start of the step
        for change in report.scripted.iter().filter(|c| c.result == Ok(true)) {
            self.grasp_changed[change.handle] = from;
            self.grasp_dirty[change.handle] = true;
        }
        for (i, o) in report.objects.iter().enumerate() {
            self.counters.unconverged_steps[i] += u64::from(!o.converged);
            self.counters.rejected_steps[i] += u64::from(o.kept_previous_state);
        }
        self.last_step = Some((report.clone(), elapsed));
        self.counters.camera_frames_skipped += self.cameras.on_state(&self.scene);
        (report, elapsed)
    }

    /// Back to t = 0: the world's initial state; handles follow the script until a new
    /// pose arrives (stamps are accepted afresh); counters are kept.
    fn reset(&mut self) {
        self.scene.world.reset();
        self.counters.camera_frames_skipped += self.cameras.restart();
        self.counters.camera_frames_skipped += self.cameras.on_state(&self.scene);
        for i in &mut self.inputs {
            i.clear_target();
        }
        self.counters.episode += 1;
        self.last_step = None;
        self.grasp_changed
            .iter_mut()
            .for_each(|t| *t = Time::default());
    }

    /// The step that made the current state and its wall time, s (None: step 0).
    pub fn last_step(&self) -> Option<&(StepReport, f64)> {
        self.last_step.as_ref()
    }

    /// The stamp of the current state: its simulated time after the origin.
    pub fn stamp(&self) -> Time {
        stamp_at(self.origin_ns, self.scene.world.time())
    }

    /// The messages of the current state.
    pub fn frame(&mut self, content: Content) -> Result<Frame, CdrError> {
        let (report, duration) = match &self.last_step {
            Some((r, d)) => (Some(r), *d),
            None => (None, 0.0),
        };
        let frame = self.make_frame(&self.scene, report, duration, content)?;
        self.grasp_dirty.iter_mut().for_each(|d| *d = false);
        Ok(frame)
    }

    /// [`Session::frame`] of another copy of this session's scene (`run --record`
    /// reads the runner's scene instead of cloning its world into the session each
    /// step): the world's state from `scene` and `report` (None: step 0) with its wall
    /// time `step_duration` (s), the inputs and counters from `self`.
    pub fn frame_of(
        &mut self,
        scene: &Scene,
        report: Option<&StepReport>,
        step_duration: f64,
        content: Content,
    ) -> Result<Frame, CdrError> {
        let frame = self.make_frame(scene, report, step_duration, content)?;
        self.grasp_dirty.iter_mut().for_each(|d| *d = false);
        Ok(frame)
    }

    /// A new state of another copy of this session's scene (`run --record`, see
    /// [`Session::frame_of`]): its camera ticks fall due.
    pub fn note_state_of(&mut self, scene: &Scene) {
        self.counters.camera_frames_skipped += self.cameras.on_state(scene);
    }

    /// [`Command::Capture`] applied to another copy of this session's scene (see
    /// [`Session::note_state_of`]); returns the tick captured.
    pub fn capture_of(
        &mut self,
        scene: &Scene,
        camera: usize,
        world_from_optical: &Pose,
    ) -> Option<u64> {
        let stamp = stamp_at(self.origin_ns, scene.world.time());
        self.cameras
            .capture(scene, camera, world_from_optical, stamp)
    }

    /// The frame of the state of `scene` (see [`Session::frame_of`]).
    fn make_frame(
        &self,
        scene: &Scene,
        report: Option<&StepReport>,
        step_duration: f64,
        content: Content,
    ) -> Result<Frame, CdrError> {
        let p = Produce {
            scene,
            style: &self.style,
            inputs: &self.inputs,
            handle_topics: &self.handle_topics,
            counters: &self.counters,
            paused: self.paused,
            report,
            step_duration,
            grasp_changed: &self.grasp_changed,
            grasp_dirty: &self.grasp_dirty,
            origin_ns: self.origin_ns,
        };
        let mut messages = Vec::with_capacity(self.table.rows.len());
        for row in &self.table.rows {
            let wanted = match content {
                Content::All => true,
                Content::Statuses => row.kind.name == "status" || row.kind.on_change,
            };
            let m = if wanted {
                row.kind.producer.produce(&p, row.scope).transpose()?
            } else {
                None
            };
            messages.push(m);
        }
        Ok(Frame {
            stamp: p.stamp(),
            messages,
        })
    }
}
