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

use crate::geometry::{Point2, Point3, Pose, Rotation, SurfaceMesh};

use crate::wire::convert::to_transform;
use crate::wire::msgs::{TFMessage, TransformStamped};

use super::produce::{Produce, Scope};

/// Material points closer than this to a triangle (in barycentric units) count as inside
/// it: grasp and end points lie on the pattern's boundary.
const INSIDE_TOLERANCE: f64 = 1e-6;

/// The world frame at material point `m` of `mesh` (None: outside the pattern, or a
/// degenerate mesh).
fn frame_at(mesh: &SurfaceMesh, m: Point2) -> Option<Pose> {
    let mut best: Option<(f64, usize, [f64; 3])> = None;
    for (k, t) in mesh.triangles.iter().enumerate() {
        let [a, b, c] = t.map(|i| mesh.material[i as usize]);
        let (e1, e2) = (b - a, c - a);
        let det = e1.x * e2.y - e1.y * e2.x;
        if det.abs() < 1e-18 {
            continue;
        }
        let d = m - a;
        let l1 = (d.x * e2.y - d.y * e2.x) / det;
        let l2 = (e1.x * d.y - e1.y * d.x) / det;
        let bary = [1.0 - l1 - l2, l1, l2];
        // how far outside: the most negative coordinate (0 inside)
        let outside = -bary.iter().cloned().fold(0.0_f64, f64::min);
        if best.is_none_or(|(o, _, _)| outside < o) {
            best = Some((outside, k, bary));
        }
    }
    let (outside, k, bary) = best?;
    if outside > INSIDE_TOLERANCE {
        return None;
    }
    let t = mesh.triangles[k];
    let [pa, pb, pc] = t.map(|i| mesh.vertices[i as usize]);
    let [ma, mb, mc] = t.map(|i| mesh.material[i as usize]);
    let origin = Point3::from(pa.coords * bary[0] + pb.coords * bary[1] + pc.coords * bary[2]);
    // the affine map's image of the material u axis: solve [e1 e2] [s; r] = (1, 0)
    let (e1, e2) = (mb - ma, mc - ma);
    let det = e1.x * e2.y - e1.y * e2.x;
    let (s, r) = (e2.y / det, -e1.y / det);
    let x = (pb - pa) * s + (pc - pa) * r;
    let mut z = (pb - pa).cross(&(pc - pa));
    if det < 0.0 {
        z = -z;
    }
    let (x, z) = (x.try_normalize(1e-15)?, z.try_normalize(1e-15)?);
    let y = z.cross(&x);
    let x = y.cross(&z);
    let rotation = Rotation::from_matrix(&nalgebra::Matrix3::from_columns(&[x, y, z]));
    if !origin.coords.iter().all(|c| c.is_finite()) {
        return None;
    }
    Some(Pose::from_parts(origin.coords.into(), rotation))
}

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
                frame_at(mesh, h.material_point),
            );
        }
        if let Some([start, end]) = ends(mesh) {
            push(format!("{name}/start"), frame_at(mesh, start));
            push(format!("{name}/end"), frame_at(mesh, end));
        }
    }
    Some(TFMessage { transforms })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{Vector3, VertexRegion};

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
            let f = frame_at(&mesh, m).unwrap();
            let want = place * Pose::translation(m.x, m.y, 0.0);
            assert!((f.translation.vector - want.translation.vector).norm() < 1e-12);
            assert!(f.rotation.angle_to(&want.rotation) < 1e-12, "{m}");
        }
        assert!(frame_at(&mesh, Point2::new(1.5, 0.5)).is_none());
        let [s, e] = ends(&mesh).unwrap();
        assert_eq!((s, e), (Point2::new(0.0, 0.5), Point2::new(1.0, 0.5)));
    }

    #[test]
    fn a_folded_pattern_gives_each_side_its_own_frame() {
        // fold the right triangle up about the diagonal: its frame's z follows it
        let mut mesh = square(&Pose::identity());
        mesh.vertices[1] = Point3::new(0.5, 0.5, std::f64::consts::FRAC_1_SQRT_2);
        let f = frame_at(&mesh, Point2::new(0.7, 0.2)).unwrap();
        let z = f.rotation * Vector3::z();
        assert!(z.z < 0.99 && z.z > 0.0, "{z}");
        let g = frame_at(&mesh, Point2::new(0.2, 0.7)).unwrap();
        assert!(g.rotation.angle() < 1e-12);
    }
}
