//! One linear inequality besides the box, |Σ_{i in S} x_i| <= bound over a contiguous
//! index range S (a slab): the projection onto the box and the slab, and whether x
//! sits on one of its two faces.
//!
//! The ribbon needs exactly one: after the substitution z_k = c_k - c_{k-1} the crease
//! bounds of eq. (1) are a box, and the last one, |c_{n-1}| <= Δc_max, is
//! |Σ_k z_k| <= Δc_max (sec. 5.1). The trust-region solver holds it exactly, instead of
//! by the augmented-Lagrangian term mu/2 min(C + λ/μ, 0)^2, whose curvature jumps
//! between 0 and mu at the bound (docs/ribbon_chain_solver.md).

use std::ops::Range;

/// |Σ_{i in start..end} x_i| <= bound (bound >= 0).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Slab {
    pub range: Range<usize>,
    pub bound: f64,
}

/// Relative tolerance of "on a face": |Σ| >= bound - eps (1 + bound), as for a box bound.
const FACE_EPS: f64 = 1e-12;

/// `y` projected onto the box [lower, upper] and, if any, the slab: the feasible set of
/// both Newton methods that can hold the end crease exactly.
pub fn project_feasible(slab: Option<&Slab>, y: &mut [f64], lower: &[f64], upper: &[f64]) {
    match slab {
        Some(slab) => {
            slab.project(y, lower, upper, 0.0);
        }
        None => {
            for i in 0..y.len() {
                y[i] = y[i].clamp(lower[i], upper[i]);
            }
        }
    }
}

/// |P(x - g) - x|_inf, P the projection onto the box and, if any, the slab (both Newton
/// methods' stopping measure), and the slab projection's multiplier τ (0 without one).
/// `point` is a kept buffer.
pub fn projected_gradient(
    slab: Option<&Slab>,
    (x, g): (&[f64], &[f64]),
    (lower, upper): (&[f64], &[f64]),
    point: &mut Vec<f64>,
) -> (f64, f64) {
    let Some(slab) = slab else {
        return (super::projected_gradient_inf(x, g, lower, upper), 0.0);
    };
    point.clear();
    point.extend(x.iter().zip(g).map(|(a, b)| a - b));
    let tau = slab.project(point, lower, upper, 0.0);
    let norm = point
        .iter()
        .zip(x)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    (norm, tau)
}

impl Slab {
    /// Σ_{i in S} x_i, summed from the first entry on: the same floating-point value as
    /// the ribbon's c_{n-1} = (((z_1 + z_2) + z_3) + ...) of `ribbon::step::z_to_q`.
    pub fn sum(&self, x: &[f64]) -> f64 {
        x[self.range.clone()].iter().sum()
    }

    /// The face x sits on: +1 (Σ = bound), -1 (Σ = -bound) or 0 (inside).
    pub fn face(&self, x: &[f64]) -> f64 {
        let s = self.sum(x);
        if s.abs() >= self.bound - FACE_EPS * (1.0 + self.bound) {
            s.signum()
        } else {
            0.0
        }
    }

    /// Project `y` onto the box [lower, upper] and the slab: x_i = clamp(y_i - τ) on S
    /// with the one multiplier τ that puts Σ on the face it crossed (Σ clamp(y_i - τ) is
    /// continuous, piecewise linear and non-increasing in τ), x_i = clamp(y_i) off S.
    /// The Euclidean projection; the caller guarantees that box and slab intersect.
    /// Afterwards |Σ| <= bound holds exactly in floating point (see [`Self::sum`]).
    /// `hint`: a τ to start the search from (the last projection's, on a path of
    /// nearby points). Returns τ (0 where only the box was needed). No allocation.
    pub fn project(&self, y: &mut [f64], lower: &[f64], upper: &[f64], hint: f64) -> f64 {
        for i in 0..y.len() {
            if !self.range.contains(&i) {
                y[i] = y[i].clamp(lower[i], upper[i]);
            }
        }
        let (s0, _) = self.clamped_sum(y, lower, upper, 0.0);
        let target = s0.clamp(-self.bound, self.bound);
        let tau = if s0 == target {
            0.0
        } else {
            self.multiplier(y, lower, upper, target, hint)
        };
        for i in self.range.clone() {
            y[i] = (y[i] - tau).clamp(lower[i], upper[i]);
        }
        self.settle(y, lower, upper);
        tau
    }

