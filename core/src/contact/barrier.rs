//! The pieces of contact inside the step (Incremental Potential Contact, Li et al. 2020;
//! the design: docs/contact_barrier.md): the smoothly clamped log barrier on a gap, the
//! friction mollifier, the static closest-point distances of point-triangle and
//! edge-edge pairs with the weights of their gradient, and conservative advancement
//! (additive CCD, Li et al. 2021) of linearly moving pairs. Pure math: no ribbon, no
//! mesh.

use crate::geometry::Vector3;

/// Parameters of the barrier method (SI).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BarrierSettings {
    /// Shell thickness ξ, m: a mid-surface keeps ξ/2 from collider surfaces and ξ from
    /// another mid-surface (another ribbon, or a non-neighbouring part of itself).
    pub thickness: f64,
    /// ŝ, m: the barrier acts on gaps (distance beyond the thickness) below this.
    pub activation_distance: f64,
    /// p̂, Pa: the contact pressure at a gap of ŝ/2 (sets κ, see [`Self::stiffness`]).
    pub barrier_pressure: f64,
    /// ε_v, m/s: below this slip speed friction is a viscous stick (IPC's mollifier).
    pub friction_velocity: f64,
    /// Coulomb coefficient μ between two contact bodies (ribbons), >= 0; 0: they slide
    /// freely over each other.
    pub body_friction: f64,
    /// Contacts between non-neighbouring parts of one ribbon.
    pub self_contact: bool,
}

impl Default for BarrierSettings {
    fn default() -> Self {
        BarrierSettings {
            thickness: 1e-3,
            activation_distance: 1e-4,
            barrier_pressure: 1e3,
            friction_velocity: 1e-4,
            body_friction: 0.0,
            self_contact: true,
        }
    }
}

impl BarrierSettings {
    /// κ, Pa/m: the pressure of the barrier at gap s is p(s) = -κ b'(s), and
    /// -b'(ŝ/2) = (ln 2 + 1/2) ŝ, so κ = p̂ / ((ln 2 + 1/2) ŝ).
    pub fn stiffness(&self) -> f64 {
        self.barrier_pressure / ((std::f64::consts::LN_2 + 0.5) * self.activation_distance)
    }

    /// Material distance along the centerline below which two parts of one ribbon are
    /// neighbours and never interact, m: π ξ / 2, the arc of the tightest fold of a
    /// shell of thickness ξ (a half circle of diameter ξ).
    pub fn neighbour_skip(&self) -> f64 {
        0.5 * std::f64::consts::PI * self.thickness
    }

    /// Why these settings cannot work, if they cannot: positive values, and ŝ below
    /// (π/2 - 1) ξ so that a flat ribbon has no active self pair (pairs beyond the
    /// neighbour skip are then farther than ξ + ŝ).
    pub fn check(&self) -> Result<(), String> {
        let named = [
            ("thickness", self.thickness),
            ("activation_distance", self.activation_distance),
            ("barrier_pressure", self.barrier_pressure),
            ("friction_velocity", self.friction_velocity),
        ];
        for (name, v) in named {
            if !(v.is_finite() && v > 0.0) {
                return Err(format!("{name} must be positive and finite, got {v}"));
            }
        }
        if !(self.body_friction.is_finite() && self.body_friction >= 0.0) {
            return Err(format!(
                "ribbon_friction must be finite and >= 0, got {}",
                self.body_friction
            ));
        }
        let most = (0.5 * std::f64::consts::PI - 1.0) * self.thickness;
        if self.activation_distance >= most {
            return Err(format!(
                "activation_distance {} m must be below (pi/2 - 1) * thickness = {most:.3e} m: a flat ribbon's parts one neighbour skip apart would touch",
                self.activation_distance
            ));
        }
        Ok(())
    }
}

/// What a pair is against.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum PairSource {
    /// Collider k.
    Collider(usize),
    /// Other body b (in the order of `ContactEnv::others`).
    Body(usize),
    /// The ribbon itself.
    #[default]
    Itself,
}

