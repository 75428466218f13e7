//! A primal-dual interior-point method for bound-constrained minimization with one
//! optional slab |Σ_S x_i| <= b (issue 47, `solver.kind: interior_point`), in the
//! family of IPOPT (Wächter and Biegler 2006) restricted to inequalities that are
//! bounds on the unknowns or on one sum of them, so that the primal-dual system
//! condenses onto the Newton matrix of f itself:
//!
//! (H + Σ + ρ a a^T + δ_w I) Δx = -∇φ_μ(x),
//!
//! Σ = Z_L S_L^{-1} + Z_U S_U^{-1} on the bounded unknowns (a diagonal, which the
//! ribbon's chain sweep takes per crease), a the slab's indicator and ρ = v_+ / r_+ +
//! v_- / r_- (on the chain: a penalty on its terminal value c_{n-1} = Σ z_k, so no
//! Sherman-Morrison is needed), φ_μ = f - μ Σ ln(slacks) the barrier objective. The
//! duals follow from Δx (dz = μ/s - z - σ ds). Nonconvexity by IPOPT's inertia
//! correction: δ_w = 0 first, raised only when the factorization is not positive
//! definite (8x, from a third of the last one). Fraction to the boundary τ =
//! max(0.99, 1 - μ) for primal and dual steps separately; an Armijo backtracking on
//! φ_μ (the exact merit function here: there are no equality constraints inside);
//! μ monotone (Fiacco-McCormick): μ <- max(μ_min, min(κ_μ μ, μ^θ)) once the barrier
//! problem's error is below κ_ε μ. The stop is the projected Newton method's: the
//! projected gradient onto box and slab, so both solvers end on the same test.
//!
//! Warm start: x pushed strictly inside by a fraction of each bound's width, the duals
//! of the last solve (same dimension) kept and μ set from their complementarity.

mod dense;
#[cfg(test)]
mod tests;

use super::projected_newton::{BoxProblem, NewtonMatrix, NewtonOptions, NewtonResult};
use super::slab::Slab;

/// What the interior-point method needs of a Newton matrix: a factorization of
/// H + diag(shift) (+ rho (Σ_{i in range} d_i)^2) on every unknown and solves with it.
pub trait BarrierMatrix: NewtonMatrix {
    /// Factorize H + diag(shift) + rho a a^T (a the indicator of `face.0`, rho =
    /// `face.1`) over all unknowns. False where not positive definite.
    fn factor_shifted(
        &mut self,
        shift: &[f64],
        face: Option<(std::ops::Range<usize>, f64)>,
    ) -> bool;
    /// Solve with the last factorization (full length). False if not finite.
    fn solve_shifted(&mut self, rhs: &[f64], out: &mut [f64]) -> bool;
}

/// Fraction-to-the-boundary floor (IPOPT's τ_min).
const TAU_MIN: f64 = 0.99;
/// Armijo constant on φ_μ.
const ARMIJO: f64 = 1e-4;
/// Barrier update: μ <- min(KAPPA_MU μ, μ^THETA) once E_μ <= KAPPA_EPS μ.
const KAPPA_MU: f64 = 0.2;
const THETA_MU: f64 = 1.5;
const KAPPA_EPS: f64 = 10.0;
/// Dual safeguard: z within [μ / (K s), K μ / s].
const KAPPA_SIGMA: f64 = 1e10;
/// Inertia correction (IPOPT): first δ_w, its growth (after none before / after one
/// before), its decrease from the last one, its bounds.
const DELTA_FIRST: f64 = 1e-4;
const DELTA_GROW_FIRST: f64 = 100.0;
const DELTA_GROW: f64 = 8.0;
const DELTA_SHRINK: f64 = 1.0 / 3.0;
const DELTA_MIN: f64 = 1e-20;
const DELTA_MAX: f64 = 1e40;
/// The smallest μ, a fraction of the projected-gradient tolerance. The slack at an
/// active bound ends near μ / z: with 1e-3 (z ~ 1e-4 on the extreme torsion) the crease
/// differences stayed 1e-5 of Δc_max inside their bounds, where the singular-point test
/// (1e-6 of Δc_max) does not see them (1-2 singular points at n = 400 against the
/// damped solver's 38-65); 1e-6 puts them there in fewer iterations (median 36 against
/// 45 at n = 400, seed 1), 1e-9 takes more (47).
const MU_MIN: f64 = 1e-6;
/// The start is pushed inside by this fraction of each bound's width (IPOPT's
/// bound_frac κ_2 = 1e-2; 1e-3 and 1e-4 took 1.4x the iterations on the extreme
/// torsion at n = 400, docs/ribbon_chain_solver.md 2026-12-07).
const PUSH: f64 = 1e-2;
/// A warm start's μ: this times the average complementarity of the kept duals at the
/// pushed start (1: 1.2x the iterations at n = 400; 1e4: the same as 100).
const MU_WARM: f64 = 100.0;

