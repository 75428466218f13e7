//! [`GeometricMesh`], the mesh of S_G built from a [`GeometricLayer`]: vertices with
//! pattern and world positions, the curved faces between consecutive rulings, and the
//! flat triangles of a constrained Delaunay triangulation of the rest (Schreck et al.
//! sec. 3.2). Rebuilt after each edit of the structure.

use std::collections::BTreeMap;

use super::{Endpoint, GeometricLayer, MERGE_ARC};
use crate::geometry::{Point2, Point3, Vector3};
use crate::paper::pattern::{
    in_convex_polygon, newell_normal, polygon_area, segments_cross, Pattern,
};

/// What an S_G vertex is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum GVertexKind {
    /// On ∂S̄ at arc length `s` (corners, handle anchors, ruling ends, junction points).
    Boundary { s: f64 },
    /// An interior singular vertex.
    Singular { id: u64 },
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GVertex {
    pub material: Point2,
    pub position: Point3,
    pub kind: GVertexKind,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FaceKind {
    /// A triangle of a flat region.
    Flat,
    /// The face between rulings `face` and `face + 1` of curved region `region`
    /// (index into `GeometricLayer::regions`).
    Curved { region: usize, face: usize },
}

#[derive(Clone, Debug, PartialEq)]
pub struct GFace {
    /// Counter-clockwise in the pattern.
    pub vertices: Vec<u32>,
    pub kind: FaceKind,
}

/// What an S_G edge is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EdgeKind {
    /// An edge of the flat triangulation only.
    Plain,
    Boundary,
    Ruling {
        region: usize,
        index: usize,
    },
    Crease {
        index: usize,
    },
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GEdge {
    pub faces: [Option<usize>; 2],
    pub kind: EdgeKind,
}

/// The mesh of S_G (see the module doc).
#[derive(Clone, Debug, Default)]
pub struct GeometricMesh {
    pub vertices: Vec<GVertex>,
    pub faces: Vec<GFace>,
    /// Boundary vertices in arc-length order.
    pub boundary: Vec<u32>,
    /// Undirected edges (lower index first).
    pub edges: BTreeMap<(u32, u32), GEdge>,
    /// World unit normal of each face (Newell), oriented with the pattern's +z.
    pub normals: Vec<Vector3>,
    /// Each region's rulings as vertex pairs (a, b).
    pub ruling_vertices: Vec<Vec<[u32; 2]>>,
    /// Each crease as a vertex pair.
    pub crease_vertices: Vec<[u32; 2]>,
}

/// Why the structure does not give a valid mesh.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum MeshError {
    #[error("segments cross: {0}")]
    Crossing(String),
    #[error("an endpoint is not a vertex: {0}")]
    MissingEndpoint(String),
    #[error("invalid curved face: {0}")]
    BadFace(String),
    #[error("triangulation: {0}")]
    Triangulation(String),
}

pub fn edge_key(a: u32, b: u32) -> (u32, u32) {
    if a < b {
        (a, b)
    } else {
        (b, a)
    }
}

