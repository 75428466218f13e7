//! The grasp services' requests made into commands: names resolved, the nearest
//! graspable point found, refusals worded. A refusal changes nothing, so it is not a
//! command; what is recorded and replayed is the resolved grasp.

use crate::geometry::{Point2, Point3};
use crate::sim::{Hold, OrientationMode, World};
use crate::wire::msgs::GraspRequest;

use super::command::Command;

/// A grasp resolved from a request: the command, and how far the point grasped is
/// from the world point asked for (m; 0 by material point).
#[derive(Clone, Debug, PartialEq)]
pub struct Resolved {
    pub command: Command,
    pub distance: f64,
}

/// The handle named `name`, or why not.
pub fn handle_index(world: &World, name: &str) -> Result<usize, String> {
    world
        .handles()
        .iter()
        .position(|h| h.name == name)
        .ok_or_else(|| {
            let names: Vec<&str> = world.handles().iter().map(|h| h.name.as_str()).collect();
            format!("no handle `{name}` (handles: {})", names.join(", "))
        })
}

/// The object named `name` (empty: the scene's only object), or why not.
fn object_index(world: &World, name: &str) -> Result<usize, String> {
    let names = world.object_names();
    if name.is_empty() {
        return match names.len() {
            1 => Ok(0),
            _ => Err(format!(
                "the scene has several objects: name one ({})",
                names.join(", ")
            )),
        };
    }
    names
        .iter()
        .position(|n| n == name)
        .ok_or_else(|| format!("no object `{name}` (objects: {})", names.join(", ")))
}

/// The hold a request names: `position`, `normal` (with the handle's scene stiffness,
/// or 1 J), `full`; empty: as the scene declared the handle.
fn hold_of(world: &World, handle: usize, name: &str) -> Result<Option<Hold>, String> {
    Ok(match name {
        "" => None,
        "position" => Some(Hold::Position),
        "normal" => {
            let stiffness = match world.scene_handles()[handle].orientation {
                OrientationMode::Normal { stiffness } => stiffness,
                _ => DEFAULT_NORMAL_STIFFNESS,
            };
            Some(Hold::Normal { stiffness })
        }
        "full" => Some(Hold::Full),
        other => {
            return Err(format!(
                "unknown hold `{other}`: position, normal, full, or empty for the handle's own"
            ))
        }
    })
}

/// Normal-guiding stiffness K of a `normal` hold for a handle the scene gives none, J
/// (the scene files' default).
const DEFAULT_NORMAL_STIFFNESS: f64 = 1.0;

/// A `~/grasp` request as a command, or why it is refused.
pub fn resolve_grasp(world: &World, req: &GraspRequest) -> Result<Resolved, String> {
    let handle = handle_index(world, &req.handle)?;
    let object = object_index(world, &req.object)?;
    let hold = hold_of(world, handle, &req.hold)?;
    let sim = world.object(object);
    let (material_point, distance) = if req.by_material_point {
        let m = Point2::new(req.material_point[0], req.material_point[1]);
        (sim.graspable(&m)?, 0.0)
    } else {
        let p = &req.world_point;
        let at = Point3::new(p.x, p.y, p.z);
        if !at.coords.iter().all(|x| x.is_finite()) || !(req.max_distance >= 0.0) {
            return Err("world_point must be finite and max_distance >= 0 (m)".into());
        }
        let found = sim
            .nearest_graspable(&at)
            .ok_or("the object has no surface to grasp")?;
        if !(found.distance <= req.max_distance) {
            return Err(format!(
                "the nearest graspable point of `{}` is {:.4} m from world_point, farther than \
                 max_distance {:.4} m",
                world.object_names()[object],
                found.distance,
                req.max_distance
            ));
        }
        (found.material, found.distance)
    };
    Ok(Resolved {
        command: Command::Grasp {
            handle,
            object,
            material_point,
            hold,
        },
        distance,
    })
}

/// A gripper's `/handles/<handle>/grasp` close: the surface point of the handle's
/// object nearest its current target, within its `grasp_radius`, held as the scene
/// declared the handle.
pub fn resolve_close(world: &World, handle: usize) -> Result<Resolved, String> {
    let spec = &world.handles()[handle];
    let target = world.current_targets()[handle].translation.vector;
    let req = GraspRequest {
        handle: spec.name.clone(),
        object: world.object_names()[spec.object].clone(),
        by_material_point: false,
        world_point: crate::wire::convert::point(&Point3::from(target)),
        max_distance: spec.grasp_radius,
        ..GraspRequest::default()
    };
    resolve_grasp(world, &req)
}
