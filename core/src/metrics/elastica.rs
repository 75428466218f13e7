//! Exact solutions of the planar elastica, solved inside the project so the ribbon's
//! error is measured against the truth rather than against itself.
//!
//! A strip bent about its width axis (c = 0, no twist) is an inextensible,
//! unshearable planar rod of bending stiffness B (N m^2): with the ribbon's
//! `alpha (n w / l) psi^2` per crease, psi = kappa l/n gives `alpha w kappa^2` per unit
//! length, i.e. (B/2) kappa^2 with **B = 2 alpha w**. In the x-z plane, with theta the
//! tangent angle (from x towards z), m = B theta' the moment the part beyond s exerts
//! on the part before it, n the force it exerts and f the load per unit length,
//! equilibrium reads (Kirchhoff; e.g. Antman, *Nonlinear Problems of Elasticity*,
//! ch. 4)
//!
//! ```text
//! x' = cos theta,  z' = sin theta,  B theta' = m,
//! m' = -(cos theta n_z - sin theta n_x),  n' = -f.
//! ```
//!
//! - [`heavy_cantilever`]: clamped at s = 0, free at s = L, under its own weight:
//!   a shooting method on m(0) (RK4, bisection on m(L) = 0). Small loads tend to the
//!   Euler-Bernoulli deflection w(s) = q s^2 (6 L^2 - 4 L s + s^2) / (24 B)
//!   (Timoshenko & Gere, *Theory of Elastic Stability* / Gere & Timoshenko, *Mechanics
//!   of Materials*, table of beam deflections), which the tests check.
//! - [`clamped_buckled`]: both ends clamped, end-to-end distance D < L, no load: the
//!   first (symmetric) mode of the Euler elastica in closed form, four quarter waves
//!   of `theta'' = -lambda^2 sin theta` (Timoshenko & Gere sec. 2.7, Love's *Treatise*
//!   sec. 263): lambda = 4 K(k) / L, D / L = 2 E(k) / K(k) - 1, midpoint rise k L / K(k),
//!   k = sin(theta_max / 2); the shape by RK4 from the clamp.
//! - [`cantilever_mode`]: the first clamped-free Euler-Bernoulli bending mode,
//!   1 + cos(beta L) cosh(beta L) = 0, beta_1 L = 1.875104 (e.g. Meirovitch,
//!   *Elements of Vibration Analysis*; Timoshenko, *Vibration Problems in Engineering*),
//!   omega_1 = (beta_1 L)^2 sqrt(B / (mu L^4)).

/// The centerline of an exact solution, sampled at `stations + 1` equally spaced
/// arc lengths, with tangent angles for cubic Hermite interpolation.
#[derive(Clone, Debug, PartialEq)]
pub struct PlanarCurve {
    /// Length L, m.
    pub length: f64,
    /// (x, z) at s_i = i L / stations, m.
    pub points: Vec<[f64; 2]>,
    /// theta at s_i, rad.
    pub angles: Vec<f64>,
}

impl PlanarCurve {
    /// (x, z) at arc length s (m, clamped into [0, L]): cubic Hermite between the
    /// samples with the exact tangents (error O(h^4) in the sample spacing h).
    pub fn at(&self, s: f64) -> [f64; 2] {
        let steps = self.points.len() - 1;
        let h = self.length / steps as f64;
        let u = (s.clamp(0.0, self.length) / h).min(steps as f64);
        let i = (u.floor() as usize).min(steps - 1);
        let t = u - i as f64;
        let (p0, p1) = (self.points[i], self.points[i + 1]);
        let (a0, a1) = (self.angles[i], self.angles[i + 1]);
        let (h00, h10, h01, h11) = (
            (1.0 + 2.0 * t) * (1.0 - t) * (1.0 - t),
            t * (1.0 - t) * (1.0 - t),
            t * t * (3.0 - 2.0 * t),
            t * t * (t - 1.0),
        );
        let d0 = [a0.cos() * h, a0.sin() * h];
        let d1 = [a1.cos() * h, a1.sin() * h];
        [0, 1].map(|c| h00 * p0[c] + h10 * d0[c] + h01 * p1[c] + h11 * d1[c])
    }
    /// The free end (s = L), m.
    pub fn end(&self) -> [f64; 2] {
        *self.points.last().expect("at least two samples")
    }
}

