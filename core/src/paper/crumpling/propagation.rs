//! Appendix A of Schreck et al.: the imaginary rulings of T_comp propagated through
//! its flat region along v_perp (the four cases of fig. 6) until they meet a border
//! on each side.

use nalgebra::Vector2;

use super::outcome::Unchanged;
use crate::paper::geometric::{edge_key, EdgeKind, Endpoint, FaceKind, GVertexKind, GeometricMesh};

/// Where a propagated strip of imaginary rulings ends (fig. 6, fig. 23).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Border {
    /// Fig. 6(b): an edge of ∂S̄, free to bend.
    Boundary,
    /// Fig. 6(c): an edge shared with another flat region (dihedral > theta_0) or a
    /// crease, given by its ends.
    FlatFold { a: Endpoint, b: Endpoint },
    /// Fig. 6(d): ruling `ruling` of the curved region with id `region`.
    CurvedRuling { region: u64, ruling: usize },
    /// Fig. 23 (bottom): a singular vertex of T_comp opposite the crossed edge.
    Singular { id: u64 },
}

/// The triangle strip of appendix A.
#[derive(Clone, Debug, PartialEq)]
pub struct Strip {
    /// T_comp first, then the collected triangles of F.
    pub faces: Vec<usize>,
    /// Borders in the +v_perp and -v_perp directions.
    pub borders: [Border; 2],
    /// The last face of F on each side (the side of F a border is seen from).
    pub last_faces: [usize; 2],
}

/// Outward normal (pattern) of edge k of face f (vertices k -> k+1, counter-clockwise).
fn edge_outward(gmesh: &GeometricMesh, f: usize, k: usize) -> (u32, u32, Vector2<f64>) {
    let vs = &gmesh.faces[f].vertices;
    let (a, b) = (vs[k], vs[(k + 1) % vs.len()]);
    let d = gmesh.vertices[b as usize].material - gmesh.vertices[a as usize].material;
    (a, b, Vector2::new(d.y, -d.x))
}

/// |sin| of the angle between edge (a, b) and `dir`.
fn edge_angle(gmesh: &GeometricMesh, a: u32, b: u32, dir: &Vector2<f64>) -> f64 {
    let d = (gmesh.vertices[b as usize].material - gmesh.vertices[a as usize].material).normalize();
    (d.x * dir.y - d.y * dir.x).abs()
}

/// Appendix A: propagate the imaginary rulings of `t_comp` (a flat triangle of the
/// region `labels[t_comp]`) along `v_perp` in both directions; the reason when it
/// does not reach a border on each side.
pub fn propagate(
    gmesh: &GeometricMesh,
    labels: &[usize],
    t_comp: usize,
    v_perp: &Vector2<f64>,
) -> Result<Strip, Unchanged> {
    let face = &gmesh.faces[t_comp];
    if face.vertices.len() != 3 || face.kind != FaceKind::Flat {
        return Err(Unchanged::NoTriangle);
    }
    // the two edges most crossed by the rulings (largest angle with v_perp), one
    // facing +v_perp and one facing -v_perp
    let edges: Vec<(usize, f64, f64)> = (0..3)
        .map(|k| {
            let (a, b, n) = edge_outward(gmesh, t_comp, k);
            (k, edge_angle(gmesh, a, b, v_perp), n.dot(v_perp))
        })
        .collect();
    let first = edges
        .iter()
        .copied()
        .max_by(|x, y| x.1.total_cmp(&y.1))
        .ok_or(Unchanged::NoTriangle)?;
    let second = edges
        .iter()
        .copied()
        .filter(|e| e.0 != first.0 && e.2 * first.2 < 0.0)
        .max_by(|x, y| x.1.total_cmp(&y.1))
        .ok_or(Unchanged::NoTriangle)?;
    let mut strip = Strip {
        faces: vec![t_comp],
        borders: [Border::Boundary, Border::Boundary],
        last_faces: [t_comp, t_comp],
    };
    for (k, _, facing) in [first, second] {
        let side = if facing > 0.0 { 0 } else { 1 };
        let dir = if facing > 0.0 { *v_perp } else { -v_perp };
        // fig. 23 bottom: the singular vertex opposite the largest-angle edge is the
        // border on the other side
        if k == first.0 {
            let opposite = face.vertices[(k + 2) % 3];
            if let GVertexKind::Singular { id } = gmesh.vertices[opposite as usize].kind {
                strip.borders[1 - side] = Border::Singular { id };
                strip.borders[side] = walk(
                    gmesh,
                    labels,
                    t_comp,
                    k,
                    &dir,
                    &mut strip.faces,
                    &mut strip.last_faces[side],
                )?;
                return Ok(strip);
            }
        }
        strip.borders[side] = walk(
            gmesh,
            labels,
            t_comp,
            k,
            &dir,
            &mut strip.faces,
            &mut strip.last_faces[side],
        )?;
    }
    Ok(strip)
}

