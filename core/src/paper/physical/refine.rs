//! S_P's triangulation without caps. A triangle of the constrained Delaunay
//! triangulation with an angle near 180 deg (a cap) lies against a constrained segment
//! (a ruling, a crease or the boundary) with its apex close to it: Delaunay never makes
//! one across a free edge. In a cap the area, and so the FEM's Green strain and the
//! hinge weights 3 |e|^2 / (A_1 + A_2), are ill-conditioned in the edge lengths: edges
//! within 0.1 % of their pattern lengths left a cap with 37 % too much area
//! (docs/paper_simulator.md, "S_P triangle quality"). Each such segment is split at the
//! foot of the cap's apex, which leaves two right-angled triangles whose areas are as
//! well conditioned as their edges, and the triangulation is redone.

use super::{PhysicalMesh, SampleKind};
use crate::geometry::{Point2, Point3};
use crate::paper::geometric::{EdgeKind, GeometricMesh};
use crate::paper::params::PaperParams;
use crate::paper::pattern::Pattern;

type Cdt = spade::ConstrainedDelaunayTriangulation<spade::Point2<f64>>;

/// A triangle whose largest pattern angle exceeds this is a cap, rad (150 deg).
const CAP_ANGLE: f64 = 150.0 * std::f64::consts::PI / 180.0;

/// Rounds of splitting, at most. Each round splits every segment a cap lies against;
/// a split leaves no cap behind unless another vertex is as close to the new pieces,
/// so one or two rounds suffice on the paper scenes.
const MAX_ROUNDS: usize = 8;

/// The triangulation of `sp`'s vertices with its boundary and S_G's rulings and
/// creases kept, after splitting the constrained segments that caps lie against (the
/// new vertices are added to `sp`, placed by `position`). A foot closer than twice
/// the smallest boundary spacing to an end of its segment is not split: there the apex
/// nearly sits on that vertex.
pub(super) fn triangulate(
    sp: &mut PhysicalMesh,
    gmesh: &GeometricMesh,
    pattern: &Pattern,
    params: &PaperParams,
    position: &dyn Fn(&Point2) -> Point3,
) -> Result<Cdt, String> {
    let mut chains: Vec<Vec<u32>> = gmesh
        .edges
        .iter()
        .filter(|(_, e)| matches!(e.kind, EdgeKind::Ruling { .. } | EdgeKind::Crease { .. }))
        .map(|(&(a, b), _)| vec![a, b])
        .collect();
    let shortest = 2.0 * params.min_boundary_spacing();
    for _ in 0..MAX_ROUNDS {
        let cdt = sp.triangulate(&chains)?;
        let mut split = false;
        for ([a, b], t) in cap_segments(sp, &cdt) {
            let len = (sp.material[a as usize] - sp.material[b as usize]).norm();
            if t * len < shortest || (1.0 - t) * len < shortest {
                continue;
            }
            split |= split_chain(sp, &mut chains, [a, b], t, position)
                || split_boundary(sp, pattern, [a, b], t, position);
        }
        if !split {
            return Ok(cdt);
        }
    }
    sp.triangulate(&chains)
}

/// The longest edge [a, b] (a < b) of every cap of `cdt`, each once, with the fraction
/// t in [0, 1] of the foot of the cap's apex along it, from a.
fn cap_segments(sp: &PhysicalMesh, cdt: &Cdt) -> Vec<([u32; 2], f64)> {
    use spade::Triangulation;
    let mut out: Vec<([u32; 2], f64)> = Vec::new();
    for face in cdt.inner_faces() {
        let vs = face.vertices().map(|v| v.fix().index() as u32);
        let m = vs.map(|v| sp.material[v as usize]);
        for k in 0..3 {
            if angle_at(&m[k], &m[(k + 1) % 3], &m[(k + 2) % 3]) <= CAP_ANGLE {
                continue;
            }
            let (p, q) = (vs[(k + 1) % 3], vs[(k + 2) % 3]);
            let (a, b) = (p.min(q), p.max(q));
            let (ma, mb) = (sp.material[a as usize], sp.material[b as usize]);
            let ab = mb - ma;
            let t = ((m[k] - ma).dot(&ab) / ab.norm_squared()).clamp(0.0, 1.0);
            if !out.iter().any(|(key, _)| *key == [a, b]) {
                out.push(([a, b], t));
            }
        }
    }
    out
}

/// The angle at `p` of the triangle (p, q, r), rad.
fn angle_at(p: &Point2, q: &Point2, r: &Point2) -> f64 {
    let (u, v) = (q - p, r - p);
    let den = u.norm() * v.norm();
    if den <= 0.0 {
        return 0.0;
    }
    (u.dot(&v) / den).clamp(-1.0, 1.0).acos()
}

/// Split segment [a, b] at fraction `t` (from a) if it is a piece of a ruling or
/// crease chain.
fn split_chain(
    sp: &mut PhysicalMesh,
    chains: &mut [Vec<u32>],
    [a, b]: [u32; 2],
    t: f64,
    position: &dyn Fn(&Point2) -> Point3,
) -> bool {
    for chain in chains.iter_mut() {
        let Some(i) = chain
            .windows(2)
            .position(|w| (w[0] == a && w[1] == b) || (w[0] == b && w[1] == a))
        else {
            continue;
        };
        let m = Point2::from(
            sp.material[a as usize].coords * (1.0 - t) + sp.material[b as usize].coords * t,
        );
        let v = sp.push_sample(m, position, SampleKind::CapSplit);
        chain.insert(i + 1, v);
        return true;
    }
    false
}

/// Split segment [a, b] at fraction `t` (from a) if it is a piece of the boundary: a
/// boundary vertex at that arc length.
fn split_boundary(
    sp: &mut PhysicalMesh,
    pattern: &Pattern,
    [a, b]: [u32; 2],
    t: f64,
    position: &dyn Fn(&Point2) -> Point3,
) -> bool {
    let n = sp.boundary.len();
    let Some((k, t)) = (0..n).find_map(|k| {
        let (x, y) = (sp.boundary[k], sp.boundary[(k + 1) % n]);
        match (x == a && y == b, x == b && y == a) {
            (true, _) => Some((k, t)),
            (_, true) => Some((k, 1.0 - t)),
            _ => None,
        }
    }) else {
        return false;
    };
    let (s0, s1) = (sp.boundary_arc[k], sp.boundary_arc[(k + 1) % n]);
    // a singular vertex on the boundary has no arc length
    if !(s0.is_finite() && s1.is_finite()) {
        return false;
    }
    let s = pattern.wrap(s0 + t * pattern.arc_ccw(s0, s1));
    let v = sp.push_sample(pattern.point_at(s), position, SampleKind::CapSplit);
    // the boundary stays in arc-length order
    let at = sp.boundary_arc.partition_point(|&x| x < s);
    sp.boundary.insert(at, v);
    sp.boundary_arc.insert(at, s);
    true
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_angle_of_a_cap_is_near_pi_and_of_a_right_triangle_half_pi() {
        let (p, q, r) = (
            Point2::new(0.0, 0.001),
            Point2::new(-0.05, 0.0),
            Point2::new(0.05, 0.0),
        );
        assert!(angle_at(&p, &q, &r) > CAP_ANGLE);
        let (p, q, r) = (
            Point2::origin(),
            Point2::new(1.0, 0.0),
            Point2::new(0.0, 2.0),
        );
        assert!((angle_at(&p, &q, &r) - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
        // a degenerate corner has no angle
        assert_eq!(angle_at(&p, &p, &r), 0.0);
    }
}
