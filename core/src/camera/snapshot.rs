//! What a frame is rendered from: the objects' meshes and the colliders' poses at one
//! instant, copied out of the world so the camera can draw while the world steps on.

use crate::contact::Collider;
use crate::geometry::{Pose, SurfaceMesh};
use crate::sim::World;

/// The scene a camera sees at one instant (world frame).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Snapshot {
    /// Every object's surface mesh, in object order.
    pub meshes: Vec<SurfaceMesh>,
    /// `world_from_collider` of each collider of [`world_colliders`] (a collider carried
    /// by a handle at its handle's current target).
    pub collider_poses: Vec<Pose>,
}

impl Snapshot {
    /// Copy `world`'s meshes and collider poses into this snapshot, reusing its buffers:
    /// no allocation once warm (unless a mesh grew, as a remeshed paper sheet does).
    pub fn capture(&mut self, world: &World) {
        let n = world.object_names().len();
        self.meshes.resize_with(n, SurfaceMesh::default);
        for (o, dst) in self.meshes.iter_mut().enumerate() {
            let src = world.mesh(o);
            dst.vertices.clone_from(&src.vertices);
            dst.triangles.clone_from(&src.triangles);
            dst.material.clone_from(&src.material);
            dst.rulings.clone_from(&src.rulings);
            dst.regions.clone_from(&src.regions);
        }
        let targets = world.current_targets();
        self.collider_poses.clear();
        self.collider_poses
            .extend(world_colliders(world).iter().map(|c| c.world_pose(targets)));
    }
}

/// The colliders a camera of `world` draws (whichever contact method runs them; none
/// without contact), in the order of [`Snapshot::collider_poses`]: give them to
/// [`Renderer::new`](super::Renderer::new).
pub fn world_colliders(world: &World) -> &[Collider] {
    world.colliders()
}