/// State of the planar rod ODE: x, z (m), theta (rad), m (N m), n_x, n_z (N).
type State = [f64; 6];

fn derivative(y: &State, bending: f64, load: [f64; 2]) -> State {
    let (c, s) = (y[2].cos(), y[2].sin());
    [
        c,
        s,
        y[3] / bending,
        -(c * y[5] - s * y[4]),
        -load[0],
        -load[1],
    ]
}

/// RK4 from s = 0 to `length` in `steps` steps; returns the states at every station.
fn integrate(start: State, length: f64, steps: usize, bending: f64, load: [f64; 2]) -> Vec<State> {
    let h = length / steps as f64;
    let mut y = start;
    let mut out = Vec::with_capacity(steps + 1);
    out.push(y);
    let add = |a: &State, b: &State, t: f64| -> State { std::array::from_fn(|i| a[i] + t * b[i]) };
    for _ in 0..steps {
        let k1 = derivative(&y, bending, load);
        let k2 = derivative(&add(&y, &k1, 0.5 * h), bending, load);
        let k3 = derivative(&add(&y, &k2, 0.5 * h), bending, load);
        let k4 = derivative(&add(&y, &k3, h), bending, load);
        y = std::array::from_fn(|i| y[i] + h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]));
        out.push(y);
    }
    out
}

fn curve(states: &[State], length: f64) -> PlanarCurve {
    PlanarCurve {
        length,
        points: states.iter().map(|y| [y[0], y[1]]).collect(),
        angles: states.iter().map(|y| y[2]).collect(),
    }
}

/// RK4 steps of the exact solutions: the global error, O((L / steps)^4), is below
/// 1e-13 relative for the loads the tests use (checked by halving in the tests).
const STEPS: usize = 4000;

/// A cantilever clamped horizontally at the origin (theta(0) = 0) and free at s = L,
/// under its weight q (N/m, acting along -z): B theta'' = q (L - s) cos theta,
/// theta'(L) = 0. Shooting on the root moment m(0), which lies in [-q L^2 / 2, 0]
/// (m(L) > 0 at m(0) = 0 and <= 0 at -q L^2 / 2 while |theta| < pi/2), by bisection.
pub fn heavy_cantilever(length: f64, bending: f64, weight_per_length: f64) -> PlanarCurve {
    heavy_cantilever_in(length, bending, weight_per_length, STEPS)
}

