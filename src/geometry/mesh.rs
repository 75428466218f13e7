//! The triangle mesh every simulator hands to the edges (markers, bags, stats, contact).

use super::{Point2, Point3};

/// Which kind of region a vertex belongs to (coloured differently in markers).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VertexRegion {
    /// Part of a flat region (paper) or a ribbon element with no bending.
    Flat,
    /// Part of a curved (ruled) region.
    Curved,
    /// A singular vertex (apex where rulings meet).
    Singular,
}

/// A surface mesh in world coordinates with its flat-pattern (material) coordinates.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SurfaceMesh {
    /// Vertex positions in the world frame, m.
    pub vertices: Vec<Point3>,
    /// Triangles as vertex indices, counter-clockwise seen from the material +z side.
    pub triangles: Vec<[u32; 3]>,
    /// Flat-pattern coordinates of each vertex, m.
    pub material: Vec<Point2>,
    /// Ruling / crease segments as vertex index pairs.
    pub rulings: Vec<[u32; 2]>,
    /// Region of each vertex (same length as `vertices`).
    pub regions: Vec<VertexRegion>,
}

impl SurfaceMesh {
    /// True when every vertex coordinate is finite.
    pub fn is_finite(&self) -> bool {
        self.vertices
            .iter()
            .all(|p| p.coords.iter().all(|x| x.is_finite()))
    }

    /// Unique undirected edges of the triangles, sorted (deterministic order).
    pub fn edges(&self) -> Vec<[u32; 2]> {
        let mut edges: Vec<[u32; 2]> = self
            .triangles
            .iter()
            .flat_map(|t| [[t[0], t[1]], [t[1], t[2]], [t[2], t[0]]])
            .map(|[a, b]| if a < b { [a, b] } else { [b, a] })
            .collect();
        edges.sort_unstable();
        edges.dedup();
        edges
    }

    /// Largest relative edge-length error against the flat pattern:
    /// max over edges of |len_world - len_material| / len_material (dimensionless).
    pub fn isometry_error(&self) -> f64 {
        let mut worst: f64 = 0.0;
        for [a, b] in self.edges() {
            let (a, b) = (a as usize, b as usize);
            let rest = (self.material[a] - self.material[b]).norm();
            if rest <= 1e-12 {
                continue;
            }
            let len = (self.vertices[a] - self.vertices[b]).norm();
            worst = worst.max((len - rest).abs() / rest);
        }
        worst
    }
}
