//! The 2D pattern S̄ (Schreck et al. sec. 3.2): a convex polygon in material
//! coordinates (m), its boundary ∂S̄ parameterized by arc length `s` (m, counter-clockwise
//! from the first corner), and the small 2D predicates the remeshing needs.

use crate::geometry::{Point2, Vector3};
use nalgebra::Vector2;

/// Distances below this are the same point in the pattern, m (far below any sampling
/// distance: 1/rho_bound is ~8 mm).
pub const SAME_POINT: f64 = 1e-9;

/// A convex polygon, counter-clockwise, in material coordinates (m).
#[derive(Clone, Debug, PartialEq)]
pub struct Pattern {
    corners: Vec<Point2>,
    /// Arc length at each corner; `cumulative[n]` is the perimeter.
    cumulative: Vec<f64>,
}

impl Pattern {
    /// The rectangle [0, width] x [0, height], m.
    pub fn rectangle(width: f64, height: f64) -> Pattern {
        Pattern::convex(vec![
            Point2::new(0.0, 0.0),
            Point2::new(width, 0.0),
            Point2::new(width, height),
            Point2::new(0.0, height),
        ])
    }

    /// A convex polygon from its corners, counter-clockwise.
    pub fn convex(corners: Vec<Point2>) -> Pattern {
        let mut cumulative = Vec::with_capacity(corners.len() + 1);
        let mut s = 0.0;
        cumulative.push(0.0);
        for i in 0..corners.len() {
            s += (corners[(i + 1) % corners.len()] - corners[i]).norm();
            cumulative.push(s);
        }
        Pattern {
            corners,
            cumulative,
        }
    }

    pub fn corners(&self) -> &[Point2] {
        &self.corners
    }

    /// Arc length of corner `i`, m.
    pub fn corner_arc(&self, i: usize) -> f64 {
        self.cumulative[i]
    }

    /// Perimeter of ∂S̄, m.
    pub fn perimeter(&self) -> f64 {
        self.cumulative[self.corners.len()]
    }

    /// L_paper: the largest extent of the sheet (bounding-box side), m (table VI).
    pub fn paper_length(&self) -> f64 {
        let (mut lo, mut hi) = (self.corners[0], self.corners[0]);
        for c in &self.corners {
            lo = Point2::new(lo.x.min(c.x), lo.y.min(c.y));
            hi = Point2::new(hi.x.max(c.x), hi.y.max(c.y));
        }
        (hi.x - lo.x).max(hi.y - lo.y)
    }

    /// `s` wrapped into [0, perimeter).
    pub fn wrap(&self, s: f64) -> f64 {
        let p = self.perimeter();
        let w = s.rem_euclid(p);
        if p - w < SAME_POINT {
            0.0
        } else {
            w
        }
    }

    /// Index of the side (corner i to corner i+1) holding arc length `s`.
    pub fn side_of(&self, s: f64) -> usize {
        let s = self.wrap(s);
        let n = self.corners.len();
        (0..n)
            .find(|&i| s < self.cumulative[i + 1])
            .unwrap_or(n - 1)
    }

    /// Point of ∂S̄ at arc length `s`, m.
    pub fn point_at(&self, s: f64) -> Point2 {
        let s = self.wrap(s);
        let i = self.side_of(s);
        let n = self.corners.len();
        let (a, b) = (self.corners[i], self.corners[(i + 1) % n]);
        let len = self.cumulative[i + 1] - self.cumulative[i];
        let t = if len > 0.0 {
            (s - self.cumulative[i]) / len
        } else {
            0.0
        };
        a + (b - a) * t
    }

