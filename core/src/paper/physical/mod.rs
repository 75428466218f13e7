//! The physical mesh S_P (Schreck et al. sec. 4, fig. 4): S_G enriched with boundary
//! samples (density rho_bound), interior samples of the flat regions (density rho_int)
//! and the barycenters of the curved faces, Delaunay-connected with the boundary and
//! the rulings and creases of S_G kept. By default two departures from fig. 4, for the
//! triangles' shape: the barycenters are connected by the triangulation, not as a fan
//! over each curved face, and a triangle with an angle near 180 deg has the segment it
//! lies against split ([`refine`]); `length_restoration: paper` builds fig. 4's fans
//! ([`fans`]). See docs/paper_simulator.md ("S_P without caps"). S_P carries the state
//! between frames (positions, velocities) and is the mesh that is simulated (step 1),
//! length-restored (step 3) and displayed.

mod fans;
mod interpolate;
mod refine;

pub use interpolate::Interpolator;

use std::collections::BTreeMap;

use super::geometric::{EdgeKind, FaceKind, GVertexKind, GeometricLayer, GeometricMesh};
use super::params::{LengthRestoration, PaperParams};
use super::pattern::{in_convex_polygon, orient, point_segment, Pattern};
use crate::geometry::{Point2, Point3, Vector3, VertexRegion};

/// Where the samples of a new S_P go.
#[derive(Clone, Copy)]
pub enum Placement<'a> {
    /// The paper's (fig. 4: S_P is S_G enriched): on S_G's piecewise-planar surface,
    /// a sample on a curved face's boundary on this curve (arc length, m -> point).
    OnGeometricLayer(&'a dyn Fn(f64) -> Point3),
    /// Ours: at this point of the previous S_P (pattern point -> point), which keeps
    /// the shape the FEM step gave the sheet; S_G's flat triangles are chords of it.
    Interpolated(&'a dyn Fn(&Point2) -> Point3),
}

/// What an S_P vertex is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SampleKind {
    /// The S_G vertex of the same index.
    Geometric,
    /// A boundary sample (rho_bound), arc length s, m.
    BoundarySample { s: f64 },
    /// An interior sample of a flat region (rho_int).
    InteriorSample,
    /// The barycenter of a curved face.
    Barycenter,
    /// A point splitting a ruling, a crease or the boundary under a cap ([`refine`]).
    CapSplit,
}

/// A bending hinge: the interior edge (v[0], v[1]) with opposite vertices v[2]
/// (left triangle, v0 v1 v2 counter-clockwise) and v[3] (right triangle).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hinge {
    pub v: [u32; 4],
    /// Rest dihedral angle theta_rest, rad (eq. 1; preset creases).
    pub rest_angle: f64,
    /// 3 |e|^2 / (A_1 + A_2) of the pattern (discrete shells weight), dimensionless.
    pub weight: f64,
}

/// The physical mesh S_P.
#[derive(Clone, Debug, Default)]
pub struct PhysicalMesh {
    pub material: Vec<Point2>,
    pub position: Vec<Point3>,
    pub velocity: Vec<Vector3>,
    pub kind: Vec<SampleKind>,
    pub region: Vec<VertexRegion>,
    /// Counter-clockwise in the pattern.
    pub triangles: Vec<[u32; 3]>,
    /// Unique undirected edges, lower index first, sorted.
    pub edges: Vec<[u32; 2]>,
    pub hinges: Vec<Hinge>,
    /// Boundary vertices in arc-length order and their arc lengths, m.
    pub boundary: Vec<u32>,
    pub boundary_arc: Vec<f64>,
    /// S_G rulings and creases as S_P vertex pairs (display).
    pub rulings: Vec<[u32; 2]>,
    /// Number of S_G vertices (they come first, same indices).
    pub geometric_vertices: usize,
    /// Lumped mass of each vertex, kg.
    pub mass: Vec<f64>,
}