/// The arc lengths of the S_G boundary vertices, m: corners, handle anchors and the
/// boundary ends of rulings and creases, sorted and merged within [`MERGE_ARC`]. An
/// error when two are closer than the layer's `min_boundary_spacing`.
fn boundary_arcs(layer: &GeometricLayer, pattern: &Pattern) -> Result<Vec<f64>, MeshError> {
    let mut arcs: Vec<f64> = (0..pattern.corners().len())
        .map(|i| pattern.corner_arc(i))
        .collect();
    arcs.extend(layer.anchors.iter().map(|&s| pattern.wrap(s)));
    let push_end = |e: &Endpoint, arcs: &mut Vec<f64>| {
        if let Endpoint::Boundary(s) = e {
            arcs.push(pattern.wrap(*s));
        }
    };
    for r in &layer.regions {
        for ru in &r.rulings {
            push_end(&ru.a, &mut arcs);
            push_end(&ru.b, &mut arcs);
        }
    }
    for c in &layer.creases {
        push_end(&c.a, &mut arcs);
        push_end(&c.b, &mut arcs);
    }
    arcs.sort_by(f64::total_cmp);
    let per = pattern.perimeter();
    let mut merged: Vec<f64> = Vec::with_capacity(arcs.len());
    for s in arcs {
        if merged.last().is_none_or(|&l| s - l > MERGE_ARC) {
            merged.push(s);
        }
    }
    if merged.len() > 1 && per - merged[merged.len() - 1] + merged[0] <= MERGE_ARC {
        merged.pop();
    }
    if layer.min_boundary_spacing > 0.0 && merged.len() > 1 {
        for i in 0..merged.len() {
            let next = if i + 1 < merged.len() {
                merged[i + 1]
            } else {
                merged[0] + per
            };
            if next - merged[i] < layer.min_boundary_spacing {
                return Err(MeshError::BadFace(format!(
                    "boundary vertices {} m apart (< {} m)",
                    next - merged[i],
                    layer.min_boundary_spacing
                )));
            }
        }
    }
    Ok(merged)
}

/// The S_G vertex an endpoint stands for: `merged` holds the boundary vertices' arc
/// lengths (vertex i at merged[i]), `singular_index` the singular vertices' indices.
fn endpoint_index(
    e: &Endpoint,
    pattern: &Pattern,
    merged: &[f64],
    singular_index: &BTreeMap<u64, u32>,
) -> Result<u32, MeshError> {
    match e {
        Endpoint::Boundary(s) => {
            let per = pattern.perimeter();
            let s = pattern.wrap(*s);
            let i = merged.partition_point(|&x| x < s - MERGE_ARC);
            for cand in [i, 0, merged.len().saturating_sub(1)] {
                if let Some(&x) = merged.get(cand) {
                    let d = (x - s).abs().min(per - (x - s).abs());
                    if d <= MERGE_ARC * 1.5 {
                        return Ok(cand as u32);
                    }
                }
            }
            Err(MeshError::MissingEndpoint(format!("boundary s = {s}")))
        }
        Endpoint::Singular(id) => singular_index
            .get(id)
            .copied()
            .ok_or_else(|| MeshError::MissingEndpoint(format!("singular {id}"))),
    }
}

/// The segments the triangulations must keep: the boundary edges first (`nb` of
/// them), then the rulings region by region, then the creases; and each one's kind.
struct Constraints {
    segments: Vec<[usize; 2]>,
    kinds: BTreeMap<(u32, u32), EdgeKind>,
    nb: usize,
}

impl GeometricMesh {
    /// Build the mesh of `layer`. `position` gives the world position of a vertex
    /// from its kind and pattern position (the current S_P, interpolated).
    pub fn build(
        layer: &GeometricLayer,
        pattern: &Pattern,
        position: &dyn Fn(&GVertexKind, &Point2) -> Point3,
    ) -> Result<GeometricMesh, MeshError> {
        let merged = boundary_arcs(layer, pattern)?;
        let (mut mesh, singular_index) =
            GeometricMesh::with_vertices(layer, pattern, &merged, position);
        let index_of = |e: &Endpoint| endpoint_index(e, pattern, &merged, &singular_index);
        let constraints = mesh.constraint_segments(layer, &index_of)?;
        let seg_pts = mesh.check_segments(pattern, &constraints)?;
        let cdt = mesh.triangulate(&constraints)?;
        let curved = mesh.curved_faces(layer, constraints.nb)?;
        mesh.add_faces(&cdt, curved, &seg_pts)?;
        mesh.add_edges_and_normals(&constraints.kinds)?;
        Ok(mesh)
    }