/// What contact inside an object's last step did (`contact.method: barrier`).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BarrierOutcome {
    /// Pairs inside the barrier at the end of the step.
    pub active: usize,
    /// The smallest gap (distance beyond the thickness) of those pairs, m (+∞: none).
    pub min_gap: f64,
    /// Rounds of collider advance and solve (1 without moving colliders).
    pub rounds: u32,
    /// False when a moving collider could not reach its target.
    pub resolved: bool,
    /// Barrier energy at the end of the step, J.
    pub barrier_energy: f64,
    /// Bound on the work moving colliders did on the ribbon in the step, J: the
    /// barrier and friction forces on each at the end of the step times the most any of
    /// its points moved.
    pub collider_work: f64,
}

/// IPC's clamped log barrier b(s) = -(s - ŝ)^2 ln(s/ŝ) on (0, ŝ), 0 beyond, +∞ at
/// s <= 0, with its first and second derivatives (m^2, m, 1).
#[inline]
pub fn barrier(s: f64, s_hat: f64) -> (f64, f64, f64) {
    if s >= s_hat {
        return (0.0, 0.0, 0.0);
    }
    if s <= 0.0 || s.is_nan() {
        return (f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY);
    }
    let d = s - s_hat;
    let l = (s / s_hat).ln();
    let value = -d * d * l;
    let first = -(2.0 * d * l + d * d / s);
    let second = -(2.0 * l + 4.0 * d / s - d * d / (s * s));
    (value, first, second)
}

/// An orthonormal basis of the plane orthogonal to the unit vector `n` (a contact's
/// tangent plane, where friction acts).
pub fn tangent_basis(n: &Vector3) -> [Vector3; 2] {
    let helper = if n.x.abs() < 0.9 {
        Vector3::x()
    } else {
        Vector3::y()
    };
    let t1 = n.cross(&helper).normalize();
    [t1, n.cross(&t1)]
}

/// IPC's friction mollifier of the slip y = |u| >= 0 over ε_u (m): f0 with
/// f0' = f1, f1(y) = 2 y/ε - y^2/ε^2 below ε and 1 above. Returns (f0, f1(y)/y, f1'(y)),
/// the last two being what the gradient (f1/y u) and the Hessian need (both finite at
/// y = 0: f1/y -> 2/ε).
#[inline]
pub fn friction_mollifier(y: f64, eps: f64) -> (f64, f64, f64) {
    if y >= eps {
        return (y, 1.0 / y, 0.0);
    }
    let f0 = -y * y * y / (3.0 * eps * eps) + y * y / eps + eps / 3.0;
    let f1_over_y = 2.0 / eps - y / (eps * eps);
    let df1 = 2.0 / eps - 2.0 * y / (eps * eps);
    (f0, f1_over_y, df1)
}

/// The closest points of a static pair: the unit normal n from the second primitive to
/// the first, the distance d, and weights w over the pair's four points (summing to 0)
/// such that Σ w_i x_i = d n and ∂d/∂x_i = w_i n.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Closest {
    pub distance: f64,
    pub normal: Vector3,
    pub weights: [f64; 4],
}

/// Point p against triangle (a, b, c): weights over (p, a, b, c). Ericson, Real-Time
/// Collision Detection, 5.1.5 (barycentric coordinates of the closest point).
pub fn point_triangle(p: &Vector3, a: &Vector3, b: &Vector3, c: &Vector3) -> Closest {
    let (u, v, w) = closest_barycentric(p, a, b, c);
    let q = a * u + b * v + c * w;
    finish(p - q, [1.0, -u, -v, -w], || {
        // p on the triangle: its normal (a pair at distance 0 is beyond any barrier)
        (b - a).cross(&(c - a))
    })
}

/// Barycentric coordinates (of a, b, c) of the point of the triangle closest to p.
fn closest_barycentric(p: &Vector3, a: &Vector3, b: &Vector3, c: &Vector3) -> (f64, f64, f64) {
    let ab = b - a;
    let ac = c - a;
    let ap = p - a;
    let d1 = ab.dot(&ap);
    let d2 = ac.dot(&ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return (1.0, 0.0, 0.0);
    }
    let bp = p - b;
    let d3 = ab.dot(&bp);
    let d4 = ac.dot(&bp);
    if d3 >= 0.0 && d4 <= d3 {
        return (0.0, 1.0, 0.0);
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return (1.0 - v, v, 0.0);
    }
    let cp = p - c;
    let d5 = ab.dot(&cp);
    let d6 = ac.dot(&cp);
    if d6 >= 0.0 && d5 <= d6 {
        return (0.0, 0.0, 1.0);
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return (1.0 - w, 0.0, w);
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return (0.0, 1.0 - w, w);
    }
    let denom = 1.0 / (va + vb + vc);
    let v = vb * denom;
    let w = vc * denom;
    (1.0 - v - w, v, w)
}