/// Build S_P from the mesh of S_G. S_G vertices keep their positions; the samples go
/// where `placement` says (docs/paper_simulator.md, "S_P without caps").
pub fn build_physical(
    gmesh: &GeometricMesh,
    layer: &GeometricLayer,
    pattern: &Pattern,
    params: &PaperParams,
    placement: Placement,
) -> Result<PhysicalMesh, String> {
    let mut sp = PhysicalMesh::default();
    let ng = gmesh.vertices.len();
    sp.geometric_vertices = ng;
    for v in &gmesh.vertices {
        sp.material.push(v.material);
        sp.position.push(v.position);
        sp.kind.push(SampleKind::Geometric);
    }
    // the pattern polygons of S_G's curved faces
    let curved_faces: Vec<Vec<Point2>> = gmesh
        .faces
        .iter()
        .filter(|f| f.kind != FaceKind::Flat)
        .map(|f| {
            f.vertices
                .iter()
                .map(|&v| gmesh.vertices[v as usize].material)
                .collect()
        })
        .collect();
    sp.add_boundary_samples(gmesh, pattern, params, placement);
    sp.add_interior_samples(gmesh, pattern, params, placement, &curved_faces);
    let curved_of_vertex = match params.length_restoration {
        LengthRestoration::Paper => fans::triangulate(&mut sp, gmesh, pattern)?,
        LengthRestoration::StrainLimit => {
            let position = |m: &Point2| sample_position(gmesh, placement, m);
            sp.add_barycenters(&curved_faces, &position);
            let cdt = refine::triangulate(&mut sp, gmesh, pattern, params, &position)?;
            sp.add_triangles(&cdt, &curved_faces)
        }
    };
    // orientation: counter-clockwise in the pattern
    for t in sp.triangles.iter_mut() {
        let [a, b, c] = t.map(|i| sp.material[i as usize]);
        if orient(&a, &b, &c) < 0.0 {
            t.swap(1, 2);
        }
    }
    sp.velocity = vec![Vector3::zeros(); sp.material.len()];
    sp.region = (0..sp.material.len())
        .map(|v| {
            if v < ng {
                if let GVertexKind::Singular { .. } = gmesh.vertices[v].kind {
                    return VertexRegion::Singular;
                }
            }
            if curved_of_vertex[v] {
                VertexRegion::Curved
            } else {
                VertexRegion::Flat
            }
        })
        .collect();
    for rv in &gmesh.ruling_vertices {
        sp.rulings.extend(rv.iter().copied());
    }
    sp.rulings.extend(gmesh.crease_vertices.iter().copied());
    sp.finish_topology(layer, gmesh, params);
    Ok(sp)
}

