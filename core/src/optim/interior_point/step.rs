//! The interior-point iteration's pieces: the condensed system with inertia
//! correction, the duals' step, fraction to the boundary, the barrier update.

use super::*;

impl<M: BarrierMatrix> InteriorPoint<M> {
    /// The primal step dx (into `self.dx`) from the condensed system, -∇φ_μ in
    /// `self.rhs`, and the duals' steps. False if no factorization succeeds.
    pub(super) fn direction(&mut self, x: &[f64], lower: &[f64], upper: &[f64]) -> bool {
        let mu = self.mu;
        for i in 0..x.len() {
            let mut sigma = 0.0;
            let mut barrier_g = 0.0;
            if lower[i].is_finite() {
                let s = x[i] - lower[i];
                sigma += self.zl[i] / s;
                barrier_g -= mu / s;
            }
            if upper[i].is_finite() {
                let s = upper[i] - x[i];
                sigma += self.zu[i] / s;
                barrier_g += mu / s;
            }
            self.shift[i] = sigma;
            self.rhs[i] = -(self.g[i] + barrier_g);
        }
        let face = match (self.slab.clone(), self.slab_slacks(x)) {
            (Some(slab), Some((rp, rm))) => {
                let along = mu / rp - mu / rm;
                for i in slab.range.clone() {
                    self.rhs[i] -= along;
                }
                Some((slab.range, self.v[0] / rp + self.v[1] / rm))
            }
            _ => None,
        };
        if !self.factor_corrected(face) {
            return false;
        }
        if !self.h.solve_shifted(&self.rhs, &mut self.dx) {
            return false;
        }
        for i in 0..x.len() {
            let d = self.dx[i];
            self.dzl[i] = if lower[i].is_finite() {
                let s = x[i] - lower[i];
                mu / s - self.zl[i] - self.zl[i] / s * d
            } else {
                0.0
            };
            self.dzu[i] = if upper[i].is_finite() {
                let s = upper[i] - x[i];
                mu / s - self.zu[i] + self.zu[i] / s * d
            } else {
                0.0
            };
        }
        if let (Some(slab), Some((rp, rm))) = (&self.slab, self.slab_slacks(x)) {
            let across: f64 = self.dx[slab.range.clone()].iter().sum();
            self.dv = [
                mu / rp - self.v[0] + self.v[0] / rp * across,
                mu / rm - self.v[1] - self.v[1] / rm * across,
            ];
        }
        true
    }

    /// Factorize with IPOPT's inertia correction: δ_w = 0 first (unless the last line
    /// search failed), else from a third of the last δ_w, grown 8x (100x without a
    /// last one) until positive definite.
    fn factor_corrected(&mut self, face: Option<(std::ops::Range<usize>, f64)>) -> bool {
        let mut delta = if self.force_delta {
            self.force_delta = false;
            self.delta_last.max(DELTA_FIRST)
        } else {
            0.0
        };
        let mut corrected = false;
        loop {
            self.base_shift.clear();
            self.base_shift.extend_from_slice(&self.shift);
            if delta > 0.0 {
                for s in self.shift.iter_mut() {
                    *s += delta;
                }
            }
            self.factorizations += 1;
            let ok = self.h.factor_shifted(&self.shift, face.clone());
            self.shift.copy_from_slice(&self.base_shift);
            if ok {
                if delta > 0.0 {
                    self.delta_last = delta;
                    corrected = true;
                }
                break;
            }
            delta = if delta == 0.0 {
                if self.delta_last == 0.0 {
                    DELTA_FIRST
                } else {
                    (DELTA_SHRINK * self.delta_last).max(DELTA_MIN)
                }
            } else if self.delta_last == 0.0 {
                delta * DELTA_GROW_FIRST
            } else {
                delta * DELTA_GROW
            };
            if delta > DELTA_MAX {
                return false;
            }
        }
        self.counts.corrected += u32::from(corrected);
        true
    }