fn heavy_cantilever_in(length: f64, bending: f64, q: f64, steps: usize) -> PlanarCurve {
    let shoot = |m0: f64| {
        integrate(
            [0.0, 0.0, 0.0, m0, 0.0, -q * length],
            length,
            steps,
            bending,
            [0.0, -q],
        )
    };
    let end_moment = |m0: f64| shoot(m0).last().expect("states")[3];
    let (mut lo, mut hi) = (-0.5 * q * length * length, 0.0);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if mid == lo || mid == hi {
            break;
        }
        if end_moment(mid) > 0.0 {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    curve(&shoot(0.5 * (lo + hi)), length)
}

/// Complete elliptic integrals K(k), E(k) of modulus k in [0, 1) by the arithmetic-
/// geometric mean (Abramowitz & Stegun 17.6).
fn elliptic_ke(k: f64) -> (f64, f64) {
    let (mut a, mut b) = (1.0_f64, (1.0 - k * k).sqrt());
    let mut c = k;
    let mut sum = 0.5 * c * c;
    let mut pow = 0.5;
    for _ in 0..40 {
        if c.abs() < 1e-17 {
            break;
        }
        let an = 0.5 * (a + b);
        c = 0.5 * (a - b);
        b = (a * b).sqrt();
        a = an;
        pow *= 2.0;
        sum += pow * c * c;
    }
    let kk = std::f64::consts::PI / (2.0 * a);
    (kk, kk * (1.0 - sum))
}

/// A clamped-clamped buckled strip: its exact shape and load.
#[derive(Clone, Debug, PartialEq)]
pub struct Buckled {
    pub curve: PlanarCurve,
    /// Modulus k = sin(theta_max / 2).
    pub modulus: f64,
    /// Axial compression P = lambda^2 B, N.
    pub load: f64,
    /// Rise of the midpoint above the clamps, k L / K(k), m.
    pub midpoint_rise: f64,
}

/// Both ends clamped horizontally at z = 0, `end_distance` = D apart (0 < D < L),
/// buckled upwards in the first mode (see the module doc).
pub fn clamped_buckled(length: f64, bending: f64, end_distance: f64) -> Buckled {
    let ratio = end_distance / length;
    assert!(ratio > 0.0 && ratio < 1.0, "need 0 < D < L");
    // D/L = 2E/K - 1 falls from 1 (k = 0) to -1 (k -> 1): bisect on k
    let (mut lo, mut hi) = (0.0_f64, 1.0 - 1e-15);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        let (kk, ee) = elliptic_ke(mid);
        if 2.0 * ee / kk - 1.0 > ratio {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let k = 0.5 * (lo + hi);
    let (kk, _) = elliptic_ke(k);
    let lambda = 4.0 * kk / length;
    let load = lambda * lambda * bending;
    let states = integrate(
        [0.0, 0.0, 0.0, bending * 2.0 * k * lambda, -load, 0.0],
        length,
        STEPS,
        bending,
        [0.0, 0.0],
    );
    Buckled {
        curve: curve(&states, length),
        modulus: k,
        load,
        midpoint_rise: k * length / kk,
    }
}

/// The first clamped-free bending mode of an Euler-Bernoulli beam.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CantileverMode {
    pub length: f64,
    /// beta_1 (1/m): the first root of 1 + cos(beta L) cosh(beta L) = 0, over L.
    pub beta: f64,
    /// sigma = (cosh bL + cos bL) / (sinh bL + sin bL).
    sigma: f64,
}

impl CantileverMode {
    /// The mode of a beam of length L (m).
    pub fn new(length: f64) -> Self {
        // Newton on f(x) = 1 + cos x cosh x from 1.875 (converges in a few steps)
        let mut x = 1.875_f64;
        for _ in 0..50 {
            let f = 1.0 + x.cos() * x.cosh();
            let df = -x.sin() * x.cosh() + x.cos() * x.sinh();
            let dx = f / df;
            x -= dx;
            if dx.abs() < 1e-15 {
                break;
            }
        }
        let sigma = (x.cosh() + x.cos()) / (x.sinh() + x.sin());
        CantileverMode {
            length,
            beta: x / length,
            sigma,
        }
    }
    /// beta_1 L (dimensionless, 1.8751...); the tests check it against the known root.
    #[cfg(test)]
    fn beta_l(&self) -> f64 {
        self.beta * self.length
    }
    /// omega_1 = beta_1^2 sqrt(B / mu), rad/s, for bending stiffness B (N m^2) and mass
    /// per length mu (kg/m).
    pub fn angular_frequency(&self, bending: f64, mass_per_length: f64) -> f64 {
        self.beta * self.beta * (bending / mass_per_length).sqrt()
    }
    /// Mode shape phi(s), normalized to phi(L) = 1.
    pub fn shape(&self, s: f64) -> f64 {
        self.raw(s) / self.raw(self.length)
    }
    /// Slope phi'(s) (1/m), with the same normalization.
    pub fn slope(&self, s: f64) -> f64 {
        let b = self.beta;
        let x = b * s;
        b * (x.sinh() + x.sin() - self.sigma * (x.cosh() - x.cos())) / self.raw(self.length)
    }
    fn raw(&self, s: f64) -> f64 {
        let x = self.beta * s;
        x.cosh() - x.cos() - self.sigma * (x.sinh() - x.sin())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A small weight gives the Euler-Bernoulli deflection (relative error of order
    /// (q L^3 / B)^2 from the geometric nonlinearity: 1e-4 at q L^3 / B = 0.01).
    #[test]
    fn a_lightly_loaded_heavy_cantilever_has_the_beam_deflection() {
        let (l, b, q) = (1.0, 1.0, 0.01);
        let c = heavy_cantilever(l, b, q);
        for s in [0.25, 0.5, 0.75, 1.0] {
            let w = q * s * s * (6.0 * l * l - 4.0 * l * s + s * s) / (24.0 * b);
            let z = c.at(s)[1];
            assert!((-z - w).abs() < 1e-4 * w, "s {s}: {z} vs {w}");
        }
        // the free end carries no moment
        assert!((c.end()[1] + q / (8.0 * b)).abs() < 1e-4 * q / 8.0);
    }

    /// RK4 at STEPS is converged: half the steps moves the tip by < 1e-12 L at a large
    /// deflection (q L^3 / B = 10, tip ~0.7 L down).
    #[test]
    fn the_shooting_solution_is_converged_in_its_steps() {
        let (l, b, q) = (1.0, 0.01, 0.1);
        let fine = heavy_cantilever(l, b, q);
        let coarse = heavy_cantilever_in(l, b, q, STEPS / 2);
        let (a, c) = (fine.end(), coarse.end());
        let d = ((a[0] - c[0]).powi(2) + (a[1] - c[1]).powi(2)).sqrt();
        assert!(d < 1e-12, "{d}");
        assert!(a[1] < -0.6 && a[0] > 0.3, "{a:?}");
    }

    #[test]
    fn elliptic_integrals_match_tabulated_values() {
        // K(0) = E(0) = pi/2; k = sin 45 deg: K = 1.8540746773, E = 1.3506438810 (A&S
        // table 17.5)
        let (k0, e0) = elliptic_ke(0.0);
        assert!((k0 - std::f64::consts::FRAC_PI_2).abs() < 1e-15);
        assert!((e0 - std::f64::consts::FRAC_PI_2).abs() < 1e-15);
        let (k, e) = elliptic_ke(std::f64::consts::FRAC_1_SQRT_2);
        assert!((k - 1.854_074_677_3).abs() < 1e-9, "{k}");
        assert!((e - 1.350_643_881_0).abs() < 1e-9, "{e}");
    }

    /// The closed form meets the clamped boundary conditions at the far end and its
    /// midpoint rise; the buckling load tends to 4 pi^2 B / L^2 as D -> L.
    #[test]
    fn the_buckled_strip_closes_on_its_far_clamp() {
        let (l, b) = (1.0, 0.01);
        for d in [0.98, 0.9, 0.7] {
            let s = clamped_buckled(l, b, d);
            let end = s.curve.end();
            let theta = *s.curve.angles.last().unwrap();
            assert!((end[0] - d).abs() < 1e-11, "{d}: {end:?}");
            assert!(
                end[1].abs() < 1e-11 && theta.abs() < 1e-10,
                "{d}: {end:?} {theta}"
            );
            let mid = s.curve.at(0.5 * l);
            assert!((mid[1] - s.midpoint_rise).abs() < 1e-11);
            assert!((mid[0] - 0.5 * d).abs() < 1e-11);
        }
        let euler = 4.0 * std::f64::consts::PI.powi(2) * b / (l * l);
        let slight = clamped_buckled(l, b, 0.9999);
        assert!(
            (slight.load / euler - 1.0).abs() < 1e-3,
            "{}",
            slight.load / euler
        );
    }

    #[test]
    fn the_first_cantilever_mode_is_the_textbook_one() {
        let m = CantileverMode::new(2.0);
        assert!(
            (m.beta_l() - 1.875_104_068_7).abs() < 1e-9,
            "{}",
            m.beta_l()
        );
        assert!(m.shape(0.0).abs() < 1e-15 && m.slope(0.0).abs() < 1e-15);
        assert!((m.shape(2.0) - 1.0).abs() < 1e-15);
        // slope against a central difference of the shape
        let s = 1.3;
        let fd = (m.shape(s + 1e-6) - m.shape(s - 1e-6)) / 2e-6;
        assert!((m.slope(s) - fd).abs() < 1e-8);
        // omega = 3.5160 sqrt(B / (mu L^4))
        let w = m.angular_frequency(1.0, 1.0) * 4.0;
        assert!((w - 3.516_015).abs() < 1e-5, "{w}");
    }
}
