//! The physical mesh S_P (Schreck et al. sec. 4, fig. 4): S_G enriched with boundary
//! samples (density rho_bound) and interior samples of the flat regions (density
//! rho_int), Delaunay-connected with the rulings and creases of S_G kept, and the faces of the curved
//! regions split at their barycenter. S_P carries the state between frames (positions,
//! velocities) and is the mesh that is simulated (step 1), length-restored (step 3)
//! and displayed.

use std::collections::BTreeMap;

use super::geometric::{EdgeKind, FaceKind, GVertexKind, GeometricLayer, GeometricMesh};
use super::params::PaperParams;
use super::pattern::{in_convex_polygon, orient, point_segment, Pattern};
use crate::geometry::{Point2, Point3, Vector3, VertexRegion};

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

fn quantize(p: &Point2) -> (i64, i64) {
    ((p.x * 1e9).round() as i64, (p.y * 1e9).round() as i64)
}

/// Interpolates positions and velocities of an S_P at pattern points: exact at its
/// vertices, barycentric inside its triangles, cubic (Catmull-Rom) along its boundary
/// curve (sec. 5, appendix B: "cubic interpolation along the boundary curve given by
/// the mesh S_P").
pub struct Interpolator<'a> {
    mesh: &'a PhysicalMesh,
    exact: BTreeMap<(i64, i64), u32>,
    pattern: &'a Pattern,
}

impl<'a> Interpolator<'a> {
    pub fn new(mesh: &'a PhysicalMesh, pattern: &'a Pattern) -> Self {
        let exact = mesh
            .material
            .iter()
            .enumerate()
            .map(|(i, m)| (quantize(m), i as u32))
            .collect();
        Interpolator {
            mesh,
            exact,
            pattern,
        }
    }

    /// The vertex at `m`, if any.
    pub fn vertex_at(&self, m: &Point2) -> Option<u32> {
        self.exact.get(&quantize(m)).copied()
    }

    /// Barycentric coordinates of `m` in the best triangle (smallest violation).
    fn locate(&self, m: &Point2) -> Option<([u32; 3], [f64; 3])> {
        let mut best: Option<(f64, [u32; 3], [f64; 3])> = None;
        for t in &self.mesh.triangles {
            let [a, b, c] = t.map(|i| self.mesh.material[i as usize]);
            let det = orient(&a, &b, &c);
            if det.abs() < 1e-18 {
                continue;
            }
            let l1 = orient(&a, m, &c) / det;
            let l2 = orient(&a, &b, m) / det;
            let l0 = 1.0 - l1 - l2;
            let out = (-l0).max(-l1).max(-l2).max(0.0);
            if best.as_ref().is_none_or(|(o, _, _)| out < *o) {
                best = Some((out, *t, [l0, l1, l2]));
                if out == 0.0 {
                    break;
                }
            }
        }
        best.map(|(_, t, l)| (t, l))
    }

    /// World position at pattern point `m`, m.
    pub fn position(&self, m: &Point2) -> Point3 {
        if let Some(v) = self.vertex_at(m) {
            return self.mesh.position[v as usize];
        }
        if self.pattern.signed_inside_distance(m) < 1e-9 {
            if let Some(s) = self.pattern.arc_of(m, 1e-7) {
                return self.boundary_position(s);
            }
        }
        match self.locate(m) {
            Some((t, l)) => Point3::from(
                self.mesh.position[t[0] as usize].coords * l[0]
                    + self.mesh.position[t[1] as usize].coords * l[1]
                    + self.mesh.position[t[2] as usize].coords * l[2],
            ),
            None => Point3::new(m.x, m.y, 0.0),
        }
    }

    /// World position of the S_G vertex of kind `k` at pattern point `m`, m: the S_P
    /// vertex there if any, else on the boundary curve (boundary vertices) or inside
    /// S_P (singular vertices).
    pub fn geometric_vertex(&self, k: &GVertexKind, m: &Point2) -> Point3 {
        match k {
            GVertexKind::Boundary { s } => match self.vertex_at(m) {
                Some(v) => self.mesh.position[v as usize],
                None => self.boundary_position(*s),
            },
            GVertexKind::Singular { .. } => self.position(m),
        }
    }