/// Counts of one solve (for the measurements of docs/ribbon_chain_solver.md).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BarrierCounts {
    /// Barrier-parameter decreases.
    pub mu_stages: u32,
    /// Iterations whose factorization needed δ_w > 0.
    pub corrected: u32,
    /// Line-search cuts (trials rejected).
    pub cuts: u32,
    /// Final μ.
    pub mu: f64,
    /// Iterations before the first decrease of μ (on the first barrier problem).
    pub first_stage_iterations: u32,
}

/// Workspace of the interior-point method; buffers reused between calls.
#[derive(Default)]
pub struct InteriorPoint<M: BarrierMatrix> {
    h: M,
    g: Vec<f64>,
    g_trial: Vec<f64>,
    /// Duals of the lower and upper bounds (0 where unbounded).
    zl: Vec<f64>,
    zu: Vec<f64>,
    dzl: Vec<f64>,
    dzu: Vec<f64>,
    /// The slab's duals (of b - Σ >= 0 and b + Σ >= 0) and their steps.
    v: [f64; 2],
    dv: [f64; 2],
    shift: Vec<f64>,
    /// Σ without δ_w (restored after each trial factorization).
    base_shift: Vec<f64>,
    rhs: Vec<f64>,
    dx: Vec<f64>,
    trial: Vec<f64>,
    point: Vec<f64>,
    slab: Option<Slab>,
    mu: f64,
    /// Last δ_w > 0 (0: none yet).
    delta_last: f64,
    /// A line search failed: the next factorization starts at δ_w = `delta_last`.
    force_delta: bool,

    /// Whether the duals come from a solve of this dimension (warm start).
    warm: bool,
    factorizations: u32,
    pub counts: BarrierCounts,
}

impl<M: BarrierMatrix> Clone for InteriorPoint<M> {
    fn clone(&self) -> Self {
        self.fresh_with_history()
    }
}

impl<M: BarrierMatrix> std::fmt::Debug for InteriorPoint<M> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("InteriorPoint")
            .field("mu", &self.mu)
            .finish()
    }
}

struct State {
    f: f64,
    /// φ_μ at x.
    phi: f64,
    pg: f64,
    iterations: u32,
    evaluations: u32,
    hessian_ready: bool,
}

impl<M: BarrierMatrix> InteriorPoint<M> {
    pub fn new() -> Self {
        Self::default()
    }

    /// A workspace whose next solve runs as this one's would (the duals, μ and δ_w
    /// carried from solve to solve are copied).
    pub fn fresh_with_history(&self) -> Self {
        InteriorPoint {
            zl: self.zl.clone(),
            zu: self.zu.clone(),
            v: self.v,
            mu: self.mu,
            delta_last: self.delta_last,
            warm: self.warm,
            ..Self::default()
        }
    }

    /// Minimize `problem` over [lower, upper] and `slab` from `x` (moved strictly
    /// inside first), writing the last iterate to `x`.
    pub fn minimize(
        &mut self,
        problem: &mut impl BoxProblem<Matrix = M>,
        x: &mut [f64],
        lower: &[f64],
        upper: &[f64],
        slab: Option<Slab>,
        options: &NewtonOptions,
    ) -> NewtonResult {
        self.slab = slab;
        // (per solve: a clone made between solves continues bit for bit)
        self.force_delta = false;
        self.counts = BarrierCounts::default();
        self.factorizations = 0;
        self.counts.first_stage_iterations = 0;
        let n = x.len();
        for v in [&mut self.g, &mut self.g_trial, &mut self.dzl, &mut self.dzu] {
            v.resize(n, 0.0);
        }
        for v in [
            &mut self.shift,
            &mut self.rhs,
            &mut self.dx,
            &mut self.trial,
        ] {
            v.resize(n, 0.0);
        }
        self.push_inside(x, lower, upper);
        let f = problem.evaluate(x, Some(&mut self.g), None);
        let mut state = State {
            f,
            phi: 0.0,
            pg: self.projected_gradient(x, lower, upper),
            iterations: 0,
            evaluations: 1,
            hessian_ready: false,
        };
        let pgtol = match options.pgtol_relative_to_start {
            Some(factor) => factor * state.pg.max(1e-300),
            None => options.pgtol,
        };
        let initial_pg = state.pg;
        let mu_min = MU_MIN * pgtol;
        self.start_duals(x, lower, upper, mu_min);
        state.phi = self.barrier(x, lower, upper, state.f);
        let mut converged = state.pg <= pgtol;
        let finite = state.f.is_finite();
        while finite && !converged && state.iterations < options.max_iterations {
            state.iterations += 1;
            let phi_old = state.phi;
            if !self.iterate(problem, x, lower, upper, &mut state) {
                break;
            }
            state.pg = self.projected_gradient(x, lower, upper);
            converged = state.pg <= pgtol;
            // The resampling operator's kinks stall the gradient (as for the projected
            // Newton method's FTOL test): a step that lowers φ_μ by less than ftol
            // relative ends this barrier problem, and the solve once μ is at its floor.
            let stalled =
                phi_old - state.phi <= options.ftol * phi_old.abs().max(state.phi.abs()).max(1.0);
            if stalled && !converged {
                if self.mu <= mu_min {
                    converged = true;
                } else {
                    self.next_mu(mu_min);
                    state.phi = self.barrier(x, lower, upper, state.f);
                }
            }
            if self.counts.mu_stages == 0 {
                self.counts.first_stage_iterations = state.iterations;
            }
            self.update_mu(x, lower, upper, mu_min, &mut state);
        }
        self.counts.mu = self.mu;
        self.warm = true;
        NewtonResult {
            f: state.f,
            iterations: state.iterations,
            evaluations: state.evaluations,
            projected_gradient_inf: state.pg,
            factorizations: self.factorizations,
            initial_projected_gradient_inf: initial_pg,
            converged,
        }
    }

