//! A robot's links as kinematic colliders of the world (`robot_colliders:`): the
//! description in force, which links are in the world and where each was last seen.
//!
//! Two commands change it: a description that arrived ([`super::Command::RobotDescription`])
//! and the links' poses the node looked up in TF for a step
//! ([`super::Command::LinkPoses`]). A link enters the world at the first pose found for
//! it, at rest there; from then on each step moves its colliders from where they were
//! to the newest pose (the contact stage takes their velocity from the two), and a
//! failed lookup leaves it where it was. A new description replaces the links (those
//! already seen keep their poses) before the next step.

use std::sync::Arc;

use crate::contact::Collider;
use crate::geometry::Pose;
use crate::scene::urdf::RobotDescription;
use crate::sim::World;
use crate::wire::msgs::{Transform, TransformStamped};

use super::input::MIN_QUATERNION_NORM;

/// A robot description as the edge that received it loaded it: the links, or why the
/// text is not a URDF (the description in force then stays).
pub type LoadedDescription = Result<Arc<RobotDescription>, String>;

/// The robot's links in the session.
#[derive(Clone, Debug, Default)]
pub struct RobotLinks {
    description: Option<Arc<RobotDescription>>,
    /// Per link of the description: its newest pose (`world_from_link`; None: never
    /// found).
    poses: Vec<Option<Pose>>,
    /// The world's kinematic bodies, in order: the index of the link each one is.
    bodies: Vec<usize>,
}

impl RobotLinks {
    /// The description in force (None: none arrived yet).
    pub fn description(&self) -> Option<&RobotDescription> {
        self.description.as_deref()
    }

    /// The links in the world (found at least once), in body order.
    pub fn links_in_world(&self) -> Vec<&str> {
        let d = self.description.as_deref();
        self.bodies
            .iter()
            .filter_map(|&l| d.map(|d| d.links[l].name.as_str()))
            .collect()
    }

    /// A description arrived: its links replace the previous ones; a link of the same
    /// TF frame keeps its pose (and its place in the world, at rest where it is).
    pub fn set_description(
        &mut self,
        loaded: &LoadedDescription,
        world: &mut World,
        friction: f64,
    ) -> Result<(), String> {
        let description = loaded.as_ref().map_err(Clone::clone)?;
        let old = self.description.as_deref();
        let current = world.kinematic_poses();
        let poses = description
            .links
            .iter()
            .map(|link| {
                let l = old?.links.iter().position(|o| o.frame == link.frame)?;
                // a link in the world is where the world put it; else its newest pose
                match self.bodies.iter().position(|&k| k == l) {
                    Some(b) => current.get(b).copied(),
                    None => self.poses.get(l).copied().flatten(),
                }
            })
            .collect();
        self.description = Some(Arc::clone(description));
        self.poses = poses;
        // body indices name the old description's links: every link starts at its pose
        self.bodies.clear();
        self.rebuild(world, friction, &[])
    }

    /// The links' poses looked up for the coming step: `transforms` from the scene
    /// frame (`header.frame_id`; empty when the lookup failed, the link then stays
    /// where it is) to each link's TF frame (`child_frame_id`). Links found for the
    /// first time enter the world at rest; the others move there over the step.
    pub fn set_poses(
        &mut self,
        transforms: &[TransformStamped],
        world: &mut World,
        friction: f64,
    ) -> Result<(), String> {
        let Some(d) = self.description.as_deref() else {
            return Ok(());
        };
        let mut found: Vec<Option<Pose>> = vec![None; d.links.len()];
        for t in transforms.iter().filter(|t| !t.header.frame_id.is_empty()) {
            let link = d.links.iter().position(|k| k.frame == t.child_frame_id);
            if let (Some(l), Some(p)) = (link, link_pose(&t.transform)) {
                found[l] = Some(p);
            }
        }
        let entering: Vec<usize> = (0..found.len())
            .filter(|&l| found[l].is_some() && self.poses[l].is_none())
            .collect();
        for (l, p) in found.iter().enumerate() {
            if p.is_some() {
                self.poses[l] = *p;
            }
        }
        if !entering.is_empty() {
            self.rebuild(world, friction, &entering)?;
        }
        for (b, &l) in self.bodies.iter().enumerate() {
            if let Some(p) = found[l] {
                world.set_kinematic_pose(b, p);
            }
        }
        Ok(())
    }

    /// The world's kinematic colliders anew: every link with a pose, in link order, at
    /// rest where the world has it (`entering` links: at their new pose).
    fn rebuild(
        &mut self,
        world: &mut World,
        friction: f64,
        entering: &[usize],
    ) -> Result<(), String> {
        let Some(d) = self.description.as_deref() else {
            return Ok(());
        };
        let current = world.kinematic_poses().to_vec();
        let mut bodies = Vec::new();
        let mut start = Vec::new();
        let mut colliders = Vec::new();
        for (l, link) in d.links.iter().enumerate() {
            let Some(pose) = self.poses[l] else { continue };
            let in_world = self.bodies.iter().position(|&k| k == l);
            let at = match in_world {
                Some(b) if !entering.contains(&l) => current.get(b).copied().unwrap_or(pose),
                _ => pose,
            };
            for s in &link.shapes {
                colliders.push(Collider {
                    shape: s.shape.clone(),
                    pose: s.pose,
                    friction,
                    attached_to: Some(bodies.len()),
                });
            }
            bodies.push(l);
            start.push(at);
        }
        world
            .set_kinematic_colliders(colliders, start)
            .map_err(|e| e.to_string())?;
        self.bodies = bodies;
        Ok(())
    }
}

/// A link's pose from a looked-up transform: finite, with a quaternion that can be
/// normalized (else None: the lookup counts as failed).
fn link_pose(t: &Transform) -> Option<Pose> {
    let (p, q) = (&t.translation, &t.rotation);
    if ![p.x, p.y, p.z, q.x, q.y, q.z, q.w]
        .iter()
        .all(|v| v.is_finite())
    {
        return None;
    }
    let quaternion = nalgebra::Quaternion::new(q.w, q.x, q.y, q.z);
    if quaternion.norm() < MIN_QUATERNION_NORM {
        return None;
    }
    Some(Pose::from_parts(
        nalgebra::Translation3::new(p.x, p.y, p.z),
        nalgebra::UnitQuaternion::new_normalize(quaternion),
    ))
}
