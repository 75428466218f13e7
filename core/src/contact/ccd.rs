//! Continuous collision and proximity primitives between linearly moving points,
//! edges and triangles (vertex-face and edge-edge), the building blocks of the
//! detection (Bridson et al. 2002, Harmon et al. 2008).
//!
//! Every primitive reports a contact as four points with weights `w` (summing to zero)
//! and a unit normal `n`: the *gap* is `n · Σ w_i x_i`, the separation (m) along `n`
//! of the vertex (or first edge) from the face (or second edge). Vertex-face:
//! points (p, a, b, c), weights (1, -α, -β, -γ) with (α, β, γ) the barycentric
//! coordinates of the closest point. Edge-edge: (p1, p2, q1, q2), weights
//! (1-s, s, -(1-u), -u). The normal is oriented so that the gap at the start of the
//! motion (t = 0, the previous collision-free state) is positive: a contact always
//! pushes back to the side the primitives came from.

use parry3d_f64::query::details::closest_points_segment_segment_with_locations_nD;
use parry3d_f64::query::PointQueryWithLocation;
use parry3d_f64::shape::{SegmentPointLocation, Triangle, TrianglePointLocation};

use crate::geometry::{Point3, Vector3};

/// Where on a primitive the closest point lies: a vertex (index into the primitive's
/// points), the interior of an edge (two indices), or the interior of a face.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Location {
    Vertex(u8),
    Edge(u8, u8),
    Face,
}

/// A contact between two primitives: weights over the four points of the pair, the
/// unit normal (oriented by the start of the motion), the gap at the end of the
/// motion, m, and where on each side the closest points lie.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PrimitiveContact {
    pub weights: [f64; 4],
    pub normal: Vector3,
    /// n · Σ w_i x_i(1), m.
    pub gap: f64,
    /// Location on the first primitive (the vertex, or the first edge: points 0, 1).
    pub first: Location,
    /// Location on the second primitive (the face a, b, c as points 1..=3, or the second
    /// edge as points 2, 3).
    pub second: Location,
    /// Time of impact in [0, 1] for a crossing found by the continuous test; `None` for a
    /// proximity contact at the end of the motion.
    pub time_of_impact: Option<f64>,
}

/// Linear motion of a point from `x0` (t = 0) to `x1` (t = 1), m.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Motion {
    pub x0: Vector3,
    pub x1: Vector3,
}

impl Motion {
    #[inline]
    pub fn at(&self, t: f64) -> Vector3 {
        self.x0 + (self.x1 - self.x0) * t
    }
    #[inline]
    pub fn delta(&self) -> Vector3 {
        self.x1 - self.x0
    }
}

/// Whether the two sides of a pair, points `0..split` and `split..4`, stay farther than
/// `margin` (m) apart over the whole motion, by a separating axis of their swept boxes:
/// at every t each side lies in the box of its points at t = 0 and t = 1, so a gap
/// wider than `margin` along x, y or z rules out both a crossing and a proximity
/// contact. Exact, and cheap against the cubic it saves: a ribbon lying flat has every
/// feature pair coplanar, where the cubic's roots are all noise to bisect (2026-12-06:
/// a third of a resting step at n = 600). Exact up to round-off in the box bounds.
fn swept_apart(pts: &[Motion; 4], split: usize, margin: f64) -> bool {
    let bounds = |side: &[Motion]| {
        side.iter().fold(
            (
                Vector3::repeat(f64::INFINITY),
                Vector3::repeat(f64::NEG_INFINITY),
            ),
            |(lo, hi), m| (lo.inf(&m.x0).inf(&m.x1), hi.sup(&m.x0).sup(&m.x1)),
        )
    };
    let (alo, ahi) = bounds(&pts[..split]);
    let (blo, bhi) = bounds(&pts[split..]);
    (0..3).any(|d| alo[d] - bhi[d] > margin || blo[d] - ahi[d] > margin)
}