/// Segment (p1, p2) against segment (q1, q2): weights over (p1, p2, q1, q2). Ericson
/// 5.1.9 (closest points of two segments, degenerate segments included).
pub fn edge_edge(p1: &Vector3, p2: &Vector3, q1: &Vector3, q2: &Vector3) -> Closest {
    let d1 = p2 - p1;
    let d2 = q2 - q1;
    let r = p1 - q1;
    let a = d1.norm_squared();
    let e = d2.norm_squared();
    let f = d2.dot(&r);
    let tiny = 1e-30;
    let (s, t) = if a <= tiny && e <= tiny {
        (0.0, 0.0)
    } else if a <= tiny {
        (0.0, (f / e).clamp(0.0, 1.0))
    } else {
        let c = d1.dot(&r);
        if e <= tiny {
            ((-c / a).clamp(0.0, 1.0), 0.0)
        } else {
            let b = d1.dot(&d2);
            let denom = a * e - b * b;
            let mut s = if denom > 1e-14 * a * e {
                ((b * f - c * e) / denom).clamp(0.0, 1.0)
            } else {
                // parallel: any s; take the one nearest q1's projection
                0.0
            };
            let mut t = (b * s + f) / e;
            if t < 0.0 {
                t = 0.0;
                s = (-c / a).clamp(0.0, 1.0);
            } else if t > 1.0 {
                t = 1.0;
                s = ((b - c) / a).clamp(0.0, 1.0);
            }
            (s, t)
        }
    };
    let x = p1 + d1 * s;
    let y = q1 + d2 * t;
    finish(x - y, [1.0 - s, s, -(1.0 - t), -t], || d1.cross(&d2))
}

/// The pair's result from the difference `diff` = Σ w_i x_i; at distance 0 the normal
/// is the (normalized) fallback, or any unit vector.
fn finish(diff: Vector3, weights: [f64; 4], fallback: impl Fn() -> Vector3) -> Closest {
    let distance = diff.norm();
    let normal = if distance > 0.0 {
        diff / distance
    } else {
        let f = fallback();
        let l = f.norm();
        if l > 0.0 {
            f / l
        } else {
            Vector3::z()
        }
    };
    Closest {
        distance,
        normal,
        weights,
    }
}

/// IPC's edge-edge mollifier: the edge-edge distance is not differentiable where the
/// two edges are parallel (the closest points are not unique), so an edge-edge pair's
/// barrier is multiplied by m(c) = 2 c/ε - c^2/ε^2 for c = |a × b|^2 < ε (1 above),
/// ε = 1e-3 |a|^2 |b|^2 with the edges' rest lengths ([`mollifier_threshold`]): the
/// product is C^1 and vanishes for parallel edges, whose contact the point-triangle
/// pairs carry. Returns m and its gradient with respect to the four points (p1, p2,
/// q1, q2) of the pair at constant ε (zero when m = 1).
pub fn edge_mollifier(
    p1: &Vector3,
    p2: &Vector3,
    q1: &Vector3,
    q2: &Vector3,
    eps: f64,
) -> (f64, [Vector3; 4]) {
    let (a, b) = (p2 - p1, q2 - q1);
    let axb = a.cross(&b);
    let c = axb.norm_squared();
    if c >= eps || eps == 0.0 {
        return (1.0, [Vector3::zeros(); 4]);
    }
    let m = 2.0 * c / eps - c * c / (eps * eps);
    let dm = 2.0 / eps - 2.0 * c / (eps * eps);
    // dc = 2 (a × b) . (da × b + a × db)
    let da = b.cross(&axb) * (2.0 * dm);
    let db = axb.cross(&a) * (2.0 * dm);
    (m, [-da, da, -db, db])
}