    /// Move x strictly inside: every finite bound at least `push` times the box's
    /// width away (or `push` max(1, |bound|) for a half-bounded unknown), the slab's
    /// sum likewise inside b.
    fn push_inside(&mut self, x: &mut [f64], lower: &[f64], upper: &[f64]) {
        let push = PUSH;
        let margin = |l: f64, u: f64| {
            if l.is_finite() && u.is_finite() {
                push * (u - l)
            } else if l.is_finite() {
                push * l.abs().max(1.0)
            } else if u.is_finite() {
                push * u.abs().max(1.0)
            } else {
                0.0
            }
        };
        let mut lo = std::mem::take(&mut self.point);
        lo.clear();
        lo.extend((0..x.len()).map(|i| lower[i] + margin(lower[i], upper[i])));
        let mut hi = std::mem::take(&mut self.trial);
        hi.clear();
        hi.extend((0..x.len()).map(|i| upper[i] - margin(lower[i], upper[i])));
        match &self.slab {
            Some(slab) => {
                let inner = Slab {
                    range: slab.range.clone(),
                    bound: slab.bound * (1.0 - 2.0 * push),
                };
                inner.project(x, &lo, &hi, 0.0);
            }
            None => {
                for i in 0..x.len() {
                    x[i] = x[i].clamp(lo[i], hi[i]);
                }
            }
        }
        self.point = lo;
        self.trial = hi;
    }

    /// The slacks of the slab at x: (b - Σ, b + Σ), or None without one.
    fn slab_slacks(&self, x: &[f64]) -> Option<(f64, f64)> {
        self.slab.as_ref().map(|s| {
            let sum = s.sum(x);
            (s.bound - sum, s.bound + sum)
        })
    }

    /// The duals at the start: the last solve's (same dimension), μ = MU_WARM times
    /// their average complementarity at the pushed start, each dual kept within the
    /// safeguard; without them, centred (z = μ / s) on μ = the average of s |g| over
    /// the bounded unknowns (the barrier's force μ / s then matches the gradient's).
    fn start_duals(&mut self, x: &[f64], lower: &[f64], upper: &[f64], mu_min: f64) {
        let n = x.len();
        let warm = self.warm && self.zl.len() == n;
        self.zl.resize(n, 0.0);
        self.zu.resize(n, 0.0);
        if !warm {
            // centred: μ0 from the gradient scale times the slacks
            let mut sum = 0.0;
            let mut count = 0usize;
            for i in 0..n {
                if lower[i].is_finite() || upper[i].is_finite() {
                    let s = (x[i] - lower[i]).min(upper[i] - x[i]);
                    sum += s * self.g[i].abs();
                    count += 1;
                }
            }
            self.mu = (sum / count.max(1) as f64).max(mu_min);
            for i in 0..n {
                self.zl[i] = if lower[i].is_finite() {
                    self.mu / (x[i] - lower[i])
                } else {
                    0.0
                };
                self.zu[i] = if upper[i].is_finite() {
                    self.mu / (upper[i] - x[i])
                } else {
                    0.0
                };
            }
            if let Some((rp, rm)) = self.slab_slacks(x) {
                self.v = [self.mu / rp, self.mu / rm];
            }
            return;
        }
        let mut sum = 0.0;
        let mut count = 0usize;
        for i in 0..n {
            if lower[i].is_finite() {
                sum += self.zl[i] * (x[i] - lower[i]);
                count += 1;
            }
            if upper[i].is_finite() {
                sum += self.zu[i] * (upper[i] - x[i]);
                count += 1;
            }
        }
        if let Some((rp, rm)) = self.slab_slacks(x) {
            sum += self.v[0] * rp + self.v[1] * rm;
            count += 2;
        }
        self.mu = (MU_WARM * sum / count.max(1) as f64).max(mu_min);
        self.safeguard_duals(x, lower, upper);
    }