/// The most the distance between the two sides (points `0..split`, `split..4`) can
/// change over the motion, m: the distance from a point to a segment's or a triangle's
/// convex hull moves by at most the largest displacement on each side. A pair whose
/// distance at the end exceeds the margin by more than this never came within it, so
/// the crossing test can be skipped without changing its answer: the case of a resting
/// ribbon, whose coplanar neighbours the swept boxes cannot separate.
fn travel(pts: &[Motion; 4], split: usize) -> f64 {
    let most = |side: &[Motion]| side.iter().fold(0.0f64, |m, p| m.max(p.delta().norm()));
    most(&pts[..split]) + most(&pts[split..])
}

/// Real roots of `c[0] + c[1] t + c[2] t^2 + c[3] t^3` in [0, 1], ascending, written to
/// `out`; returns how many. Roots of even multiplicity (tangencies) are reported when
/// the cubic's value there is within `1e-12` of its coefficient scale.
fn cubic_roots_unit(c: [f64; 4], out: &mut [f64; 4]) -> usize {
    let scale = c.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    if scale == 0.0 || !scale.is_finite() {
        return 0;
    }
    let c = [c[0] / scale, c[1] / scale, c[2] / scale, c[3] / scale];
    let f = |t: f64| ((c[3] * t + c[2]) * t + c[1]) * t + c[0];
    // Critical points: roots of 3 c3 t^2 + 2 c2 t + c1 inside (0, 1).
    let mut knots = [0.0; 4];
    let mut nk = 0;
    knots[nk] = 0.0;
    nk += 1;
    let (qa, qb, qc) = (3.0 * c[3], 2.0 * c[2], c[1]);
    let mut crit = [f64::NAN; 2];
    if qa.abs() > 1e-14 {
        let disc = qb * qb - 4.0 * qa * qc;
        if disc >= 0.0 {
            let sq = disc.sqrt();
            // numerically stable quadratic roots
            let q = -0.5 * (qb + qb.signum() * sq);
            let r1 = q / qa;
            let r2 = if q != 0.0 { qc / q } else { r1 };
            crit = if r1 < r2 { [r1, r2] } else { [r2, r1] };
        }
    } else if qb.abs() > 1e-14 {
        crit[0] = -qc / qb;
    }
    for r in crit {
        if r.is_finite() && r > 0.0 && r < 1.0 {
            knots[nk] = r;
            nk += 1;
        }
    }
    knots[nk] = 1.0;
    nk += 1;
    let mut count = 0;
    let tangency = 1e-12;
    for i in 0..nk - 1 {
        let (mut a, mut b) = (knots[i], knots[i + 1]);
        let (mut fa, fb) = (f(a), f(b));
        if fa == 0.0 {
            push_root(out, &mut count, a);
            continue;
        }
        if fa * fb > 0.0 {
            continue;
        }
        if fb == 0.0 {
            // reported as the start of the next interval (or the end, below)
            if i + 2 == nk {
                push_root(out, &mut count, b);
            }
            continue;
        }
        // monotone on [a, b] with a sign change: safeguarded bisection / secant
        for _ in 0..100 {
            let m = 0.5 * (a + b);
            let fm = f(m);
            if fm == 0.0 || (b - a) < 1e-15 {
                a = m;
                b = m;
                break;
            }
            if (fm > 0.0) == (fa > 0.0) {
                a = m;
                fa = fm;
            } else {
                b = m;
            }
        }
        push_root(out, &mut count, 0.5 * (a + b));
    }
    // tangencies at interior critical points (no sign change)
    for r in crit {
        if r.is_finite() && r > 0.0 && r < 1.0 && f(r).abs() <= tangency {
            push_root(out, &mut count, r);
        }
    }
    out[..count].sort_by(f64::total_cmp);
    count
}

fn push_root(out: &mut [f64; 4], count: &mut usize, t: f64) {
    if *count < out.len() && !out[..*count].iter().any(|r| (r - t).abs() < 1e-13) {
        out[*count] = t;
        *count += 1;
    }
}