    /// A mesh holding only the vertices: the boundary vertices at the arc lengths
    /// `merged` (in that order), then the singular vertices; and the singular
    /// vertices' indices by id.
    fn with_vertices(
        layer: &GeometricLayer,
        pattern: &Pattern,
        merged: &[f64],
        position: &dyn Fn(&GVertexKind, &Point2) -> Point3,
    ) -> (GeometricMesh, BTreeMap<u64, u32>) {
        let mut mesh = GeometricMesh::default();
        for &s in merged {
            let m = pattern.point_at(s);
            let kind = GVertexKind::Boundary { s };
            mesh.vertices.push(GVertex {
                material: m,
                position: position(&kind, &m),
                kind,
            });
        }
        mesh.boundary = (0..merged.len() as u32).collect();
        let mut singular_index = BTreeMap::new();
        for sv in &layer.singular {
            let kind = GVertexKind::Singular { id: sv.id };
            singular_index.insert(sv.id, mesh.vertices.len() as u32);
            mesh.vertices.push(GVertex {
                material: sv.material,
                position: position(&kind, &sv.material),
                kind,
            });
        }
        (mesh, singular_index)
    }

    /// The boundary edges, rulings and creases as vertex pairs (fills
    /// `ruling_vertices` and `crease_vertices`); an error for a ruling or crease with
    /// equal ends, on the boundary, or duplicating another edge.
    fn constraint_segments(
        &mut self,
        layer: &GeometricLayer,
        index_of: &dyn Fn(&Endpoint) -> Result<u32, MeshError>,
    ) -> Result<Constraints, MeshError> {
        let nb = self.boundary.len();
        let mut segments: Vec<[usize; 2]> = Vec::new();
        let mut kinds: BTreeMap<(u32, u32), EdgeKind> = BTreeMap::new();
        for i in 0..nb {
            let (a, b) = (i as u32, ((i + 1) % nb) as u32);
            segments.push([a as usize, b as usize]);
            kinds.insert(edge_key(a, b), EdgeKind::Boundary);
        }
        for (ri, r) in layer.regions.iter().enumerate() {
            let mut rv = Vec::with_capacity(r.rulings.len());
            for (k, ru) in r.rulings.iter().enumerate() {
                let (a, b) = (index_of(&ru.a)?, index_of(&ru.b)?);
                if a == b {
                    return Err(MeshError::BadFace(format!(
                        "ruling {k} of region {} has equal ends",
                        r.id
                    )));
                }
                rv.push([a, b]);
                let key = edge_key(a, b);
                if let Some(EdgeKind::Boundary) = kinds.get(&key) {
                    return Err(MeshError::BadFace("a ruling lies on the boundary".into()));
                }
                if kinds.contains_key(&key) {
                    return Err(MeshError::Crossing("two rulings share both ends".into()));
                }
                kinds.insert(
                    key,
                    EdgeKind::Ruling {
                        region: ri,
                        index: k,
                    },
                );
                segments.push([a as usize, b as usize]);
            }
            self.ruling_vertices.push(rv);
        }
        for (ci, c) in layer.creases.iter().enumerate() {
            let (a, b) = (index_of(&c.a)?, index_of(&c.b)?);
            if a == b {
                return Err(MeshError::BadFace("crease with equal ends".into()));
            }
            let key = edge_key(a, b);
            if kinds.contains_key(&key) {
                return Err(MeshError::Crossing("a crease duplicates an edge".into()));
            }
            kinds.insert(key, EdgeKind::Crease { index: ci });
            segments.push([a as usize, b as usize]);
            self.crease_vertices.push([a, b]);
        }
        Ok(Constraints {
            segments,
            kinds,
            nb,
        })
    }

