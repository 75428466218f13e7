//! Ground truth for scoring a tracker: an object's mesh vertices in the scene frame
//! with their material (flat-pattern) coordinates, as a point cloud of x, y, z, u, v.

use crate::geometry::SurfaceMesh;

/// Bytes per ground-truth point: x, y, z (m, scene frame), u, v (m, material), each a
/// little-endian float32.
pub const TRUTH_POINT_STEP: usize = 20;

/// The ground-truth cloud's `PointField`s: name and byte offset, each a FLOAT32
/// (datatype 7), count 1.
pub const TRUTH_FIELDS: [(&str, u32); 5] = [("x", 0), ("y", 4), ("z", 8), ("u", 12), ("v", 16)];

/// Fill `out` with `mesh`'s vertices (one point each, in vertex order: an unorganized
/// cloud of height 1 and width `mesh.vertices.len()`); returns the point count.
/// Reuses `out`'s buffer: no allocation once it has held a mesh this large.
pub fn fill_mesh_points(mesh: &SurfaceMesh, out: &mut Vec<u8>) -> usize {
    out.clear();
    for (k, p) in mesh.vertices.iter().enumerate() {
        let m = mesh.material.get(k).map_or([f64::NAN; 2], |m| [m.x, m.y]);
        for v in [p.x, p.y, p.z, m[0], m[1]] {
            out.extend_from_slice(&(v as f32).to_le_bytes());
        }
    }
    mesh.vertices.len()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{Point2, Point3, VertexRegion};

    #[test]
    fn each_vertex_is_x_y_z_u_v() {
        let mesh = SurfaceMesh {
            vertices: vec![Point3::new(1.0, 2.0, 3.0), Point3::new(-0.5, 0.25, 0.125)],
            triangles: vec![],
            material: vec![Point2::new(0.1, 0.2), Point2::new(0.3, -0.4)],
            rulings: vec![],
            regions: vec![VertexRegion::Flat; 2],
        };
        let mut out = vec![9u8; 3];
        assert_eq!(fill_mesh_points(&mesh, &mut out), 2);
        assert_eq!(out.len(), 2 * TRUTH_POINT_STEP);
        let at = |k: usize| f32::from_le_bytes(out[4 * k..4 * k + 4].try_into().unwrap());
        let read: Vec<f32> = (0..10).map(at).collect();
        assert_eq!(
            read,
            [1.0, 2.0, 3.0, 0.1, 0.2, -0.5, 0.25, 0.125, 0.3, -0.4]
        );
        let capacity = out.capacity();
        fill_mesh_points(&mesh, &mut out);
        assert_eq!(out.capacity(), capacity);
    }
}