/// Coefficients of `(B(t) × C(t)) · P(t)` for linear B, C, P.
fn triple_cubic(
    b0: Vector3,
    db: Vector3,
    c0: Vector3,
    dc: Vector3,
    p0: Vector3,
    dp: Vector3,
) -> [f64; 4] {
    let n0 = b0.cross(&c0);
    let n1 = b0.cross(&dc) + db.cross(&c0);
    let n2 = db.cross(&dc);
    [
        n0.dot(&p0),
        n0.dot(&dp) + n1.dot(&p0),
        n1.dot(&dp) + n2.dot(&p0),
        n2.dot(&dp),
    ]
}

fn triangle_location(loc: &TrianglePointLocation) -> ([f64; 3], Location) {
    let bary = loc.barycentric_coordinates().unwrap_or([1.0 / 3.0; 3]);
    let l = match *loc {
        TrianglePointLocation::OnVertex(i) => Location::Vertex(i as u8 + 1),
        TrianglePointLocation::OnEdge(0, _) => Location::Edge(1, 2),
        TrianglePointLocation::OnEdge(1, _) => Location::Edge(2, 3),
        TrianglePointLocation::OnEdge(_, _) => Location::Edge(1, 3),
        _ => Location::Face,
    };
    (bary, l)
}

fn segment_location(loc: &SegmentPointLocation, first: u8) -> (f64, Location) {
    match *loc {
        SegmentPointLocation::OnVertex(0) => (0.0, Location::Vertex(first)),
        SegmentPointLocation::OnVertex(_) => (1.0, Location::Vertex(first + 1)),
        SegmentPointLocation::OnEdge([_, s]) => (s, Location::Edge(first, first + 1)),
    }
}

/// Orient `n` so that the gap of the start configuration is positive; returns the gap
/// at the end of the motion along the oriented normal.
fn orient(n: &mut Vector3, weights: &[f64; 4], pts: &[Motion; 4]) -> f64 {
    let g0: Vector3 = (0..4).map(|i| pts[i].x0 * weights[i]).sum();
    if n.dot(&g0) < 0.0 {
        *n = -*n;
    }
    let g1: Vector3 = (0..4).map(|i| pts[i].x1 * weights[i]).sum();
    n.dot(&g1)
}

/// Unit normal of triangle (a, b, c), or `None` when degenerate.
fn triangle_normal(a: &Vector3, b: &Vector3, c: &Vector3) -> Option<Vector3> {
    let n = (b - a).cross(&(c - a));
    let len = n.norm();
    (len > 1e-300).then(|| n / len)
}

/// Closest points of vertex `pts[0]` and triangle `pts[1..4]` at time `t`.
fn vertex_face_at(pts: &[Motion; 4], t: f64) -> (f64, [f64; 3], Location, Vector3) {
    let p = pts[0].at(t);
    let tri = Triangle::new(
        Point3::from(pts[1].at(t)),
        Point3::from(pts[2].at(t)),
        Point3::from(pts[3].at(t)),
    );
    let (proj, loc) = tri.project_local_point_and_get_location(&Point3::from(p), false);
    let (bary, l) = triangle_location(&loc);
    let d = p - proj.point.coords;
    (d.norm(), bary, l, d)
}