/// Walk from face `f` through its edge `k` in direction `dir` (appendix A).
fn walk(
    gmesh: &GeometricMesh,
    labels: &[usize],
    f: usize,
    k: usize,
    dir: &Vector2<f64>,
    faces: &mut Vec<usize>,
    last: &mut usize,
) -> Result<Border, Unchanged> {
    let (mut cur, mut a, mut b) = {
        let (a, b, _) = edge_outward(gmesh, f, k);
        (f, a, b)
    };
    for _ in 0..10_000 {
        *last = cur;
        let e = gmesh
            .edges
            .get(&edge_key(a, b))
            .ok_or(Unchanged::StripLost)?;
        let other = e.faces.iter().flatten().copied().find(|&g| g != cur);
        let Some(g) = other else {
            return Ok(Border::Boundary); // fig. 6(b)
        };
        match (gmesh.faces[g].kind, e.kind) {
            (FaceKind::Curved { .. }, EdgeKind::Ruling { region, index })
            | (FaceKind::Flat, EdgeKind::Ruling { region, index }) => {
                return Ok(Border::CurvedRuling {
                    region: region as u64, // region index, mapped to an id by the caller
                    ruling: index,
                }); // fig. 6(d)
            }
            (FaceKind::Curved { .. }, _) => return Err(Unchanged::StripIntoCurved),
            (FaceKind::Flat, EdgeKind::Crease { .. }) => {
                return Ok(Border::FlatFold {
                    a: gmesh.endpoint_of(a),
                    b: gmesh.endpoint_of(b),
                });
            }
            (FaceKind::Flat, _) if labels[g] != labels[cur] => {
                return Ok(Border::FlatFold {
                    a: gmesh.endpoint_of(a),
                    b: gmesh.endpoint_of(b),
                }); // fig. 6(c)
            }
            _ => {}
        }
        // fig. 6(a): same flat region, continue through the edge of g (other than e)
        // forming the greatest angle with dir, ahead of us
        if faces.contains(&g) {
            return Err(Unchanged::StripLost);
        }
        faces.push(g);
        let n = gmesh.faces[g].vertices.len();
        let mut best: Option<(bool, f64, u32, u32)> = None;
        for kk in 0..n {
            let (p, q, out) = edge_outward(gmesh, g, kk);
            if edge_key(p, q) == edge_key(a, b) {
                continue;
            }
            let ahead = out.dot(dir) > 0.0;
            let angle = edge_angle(gmesh, p, q, dir);
            let better = match best {
                None => true,
                Some((bahead, bangle, _, _)) => (ahead, angle) > (bahead, bangle),
            };
            if better {
                best = Some((ahead, angle, p, q));
            }
        }
        let (_, _, p, q) = best.ok_or(Unchanged::StripLost)?;
        cur = g;
        a = p;
        b = q;
    }
    Err(Unchanged::StripLost)
}