    /// The largest primal and dual steps (at most 1) that keep every slack and dual
    /// above (1 - τ) of its value, τ = max(TAU_MIN, 1 - μ).
    pub(super) fn fraction_to_boundary(
        &self,
        x: &[f64],
        lower: &[f64],
        upper: &[f64],
    ) -> (f64, f64) {
        let tau = TAU_MIN.max(1.0 - self.mu);
        let mut ap: f64 = 1.0;
        let mut ad: f64 = 1.0;
        let limit = |value: f64, step: f64| {
            if step < 0.0 {
                -tau * value / step
            } else {
                f64::INFINITY
            }
        };
        for i in 0..x.len() {
            let d = self.dx[i];
            if lower[i].is_finite() {
                ap = ap.min(limit(x[i] - lower[i], d));
                ad = ad.min(limit(self.zl[i], self.dzl[i]));
            }
            if upper[i].is_finite() {
                ap = ap.min(limit(upper[i] - x[i], -d));
                ad = ad.min(limit(self.zu[i], self.dzu[i]));
            }
        }
        if let (Some(slab), Some((rp, rm))) = (&self.slab, self.slab_slacks(x)) {
            let across: f64 = self.dx[slab.range.clone()].iter().sum();
            ap = ap.min(limit(rp, -across)).min(limit(rm, across));
            ad = ad
                .min(limit(self.v[0], self.dv[0]))
                .min(limit(self.v[1], self.dv[1]));
        }
        (ap, ad)
    }

    /// The duals' step of length `alpha` (x already moved), then the safeguard.
    pub(super) fn step_duals(&mut self, alpha: f64, x: &[f64], lower: &[f64], upper: &[f64]) {
        for i in 0..x.len() {
            self.zl[i] += alpha * self.dzl[i];
            self.zu[i] += alpha * self.dzu[i];
        }
        if self.slab.is_some() {
            self.v[0] += alpha * self.dv[0];
            self.v[1] += alpha * self.dv[1];
        }
        self.safeguard_duals(x, lower, upper);
    }

    /// The barrier problem's optimality error at x: stationarity of the Lagrangian
    /// (g - z_L + z_U + a (v_+ - v_-)) and complementarity (z s - μ), infinity norms.
    fn barrier_error(&self, x: &[f64], lower: &[f64], upper: &[f64], mu: f64) -> f64 {
        let along = self
            .slab
            .as_ref()
            .map(|_| self.v[0] - self.v[1])
            .unwrap_or(0.0);
        let range = self.slab.as_ref().map(|s| s.range.clone()).unwrap_or(0..0);
        let mut err: f64 = 0.0;
        for i in 0..x.len() {
            let mut r = self.g[i] - self.zl[i] + self.zu[i];
            if range.contains(&i) {
                r += along;
            }
            err = err.max(r.abs());
            if lower[i].is_finite() {
                err = err.max((self.zl[i] * (x[i] - lower[i]) - mu).abs());
            }
            if upper[i].is_finite() {
                err = err.max((self.zu[i] * (upper[i] - x[i]) - mu).abs());
            }
        }
        if let Some((rp, rm)) = self.slab_slacks(x) {
            err = err
                .max((self.v[0] * rp - mu).abs())
                .max((self.v[1] * rm - mu).abs());
        }
        err
    }

    /// μ <- max(mu_min, min(KAPPA_MU μ, μ^THETA)).
    pub(super) fn next_mu(&mut self, mu_min: f64) {
        self.mu = (KAPPA_MU * self.mu).min(self.mu.powf(THETA_MU)).max(mu_min);
        self.counts.mu_stages += 1;
    }

    /// Fiacco-McCormick: while the barrier problem is solved to KAPPA_EPS μ, μ <-
    /// max(mu_min, min(KAPPA_MU μ, μ^THETA)); φ_μ re-evaluated at x.
    pub(super) fn update_mu(
        &mut self,
        x: &[f64],
        lower: &[f64],
        upper: &[f64],
        mu_min: f64,
        state: &mut State,
    ) {
        let mut changed = false;
        while self.mu > mu_min
            && self.barrier_error(x, lower, upper, self.mu) <= KAPPA_EPS * self.mu
        {
            self.next_mu(mu_min);
            changed = true;
        }
        if changed {
            state.phi = self.barrier(x, lower, upper, state.f);
        }
    }
}