impl PhysicalMesh {
    /// Boundary samples (rho_bound): a fixed lattice of arc lengths (temporal
    /// coherence), kept away from the S_G boundary vertices. Sets `boundary` and
    /// `boundary_arc` (every boundary vertex in arc-length order).
    fn add_boundary_samples(
        &mut self,
        gmesh: &GeometricMesh,
        pattern: &Pattern,
        params: &PaperParams,
        placement: Placement,
    ) {
        let per = pattern.perimeter();
        let nsamples = ((per * params.boundary_density).round() as usize).max(4);
        let spacing = per / nsamples as f64;
        let gap = 0.4 * spacing;
        let gb: Vec<(f64, u32)> = gmesh
            .boundary
            .iter()
            .map(|&v| match gmesh.vertices[v as usize].kind {
                GVertexKind::Boundary { s } => (s, v),
                GVertexKind::Singular { .. } => (f64::NAN, v),
            })
            .collect();
        let mut boundary: Vec<(f64, u32)> = gb.clone();
        for k in 0..nsamples {
            let s = k as f64 * spacing;
            // the S_G boundary edge holding s
            let i = match gb.partition_point(|&(x, _)| x <= s) {
                0 => gb.len() - 1,
                i => i - 1,
            };
            let j = (i + 1) % gb.len();
            let ((s0, v0), (s1, v1)) = (gb[i], gb[j]);
            let (d0, d1) = (pattern.arc_ccw(s0, s), pattern.arc_ccw(s, s1));
            if d0 < gap || d1 < gap {
                continue;
            }
            let m = pattern.point_at(s);
            let pos = match placement {
                Placement::Interpolated(at) => at(&m),
                Placement::OnGeometricLayer(curve) => {
                    // on the straight S_G edge when it borders flat faces only
                    let flat = gmesh
                        .edge_faces(v0, v1)
                        .iter()
                        .flatten()
                        .all(|&f| gmesh.faces[f].kind == FaceKind::Flat);
                    if flat {
                        let t = d0 / (d0 + d1);
                        Point3::from(
                            gmesh.vertices[v0 as usize].position.coords * (1.0 - t)
                                + gmesh.vertices[v1 as usize].position.coords * t,
                        )
                    } else {
                        curve(s)
                    }
                }
            };
            boundary.push((s, self.material.len() as u32));
            self.material.push(m);
            self.position.push(pos);
            self.kind.push(SampleKind::BoundarySample { s });
        }
        boundary.sort_by(|a, b| a.0.total_cmp(&b.0));
        self.boundary = boundary.iter().map(|&(_, v)| v).collect();
        self.boundary_arc = boundary.iter().map(|&(s, _)| s).collect();
    }

    /// Interior samples (rho_int): a fixed triangular lattice of spacing d, area per
    /// sample (sqrt 3 / 2) d^2 = 1 / rho_int, kept in the flat faces away from the
    /// S_G vertices, rulings and creases; each lies in its flat triangle.
    fn add_interior_samples(
        &mut self,
        gmesh: &GeometricMesh,
        pattern: &Pattern,
        params: &PaperParams,
        placement: Placement,
        curved_polys: &[Vec<Point2>],
    ) {
        let d = (2.0 / (3f64.sqrt() * params.interior_density)).sqrt();
        let row = 0.5 * 3f64.sqrt() * d;
        let corners = pattern.corners();
        let (mut lo, mut hi) = (corners[0], corners[0]);
        for c in corners {
            lo = Point2::new(lo.x.min(c.x), lo.y.min(c.y));
            hi = Point2::new(hi.x.max(c.x), hi.y.max(c.y));
        }
        // structural S_G edges (rulings, creases) are kept in S_P; the plain edges of
        // the flat triangulation are not (they would stiffen the flat regions along
        // arbitrary lines, and a flat region must be free to bend in any direction,
        // sec. 3.1)
        let mut gedges: Vec<[Point2; 2]> = Vec::new();
        for (&(a, b), e) in &gmesh.edges {
            if matches!(e.kind, EdgeKind::Ruling { .. } | EdgeKind::Crease { .. }) {
                gedges.push([
                    gmesh.vertices[a as usize].material,
                    gmesh.vertices[b as usize].material,
                ]);
            }
        }
        let nrows = ((hi.y - lo.y) / row).ceil() as i64 + 1;
        let ncols = ((hi.x - lo.x) / d).ceil() as i64 + 2;
        for j in 0..nrows {
            let y = lo.y + 0.5 * row + j as f64 * row;
            let shift = if j % 2 == 0 { 0.25 * d } else { 0.75 * d };
            for i in 0..ncols {
                let p = Point2::new(lo.x + shift + i as f64 * d, y);
                if pattern.signed_inside_distance(&p) < 0.4 * d {
                    continue;
                }
                if gmesh
                    .vertices
                    .iter()
                    .any(|v| (v.material - p).norm() < 0.4 * d)
                {
                    continue;
                }
                if gedges
                    .iter()
                    .any(|[a, b]| point_segment(&p, a, b).0 < 0.25 * d)
                {
                    continue;
                }
                if curved_polys
                    .iter()
                    .any(|poly| in_convex_polygon(poly, &p, -1e-12))
                {
                    continue;
                }
                if gmesh.flat_face_at(&p).is_none() {
                    continue;
                }
                self.material.push(p);
                self.position.push(sample_position(gmesh, placement, &p));
                self.kind.push(SampleKind::InteriorSample);
            }
        }
    }