    /// Σ clamp(y_i - τ) over S and the number of entries strictly inside their box
    /// there (minus the slope of the sum in τ), in one pass.
    fn clamped_sum(&self, y: &[f64], lower: &[f64], upper: &[f64], tau: f64) -> (f64, usize) {
        let mut sum = 0.0;
        let mut inside = 0;
        for i in self.range.clone() {
            let v = y[i] - tau;
            if v <= lower[i] {
                sum += lower[i];
            } else if v >= upper[i] {
                sum += upper[i];
            } else {
                sum += v;
                inside += 1;
            }
        }
        (sum, inside)
    }

    /// The τ with Σ clamp(y_i - τ) = target: Newton's method on the piecewise linear
    /// φ(τ) from `hint` (exact once no kink is left between it and the root), kept in
    /// a bracket and falling back to regula falsi (Illinois) inside it.
    fn multiplier(&self, y: &[f64], lower: &[f64], upper: &[f64], target: f64, hint: f64) -> f64 {
        // φ(0) has the sign of target (Σ is beyond the face it crossed)
        let (mut lo, mut hi) = if target > 0.0 {
            (0.0, f64::INFINITY)
        } else {
            (f64::NEG_INFINITY, 0.0)
        };
        let (mut f_lo, mut f_hi) = (f64::NAN, f64::NAN);
        let width = self
            .range
            .clone()
            .map(|i| (upper[i] - lower[i]).min(1e300))
            .fold(0.0, f64::max);
        let mut tau = if hint.is_finite() && hint > lo && hint < hi {
            hint
        } else {
            0.0
        };
        let mut side = 0;
        for _ in 0..200 {
            let (sum, inside) = self.clamped_sum(y, lower, upper, tau);
            let value = sum - target;
            if value == 0.0 {
                return tau;
            }
            if value > 0.0 {
                lo = tau;
                f_lo = value;
            } else {
                hi = tau;
                f_hi = value;
            }
            if hi - lo <= 4.0 * f64::EPSILON * tau.abs().max(f64::MIN_POSITIVE) {
                break;
            }
            let newton = tau + value / inside.max(1) as f64;
            tau = if inside > 0 && newton > lo && newton < hi {
                newton
            } else if lo.is_finite() && hi.is_finite() {
                // regula falsi, halving the stale end's value (Illinois)
                if value > 0.0 {
                    if side == 1 {
                        f_hi *= 0.5;
                    }
                    side = 1;
                } else {
                    if side == -1 {
                        f_lo *= 0.5;
                    }
                    side = -1;
                }
                let t = lo + f_lo * (hi - lo) / (f_lo - f_hi);
                if t > lo && t < hi {
                    t
                } else {
                    0.5 * (lo + hi)
                }
            } else {
                // no bracket yet: step out by the widest box
                tau + value.signum() * width.max(value.abs())
            };
        }
        // the bracket's end on the feasible side (Σ within the bound)
        if hi.is_finite() && target > 0.0 {
            hi
        } else if lo.is_finite() && target < 0.0 {
            lo
        } else {
            tau
        }
    }