    /// Velocity at pattern point `m`, m/s.
    pub fn velocity(&self, m: &Point2) -> Vector3 {
        if let Some(v) = self.vertex_at(m) {
            return self.mesh.velocity[v as usize];
        }
        match self.locate(m) {
            Some((t, l)) => {
                self.mesh.velocity[t[0] as usize] * l[0]
                    + self.mesh.velocity[t[1] as usize] * l[1]
                    + self.mesh.velocity[t[2] as usize] * l[2]
            }
            None => Vector3::zeros(),
        }
    }

    /// World position of the boundary point at arc length `s` by Catmull-Rom
    /// interpolation of the S_P boundary vertices of the same side (corners are kept
    /// sharp: the tangent at a side's end is the one-sided difference).
    pub fn boundary_position(&self, s: f64) -> Point3 {
        let b = &self.mesh.boundary;
        let arc = &self.mesh.boundary_arc;
        let n = b.len();
        if n < 2 {
            let m = self.pattern.point_at(s);
            return Point3::new(m.x, m.y, 0.0);
        }
        let s = self.pattern.wrap(s);
        // segment k: arc[k] <= s < arc[k+1] (cyclic)
        let k = match arc.partition_point(|&x| x <= s) {
            0 => n - 1,
            i => i - 1,
        };
        let k1 = (k + 1) % n;
        let per = self.pattern.perimeter();
        let len = self.pattern.arc_ccw(arc[k], arc[k1]).max(1e-15);
        let t = (self.pattern.arc_ccw(arc[k], s) / len).clamp(0.0, 1.0);
        let p1 = self.mesh.position[b[k] as usize].coords;
        let p2 = self.mesh.position[b[k1] as usize].coords;
        if t == 0.0 {
            return Point3::from(p1);
        }
        let side = self.pattern.side_of(arc[k] + 0.5 * len);
        let same_side = |i: usize| {
            let a = arc[i];
            // a corner belongs to both sides
            let is_corner = (0..self.pattern.corners().len())
                .any(|c| (self.pattern.corner_arc(c) - a).abs() < 1e-9 || (per - a).abs() < 1e-9);
            is_corner || self.pattern.side_of(a) == side
        };
        let (k0, k2) = ((k + n - 1) % n, (k1 + 1) % n);
        let corner_k = !same_side(k0) || self.is_corner(arc[k]);
        let corner_k1 = !same_side(k2) || self.is_corner(arc[k1]);
        let p0 = if corner_k {
            2.0 * p1 - p2
        } else {
            self.mesh.position[b[k0] as usize].coords
        };
        let p3 = if corner_k1 {
            2.0 * p2 - p1
        } else {
            self.mesh.position[b[k2] as usize].coords
        };
        // uniform Catmull-Rom
        let t2 = t * t;
        let t3 = t2 * t;
        let v = 0.5
            * ((2.0 * p1)
                + (-p0 + p2) * t
                + (2.0 * p0 - 5.0 * p1 + 4.0 * p2 - p3) * t2
                + (-p0 + 3.0 * p1 - 3.0 * p2 + p3) * t3);
        Point3::from(v)
    }

    fn is_corner(&self, s: f64) -> bool {
        let per = self.pattern.perimeter();
        (0..self.pattern.corners().len()).any(|c| {
            let d = (self.pattern.corner_arc(c) - s).abs();
            d < 1e-9 || (per - d).abs() < 1e-9
        })
    }
}

