//! Grasp and release at run time: the world's handles as an editable set.
//!
//! A handle is a gripper that always has a target; what it holds changes between steps.
//! A grasp holds a material point of an object where it is at that moment, relative to
//! the gripper's current target (no snap: the attachment's `gripper_from_grasp` is
//! fixed then), as a new attachment (`generation` + 1); a release lets go. Each change
//! tells the objects concerned ([`ObjectSim::handles_changed`]), which rebuild their
//! handle terms. Scripted grasps and releases ([`HandleSpec::script`]) go through the
//! same functions at the start of the step they fall in, while nobody drives the handle.

use crate::geometry::{Point2, Point3, Pose};

use super::handle::{GraspError, HandleSpec, Hold, ScriptedChange};
use super::world::World;

/// Where a grasp closes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum GraspAt {
    /// This point of the object's flat pattern, m.
    Material(Point2),
    /// The graspable point nearest this world point (m), refused when it is farther
    /// than `max_distance` (m).
    Nearest { point: Point3, max_distance: f64 },
}

/// What a grasp did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Grasped {
    /// The object held.
    pub object: usize,
    /// The point held, m, flat pattern.
    pub material_point: Point2,
    /// From the requested world point to it, m (0 for a grasp by material point).
    pub distance: f64,
    /// False when the handle already held exactly this (nothing changed).
    pub changed: bool,
}

impl World {
    /// Handle `handle` grasps object `object` at `at`, held as `hold` (None: as the
    /// scene declared the handle). The point is held where it is now relative to the
    /// handle's current target. Grasping what the handle already holds the same way
    /// changes nothing (`changed` false); grasping elsewhere moves the hold.
    pub fn grasp(
        &mut self,
        handle: usize,
        object: usize,
        at: GraspAt,
        hold: Option<Hold>,
    ) -> Result<Grasped, GraspError> {
        let spec = self
            .handles
            .get(handle)
            .ok_or(GraspError::UnknownHandle(handle))?;
        let target = self.last_targets[handle];
        let sim = self
            .objects
            .get(object)
            .ok_or(GraspError::UnknownObject(object))?;
        let (material_point, distance) = match at {
            GraspAt::Material(m) => (sim.graspable(&m).map_err(GraspError::NotGraspable)?, 0.0),
            GraspAt::Nearest {
                point,
                max_distance,
            } => {
                let s = sim.nearest_graspable(&point).ok_or(GraspError::NoSurface)?;
                if !(s.distance <= max_distance) {
                    return Err(GraspError::TooFar {
                        distance: s.distance,
                        max: max_distance,
                    });
                }
                (s.material, s.distance)
            }
        };
        let (axes, orientation) = match hold {
            Some(h) => h.parts(),
            None => {
                let scene = &self.initial_handles[handle];
                (scene.position_axes, scene.orientation)
            }
        };
        let same = spec.attached
            && spec.object == object
            && spec.material_point == material_point
            && spec.position_axes == axes
            && spec.orientation == orientation;
        let grasped = Grasped {
            object,
            material_point,
            distance,
            changed: !same,
        };
        if same {
            return Ok(grasped);
        }
        // gripper_from_grasp, so that the point is held where it is now
        let world_from_grasp = sim
            .grasp_pose(&material_point)
            .ok_or(GraspError::NoSurface)?;
        let offset: Pose = target.inverse() * world_from_grasp;
        let before = spec.holds_object();
        let spec = &mut self.handles[handle];
        spec.object = object;
        spec.material_point = material_point;
        spec.position_axes = axes;
        spec.orientation = orientation;
        spec.attached = true;
        spec.grasp_offset = Some(offset);
        spec.generation += 1;
        self.handles_changed(before.into_iter().chain([object]));
        Ok(grasped)
    }

    /// Handle `handle` lets go. Returns whether it held something (false: nothing
    /// changed).
    pub fn release(&mut self, handle: usize) -> Result<bool, GraspError> {
        let spec = self
            .handles
            .get(handle)
            .ok_or(GraspError::UnknownHandle(handle))?;
        if !spec.attached {
            return Ok(false);
        }
        if self.objects[spec.object].drives_base(handle) {
            return Err(GraspError::DrivesBase(handle));
        }
        let object = spec.object;
        self.handles[handle].attached = false;
        self.handles_changed([object]);
        Ok(true)
    }

    /// Tell each of `objects` (indices, repeats allowed) that the handles changed.
    fn handles_changed(&mut self, objects: impl IntoIterator<Item = usize>) {
        let mut told: Vec<usize> = Vec::new();
        for o in objects {
            if told.contains(&o) {
                continue;
            }
            told.push(o);
            self.objects[o].handles_changed(o, &self.handles);
        }
    }

    /// The scripted grasps and releases due at the start of the step ending at `t_next`
    /// (s), for the handles that follow their script in it (`targets[h]` None). An event
    /// is due when the step ends at its time or later, within half a step: the time
    /// accumulates dt, so 460 steps of 0.01 s end at 4.599999999999937 s, and an event
    /// at 4.6 s belongs to that step, not the next.
    /// Returns what each did, (handle, grasp or release, outcome) for the report.
    pub(super) fn apply_script(
        &mut self,
        t_next: f64,
        targets: &[Option<Pose>],
    ) -> Vec<ScriptedChange> {
        let mut out = Vec::new();
        for h in 0..self.handles.len() {
            while let Some(event) = self.handles[h].script.get(self.script_next[h]).copied() {
                if t_next < event.time - 0.5 * self.dt() {
                    break;
                }
                self.script_next[h] += 1;
                if targets.get(h).copied().flatten().is_some() {
                    continue; // driven from outside: the script's grasps do not act
                }
                let result = if event.grasp {
                    let spec = &self.handles[h];
                    let at = GraspAt::Nearest {
                        point: Point3::from(self.last_targets[h].translation.vector),
                        max_distance: spec.grasp_radius,
                    };
                    self.grasp(h, spec.object, at, None).map(|g| g.changed)
                } else {
                    self.release(h)
                };
                out.push(ScriptedChange {
                    handle: h,
                    grasp: event.grasp,
                    result,
                });
            }
        }
        out
    }
}

impl HandleSpec {
    /// The object the handle holds now, if any.
    fn holds_object(&self) -> Option<usize> {
        self.attached.then_some(self.object)
    }
}