    /// Arc length of `p` when it lies on ∂S̄ within `tol` (m).
    pub fn arc_of(&self, p: &Point2, tol: f64) -> Option<f64> {
        let n = self.corners.len();
        let mut best: Option<(f64, f64)> = None;
        for i in 0..n {
            let (a, b) = (self.corners[i], self.corners[(i + 1) % n]);
            let (d, t) = point_segment(p, &a, &b);
            if d <= tol && best.is_none_or(|(bd, _)| d < bd) {
                let len = self.cumulative[i + 1] - self.cumulative[i];
                best = Some((d, self.wrap(self.cumulative[i] + t * len)));
            }
        }
        best.map(|(_, s)| s)
    }

    /// True when `p` is inside the polygon or within `tol` of it (m).
    pub fn contains(&self, p: &Point2, tol: f64) -> bool {
        self.signed_inside_distance(p) >= -tol
    }

    /// Distance from `p` to ∂S̄, positive inside, negative outside, m.
    pub fn signed_inside_distance(&self, p: &Point2) -> f64 {
        let n = self.corners.len();
        let mut d = f64::INFINITY;
        for i in 0..n {
            let (a, b) = (self.corners[i], self.corners[(i + 1) % n]);
            let t = (b - a).normalize();
            // inward normal of a counter-clockwise polygon
            let inward = Vector2::new(-t.y, t.x);
            d = d.min((p - a).dot(&inward));
        }
        d
    }

    /// Counter-clockwise arc length from `from` to `to`, in [0, perimeter).
    pub fn arc_ccw(&self, from: f64, to: f64) -> f64 {
        (to - from).rem_euclid(self.perimeter())
    }

    /// The chord of the line `origin + t dir` inside the polygon: the arc lengths and
    /// parameters of its two ends, the one at smaller t first. None if it misses.
    pub fn clip_line(&self, origin: &Point2, dir: &Vector2<f64>) -> Option<[(f64, f64); 2]> {
        let n = self.corners.len();
        let (mut t_lo, mut t_hi) = (f64::NEG_INFINITY, f64::INFINITY);
        for i in 0..n {
            let (a, b) = (self.corners[i], self.corners[(i + 1) % n]);
            let t = (b - a).normalize();
            let inward = Vector2::new(-t.y, t.x);
            // inside: (origin + t dir - a) . inward >= 0
            let c0 = (origin - a).dot(&inward);
            let c1 = dir.dot(&inward);
            if c1.abs() < 1e-15 {
                if c0 < 0.0 {
                    return None;
                }
                continue;
            }
            let t_edge = -c0 / c1;
            if c1 > 0.0 {
                t_lo = t_lo.max(t_edge);
            } else {
                t_hi = t_hi.min(t_edge);
            }
        }
        if t_hi - t_lo <= SAME_POINT * 10.0 {
            return None;
        }
        let p_lo = origin + dir * t_lo;
        let p_hi = origin + dir * t_hi;
        let s_lo = self.arc_of(&p_lo, 1e-7)?;
        let s_hi = self.arc_of(&p_hi, 1e-7)?;
        Some([(s_lo, t_lo), (s_hi, t_hi)])
    }
}