/// Build S_P from the mesh of S_G. Vertex positions: S_G vertices keep theirs; boundary
/// samples on a flat triangle's edge are on the straight edge, on a curved face's
/// boundary they follow `boundary_curve`; interior samples lie in their flat triangle;
/// barycenters are the mean of their face's vertices.
pub fn build_physical(
    gmesh: &GeometricMesh,
    layer: &GeometricLayer,
    pattern: &Pattern,
    params: &PaperParams,
    boundary_curve: &dyn Fn(f64) -> Point3,
) -> Result<PhysicalMesh, String> {
    let mut sp = PhysicalMesh::default();
    let ng = gmesh.vertices.len();
    sp.geometric_vertices = ng;
    for v in &gmesh.vertices {
        sp.material.push(v.material);
        sp.position.push(v.position);
        sp.kind.push(SampleKind::Geometric);
    }
    let boundary = sp.add_boundary_samples(gmesh, pattern, params, boundary_curve);
    sp.add_interior_samples(gmesh, pattern, params);
    let cdt = sp.triangulate(gmesh)?;
    let curved_faces = curved_face_polygons(gmesh, pattern, &boundary);
    let mut curved_of_vertex = vec![false; sp.material.len()];
    for (poly, _) in &curved_faces {
        for &v in poly {
            curved_of_vertex[v as usize] = true;
        }
    }
    sp.add_triangles(&cdt, &curved_faces);
    curved_of_vertex.resize(sp.material.len(), true);
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

/// The polygon of each curved S_G face in S_P vertices (its corners with the boundary
/// samples lying on its boundary edges, in order) and its corners' pattern points.
/// `boundary`: every S_P boundary vertex with its arc length, sorted.
fn curved_face_polygons(
    gmesh: &GeometricMesh,
    pattern: &Pattern,
    boundary: &[(f64, u32)],
) -> Vec<(Vec<u32>, Vec<Point2>)> {
    let ng = gmesh.vertices.len();
    let per = pattern.perimeter();
    let mut curved_faces: Vec<(Vec<u32>, Vec<Point2>)> = Vec::new();
    for f in &gmesh.faces {
        if f.kind == FaceKind::Flat {
            continue;
        }
        let mut poly: Vec<u32> = Vec::new();
        let n = f.vertices.len();
        for i in 0..n {
            let (a, b) = (f.vertices[i], f.vertices[(i + 1) % n]);
            poly.push(a);
            if let (GVertexKind::Boundary { s: sa }, GVertexKind::Boundary { s: sb }) = (
                gmesh.vertices[a as usize].kind,
                gmesh.vertices[b as usize].kind,
            ) {
                let is_boundary_edge = gmesh
                    .edges
                    .get(&super::geometric::edge_key(a, b))
                    .is_some_and(|e| e.kind == super::geometric::EdgeKind::Boundary);
                if is_boundary_edge {
                    // samples strictly between, in the direction a -> b
                    let fwd = pattern.arc_ccw(sa, sb) < 0.5 * per;
                    let mut between: Vec<(f64, u32)> = boundary
                        .iter()
                        .filter(|&&(s, v)| {
                            (v as usize) >= ng && {
                                let (x, y) = if fwd { (sa, sb) } else { (sb, sa) };
                                let da = pattern.arc_ccw(x, s);
                                da > 0.0 && da < pattern.arc_ccw(x, y)
                            }
                        })
                        .map(|&(s, v)| {
                            let key = if fwd {
                                pattern.arc_ccw(sa, s)
                            } else {
                                pattern.arc_ccw(s, sa)
                            };
                            (key, v)
                        })
                        .collect();
                    between.sort_by(|x, y| x.0.total_cmp(&y.0));
                    poly.extend(between.iter().map(|&(_, v)| v));
                }
            }
        }
        let mats: Vec<Point2> = f
            .vertices
            .iter()
            .map(|&v| gmesh.vertices[v as usize].material)
            .collect();
        curved_faces.push((poly, mats));
    }
    curved_faces
}

impl PhysicalMesh {
    /// Boundary samples (rho_bound): a fixed lattice of arc lengths (temporal
    /// coherence), kept away from the S_G boundary vertices. Sets `boundary` and
    /// `boundary_arc`; returns every boundary vertex with its arc length, sorted.
    fn add_boundary_samples(
        &mut self,
        gmesh: &GeometricMesh,
        pattern: &Pattern,
        params: &PaperParams,
        boundary_curve: &dyn Fn(f64) -> Point3,
    ) -> Vec<(f64, u32)> {
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
            let (s0, v0) = gb[i];
            let (s1, v1) = gb[j];
            let d0 = pattern.arc_ccw(s0, s);
            let d1 = pattern.arc_ccw(s, s1);
            if d0 < gap || d1 < gap {
                continue;
            }
            let faces = gmesh.edge_faces(v0, v1);
            let flat = faces
                .iter()
                .flatten()
                .all(|&f| gmesh.faces[f].kind == FaceKind::Flat);
            let m = pattern.point_at(s);
            let pos = if flat {
                let t = d0 / (d0 + d1);
                Point3::from(
                    gmesh.vertices[v0 as usize].position.coords * (1.0 - t)
                        + gmesh.vertices[v1 as usize].position.coords * t,
                )
            } else {
                boundary_curve(s)
            };
            boundary.push((s, self.material.len() as u32));
            self.material.push(m);
            self.position.push(pos);
            self.kind.push(SampleKind::BoundarySample { s });
        }
        boundary.sort_by(|a, b| a.0.total_cmp(&b.0));
        self.boundary = boundary.iter().map(|&(_, v)| v).collect();
        self.boundary_arc = boundary.iter().map(|&(s, _)| s).collect();
        boundary
    }

    /// Interior samples (rho_int): a fixed triangular lattice of spacing d, area per
    /// sample (sqrt 3 / 2) d^2 = 1 / rho_int, kept in the flat faces away from the
    /// S_G vertices, rulings and creases; each lies in its flat triangle.
    fn add_interior_samples(
        &mut self,
        gmesh: &GeometricMesh,
        pattern: &Pattern,
        params: &PaperParams,
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
        let curved_polys: Vec<Vec<Point2>> = gmesh
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
                let Some(f) = gmesh.flat_face_at(&p) else {
                    continue;
                };
                let [a, b, c] = [0, 1, 2].map(|k| gmesh.faces[f].vertices[k] as usize);
                let (ma, mb, mc) = (
                    gmesh.vertices[a].material,
                    gmesh.vertices[b].material,
                    gmesh.vertices[c].material,
                );
                let det = orient(&ma, &mb, &mc);
                let l1 = orient(&ma, &p, &mc) / det;
                let l2 = orient(&ma, &mb, &p) / det;
                let l0 = 1.0 - l1 - l2;
                let pos = Point3::from(
                    gmesh.vertices[a].position.coords * l0
                        + gmesh.vertices[b].position.coords * l1
                        + gmesh.vertices[c].position.coords * l2,
                );
                self.material.push(p);
                self.position.push(pos);
                self.kind.push(SampleKind::InteriorSample);
            }
        }
    }

    /// The constrained Delaunay triangulation of the vertices so far with the
    /// boundary (split at the samples) and every ruling and crease of S_G.
    fn triangulate(
        &self,
        gmesh: &GeometricMesh,
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
        for (&(a, b), e) in &gmesh.edges {
            if matches!(e.kind, EdgeKind::Ruling { .. } | EdgeKind::Crease { .. }) {
                constraints.push([a as usize, b as usize]);
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

    /// The triangles: those of `cdt` outside the curved faces, then each curved face
    /// as a fan around a new barycenter vertex (sec. 4, fig. 4), a triangle as itself.
    fn add_triangles(
        &mut self,
        cdt: &spade::ConstrainedDelaunayTriangulation<spade::Point2<f64>>,
        curved_faces: &[(Vec<u32>, Vec<Point2>)],
    ) {
        use spade::Triangulation;
        let ng = self.geometric_vertices;
        for face in cdt.inner_faces() {
            let vs = face.vertices().map(|v| v.fix().index() as u32);
            let m = vs.map(|v| self.material[v as usize]);
            let c = Point2::from((m[0].coords + m[1].coords + m[2].coords) / 3.0);
            if curved_faces
                .iter()
                .any(|(_, p)| in_convex_polygon(p, &c, 0.0))
            {
                continue;
            }
            self.triangles.push(vs);
        }
        for (poly, _) in curved_faces {
            if poly.len() == 3 {
                self.triangles.push([poly[0], poly[1], poly[2]]);
                continue;
            }
            // barycenter of the S_G face (its corners), not of the samples
            let mut m = nalgebra::Vector2::zeros();
            let mut p = Vector3::zeros();
            let mut count = 0.0;
            for &v in poly {
                if (v as usize) < ng {
                    m += self.material[v as usize].coords;
                    p += self.position[v as usize].coords;
                    count += 1.0;
                }
            }
            let c = self.material.len() as u32;
            self.material.push(Point2::from(m / count));
            self.position.push(Point3::from(p / count));
            self.kind.push(SampleKind::Barycenter);
            for i in 0..poly.len() {
                self.triangles
                    .push([c, poly[i], poly[(i + 1) % poly.len()]]);
            }
        }
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
