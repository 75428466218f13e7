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

/// Edge strains of a mesh against its flat pattern, strain = (l - l_rest) / l_rest per
/// edge (dimensionless, given in %). Schreck et al.'s table IV measures compression
/// only (the first two); stretch is measured as well because a sheet of paper stretches
/// no more than it compresses.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct EdgeStrain {
    /// Mean over edges of max(0, -strain), %.
    pub compression_mean_pct: f64,
    /// Share of edges with strain < -1 %, %.
    pub compressed_edges_pct: f64,
    /// Mean over edges of |strain|, %.
    pub strain_mean_pct: f64,
    /// Largest |strain|, %.
    pub strain_max_pct: f64,
    /// Largest stretch max(0, strain), %.
    pub stretch_max_pct: f64,
    /// Share of edges with |strain| > 1 % (compressed or stretched), %.
    pub strained_edges_pct: f64,
}

/// The edge-strain threshold of table IV's "edges compressed over 1 %", also used for
/// stretch (dimensionless).
pub const STRAIN_THRESHOLD: f64 = 0.01;

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

    /// Edge strains against the flat pattern over the triangles' edges (edges shorter
    /// than 1e-12 m in the pattern, welded seams, are skipped).
    pub fn edge_strain(&self) -> EdgeStrain {
        let mut e = EdgeStrain::default();
        let mut n = 0usize;
        let (mut compressed, mut strained) = (0usize, 0usize);
        for [a, b] in self.edges() {
            let (a, b) = (a as usize, b as usize);
            let rest = (self.material[a] - self.material[b]).norm();
            if rest <= 1e-12 {
                continue;
            }
            let strain = ((self.vertices[a] - self.vertices[b]).norm() - rest) / rest;
            n += 1;
            e.compression_mean_pct += (-strain).max(0.0);
            e.strain_mean_pct += strain.abs();
            e.strain_max_pct = e.strain_max_pct.max(strain.abs());
            e.stretch_max_pct = e.stretch_max_pct.max(strain);
            compressed += usize::from(strain < -STRAIN_THRESHOLD);
            strained += usize::from(strain.abs() > STRAIN_THRESHOLD);
        }
        if n == 0 {
            return EdgeStrain::default();
        }
        let n = n as f64;
        EdgeStrain {
            compression_mean_pct: 100.0 * e.compression_mean_pct / n,
            compressed_edges_pct: 100.0 * compressed as f64 / n,
            strain_mean_pct: 100.0 * e.strain_mean_pct / n,
            strain_max_pct: 100.0 * e.strain_max_pct,
            stretch_max_pct: 100.0 * e.stretch_max_pct,
            strained_edges_pct: 100.0 * strained as f64 / n,
        }
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

#[cfg(test)]
mod tests {
    use super::*;

    /// One right triangle with legs of 1 m: stretching one leg by 2 % and compressing
    /// the other by 0.5 % gives those strains (the hypotenuse follows).
    #[test]
    fn edge_strain_measures_stretch_and_compression() {
        let material = vec![
            Point2::new(0.0, 0.0),
            Point2::new(1.0, 0.0),
            Point2::new(0.0, 1.0),
        ];
        let mut mesh = SurfaceMesh {
            vertices: material
                .iter()
                .map(|m| Point3::new(m.x, m.y, 0.0))
                .collect(),
            triangles: vec![[0, 1, 2]],
            regions: vec![VertexRegion::Flat; 3],
            material,
            rulings: Vec::new(),
        };
        assert_eq!(mesh.edge_strain(), EdgeStrain::default());
        mesh.vertices[1].x = 1.02;
        mesh.vertices[2].y = 0.995;
        let e = mesh.edge_strain();
        let hyp = (1.02f64.hypot(0.995) - 2f64.sqrt()) / 2f64.sqrt();
        assert!((e.strain_max_pct - 2.0).abs() < 1e-9, "{e:?}");
        assert!((e.stretch_max_pct - 2.0).abs() < 1e-9);
        assert!((e.compression_mean_pct - 0.5 / 3.0).abs() < 1e-9);
        assert!((e.strain_mean_pct - (2.0 + 0.5 + 100.0 * hyp.abs()) / 3.0).abs() < 1e-9);
        // only the stretched leg is over 1 %; none is compressed over 1 %
        assert!((e.strained_edges_pct - 100.0 / 3.0).abs() < 1e-9);
        assert_eq!(e.compressed_edges_pct, 0.0);
        mesh.vertices[2].y = 0.98;
        let e = mesh.edge_strain();
        assert!((e.compressed_edges_pct - 100.0 / 3.0).abs() < 1e-9);
        assert!((e.strained_edges_pct - 200.0 / 3.0).abs() < 1e-9);
    }
}
