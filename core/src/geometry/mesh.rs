//! The triangle mesh every simulator hands to the edges (markers, bags, stats, contact).

use super::{Point2, Point3, Pose, Rotation};

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

/// A point of a mesh's surface: where it is in the flat pattern and in the world.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfacePoint {
    /// Flat-pattern coordinates, m.
    pub material: Point2,
    /// World position, m.
    pub position: Point3,
    /// Distance from the point it was found for, m.
    pub distance: f64,
}

impl SurfaceMesh {
    /// The point of the surface nearest `p`: the closest point of each triangle (ties
    /// keep the first triangle), mapped to the pattern through its barycentric
    /// coordinates. None for an empty or non-finite mesh.
    pub fn nearest_surface_point(&self, p: &Point3) -> Option<SurfacePoint> {
        let mut best: Option<SurfacePoint> = None;
        for t in &self.triangles {
            let [a, b, c] = t.map(|i| self.vertices[i as usize]);
            let w = closest_on_triangle(p, &a, &b, &c);
            let q = Point3::from(a.coords * w[0] + b.coords * w[1] + c.coords * w[2]);
            let d = (q - p).norm();
            if best.is_none_or(|b| d < b.distance) {
                let [ma, mb, mc] = t.map(|i| self.material[i as usize]);
                let m = Point2::from(ma.coords * w[0] + mb.coords * w[1] + mc.coords * w[2]);
                best = Some(SurfacePoint {
                    material: m,
                    position: q,
                    distance: d,
                });
            }
        }
        best.filter(|b| b.distance.is_finite())
    }

    /// The point nearest `p` on the edges `on_edge` accepts (given the two endpoints'
    /// pattern coordinates), e.g. the pattern's outline. None when no edge is accepted.
    pub fn nearest_edge_point(
        &self,
        p: &Point3,
        on_edge: &dyn Fn(&Point2, &Point2) -> bool,
    ) -> Option<SurfacePoint> {
        let mut best: Option<SurfacePoint> = None;
        for [i, j] in self.edges() {
            let (mi, mj) = (self.material[i as usize], self.material[j as usize]);
            if !on_edge(&mi, &mj) {
                continue;
            }
            let (a, b) = (self.vertices[i as usize], self.vertices[j as usize]);
            let ab = b - a;
            let len2 = ab.norm_squared();
            let s = if len2 > 0.0 {
                ((p - a).dot(&ab) / len2).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let q = a + ab * s;
            let d = (q - p).norm();
            if best.is_none_or(|b| d < b.distance) {
                best = Some(SurfacePoint {
                    material: mi + (mj - mi) * s,
                    position: q,
                    distance: d,
                });
            }
        }
        best.filter(|b| b.distance.is_finite())
    }
}

/// Material points closer than this to a triangle (in barycentric units) count as inside
/// it: grasp and end points lie on the pattern's boundary.
const INSIDE_TOLERANCE: f64 = 1e-6;

impl SurfaceMesh {
    /// The world frame at material point `m` (m): origin the barycentric image of `m` in
    /// the triangle holding it in the pattern, x the image of the material u direction,
    /// z the triangle's normal (material +z side), y = z x x; for an isometric mesh the
    /// material frame itself carried along. None: outside the pattern, or degenerate.
    pub fn frame_at(&self, m: Point2) -> Option<Pose> {
        let mesh = self;
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
}

/// Barycentric coordinates of the point of triangle (a, b, c) closest to `p` (Ericson,
/// Real-Time Collision Detection, 5.1.5: the Voronoi regions of the vertices, edges
/// and face in turn).
fn closest_on_triangle(p: &Point3, a: &Point3, b: &Point3, c: &Point3) -> [f64; 3] {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(&ap), ac.dot(&ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return [1.0, 0.0, 0.0];
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(&bp), ac.dot(&bp));
    if d3 >= 0.0 && d4 <= d3 {
        return [0.0, 1.0, 0.0];
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return [1.0 - v, v, 0.0];
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(&cp), ac.dot(&cp));
    if d6 >= 0.0 && d5 <= d6 {
        return [0.0, 0.0, 1.0];
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return [1.0 - w, 0.0, w];
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return [0.0, 1.0 - w, w];
    }
    let denom = 1.0 / (va + vb + vc);
    let (v, w) = (vb * denom, vc * denom);
    [1.0 - v - w, v, w]
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

    /// The closest point of a triangle agrees with a dense sampling of the triangle
    /// (never farther than the best sample; within the sampling's spacing of it), for
    /// points in every Voronoi region; the pattern point is the same barycentric mix.
    #[test]
    fn nearest_surface_point_matches_a_dense_sampling() {
        let mesh = SurfaceMesh {
            vertices: vec![
                Point3::new(0.0, 0.0, 0.0),
                Point3::new(1.0, 0.2, 0.1),
                Point3::new(0.3, 0.8, -0.2),
            ],
            triangles: vec![[0, 1, 2]],
            material: vec![
                Point2::new(0.0, 0.0),
                Point2::new(1.0, 0.0),
                Point2::new(0.0, 1.0),
            ],
            ..Default::default()
        };
        let n = 400;
        let samples: Vec<(f64, f64)> = (0..=n)
            .flat_map(|i| (0..=n - i).map(move |j| (i as f64 / n as f64, j as f64 / n as f64)))
            .collect();
        for p in [
            Point3::new(-0.5, -0.5, 0.3),
            Point3::new(1.5, 0.2, 0.0),
            Point3::new(0.2, 1.2, 0.5),
            Point3::new(0.6, -0.3, 0.0),
            Point3::new(0.4, 0.4, 0.7),
            Point3::new(0.9, 0.7, -0.4),
            Point3::new(-0.4, 0.5, 0.0),
        ] {
            let found = mesh.nearest_surface_point(&p).unwrap();
            let sampled = samples
                .iter()
                .map(|&(v, w)| {
                    let q = mesh.vertices[0].coords * (1.0 - v - w)
                        + mesh.vertices[1].coords * v
                        + mesh.vertices[2].coords * w;
                    (q - p.coords).norm()
                })
                .fold(f64::INFINITY, f64::min);
            assert!(
                found.distance <= sampled + 1e-12,
                "{p}: {} > {sampled}",
                found.distance
            );
            // the sampling's spacing is 1/400 of an edge (~3e-3 m)
            assert!(sampled - found.distance < 3e-3, "{p}");
            let m = found.material;
            let q = mesh.vertices[0].coords * (1.0 - m.x - m.y)
                + mesh.vertices[1].coords * m.x
                + mesh.vertices[2].coords * m.y;
            assert!((q - found.position.coords).norm() < 1e-12, "{p}");
        }
        // the edge search: only the edge the filter accepts
        let bottom = |a: &Point2, b: &Point2| a.y == 0.0 && b.y == 0.0;
        let e = mesh
            .nearest_edge_point(&Point3::new(0.3, 0.8, 0.0), &bottom)
            .unwrap();
        assert_eq!(e.material.y, 0.0);
        assert!(mesh
            .nearest_edge_point(&Point3::origin(), &|_, _| false)
            .is_none());
    }
}