    /// The barycenter of each curved face with more than three corners (sec. 4,
    /// fig. 4: it lets the FEM bend the face), at the mean of the corners' pattern
    /// points.
    fn add_barycenters(
        &mut self,
        curved_faces: &[Vec<Point2>],
        position: &dyn Fn(&Point2) -> Point3,
    ) {
        for corners in curved_faces.iter().filter(|c| c.len() > 3) {
            let sum: nalgebra::Vector2<f64> = corners.iter().map(|m| m.coords).sum();
            let m = Point2::from(sum / corners.len() as f64);
            self.push_sample(m, position, SampleKind::Barycenter);
        }
    }

    /// A new vertex at pattern point `m`, placed by `position`; returns its index.
    fn push_sample(
        &mut self,
        m: Point2,
        position: &dyn Fn(&Point2) -> Point3,
        kind: SampleKind,
    ) -> u32 {
        self.material.push(m);
        self.position.push(position(&m));
        self.kind.push(kind);
        (self.material.len() - 1) as u32
    }

    /// The constrained Delaunay triangulation of the vertices so far with the
    /// boundary (split at its samples) and the rulings and creases, each given as the
    /// chain of S_P vertices along it.
    fn triangulate(
        &self,
        chains: &[Vec<u32>],
    ) -> Result<spade::ConstrainedDelaunayTriangulation<spade::Point2<f64>>, String> {
        let nb = self.boundary.len();
        let mut constraints: Vec<[usize; 2]> = (0..nb)
            .map(|i| {
                [
                    self.boundary[i] as usize,
                    self.boundary[(i + 1) % nb] as usize,
                ]
            })
            .collect();
        for chain in chains {
            for w in chain.windows(2) {
                constraints.push([w[0] as usize, w[1] as usize]);
            }
        }
        let pts: Vec<spade::Point2<f64>> = self
            .material
            .iter()
            .map(|m| spade::Point2::new(m.x, m.y))
            .collect();
        let mut conflict = false;
        let cdt = spade::ConstrainedDelaunayTriangulation::<spade::Point2<f64>>::try_bulk_load_cdt(
            pts,
            constraints,
            |_| conflict = true,
        )
        .map_err(|e| format!("{e:?}"))?;
        use spade::Triangulation;
        if conflict || cdt.num_vertices() != self.material.len() {
            return Err("S_P triangulation: conflicting constraints or duplicate samples".into());
        }
        Ok(cdt)
    }

    /// The triangles of `cdt`; returns which vertices lie on a triangle inside one of
    /// the `curved_faces` (pattern polygons of S_G's curved faces).
    fn add_triangles(
        &mut self,
        cdt: &spade::ConstrainedDelaunayTriangulation<spade::Point2<f64>>,
        curved_faces: &[Vec<Point2>],
    ) -> Vec<bool> {
        use spade::Triangulation;
        let mut curved = vec![false; self.material.len()];
        for face in cdt.inner_faces() {
            let vs = face.vertices().map(|v| v.fix().index() as u32);
            let m = vs.map(|v| self.material[v as usize]);
            let c = Point2::from((m[0].coords + m[1].coords + m[2].coords) / 3.0);
            if curved_faces.iter().any(|p| in_convex_polygon(p, &c, 0.0)) {
                for v in vs {
                    curved[v as usize] = true;
                }
            }
            self.triangles.push(vs);
        }
        curved
    }