    /// z within [μ / (K s), K μ / s] for every slack s (IPOPT's safeguard).
    fn safeguard_duals(&mut self, x: &[f64], lower: &[f64], upper: &[f64]) {
        let mu = self.mu;
        let clamp = |z: f64, s: f64| z.clamp(mu / (KAPPA_SIGMA * s), KAPPA_SIGMA * mu / s);
        for i in 0..x.len() {
            if lower[i].is_finite() {
                self.zl[i] = clamp(self.zl[i], x[i] - lower[i]);
            }
            if upper[i].is_finite() {
                self.zu[i] = clamp(self.zu[i], upper[i] - x[i]);
            }
        }
        if let Some((rp, rm)) = self.slab_slacks(x) {
            self.v = [clamp(self.v[0], rp), clamp(self.v[1], rm)];
        }
    }

    /// φ_μ(x) = f - μ Σ ln(slacks); +inf outside.
    fn barrier(&self, x: &[f64], lower: &[f64], upper: &[f64], f: f64) -> f64 {
        let mut logs = 0.0;
        for i in 0..x.len() {
            if lower[i].is_finite() {
                let s = x[i] - lower[i];
                if s <= 0.0 {
                    return f64::INFINITY;
                }
                logs += s.ln();
            }
            if upper[i].is_finite() {
                let s = upper[i] - x[i];
                if s <= 0.0 {
                    return f64::INFINITY;
                }
                logs += s.ln();
            }
        }
        if let Some((rp, rm)) = self.slab_slacks(x) {
            if rp <= 0.0 || rm <= 0.0 {
                return f64::INFINITY;
            }
            logs += rp.ln() + rm.ln();
        }
        f - self.mu * logs
    }

    /// ||P(x - g) - x||_inf with P onto box and slab.
    fn projected_gradient(&mut self, x: &[f64], lower: &[f64], upper: &[f64]) -> f64 {
        let (norm, _) = super::slab::projected_gradient(
            self.slab.as_ref(),
            (x, &self.g),
            (lower, upper),
            &mut self.point,
        );
        norm
    }

    /// One iteration: the condensed system with inertia correction, the duals' steps,
    /// fraction to the boundary, Armijo on φ_μ. False: no progress possible.
    fn iterate(
        &mut self,
        problem: &mut impl BoxProblem<Matrix = M>,
        x: &mut [f64],
        lower: &[f64],
        upper: &[f64],
        state: &mut State,
    ) -> bool {
        if !state.hessian_ready {
            problem.hessian(x, &mut self.h);
            state.hessian_ready = true;
        }
        if !self.direction(x, lower, upper) {
            return false;
        }
        let (alpha_p, alpha_d) = self.fraction_to_boundary(x, lower, upper);
        let safe = problem.max_step_fraction(x, &self.dx, lower, upper);
        let mut alpha = alpha_p.min(safe);
        // directional derivative of φ_μ along dx: -rhs . dx
        let slope: f64 = -self
            .rhs
            .iter()
            .zip(&self.dx)
            .map(|(r, d)| r * d)
            .sum::<f64>();
        if !(slope < 0.0) || !(alpha > 0.0) {
            return false;
        }
        let n = x.len();
        for trial in 0..40 {
            for i in 0..n {
                self.trial[i] = x[i] + alpha * self.dx[i];
            }
            state.evaluations += 1;
            let f_new = if trial == 0 {
                problem.evaluate(&self.trial, Some(&mut self.g_trial), None)
            } else {
                problem.evaluate(&self.trial, None, None)
            };
            let phi_new = self.barrier(&self.trial, lower, upper, f_new);
            if phi_new.is_finite() && phi_new <= state.phi + ARMIJO * alpha * slope {
                x.copy_from_slice(&self.trial);
                if trial == 0 {
                    std::mem::swap(&mut self.g, &mut self.g_trial);
                } else {
                    state.evaluations += 1;
                    problem.evaluate(x, Some(&mut self.g), None);
                }
                state.f = f_new;
                state.phi = phi_new;
                state.hessian_ready = false;
                self.step_duals(alpha_d, x, lower, upper);
                return true;
            }
            self.counts.cuts += 1;
            alpha *= 0.5;
        }
        // no decrease: a larger δ_w next time
        self.delta_last = (self.delta_last * 10.0).max(DELTA_FIRST);
        self.force_delta = true;
        true
    }
}

mod step;