    /// The rulings and creases in the pattern; an error when two cross, when one
    /// passes through a vertex or when one is not inside the sheet.
    fn check_segments(
        &self,
        pattern: &Pattern,
        constraints: &Constraints,
    ) -> Result<Vec<[Point2; 2]>, MeshError> {
        let nb = constraints.nb;
        let seg_pts: Vec<[Point2; 2]> = constraints
            .segments
            .iter()
            .skip(nb)
            .map(|[a, b]| [self.vertices[*a].material, self.vertices[*b].material])
            .collect();
        for i in 0..seg_pts.len() {
            for j in 0..i {
                if segments_cross(
                    &seg_pts[i][0],
                    &seg_pts[i][1],
                    &seg_pts[j][0],
                    &seg_pts[j][1],
                    1e-9,
                ) {
                    return Err(MeshError::Crossing(format!("segments {i} and {j}")));
                }
            }
            let [a, b] = constraints.segments[nb + i];
            for (vi, v) in self.vertices.iter().enumerate() {
                if vi == a || vi == b {
                    continue;
                }
                let (d, t) = crate::paper::pattern::point_segment(
                    &v.material,
                    &seg_pts[i][0],
                    &seg_pts[i][1],
                );
                if d < 1e-7 && t > 0.0 && t < 1.0 {
                    return Err(MeshError::Crossing(format!(
                        "segment {i} passes through vertex {vi}"
                    )));
                }
            }
            let mid = Point2::from((seg_pts[i][0].coords + seg_pts[i][1].coords) * 0.5);
            if !pattern.contains(&mid, 1e-9) || pattern.signed_inside_distance(&mid) < 1e-9 {
                return Err(MeshError::BadFace(format!(
                    "segment {i} is not inside the sheet"
                )));
            }
        }
        Ok(seg_pts)
    }

    /// The constrained Delaunay triangulation of the vertices with every segment.
    fn triangulate(
        &self,
        constraints: &Constraints,
    ) -> Result<spade::ConstrainedDelaunayTriangulation<spade::Point2<f64>>, MeshError> {
        let pts: Vec<spade::Point2<f64>> = self
            .vertices
            .iter()
            .map(|v| spade::Point2::new(v.material.x, v.material.y))
            .collect();
        let mut conflict = false;
        let cdt = spade::ConstrainedDelaunayTriangulation::<spade::Point2<f64>>::try_bulk_load_cdt(
            pts,
            constraints.segments.clone(),
            |_| conflict = true,
        )
        .map_err(|e| MeshError::Triangulation(format!("{e:?}")))?;
        if conflict {
            return Err(MeshError::Crossing(
                "constraint conflict in the triangulation".into(),
            ));
        }
        use spade::Triangulation;
        if cdt.num_vertices() != self.vertices.len() {
            return Err(MeshError::Triangulation("duplicate vertices".into()));
        }
        Ok(cdt)
    }

    /// The curved faces between consecutive rulings of each region, counter-clockwise
    /// in the pattern (`nb` boundary vertices).
    fn curved_faces(
        &self,
        layer: &GeometricLayer,
        nb: usize,
    ) -> Result<Vec<(Vec<u32>, FaceKind)>, MeshError> {
        let mut curved_polys: Vec<(Vec<u32>, FaceKind)> = Vec::new();
        for (ri, rv) in self.ruling_vertices.iter().enumerate() {
            for k in 0..rv.len().saturating_sub(1) {
                let [a0, b0] = rv[k];
                let [a1, b1] = rv[k + 1];
                // the chains along ∂S̄ between consecutive ruling ends pass no other end
                // of this region's rulings (the shorter one when both qualify)
                let mut others: Vec<u32> = rv.iter().flat_map(|r| [r[0], r[1]]).collect();
                let avoid_a: Vec<u32> = others
                    .iter()
                    .copied()
                    .filter(|&v| v != a0 && v != a1)
                    .collect();
                others.retain(|&v| v != b0 && v != b1);
                let chain_a = self.boundary_chain(a0, a1, &avoid_a, nb)?;
                let chain_b = self.boundary_chain(b1, b0, &others, nb)?;
                let mut poly: Vec<u32> = chain_a;
                poly.extend(chain_b);
                poly.dedup();
                if poly.len() > 1 && poly[0] == poly[poly.len() - 1] {
                    poly.pop();
                }
                if poly.len() < 3 {
                    return Err(MeshError::BadFace(format!(
                        "face {k} of region {} is degenerate",
                        layer.regions[ri].id
                    )));
                }
                let mat: Vec<Point2> = poly
                    .iter()
                    .map(|&v| self.vertices[v as usize].material)
                    .collect();
                let area = polygon_area(&mat);
                if area.abs() < 1e-12 {
                    return Err(MeshError::BadFace(format!(
                        "face {k} of region {} has no area",
                        layer.regions[ri].id
                    )));
                }
                if area < 0.0 {
                    poly.reverse();
                }
                curved_polys.push((
                    poly,
                    FaceKind::Curved {
                        region: ri,
                        face: k,
                    },
                ));
            }
        }
        Ok(curved_polys)
    }

