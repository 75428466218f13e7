//! The paper's S_P triangles (sec. 4, fig. 4), kept for `length_restoration: paper`:
//! the constrained Delaunay triangulation outside the curved faces, and each curved
//! face as a fan around a new vertex at the barycenter of its S_G corners. A fan over a
//! long strip between two rulings makes caps (docs/paper_simulator.md, "S_P triangle
//! quality"); the default builds S_P with [`super::refine`] instead.

use super::{PhysicalMesh, SampleKind};
use crate::geometry::{Point2, Point3, Vector3};
use crate::paper::geometric::{edge_key, EdgeKind, FaceKind, GVertexKind, GeometricMesh};
use crate::paper::pattern::{in_convex_polygon, Pattern};

/// The triangles of `sp` (its vertices so far: S_G's and the samples) with every
/// curved face of `gmesh` as a fan; returns which vertices lie on a curved face.
pub(super) fn triangulate(
    sp: &mut PhysicalMesh,
    gmesh: &GeometricMesh,
    pattern: &Pattern,
) -> Result<Vec<bool>, String> {
    let chains: Vec<Vec<u32>> = gmesh
        .edges
        .iter()
        .filter(|(_, e)| matches!(e.kind, EdgeKind::Ruling { .. } | EdgeKind::Crease { .. }))
        .map(|(&(a, b), _)| vec![a, b])
        .collect();
    let cdt = sp.triangulate(&chains)?;
    let curved_faces = curved_face_polygons(sp, gmesh, pattern);
    let mut curved = vec![false; sp.material.len()];
    for (poly, _) in &curved_faces {
        for &v in poly {
            curved[v as usize] = true;
        }
    }
    add_triangles(sp, &cdt, &curved_faces);
    // the barycenters
    curved.resize(sp.material.len(), true);
    Ok(curved)
}

/// The polygon of each curved S_G face in S_P vertices (its corners with the boundary
/// samples lying on its boundary edges, in order) and its corners' pattern points.
fn curved_face_polygons(
    sp: &PhysicalMesh,
    gmesh: &GeometricMesh,
    pattern: &Pattern,
) -> Vec<(Vec<u32>, Vec<Point2>)> {
    let ng = gmesh.vertices.len();
    let per = pattern.perimeter();
    let boundary: Vec<(f64, u32)> = sp
        .boundary_arc
        .iter()
        .zip(&sp.boundary)
        .map(|(&s, &v)| (s, v))
        .collect();
    let mut curved_faces: Vec<(Vec<u32>, Vec<Point2>)> = Vec::new();
    for f in gmesh.faces.iter().filter(|f| f.kind != FaceKind::Flat) {
        let mut poly: Vec<u32> = Vec::new();
        let n = f.vertices.len();
        for i in 0..n {
            let (a, b) = (f.vertices[i], f.vertices[(i + 1) % n]);
            poly.push(a);
            let (GVertexKind::Boundary { s: sa }, GVertexKind::Boundary { s: sb }) = (
                gmesh.vertices[a as usize].kind,
                gmesh.vertices[b as usize].kind,
            ) else {
                continue;
            };
            let is_boundary_edge = gmesh
                .edges
                .get(&edge_key(a, b))
                .is_some_and(|e| e.kind == EdgeKind::Boundary);
            if !is_boundary_edge {
                continue;
            }
            // samples strictly between, in the direction a -> b
            let fwd = pattern.arc_ccw(sa, sb) < 0.5 * per;
            let (x, y) = if fwd { (sa, sb) } else { (sb, sa) };
            let mut between: Vec<(f64, u32)> = boundary
                .iter()
                .filter(|&&(s, v)| {
                    let da = pattern.arc_ccw(x, s);
                    (v as usize) >= ng && da > 0.0 && da < pattern.arc_ccw(x, y)
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
        let mats: Vec<Point2> = f
            .vertices
            .iter()
            .map(|&v| gmesh.vertices[v as usize].material)
            .collect();
        curved_faces.push((poly, mats));
    }
    curved_faces
}

/// The triangles: those of `cdt` outside the curved faces, then each curved face as a
/// fan around a new barycenter vertex (sec. 4, fig. 4), a triangle as itself.
fn add_triangles(
    sp: &mut PhysicalMesh,
    cdt: &spade::ConstrainedDelaunayTriangulation<spade::Point2<f64>>,
    curved_faces: &[(Vec<u32>, Vec<Point2>)],
) {
    use spade::Triangulation;
    let ng = sp.geometric_vertices;
    for face in cdt.inner_faces() {
        let vs = face.vertices().map(|v| v.fix().index() as u32);
        let m = vs.map(|v| sp.material[v as usize]);
        let c = Point2::from((m[0].coords + m[1].coords + m[2].coords) / 3.0);
        if curved_faces
            .iter()
            .any(|(_, p)| in_convex_polygon(p, &c, 0.0))
        {
            continue;
        }
        sp.triangles.push(vs);
    }
    for (poly, _) in curved_faces {
        if poly.len() == 3 {
            sp.triangles.push([poly[0], poly[1], poly[2]]);
            continue;
        }
        // barycenter of the S_G face (its corners), not of the samples
        let mut m = nalgebra::Vector2::zeros();
        let mut p = Vector3::zeros();
        let mut count = 0.0;
        for &v in poly {
            if (v as usize) < ng {
                m += sp.material[v as usize].coords;
                p += sp.position[v as usize].coords;
                count += 1.0;
            }
        }
        let c = sp.material.len() as u32;
        sp.material.push(Point2::from(m / count));
        sp.position.push(Point3::from(p / count));
        sp.kind.push(SampleKind::Barycenter);
        for i in 0..poly.len() {
            sp.triangles.push([c, poly[i], poly[(i + 1) % poly.len()]]);
        }
    }
}