    /// Round-off: a sum a few ulps beyond the bound is brought back by moving the
    /// entries of S that are inside their box (never out of it) by the excess, at least
    /// one ulp each (an excess below an entry's ulp would not move it).
    fn settle(&self, y: &mut [f64], lower: &[f64], upper: &[f64]) {
        for _ in 0..16 {
            let s = self.sum(y);
            if s.abs() <= self.bound {
                return;
            }
            let mut left = s - s.signum() * self.bound;
            for i in self.range.clone() {
                let mut moved = (y[i] - left).clamp(lower[i], upper[i]);
                if moved == y[i] {
                    let nudged = if left > 0.0 {
                        y[i].next_down()
                    } else {
                        y[i].next_up()
                    };
                    moved = nudged.clamp(lower[i], upper[i]);
                }
                left -= y[i] - moved;
                y[i] = moved;
                if left * s <= 0.0 {
                    break;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn projection_is_the_nearest_point_of_box_and_slab() {
        // brute force over a fine grid of the 3 slab entries: the projection is the
        // nearest feasible point
        let slab = Slab {
            range: 1..4,
            bound: 1.0,
        };
        let lower = [-10.0, -0.5, -0.7, -0.5, -10.0];
        let upper = [10.0, 0.5, 0.6, 0.5, 10.0];
        for y0 in [
            [0.3, 0.9, 0.8, 0.2, -20.0],
            [0.0, -0.4, -0.6, -0.45, 1.0],
            [1.0, 0.1, 0.2, 0.3, 2.0],
            [0.0, 0.45, 0.58, 0.2, 0.0],
        ] {
            let mut y = y0;
            let tau = slab.project(&mut y, &lower, &upper, 0.0);
            assert!(slab.sum(&y).abs() <= 1.0, "{y:?}");
            for i in 0..5 {
                assert!(y[i] >= lower[i] && y[i] <= upper[i], "{y:?}");
            }
            assert_eq!(y[0], y0[0].clamp(-10.0, 10.0));
            assert_eq!(y[4], y0[4].clamp(-10.0, 10.0));
            let dist = |p: &[f64; 3]| (1..4).map(|i| (p[i - 1] - y0[i]).powi(2)).sum::<f64>();
            let found = dist(&[y[1], y[2], y[3]]);
            let steps = 60;
            let mut best = f64::INFINITY;
            for a in 0..=steps {
                for b in 0..=steps {
                    for c in 0..=steps {
                        let p = [
                            lower[1] + (upper[1] - lower[1]) * a as f64 / steps as f64,
                            lower[2] + (upper[2] - lower[2]) * b as f64 / steps as f64,
                            lower[3] + (upper[3] - lower[3]) * c as f64 / steps as f64,
                        ];
                        if p.iter().sum::<f64>().abs() <= 1.0 {
                            best = best.min(dist(&p));
                        }
                    }
                }
            }
            // the grid's nearest point is within half a cell (0.02) of the true one
            assert!(found <= best + 1e-12, "{y:?}: {found} > grid {best}");
            assert!(found >= best - 0.05, "{y:?}: {found} far below grid {best}");
            if (y0[1..4].iter().map(|v| v.clamp(-0.7, 0.6)).sum::<f64>()).abs() <= 1.0 {
                assert_eq!(tau, 0.0);
            }
        }
    }

    #[test]
    fn the_projected_sum_is_within_the_bound_in_floating_point() {
        // many entries whose exact projection puts the sum on the bound: the sum as the
        // ribbon computes c_{n-1} never exceeds it, not even by an ulp
        let n = 801;
        let bound = 0.0475;
        let lower = vec![-bound; n];
        let upper = vec![bound; n];
        let slab = Slab { range: 1..n, bound };
        for seed in 0..20u64 {
            let mut y: Vec<f64> = (0..n)
                .map(|i| ((i as u64 * 2654435761 + seed * 97) % 1000) as f64 * 1e-4 - 0.04)
                .collect();
            slab.project(&mut y, &lower, &upper, 0.0);
            let s = slab.sum(&y);
            assert!(s.abs() <= bound, "seed {seed}: {s}");
            assert!(slab.face(&y) != 0.0, "seed {seed}: {s} should be on a face");
        }
    }
}