    /// The faces: the curved ones, then the triangles of `cdt` outside them (flat).
    /// An error when a segment runs through a curved face or when the triangles do
    /// not tile a curved face exactly (it is not convex or holds a vertex).
    fn add_faces(
        &mut self,
        cdt: &spade::ConstrainedDelaunayTriangulation<spade::Point2<f64>>,
        curved_polys: Vec<(Vec<u32>, FaceKind)>,
        seg_pts: &[[Point2; 2]],
    ) -> Result<(), MeshError> {
        use spade::Triangulation;
        let curved_mats: Vec<Vec<Point2>> = curved_polys
            .iter()
            .map(|(p, _)| {
                p.iter()
                    .map(|&v| self.vertices[v as usize].material)
                    .collect()
            })
            .collect();
        // a curved face is one developable strip between two consecutive rulings: no
        // other ruling nor crease may run through it (a preset crease as a diagonal of
        // a face, its ends both on the face's boundary chains, would be fanned away in
        // S_P and lose its rest angle)
        for (k, poly) in curved_mats.iter().enumerate() {
            for (i, [p, q]) in seg_pts.iter().enumerate() {
                let mid = Point2::from((p.coords + q.coords) * 0.5);
                if in_convex_polygon(poly, &mid, 1e-9) {
                    return Err(MeshError::Crossing(format!(
                        "segment {i} runs through curved face {k}"
                    )));
                }
            }
        }
        let mut covered = vec![0.0; curved_polys.len()];
        let mut flat = Vec::new();
        for f in cdt.inner_faces() {
            let vs = f.vertices().map(|v| v.fix().index() as u32);
            let m = vs.map(|v| self.vertices[v as usize].material);
            let c = Point2::from((m[0].coords + m[1].coords + m[2].coords) / 3.0);
            let area = polygon_area(&m);
            match curved_mats
                .iter()
                .position(|poly| in_convex_polygon(poly, &c, 0.0))
            {
                Some(k) => covered[k] += area,
                None => flat.push(vs),
            }
        }
        for (k, poly) in curved_mats.iter().enumerate() {
            let area = polygon_area(poly);
            if (covered[k] - area).abs() > 1e-6 * area.max(1e-12) + 1e-15 {
                return Err(MeshError::BadFace(format!(
                    "curved face {k} is not convex or contains a vertex"
                )));
            }
        }
        for (poly, kind) in curved_polys {
            self.faces.push(GFace {
                vertices: poly,
                kind,
            });
        }
        for vs in flat {
            self.faces.push(GFace {
                vertices: vs.to_vec(),
                kind: FaceKind::Flat,
            });
        }
        Ok(())
    }

    /// Edges (with their faces and `kinds`, plain otherwise) and face normals.
    fn add_edges_and_normals(
        &mut self,
        kinds: &BTreeMap<(u32, u32), EdgeKind>,
    ) -> Result<(), MeshError> {
        for (fi, f) in self.faces.iter().enumerate() {
            let n = f.vertices.len();
            for i in 0..n {
                let key = edge_key(f.vertices[i], f.vertices[(i + 1) % n]);
                let kind = kinds.get(&key).copied().unwrap_or(EdgeKind::Plain);
                let e = self.edges.entry(key).or_insert(GEdge {
                    faces: [None, None],
                    kind,
                });
                if e.faces[0].is_none() {
                    e.faces[0] = Some(fi);
                } else if e.faces[1].is_none() {
                    e.faces[1] = Some(fi);
                } else {
                    return Err(MeshError::BadFace("an edge with three faces".into()));
                }
            }
        }
        self.normals = self
            .faces
            .iter()
            .map(|f| {
                let pts: Vec<Point3> = f
                    .vertices
                    .iter()
                    .map(|&v| self.vertices[v as usize].position)
                    .collect();
                newell_normal(&pts)
            })
            .collect();
        Ok(())
    }

