//! The frames the node publishes on `/tf` (`outputs.tf: true`): where the object really
//! is, for a planner to look up. Per object, `<object>/<handle>` at each handle's grasp
//! point and `<object>/start`, `<object>/end` at the two ends of the flat pattern's
//! long axis (a ribbon's centerline ends (0, 0) and (l, 0)); parent the scene frame.
//!
//! A frame at material point (u, v) is read off the deformed mesh: the triangle holding
//! (u, v) in the flat pattern maps it to the world affinely (an isometry for an isometric
//! mesh), so its origin is the barycentric image of (u, v), its x axis the image of the
//! material u direction, z the triangle's normal (material +z side), y = z x x. In the
//! flat rest state with identity placement it is the material frame itself.

use crate::geometry::{Point2, Pose, SurfaceMesh};

use crate::wire::convert::to_transform;
use crate::wire::msgs::{TFMessage, TransformStamped};

use super::produce::{Produce, Scope};

/// The two ends of the pattern's long axis: (u_min, v_mid) and (u_max, v_mid).
fn ends(mesh: &SurfaceMesh) -> Option<[Point2; 2]> {
    let first = mesh.material.first()?;
    let (mut lo, mut hi) = (*first, *first);
    for p in &mesh.material {
        lo = lo.inf(p);
        hi = hi.sup(p);
    }
    let v = 0.5 * (lo.y + hi.y);
    Some([Point2::new(lo.x, v), Point2::new(hi.x, v)])
}

/// Every object's grasp and end frames at the state's time, parent the scene frame. A
/// frame whose point cannot be found on a finite mesh is left out.
pub fn tf(p: &Produce, _: Scope) -> Option<TFMessage> {
    let world = &p.scene.world;
    let header = p.header();
    let mut transforms = Vec::new();
    let mut push = |child: String, pose: Option<Pose>| {
        if let Some(p) = pose {
            transforms.push(TransformStamped {
                header: header.clone(),
                child_frame_id: child,
                transform: to_transform(&p),
            });
        }
    };
    for (i, name) in world.object_names().iter().enumerate() {
        let mesh = world.mesh(i);
        if !mesh.is_finite() {
            continue;
        }
        for h in world.handles().iter().filter(|h| h.object == i) {
            push(
                format!("{name}/{}", h.name),
                mesh.frame_at(h.material_point),
            );
        }
        if let Some([start, end]) = ends(mesh) {
            push(format!("{name}/start"), mesh.frame_at(start));
            push(format!("{name}/end"), mesh.frame_at(end));
        }
    }
    Some(TFMessage { transforms })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{Point3, Vector3, VertexRegion};

    /// A unit square in the pattern (two triangles) placed by `place`.
    fn square(place: &Pose) -> SurfaceMesh {
        let material = vec![
            Point2::new(0.0, 0.0),
            Point2::new(1.0, 0.0),
            Point2::new(1.0, 1.0),
            Point2::new(0.0, 1.0),
        ];
        SurfaceMesh {
            vertices: material
                .iter()
                .map(|m| place * Point3::new(m.x, m.y, 0.0))
                .collect(),
            triangles: vec![[0, 1, 2], [0, 2, 3]],
            regions: vec![VertexRegion::Flat; 4],
            material,
            rulings: vec![],
        }
    }

    #[test]
    fn a_placed_flat_pattern_gives_the_placement_times_the_material_frame() {
        let place = Pose::new(Vector3::new(0.3, -1.0, 2.0), Vector3::new(0.4, -0.2, 1.1));
        let mesh = square(&place);
        for m in [
            Point2::new(0.25, 0.5),
            Point2::new(0.0, 0.5),
            Point2::new(1.0, 1.0),
        ] {
            let f = mesh.frame_at(m).unwrap();
            let want = place * Pose::translation(m.x, m.y, 0.0);
            assert!((f.translation.vector - want.translation.vector).norm() < 1e-12);
            assert!(f.rotation.angle_to(&want.rotation) < 1e-12, "{m}");
        }
        assert!(mesh.frame_at(Point2::new(1.5, 0.5)).is_none());
        let [s, e] = ends(&mesh).unwrap();
        assert_eq!((s, e), (Point2::new(0.0, 0.5), Point2::new(1.0, 0.5)));
    }

    #[test]
    fn a_folded_pattern_gives_each_side_its_own_frame() {
        // fold the right triangle up about the diagonal: its frame's z follows it
        let mut mesh = square(&Pose::identity());
        mesh.vertices[1] = Point3::new(0.5, 0.5, std::f64::consts::FRAC_1_SQRT_2);
        let f = mesh.frame_at(Point2::new(0.7, 0.2)).unwrap();
        let z = f.rotation * Vector3::z();
        assert!(z.z < 0.99 && z.z > 0.0, "{z}");
        let g = mesh.frame_at(Point2::new(0.2, 0.7)).unwrap();
        assert!(g.rotation.angle() < 1e-12);
    }
}