/// Distance from `p` to the segment [a, b] and the parameter of the closest point.
pub fn point_segment(p: &Point2, a: &Point2, b: &Point2) -> (f64, f64) {
    let ab = b - a;
    let len2 = ab.norm_squared();
    let t = if len2 > 0.0 {
        ((p - a).dot(&ab) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    ((a + ab * t - p).norm(), t)
}

/// Twice the signed area of the triangle (a, b, c): > 0 counter-clockwise.
pub fn orient(a: &Point2, b: &Point2, c: &Point2) -> f64 {
    (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x)
}

/// True when the open segments [p1, p2] and [q1, q2] cross at a point interior to both,
/// with a margin `tol` (m): touching at an end or at a shared vertex is not a crossing.
pub fn segments_cross(p1: &Point2, p2: &Point2, q1: &Point2, q2: &Point2, tol: f64) -> bool {
    let lp = (p2 - p1).norm();
    let lq = (q2 - q1).norm();
    if lp < SAME_POINT || lq < SAME_POINT {
        return false;
    }
    // signed distances of each segment's ends to the other's line
    let dq1 = orient(p1, p2, q1) / lp;
    let dq2 = orient(p1, p2, q2) / lp;
    let dp1 = orient(q1, q2, p1) / lq;
    let dp2 = orient(q1, q2, p2) / lq;
    (dq1 > tol && dq2 < -tol || dq1 < -tol && dq2 > tol)
        && (dp1 > tol && dp2 < -tol || dp1 < -tol && dp2 > tol)
}

/// Signed area of a polygon (> 0 counter-clockwise), m^2.
pub fn polygon_area(poly: &[Point2]) -> f64 {
    let n = poly.len();
    let mut a = 0.0;
    for i in 0..n {
        let (p, q) = (poly[i], poly[(i + 1) % n]);
        a += p.x * q.y - q.x * p.y;
    }
    0.5 * a
}

/// True when `p` is inside the convex counter-clockwise polygon, `tol` (m) inside the
/// edges (a positive `tol` excludes points on the edges).
pub fn in_convex_polygon(poly: &[Point2], p: &Point2, tol: f64) -> bool {
    let n = poly.len();
    for i in 0..n {
        let (a, b) = (poly[i], poly[(i + 1) % n]);
        let len = (b - a).norm();
        if len < SAME_POINT {
            continue;
        }
        if orient(&a, &b, p) / len < tol {
            return false;
        }
    }
    true
}

/// The 3D unit normal of a polygon (Newell's method), or zero when degenerate.
pub fn newell_normal(points: &[crate::geometry::Point3]) -> Vector3 {
    let n = points.len();
    let mut normal = Vector3::zeros();
    for i in 0..n {
        let (p, q) = (points[i], points[(i + 1) % n]);
        normal.x += (p.y - q.y) * (p.z + q.z);
        normal.y += (p.z - q.z) * (p.x + q.x);
        normal.z += (p.x - q.x) * (p.y + q.y);
    }
    let len = normal.norm();
    if len > 1e-300 {
        normal / len
    } else {
        Vector3::zeros()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn arc_length_round_trips_on_a_rectangle() {
        let p = Pattern::rectangle(0.2, 0.1);
        assert!((p.perimeter() - 0.6).abs() < 1e-15);
        for &s in &[0.0, 0.05, 0.2, 0.25, 0.31, 0.45, 0.59] {
            let q = p.point_at(s);
            let back = p.arc_of(&q, 1e-12).unwrap();
            assert!((back - s).abs() < 1e-12, "{s} -> {back}");
        }
        assert!((p.point_at(0.6) - Point2::new(0.0, 0.0)).norm() < 1e-15);
        assert!((p.paper_length() - 0.2).abs() < 1e-15);
    }

    #[test]
    fn clip_line_finds_both_ends_in_order() {
        let p = Pattern::rectangle(0.1, 0.1);
        let [(s0, t0), (s1, t1)] = p
            .clip_line(&Point2::new(0.03, 0.05), &Vector2::new(0.0, 1.0))
            .unwrap();
        assert!(t0 < t1);
        assert!((p.point_at(s0) - Point2::new(0.03, 0.0)).norm() < 1e-12);
        assert!((p.point_at(s1) - Point2::new(0.03, 0.1)).norm() < 1e-12);
        assert!(p
            .clip_line(&Point2::new(0.3, 0.05), &Vector2::new(0.0, 1.0))
            .is_none());
    }

    #[test]
    fn crossing_excludes_shared_ends() {
        let a = Point2::new(0.0, 0.0);
        let b = Point2::new(1.0, 1.0);
        let c = Point2::new(0.0, 1.0);
        let d = Point2::new(1.0, 0.0);
        assert!(segments_cross(&a, &b, &c, &d, 1e-9));
        assert!(!segments_cross(&a, &b, &a, &d, 1e-9));
        assert!(!segments_cross(&a, &c, &b, &d, 1e-9));
    }
}