    /// The boundary vertices from `from` to `to` (both included) along ∂S̄, in the
    /// direction that does not pass any of `avoid`. A single vertex when equal.
    fn boundary_chain(
        &self,
        from: u32,
        to: u32,
        avoid: &[u32],
        nb: usize,
    ) -> Result<Vec<u32>, MeshError> {
        if from == to {
            return Ok(vec![from]);
        }
        let on_boundary = |v: u32| (v as usize) < nb;
        if !on_boundary(from) || !on_boundary(to) {
            return Err(MeshError::BadFace(
                "consecutive rulings end on a singular vertex and on the boundary on the same side"
                    .into(),
            ));
        }
        let mut best: Option<Vec<u32>> = None;
        for dir in [1i64, -1] {
            let mut chain = vec![from];
            let mut v = from as i64;
            let mut ok = true;
            loop {
                v = (v + dir).rem_euclid(nb as i64);
                chain.push(v as u32);
                if v as u32 == to {
                    break;
                }
                if avoid.contains(&(v as u32)) {
                    ok = false;
                    break;
                }
            }
            let length = |c: &[u32]| -> f64 {
                c.windows(2)
                    .map(|w| {
                        (self.vertices[w[1] as usize].material
                            - self.vertices[w[0] as usize].material)
                            .norm()
                    })
                    .sum()
            };
            if ok && best.as_ref().is_none_or(|b| length(&chain) < length(b)) {
                best = Some(chain);
            }
        }
        if let Some(chain) = best {
            return Ok(chain);
        }
        Err(MeshError::BadFace(
            "no boundary chain between two rulings".into(),
        ))
    }

    /// Unsigned dihedral angle across edge (a, b), rad; None on the boundary.
    pub fn dihedral(&self, a: u32, b: u32) -> Option<f64> {
        let e = self.edges.get(&edge_key(a, b))?;
        let (f0, f1) = (e.faces[0]?, e.faces[1]?);
        let c = self.normals[f0].dot(&self.normals[f1]).clamp(-1.0, 1.0);
        Some(c.acos())
    }

    /// Region index (into the layer) of a face, if curved.
    pub fn face_region(&self, f: usize) -> Option<usize> {
        match self.faces[f].kind {
            FaceKind::Curved { region, .. } => Some(region),
            FaceKind::Flat => None,
        }
    }

    /// Faces on both sides of edge (a, b).
    pub fn edge_faces(&self, a: u32, b: u32) -> [Option<usize>; 2] {
        self.edges
            .get(&edge_key(a, b))
            .map(|e| e.faces)
            .unwrap_or([None, None])
    }

    /// Area of face `f` in the pattern, m^2.
    pub fn face_area(&self, f: usize) -> f64 {
        let m: Vec<Point2> = self.faces[f]
            .vertices
            .iter()
            .map(|&v| self.vertices[v as usize].material)
            .collect();
        polygon_area(&m)
    }

    /// The flat face (triangle) containing pattern point `p`, if any.
    pub fn flat_face_at(&self, p: &Point2) -> Option<usize> {
        self.faces.iter().position(|f| {
            f.kind == FaceKind::Flat && {
                let m: Vec<Point2> = f
                    .vertices
                    .iter()
                    .map(|&v| self.vertices[v as usize].material)
                    .collect();
                in_convex_polygon(&m, p, -1e-12)
            }
        })
    }

    /// Any face containing `p`.
    pub fn face_at(&self, p: &Point2) -> Option<usize> {
        self.faces.iter().position(|f| {
            let m: Vec<Point2> = f
                .vertices
                .iter()
                .map(|&v| self.vertices[v as usize].material)
                .collect();
            in_convex_polygon(&m, p, -1e-12)
        })
    }