/// Vertex `pts[0]` against triangle `pts[1..4]` over the motion: the earliest crossing
/// of the triangle (continuous test, zero thickness) or else, at the end of the motion,
/// proximity closer than `distance` (m). `eps` (m) is how close to the triangle a
/// coplanar vertex must be to count as a crossing.
pub fn vertex_face(pts: &[Motion; 4], distance: f64, eps: f64) -> Option<PrimitiveContact> {
    let margin = distance.max(eps);
    if swept_apart(pts, 1, margin) {
        return None;
    }
    let end = vertex_face_at(pts, 1.0);
    if end.0 - travel(pts, 1) > margin {
        return None;
    }
    let (a0, da) = (pts[1].x0, pts[1].delta());
    let coeffs = triple_cubic(
        pts[2].x0 - a0,
        pts[2].delta() - da,
        pts[3].x0 - a0,
        pts[3].delta() - da,
        pts[0].x0 - a0,
        pts[0].delta() - da,
    );
    let mut roots = [0.0; 4];
    let nr = cubic_roots_unit(coeffs, &mut roots);
    for &t in &roots[..nr] {
        let (dist, bary, loc, _) = vertex_face_at(pts, t);
        if dist <= eps {
            let Some(mut n) = triangle_normal(&pts[1].at(t), &pts[2].at(t), &pts[3].at(t)) else {
                continue;
            };
            let weights = [1.0, -bary[0], -bary[1], -bary[2]];
            let gap = orient(&mut n, &weights, pts);
            return Some(PrimitiveContact {
                weights,
                normal: n,
                gap,
                first: Location::Vertex(0),
                second: loc,
                time_of_impact: Some(t),
            });
        }
    }
    let (dist, bary, loc, d) = end;
    if dist >= distance {
        return None;
    }
    let weights = [1.0, -bary[0], -bary[1], -bary[2]];
    let mut n = if dist > 1e-12 {
        d / dist
    } else {
        triangle_normal(&pts[1].x1, &pts[2].x1, &pts[3].x1)?
    };
    let gap = orient(&mut n, &weights, pts);
    Some(PrimitiveContact {
        weights,
        normal: n,
        gap,
        first: Location::Vertex(0),
        second: loc,
        time_of_impact: None,
    })
}

/// Closest points of edges `pts[0..2]` and `pts[2..4]` at time `t`.
fn edge_edge_at(pts: &[Motion; 4], t: f64) -> (f64, [f64; 4], Location, Location, Vector3) {
    let (p1, p2, q1, q2) = (
        Point3::from(pts[0].at(t)),
        Point3::from(pts[1].at(t)),
        Point3::from(pts[2].at(t)),
        Point3::from(pts[3].at(t)),
    );
    let (l1, l2) = closest_points_segment_segment_with_locations_nD((&p1, &p2), (&q1, &q2));
    let (s, loc1) = segment_location(&l1, 0);
    let (u, loc2) = segment_location(&l2, 2);
    let weights = [1.0 - s, s, -(1.0 - u), -u];
    let d = p1.coords * weights[0]
        + p2.coords * weights[1]
        + q1.coords * weights[2]
        + q2.coords * weights[3];
    (d.norm(), weights, loc1, loc2, d)
}