/// An edge-edge pair's closest points and its mollifier with the threshold of
/// [`mollifier_threshold`]: (closest points, m, ∇m over p1, p2, q1, q2).
pub fn mollified_edge_edge(
    p1: &Vector3,
    p2: &Vector3,
    q1: &Vector3,
    q2: &Vector3,
) -> (Closest, f64, [Vector3; 4]) {
    let eps = mollifier_threshold(p1, p2, q1, q2);
    let (m, gm) = edge_mollifier(p1, p2, q1, q2, eps);
    (edge_edge(p1, p2, q1, q2), m, gm)
}

/// ε of [`edge_mollifier`] for edges of rest lengths |a|, |b| (a ribbon is isometric and
/// a collider rigid: their current lengths, which no motion changes).
pub fn mollifier_threshold(p1: &Vector3, p2: &Vector3, q1: &Vector3, q2: &Vector3) -> f64 {
    1e-3 * (p2 - p1).norm_squared() * (q2 - q1).norm_squared()
}

/// Conservative advancement of a pair along a motion t in [0, 1] (additive CCD, Li et
/// al. 2021): `gap(t)` is the pair's gap (distance minus the thickness it keeps) at t,
/// `rate` an upper bound on how fast the distance can change per unit t (the sum of
/// the largest displacements of the two sides over the motion: the distance between
/// two convex hulls is 1-Lipschitz in each point), `min_gap` the gap not to go below.
/// Returns the largest t found with every gap on [0, t] at least `min_gap`: 1 when the
/// pair cannot reach it, 0 when it starts there.
pub fn advance(gap: impl Fn(f64) -> f64, rate: f64, min_gap: f64) -> f64 {
    advance_from(gap(0.0), gap, rate, min_gap, 1.0)
}

/// [`advance`] from the gap `g0` at t = 0 (already known), over [0, `horizon`] only
/// (1 when the pair stays above the minimum up to the horizon), in at most 256 steps (a
/// pair sliding past another at a constant distance gains (g - g_min) / rate per
/// step).
pub fn advance_from(
    g0: f64,
    gap: impl Fn(f64) -> f64,
    rate: f64,
    min_gap: f64,
    horizon: f64,
) -> f64 {
    let mut g = g0;
    if g <= min_gap || !g.is_finite() {
        return 0.0;
    }
    if !(rate > 0.0) || g - rate * horizon > min_gap {
        // it cannot close the distance to the minimum before the horizon
        return 1.0;
    }
    let first = g - min_gap;
    let mut t = 0.0;
    for _ in 0..256 {
        // the distance cannot fall by more than rate * dt: safe up to t + (g - g_min)/rate
        let dt = (g - min_gap) / rate;
        t += dt;
        if t >= horizon.min(1.0) {
            return 1.0;
        }
        g = gap(t);
        if !(g - min_gap > 1e-3 * first) {
            // within a thousandth of the first clearance; below it by more than
            // round-off (the bound says it cannot be), back to where it still held
            if !(g >= min_gap - 1e-9 * first) {
                t -= dt;
            }
            return t.max(0.0);
        }
    }
    t
}