    /// The endpoint an S_G vertex stands for.
    pub fn endpoint_of(&self, v: u32) -> Endpoint {
        match self.vertices[v as usize].kind {
            GVertexKind::Boundary { s } => Endpoint::Boundary(s),
            GVertexKind::Singular { id } => Endpoint::Singular(id),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::paper::geometric::{Crease, CreaseKind, Ruling};

    fn flat_position(_: &GVertexKind, m: &Point2) -> Point3 {
        Point3::new(m.x, m.y, 0.0)
    }

    #[test]
    fn a_flat_sheet_is_two_triangles_and_a_band_of_rulings_makes_quads() {
        let pattern = Pattern::rectangle(0.1, 0.1);
        let mut layer = GeometricLayer::default();
        let mesh = GeometricMesh::build(&layer, &pattern, &flat_position).unwrap();
        assert_eq!(mesh.vertices.len(), 4);
        assert_eq!(mesh.faces.len(), 2);
        // three parallel rulings across the sheet (u = 0.03, 0.05, 0.07)
        let mut rulings = Vec::new();
        for u in [0.03, 0.05, 0.07] {
            rulings.push(Ruling {
                a: Endpoint::Boundary(u),
                b: Endpoint::Boundary(0.3 - u),
            });
        }
        layer.add_region(rulings);
        let mesh = GeometricMesh::build(&layer, &pattern, &flat_position).unwrap();
        let curved = mesh
            .faces
            .iter()
            .filter(|f| f.kind != FaceKind::Flat)
            .count();
        assert_eq!(curved, 2);
        let total: f64 = (0..mesh.faces.len()).map(|f| mesh.face_area(f)).sum();
        assert!(
            (total - 0.01).abs() < 1e-12,
            "faces tile the sheet: {total}"
        );
        // crossing segments are rejected
        layer.creases.push(Crease {
            a: Endpoint::Boundary(0.05),
            b: Endpoint::Boundary(0.35),
            kind: CreaseKind::Plastic,
        });
        assert!(GeometricMesh::build(&layer, &pattern, &flat_position).is_err());
    }

    #[test]
    fn a_curved_face_straddling_a_crease_is_rejected() {
        // the preset crease u = 0.05 and a region whose last ruling leaves its top end
        // towards the other side: the face between the rulings has the crease as a
        // diagonal (no segment crosses another, the faces still tile the sheet)
        let pattern = Pattern::rectangle(0.1, 0.1);
        let mut layer = GeometricLayer::default();
        layer.creases.push(Crease {
            a: Endpoint::Boundary(0.05),
            b: Endpoint::Boundary(0.25),
            kind: CreaseKind::Preset { rest_angle: 1.2 },
        });
        let ruling = |bottom: f64, top_u: f64| Ruling {
            a: Endpoint::Boundary(bottom),
            b: Endpoint::Boundary(0.3 - top_u),
        };
        layer.add_region(vec![ruling(0.07, 0.07), ruling(0.06, 0.06)]);
        assert!(GeometricMesh::build(&layer, &pattern, &flat_position).is_ok());
        layer.regions[0].rulings.push(ruling(0.04, 0.05));
        let err = GeometricMesh::build(&layer, &pattern, &flat_position).unwrap_err();
        assert!(matches!(err, MeshError::Crossing(_)), "{err}");
    }

    #[test]
    fn a_cone_fan_around_a_singular_vertex_meshes() {
        let pattern = Pattern::rectangle(0.1, 0.1);
        let mut layer = GeometricLayer::default();
        let s = layer.add_singular(Point2::new(0.05, 0.05));
        let rulings = [0.02, 0.04, 0.06, 0.08]
            .iter()
            .map(|&u| Ruling {
                a: Endpoint::Singular(s),
                b: Endpoint::Boundary(u),
            })
            .collect();
        layer.add_region(rulings);
        let mesh = GeometricMesh::build(&layer, &pattern, &flat_position).unwrap();
        let curved: Vec<&GFace> = mesh
            .faces
            .iter()
            .filter(|f| f.kind != FaceKind::Flat)
            .collect();
        assert_eq!(curved.len(), 3);
        assert!(curved.iter().all(|f| f.vertices.len() == 3));
        assert_eq!(layer.regions[0].singular_apex(), Some(s));
    }
}