    /// Edges, hinges with rest angles (eq. 1, preset creases), lumped masses.
    fn finish_topology(
        &mut self,
        layer: &GeometricLayer,
        gmesh: &GeometricMesh,
        params: &PaperParams,
    ) {
        let edge_tris = self.edge_triangles();
        self.edges = edge_tris.keys().map(|&(a, b)| [a, b]).collect();
        let theta = self.singular_rest_angles(params);
        let preset = preset_creases(layer, gmesh);
        self.hinges.clear();
        for (&(a, b), tris) in &edge_tris {
            if tris.len() != 2 {
                continue;
            }
            let hinge = self.hinge(a, b, tris, &theta, &preset);
            self.hinges.push(hinge);
        }
        self.lump_masses(params);
    }

    /// Every edge (sorted vertex pair) with its triangles, each with the vertex
    /// opposite the edge.
    fn edge_triangles(&self) -> BTreeMap<(u32, u32), Vec<(usize, u32)>> {
        let mut edge_tris: BTreeMap<(u32, u32), Vec<(usize, u32)>> = BTreeMap::new();
        for (ti, t) in self.triangles.iter().enumerate() {
            for k in 0..3 {
                let (a, b, c) = (t[k], t[(k + 1) % 3], t[(k + 2) % 3]);
                edge_tris
                    .entry(super::geometric::edge_key(a, b))
                    .or_default()
                    .push((ti, c));
            }
        }
        edge_tris
    }

    /// Eq. 1: the share theta_i = plastic_angle / N_i (rad) of a singular vertex's
    /// plastic angle in the rest angle of each of its N_i edges; 0 elsewhere.
    fn singular_rest_angles(&self, params: &PaperParams) -> Vec<f64> {
        let mut valence = vec![0usize; self.material.len()];
        for [a, b] in &self.edges {
            valence[*a as usize] += 1;
            valence[*b as usize] += 1;
        }
        (0..self.material.len())
            .map(|v| {
                if self.region[v] == VertexRegion::Singular && valence[v] > 0 {
                    params.plastic_angle / valence[v] as f64
                } else {
                    0.0
                }
            })
            .collect()
    }

    /// The pattern area of triangle `t` (m^2).
    fn triangle_area(&self, t: &[u32; 3]) -> f64 {
        let [a, b, c] = t.map(|i| self.material[i as usize]);
        0.5 * orient(&a, &b, &c).abs()
    }

    /// The hinge of interior edge (a, b) between the two triangles `tris` (each with
    /// its opposite vertex), oriented as in the first one: its rest angle is a preset
    /// crease's when the edge lies on one, else the singular shares `theta` of its
    /// ends with the sign of the current fold; its weight is 3 |e|^2 / (A_1 + A_2).
    fn hinge(
        &self,
        a: u32,
        b: u32,
        tris: &[(usize, u32)],
        theta: &[f64],
        preset: &[([Point2; 2], f64)],
    ) -> Hinge {
        // orient (v0, v1) as in the first triangle
        let t0 = &self.triangles[tris[0].0];
        let k = (0..3).find(|&k| t0[k] == a || t0[k] == b).unwrap_or(0);
        let (v0, v1) = if t0[k] == a && t0[(k + 1) % 3] == b || t0[(k + 2) % 3] == a && t0[k] == b {
            (a, b)
        } else {
            (b, a)
        };
        let (v2, v3) = (tris[0].1, tris[1].1);
        let e2 = (self.material[a as usize] - self.material[b as usize]).norm_squared();
        let areas = self.triangle_area(&self.triangles[tris[0].0])
            + self.triangle_area(&self.triangles[tris[1].0]);
        let mut rest = theta[a as usize] + theta[b as usize];
        let ma = self.material[a as usize];
        let mb = self.material[b as usize];
        let mut preset_rest = None;
        for (seg, angle) in preset {
            if point_segment(&ma, &seg[0], &seg[1]).0 < 1e-9
                && point_segment(&mb, &seg[0], &seg[1]).0 < 1e-9
            {
                preset_rest = Some(*angle);
            }
        }
        let hinge_v = [v0, v1, v2, v3];
        if let Some(angle) = preset_rest {
            rest = angle;
        } else if rest != 0.0 {
            // the plastic fold keeps the side it is bent to
            let current = signed_dihedral(&hinge_v.map(|i| self.position[i as usize].coords));
            if current < 0.0 {
                rest = -rest;
            }
        }
        Hinge {
            v: hinge_v,
            rest_angle: rest,
            weight: 3.0 * e2 / areas.max(1e-18),
        }
    }