/// Conservative advancement of a gap that is convex along the motion (a point moving
/// on a line against a convex solid: the signed distance of a convex set is convex):
/// each tangent line lies below the gap, so Newton's iteration from t = 0 approaches the
/// first time the gap reaches `min_gap` from below and never passes it. `gap(t)` returns
/// the gap and its slope d/dt. Returns 1 when the gap stays above `min_gap`.
pub fn advance_convex(gap: impl Fn(f64) -> (f64, f64), min_gap: f64, horizon: f64) -> f64 {
    let (mut g, mut slope) = gap(0.0);
    if g <= min_gap || !g.is_finite() {
        return 0.0;
    }
    let first = g - min_gap;
    let mut t = 0.0;
    for _ in 0..64 {
        if slope >= 0.0 {
            // convex and not decreasing: it never comes down again
            return 1.0;
        }
        let next = t + (min_gap - g) / slope;
        if next >= horizon.min(1.0) {
            return 1.0;
        }
        t = next;
        (g, slope) = gap(t);
        if g - min_gap <= 1e-3 * first {
            return t;
        }
    }
    t
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn barrier_derivatives_match_finite_differences() {
        let s_hat = 2e-4;
        for &s in &[1e-7, 1e-5, 5e-5, 1e-4, 1.9e-4] {
            let (b, db, ddb) = barrier(s, s_hat);
            let h = 1e-6 * s;
            let (bp, dbp, _) = barrier(s + h, s_hat);
            let (bm, dbm, _) = barrier(s - h, s_hat);
            let fd1 = (bp - bm) / (2.0 * h);
            let fd2 = (dbp - dbm) / (2.0 * h);
            assert!((fd1 - db).abs() <= 1e-6 * db.abs(), "s {s}: {fd1} vs {db}");
            assert!(
                (fd2 - ddb).abs() <= 1e-6 * ddb.abs(),
                "s {s}: {fd2} vs {ddb}"
            );
            assert!(b > 0.0 && db < 0.0 && ddb > 0.0);
        }
        // C^2 at ŝ: value, slope and curvature all vanish there
        let (b, db, ddb) = barrier(s_hat * (1.0 - 1e-9), s_hat);
        assert!(
            b.abs() < 1e-30 && db.abs() < 1e-20 && ddb.abs() < 1e-7,
            "{b} {db} {ddb}"
        );
        assert_eq!(barrier(s_hat, s_hat), (0.0, 0.0, 0.0));
        assert_eq!(barrier(0.0, s_hat).0, f64::INFINITY);
        assert_eq!(barrier(-1e-9, s_hat).0, f64::INFINITY);
    }

    #[test]
    fn the_stiffness_gives_the_barrier_pressure_at_half_the_activation_distance() {
        let s = BarrierSettings {
            activation_distance: 3e-4,
            barrier_pressure: 7.0,
            ..Default::default()
        };
        let (_, db, _) = barrier(1.5e-4, 3e-4);
        assert!((-s.stiffness() * db - 7.0).abs() < 1e-12);
    }

    #[test]
    fn settings_check_rejects_an_activation_distance_a_flat_ribbon_would_trip() {
        let ok = BarrierSettings {
            thickness: 2e-3,
            activation_distance: 2e-4,
            ..Default::default()
        };
        assert!(ok.check().is_ok());
        let wide = BarrierSettings {
            activation_distance: 1.2e-3,
            ..ok
        };
        assert!(wide.check().unwrap_err().contains("pi/2 - 1"));
        let zero = BarrierSettings {
            barrier_pressure: 0.0,
            ..ok
        };
        assert!(zero.check().unwrap_err().contains("barrier_pressure"));
    }

    #[test]
    fn friction_mollifier_is_c1_and_its_parts_match_finite_differences() {
        let eps = 1e-6;
        for &y in &[1e-9, 3e-7, 9.9e-7, 2e-6] {
            let (f0, f1y, df1) = friction_mollifier(y, eps);
            let h = 1e-4 * y;
            let fd =
                (friction_mollifier(y + h, eps).0 - friction_mollifier(y - h, eps).0) / (2.0 * h);
            assert!((fd - f1y * y).abs() < 1e-6, "y {y}: {fd} vs {}", f1y * y);
            let f1 = |y: f64| friction_mollifier(y, eps).1 * y;
            let fd1 = (f1(y + h) - f1(y - h)) / (2.0 * h);
            assert!(
                (fd1 - df1).abs() <= 1e-4 * (1.0 / eps),
                "y {y}: {fd1} vs {df1}"
            );
            assert!(f0 > 0.0);
        }
        // continuous at ε: f0 = ε, f1 = 1 from both sides
        let below = friction_mollifier(eps * (1.0 - 1e-12), eps);
        assert!((below.0 - eps).abs() < 1e-15 && (below.1 * eps - 1.0).abs() < 1e-9);
    }

    /// Distance of p to the triangle by dense sampling (an independent estimate).
    fn sampled_point_triangle(p: &Vector3, a: &Vector3, b: &Vector3, c: &Vector3) -> f64 {
        let n = 400;
        let mut best = f64::INFINITY;
        for i in 0..=n {
            for j in 0..=(n - i) {
                let (u, v) = (i as f64 / n as f64, j as f64 / n as f64);
                let q = a + (b - a) * u + (c - a) * v;
                best = best.min((p - q).norm());
            }
        }
        best
    }

    #[test]
    fn point_triangle_distances_and_gradients() {
        let (a, b, c) = (
            Vector3::new(0.0, 0.0, 0.0),
            Vector3::new(1.0, 0.1, 0.0),
            Vector3::new(0.2, 0.9, 0.3),
        );
        let points = [
            Vector3::new(0.3, 0.3, 0.5),   // face
            Vector3::new(-0.5, -0.2, 0.1), // vertex a
            Vector3::new(0.6, -0.4, 0.0),  // edge ab
            Vector3::new(1.5, 1.5, 0.2),   // edge bc or vertex
        ];
        for p in points {
            let r = point_triangle(&p, &a, &b, &c);
            let sampled = sampled_point_triangle(&p, &a, &b, &c);
            assert!(
                r.distance <= sampled + 1e-12 && sampled - r.distance < 5e-3,
                "{r:?} {sampled}"
            );
            let x = [p, a, b, c];
            let sum: Vector3 = (0..4).map(|i| x[i] * r.weights[i]).sum();
            assert!((sum - r.normal * r.distance).norm() < 1e-12);
            // ∂d/∂x_i = w_i n by central differences
            for i in 0..4 {
                for k in 0..3 {
                    let h = 1e-7;
                    let mut xp = x;
                    let mut xm = x;
                    xp[i][k] += h;
                    xm[i][k] -= h;
                    let dp = point_triangle(&xp[0], &xp[1], &xp[2], &xp[3]).distance;
                    let dm = point_triangle(&xm[0], &xm[1], &xm[2], &xm[3]).distance;
                    let fd = (dp - dm) / (2.0 * h);
                    assert!(
                        (fd - r.weights[i] * r.normal[k]).abs() < 1e-6,
                        "{i} {k}: {fd}"
                    );
                }
            }
        }
    }

    #[test]
    fn edge_edge_distances_and_gradients() {
        let cases = [
            // crossing skew segments
            [
                Vector3::new(0.0, 0.0, 0.0),
                Vector3::new(1.0, 0.0, 0.0),
                Vector3::new(0.5, -0.5, 0.2),
                Vector3::new(0.5, 0.5, 0.3),
            ],
            // endpoint to interior
            [
                Vector3::new(0.0, 0.0, 0.0),
                Vector3::new(1.0, 0.0, 0.0),
                Vector3::new(1.4, -0.5, 0.2),
                Vector3::new(1.3, 0.5, 0.1),
            ],
        ];
        for x in cases {
            let r = edge_edge(&x[0], &x[1], &x[2], &x[3]);
            let sum: Vector3 = (0..4).map(|i| x[i] * r.weights[i]).sum();
            assert!((sum - r.normal * r.distance).norm() < 1e-12);
            // brute force over a grid of parameters
            let mut best = f64::INFINITY;
            for i in 0..=500 {
                for j in 0..=500 {
                    let p = x[0] + (x[1] - x[0]) * (i as f64 / 500.0);
                    let q = x[2] + (x[3] - x[2]) * (j as f64 / 500.0);
                    best = best.min((p - q).norm());
                }
            }
            assert!(r.distance <= best + 1e-12 && best - r.distance < 2e-3);
            for i in 0..4 {
                for k in 0..3 {
                    let h = 1e-7;
                    let (mut xp, mut xm) = (x, x);
                    xp[i][k] += h;
                    xm[i][k] -= h;
                    let fd = (edge_edge(&xp[0], &xp[1], &xp[2], &xp[3]).distance
                        - edge_edge(&xm[0], &xm[1], &xm[2], &xm[3]).distance)
                        / (2.0 * h);
                    assert!(
                        (fd - r.weights[i] * r.normal[k]).abs() < 1e-6,
                        "{i} {k}: {fd}"
                    );
                }
            }
        }
        // parallel segments: a valid closest pair all the same
        let r = edge_edge(
            &Vector3::new(0.0, 0.0, 0.0),
            &Vector3::new(1.0, 0.0, 0.0),
            &Vector3::new(0.5, 0.0, 0.3),
            &Vector3::new(2.0, 0.0, 0.3),
        );
        assert!((r.distance - 0.3).abs() < 1e-12, "{r:?}");
    }

    #[test]
    fn the_edge_mollifier_is_c1_and_its_gradient_matches_finite_differences() {
        let x = [
            Vector3::new(0.0, 0.0, 0.0),
            Vector3::new(1.0, 0.0, 0.0),
            Vector3::new(0.3, 0.01, 0.2),
            Vector3::new(1.2, 0.03, 0.2),
        ];
        let eps = mollifier_threshold(&x[0], &x[1], &x[2], &x[3]);
        let (m, g) = edge_mollifier(&x[0], &x[1], &x[2], &x[3], eps);
        assert!(m > 0.0 && m < 1.0, "nearly parallel: {m}");
        for i in 0..4 {
            for k in 0..3 {
                let h = 1e-8;
                let (mut xp, mut xm) = (x, x);
                xp[i][k] += h;
                xm[i][k] -= h;
                let fd = (edge_mollifier(&xp[0], &xp[1], &xp[2], &xp[3], eps).0
                    - edge_mollifier(&xm[0], &xm[1], &xm[2], &xm[3], eps).0)
                    / (2.0 * h);
                assert!(
                    (fd - g[i][k]).abs() < 1e-5 * g[i].norm().max(1.0),
                    "{i} {k}: {fd} vs {}",
                    g[i][k]
                );
            }
        }
        // parallel: 0, with a zero gradient; crossing at right angles: 1
        let par = edge_mollifier(
            &x[0],
            &x[1],
            &Vector3::new(0.0, 0.0, 1.0),
            &Vector3::new(2.0, 0.0, 1.0),
            eps,
        );
        assert_eq!(par.0, 0.0);
        assert!(par.1.iter().all(|v| v.norm() == 0.0));
        let cross = edge_mollifier(
            &x[0],
            &x[1],
            &Vector3::new(0.5, -1.0, 1.0),
            &Vector3::new(0.5, 1.0, 1.0),
            eps,
        );
        assert_eq!(cross.0, 1.0);
    }

    #[test]
    fn advancement_stops_at_the_minimum_gap_and_never_beyond() {
        // a point falling onto a plane: gap 1 - 2 t (the plane at distance 1, travel 2)
        let t = advance(|t| 1.0 - 2.0 * t, 2.0, 0.1);
        let exact = 0.45;
        assert!(t <= exact && exact - t < 1e-3 * 0.9 / 2.0 + 1e-12, "{t}");
        // grazing: the gap shrinks slower than the bound; still never below the minimum
        let gap = |t: f64| ((1.0 - 2.0 * t).powi(2) + 0.04).sqrt() - 0.1;
        let t = advance(gap, 2.0, 0.05);
        assert!(gap(t) >= 0.05 - 1e-12, "{t} {}", gap(t));
        assert!(t > 0.4, "{t}");
        // a pair that never comes close is free over the whole motion
        assert_eq!(advance(|t| 1.0 + t, 0.5, 0.1), 1.0);
        // and one at the minimum gap cannot move
        assert_eq!(advance(|_| 0.1, 1.0, 0.1), 0.0);
    }

    #[test]
    fn convex_advancement_approaches_the_root_from_below() {
        // a point passing a unit sphere: gap |c + t d| - 1 (convex in t)
        let (c, d) = (Vector3::new(-2.0, 0.5, 0.0), Vector3::new(4.0, 0.0, 0.0));
        let gap = |t: f64| {
            let p = c + d * t;
            (p.norm() - 1.0, p.normalize().dot(&d))
        };
        let t = advance_convex(gap, 0.1, 1.0);
        let (g, _) = gap(t);
        assert!(g >= 0.1 && g - 0.1 < 1e-3, "{t}: {g}");
        // moving away: free
        assert_eq!(advance_convex(|t| (1.0 + t, 1.0), 0.1, 1.0), 1.0);
        // a miss: the gap dips but stays above the minimum
        let miss = |t: f64| {
            let p = Vector3::new(-2.0, 1.5, 0.0) + d * t;
            (p.norm() - 1.0, p.normalize().dot(&d))
        };
        assert_eq!(advance_convex(miss, 0.1, 1.0), 1.0);
        // a hit past the horizon is no hit
        assert_eq!(
            advance(|t| 1.0 - 2.0 * t, 2.0, 0.1),
            advance_from(1.0, |t| 1.0 - 2.0 * t, 2.0, 0.1, 1.0)
        );
        assert_eq!(advance_from(1.0, |t| 1.0 - 2.0 * t, 2.0, 0.1, 0.4), 1.0);
    }
}