/// Edge `pts[0..2]` against edge `pts[2..4]`: the earliest crossing over the motion or
/// else proximity closer than `distance` (m) at its end. See [`vertex_face`].
pub fn edge_edge(pts: &[Motion; 4], distance: f64, eps: f64) -> Option<PrimitiveContact> {
    let margin = distance.max(eps);
    if swept_apart(pts, 2, margin) {
        return None;
    }
    let end = edge_edge_at(pts, 1.0);
    if end.0 - travel(pts, 2) > margin {
        return None;
    }
    let (p0, dp) = (pts[0].x0, pts[0].delta());
    let coeffs = triple_cubic(
        pts[1].x0 - p0,
        pts[1].delta() - dp,
        pts[3].x0 - pts[2].x0,
        pts[3].delta() - pts[2].delta(),
        pts[2].x0 - p0,
        pts[2].delta() - dp,
    );
    let mut roots = [0.0; 4];
    let nr = cubic_roots_unit(coeffs, &mut roots);
    for &t in &roots[..nr] {
        let (dist, weights, l1, l2, _) = edge_edge_at(pts, t);
        if dist <= eps {
            let e1 = pts[1].at(t) - pts[0].at(t);
            let e2 = pts[3].at(t) - pts[2].at(t);
            let c = e1.cross(&e2);
            let len = c.norm();
            if len <= 1e-12 * (e1.norm() * e2.norm()).max(1e-300) {
                // parallel at impact: no well-defined crossing normal; leave it to
                // proximity and to the vertex-face tests of the end points
                continue;
            }
            let mut n = c / len;
            let gap = orient(&mut n, &weights, pts);
            return Some(PrimitiveContact {
                weights,
                normal: n,
                gap,
                first: l1,
                second: l2,
                time_of_impact: Some(t),
            });
        }
    }
    let (dist, weights, l1, l2, d) = end;
    if dist >= distance {
        return None;
    }
    let mut n = if dist > 1e-12 {
        d / dist
    } else {
        let c = (pts[1].x1 - pts[0].x1).cross(&(pts[3].x1 - pts[2].x1));
        let len = c.norm();
        if len <= 1e-300 {
            return None;
        }
        c / len
    };
    let gap = orient(&mut n, &weights, pts);
    Some(PrimitiveContact {
        weights,
        normal: n,
        gap,
        first: l1,
        second: l2,
        time_of_impact: None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn still(x: Vector3) -> Motion {
        Motion { x0: x, x1: x }
    }

    /// Neither early exit of the crossing test rejects a pair that comes within the
    /// margin: on random motions, whenever the swept boxes or the end distance minus
    /// the travel say "apart", the distance sampled along the motion (vertex-triangle
    /// and segment-segment, by parry) stays above the margin; and each exit does reject
    /// some pairs (neither is vacuous).
    #[test]
    fn early_exits_only_reject_pairs_that_stay_apart() {
        use parry3d_f64::query::PointQuery;
        use parry3d_f64::shape::Segment;
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        let point = |rng: &mut rand_chacha::ChaCha8Rng| {
            let x0 = Vector3::from_fn(|_, _| rng.random_range(-1.0..1.0));
            let x1 = x0 + Vector3::from_fn(|_, _| rng.random_range(-0.3..0.3));
            Motion { x0, x1 }
        };
        let margin = 0.05;
        // rejections by [box, travel] for [vertex-face, edge-edge]
        let mut rejected = [[0; 2]; 2];
        for _ in 0..2000 {
            let pts = [(); 4].map(|_| point(&mut rng));
            for (k, split) in [1, 2].into_iter().enumerate() {
                let end = if split == 1 {
                    vertex_face_at(&pts, 1.0).0
                } else {
                    edge_edge_at(&pts, 1.0).0
                };
                let by_box = swept_apart(&pts, split, margin);
                let by_travel = end - travel(&pts, split) > margin;
                rejected[0][k] += by_box as usize;
                rejected[1][k] += by_travel as usize;
                if !(by_box || by_travel) {
                    continue;
                }
                for i in 0..=50 {
                    let t = i as f64 / 50.0;
                    let p = pts.map(|m| Point3::from(m.at(t)));
                    let dist = if split == 1 {
                        Triangle::new(p[1], p[2], p[3]).distance_to_local_point(&p[0], true)
                    } else {
                        let (a, b) = (Segment::new(p[0], p[1]), Segment::new(p[2], p[3]));
                        parry3d_f64::query::distance(
                            &parry3d_f64::math::Isometry::identity(),
                            &a,
                            &parry3d_f64::math::Isometry::identity(),
                            &b,
                        )
                        .expect("segments")
                    };
                    assert!(dist > margin, "split {split}, t = {t}: {dist} <= {margin}");
                }
            }
        }
        assert!(rejected.iter().flatten().all(|&r| r > 100), "{rejected:?}");
    }

    #[test]
    fn cubic_roots_are_found_in_order() {
        // (t - 0.2)(t - 0.5)(t - 0.9)
        let (r1, r2, r3) = (0.2, 0.5, 0.9);
        let c = [
            -r1 * r2 * r3,
            r1 * r2 + r1 * r3 + r2 * r3,
            -(r1 + r2 + r3),
            1.0,
        ];
        let mut out = [0.0; 4];
        let n = cubic_roots_unit(c, &mut out);
        assert_eq!(n, 3);
        for (got, want) in out[..3].iter().zip([r1, r2, r3]) {
            assert!((got - want).abs() < 1e-12, "{got} vs {want}");
        }
        // linear and constant cases
        assert_eq!(cubic_roots_unit([-0.25, 1.0, 0.0, 0.0], &mut out), 1);
        assert!((out[0] - 0.25).abs() < 1e-14);
        assert_eq!(cubic_roots_unit([1.0, 0.0, 0.0, 0.0], &mut out), 0);
        // double root (tangency) at 0.5: (t - 0.5)^2
        assert_eq!(cubic_roots_unit([0.25, -1.0, 1.0, 0.0], &mut out), 1);
        assert!((out[0] - 0.5).abs() < 1e-9);
    }

    #[test]
    fn vertex_through_a_face_is_caught_and_pushed_back() {
        let tri = [
            Vector3::new(0.0, 0.0, 0.0),
            Vector3::new(1.0, 0.0, 0.0),
            Vector3::new(0.0, 1.0, 0.0),
        ];
        let p = Motion {
            x0: Vector3::new(0.2, 0.2, 0.5),
            x1: Vector3::new(0.2, 0.2, -0.5),
        };
        let c = vertex_face(
            &[p, still(tri[0]), still(tri[1]), still(tri[2])],
            1e-3,
            1e-9,
        )
        .expect("crossing");
        assert!((c.time_of_impact.unwrap() - 0.5).abs() < 1e-12);
        assert!((c.normal - Vector3::z()).norm() < 1e-12, "{:?}", c.normal);
        assert!((c.gap + 0.5).abs() < 1e-12);
        assert_eq!(c.second, Location::Face);
        // missing the triangle: no crossing, and far at the end: nothing
        let miss = Motion {
            x0: Vector3::new(2.0, 2.0, 0.5),
            x1: Vector3::new(2.0, 2.0, -0.5),
        };
        assert!(vertex_face(
            &[miss, still(tri[0]), still(tri[1]), still(tri[2])],
            1e-3,
            1e-9
        )
        .is_none());
    }

    #[test]
    fn proximity_normal_points_to_the_side_of_the_start() {
        let tri = [
            Vector3::new(0.0, 0.0, 0.0),
            Vector3::new(1.0, 0.0, 0.0),
            Vector3::new(0.0, 1.0, 0.0),
        ];
        // from below, ending 0.5 mm below: the normal points down
        let p = Motion {
            x0: Vector3::new(0.2, 0.2, -0.1),
            x1: Vector3::new(0.2, 0.2, -0.0005),
        };
        let c = vertex_face(
            &[p, still(tri[0]), still(tri[1]), still(tri[2])],
            1e-3,
            1e-9,
        )
        .expect("proximity");
        assert!(c.time_of_impact.is_none());
        assert!((c.normal + Vector3::z()).norm() < 1e-12);
        assert!((c.gap - 0.0005).abs() < 1e-12);
    }

    #[test]
    fn crossing_edges_are_caught() {
        // edge along x at z = 1 moving down to z = -1 through an edge along y at z = 0
        let p1 = Motion {
            x0: Vector3::new(-1.0, 0.3, 1.0),
            x1: Vector3::new(-1.0, 0.3, -1.0),
        };
        let p2 = Motion {
            x0: Vector3::new(1.0, 0.3, 1.0),
            x1: Vector3::new(1.0, 0.3, -1.0),
        };
        let q1 = still(Vector3::new(0.0, -1.0, 0.0));
        let q2 = still(Vector3::new(0.0, 1.0, 0.0));
        let c = edge_edge(&[p1, p2, q1, q2], 1e-3, 1e-9).expect("crossing");
        assert!((c.time_of_impact.unwrap() - 0.5).abs() < 1e-12);
        assert!((c.normal - Vector3::z()).norm() < 1e-12);
        assert!((c.gap + 1.0).abs() < 1e-12);
        assert!((c.weights[0] - 0.5).abs() < 1e-12 && (c.weights[3] + 0.65).abs() < 1e-12);
    }
}