    /// Lumped masses (kg): a third of each triangle's density x area to each corner.
    fn lump_masses(&mut self, params: &PaperParams) {
        self.mass = vec![0.0; self.material.len()];
        for ti in 0..self.triangles.len() {
            let t = self.triangles[ti];
            let m = params.density * self.triangle_area(&t) / 3.0;
            for &v in &t {
                self.mass[v as usize] += m;
            }
        }
    }
}

/// The position of a sample at pattern point `m` inside the sheet: interpolated, or
/// on S_G's flat triangle there (barycentric; the paper's), m. A point in no flat
/// triangle (a barycenter or a cap split, which only the interpolated placement
/// makes) falls back to the mean of S_G's vertices around it: the nearest S_G vertex.
fn sample_position(gmesh: &GeometricMesh, placement: Placement, m: &Point2) -> Point3 {
    if let Placement::Interpolated(at) = placement {
        return at(m);
    }
    let Some(f) = gmesh.flat_face_at(m) else {
        return gmesh
            .vertices
            .iter()
            .min_by(|a, b| (a.material - m).norm().total_cmp(&(b.material - m).norm()))
            .map_or(Point3::new(m.x, m.y, 0.0), |v| v.position);
    };
    let [a, b, c] = [0, 1, 2].map(|k| gmesh.faces[f].vertices[k] as usize);
    let (ma, mb, mc) = (
        gmesh.vertices[a].material,
        gmesh.vertices[b].material,
        gmesh.vertices[c].material,
    );
    let det = orient(&ma, &mb, &mc);
    let l1 = orient(&ma, m, &mc) / det;
    let l2 = orient(&ma, &mb, m) / det;
    let l0 = 1.0 - l1 - l2;
    Point3::from(
        gmesh.vertices[a].position.coords * l0
            + gmesh.vertices[b].position.coords * l1
            + gmesh.vertices[c].position.coords * l2,
    )
}

/// The preset creases of S_G (pattern segments, m) with their rest angles (rad).
fn preset_creases(layer: &GeometricLayer, gmesh: &GeometricMesh) -> Vec<([Point2; 2], f64)> {
    layer
        .creases
        .iter()
        .zip(&gmesh.crease_vertices)
        .filter_map(|(c, [a, b])| match c.kind {
            super::geometric::CreaseKind::Preset { rest_angle } => Some((
                [
                    gmesh.vertices[*a as usize].material,
                    gmesh.vertices[*b as usize].material,
                ],
                rest_angle,
            )),
            _ => None,
        })
        .collect()
}

/// Signed dihedral angle of hinge (x0, x1; x2 left, x3 right), rad: 0 flat, > 0 when
/// the two triangles fold towards their (common) normal side.
pub fn signed_dihedral(x: &[Vector3; 4]) -> f64 {
    let e = x[1] - x[0];
    let na = e.cross(&(x[2] - x[0]));
    let nb = (x[3] - x[0]).cross(&e);
    let el = e.norm();
    if el < 1e-300 || na.norm() < 1e-300 || nb.norm() < 1e-300 {
        return 0.0;
    }
    let sin = na.cross(&nb).dot(&e) / el;
    let cos = na.dot(&nb);
    sin.atan2(cos)
}
