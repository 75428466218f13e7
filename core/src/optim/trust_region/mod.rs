//! Trust-region projected Newton for box-constrained minimization with one optional
//! slab |Σ_S x_i| <= b, in the TRON / LANCELOT family (Conn, Gould and Toint 1988; Lin
//! and Moré 1999), for a Newton matrix that can multiply, factorize on a free set, and
//! give a direction of negative curvature where that factorization fails (the
//! ribbon's chain sweep does each in O(n)).
//!
//! One iteration, at x with gradient g and model m(s) = g.s + ½ s^T H s:
//!
//! 1. The region: the box [lower, upper] intersected with the l-infinity trust region
//!    |s_i| <= Δ u_i, u_i the unknown's unit (physical: crease-direction units and
//!    radians, metres / l for a translation), not diag(H): a box again, so every
//!    unknown, and every localized mode, has its own interval of length Δ u_i.
//! 2. The generalized Cauchy point, on the model only: s(t) = P(x - t g) - x along the
//!    projected path (P onto the region and the slab), t extrapolated or backtracked
//!    by 10 until m(s(t)) <= μ0 g.s(t) (a few O(n) products H v).
//! 3. Subspace rounds from there: the unknowns strictly inside the region are free;
//!    an undamped factorization of H on them (the slab's face, where s sits on it,
//!    held exactly by one more solve) gives the Newton step, or, where it meets
//!    negative curvature, a direction of negative curvature followed to the region's
//!    boundary; a projected search on the model along it. Rounds end when a step
//!    hits no new bound.
//! 4. The trial ([`TrustRegion::trial`], the one place a step is chosen and accepted):
//!    the problem's largest safe fraction of the step ([`BoxProblem::max_step_fraction`],
//!    1 by default), f at x + s, acceptance and the new Δ by the ratio of the actual to
//!    the predicted decrease.

mod dense;
mod model_step;
#[cfg(test)]
mod tests;

use super::projected_newton::{BoxProblem, NewtonMatrix, NewtonOptions, NewtonResult};
use super::slab::{project_feasible, Slab};

pub(crate) use dense::DenseModel;

/// What the trust-region method needs of a Newton matrix besides its diagonal.
pub trait ModelMatrix: NewtonMatrix {
    /// `out` = H v (full length).
    fn multiply(&mut self, v: &[f64], out: &mut [f64]);
    /// Factorize H_FF + shift I on the unknowns with `free[i]`, plus, with `face`,
    /// rho (Σ_{i in range, free} d_i)^2 (a penalty on crossing the slab's face: it does
    /// not change a step that keeps Σ d = 0 and makes the directions that cross it
    /// positive definite). False where that is not positive definite.
    fn factor_free(
        &mut self,
        free: &[bool],
        shift: f64,
        face: Option<(std::ops::Range<usize>, f64)>,
    ) -> bool;
    /// After a [`Self::factor_free`] that failed: the least eigenvalue of the pivot it
    /// failed at (the shift included; <= 0), if it failed at one. Growing the shift by
    /// its magnitude is enough to pass that pivot (a Schur complement grows at least as
    /// fast as the shift: S(sigma + s) >= S(sigma) + s I), but not needed: it can exceed
    /// the least shift that makes the whole matrix positive definite ([[0, 1], [1, 1]]
    /// eliminated from the end: pivot -1, least shift 0.618).
    fn failed_pivot(&self) -> Option<f64>;
    /// Solve with the last factorization: `rhs` full length (held entries ignored),
    /// `out` full length (held entries 0). False if not finite.
    fn solve_free(&mut self, rhs: &[f64], out: &mut [f64]) -> bool;
}

/// Sufficient decrease on the model (the Cauchy point and the projected searches).
const MU0: f64 = 0.01;
/// Acceptance: the actual decrease is more than this times the predicted one.
const ETA0: f64 = 1e-4;
/// Below this ratio Δ shrinks; above `ETA2` with a step on the boundary it grows.
const ETA1: f64 = 0.25;
const ETA2: f64 = 0.75;
/// Bounds of Δ (in the unknowns' units): a radius below `RADIUS_MIN` ends the solve
/// unconverged, and none grows beyond `RADIUS_MAX` (a crease direction or an angle of
/// 10 is far beyond any step the model describes).
const RADIUS_MIN: f64 = 1e-14;
const RADIUS_MAX: f64 = 10.0;
/// The radius of a first solve.
const RADIUS_START: f64 = 0.1;
/// Growth of Δ after a step on its boundary whose ratio is above `ETA2`.
const RADIUS_GROWTH: f64 = 2.0;
/// Subspace rounds per iteration (each is a factorization, a solve and a search).
const MAX_ROUNDS: usize = 12;
/// Relative tolerance of "strictly inside the region".
const INSIDE_EPS: f64 = 1e-12;

/// Workspace of the trust-region method; buffers are reused between calls (no
/// allocation once warm, with a matrix that allocates nothing once warm).
#[derive(Default)]
pub struct TrustRegion<M: ModelMatrix> {
    h: M,
    g: Vec<f64>,
    g_trial: Vec<f64>,
    /// The step s from x, H s, a direction w and H w, a point of a path and H of it.
    s: Vec<f64>,
    hs: Vec<f64>,
    /// The best point of the model step so far (s and H s): it never ends above it.
    best_s: Vec<f64>,
    best_hs: Vec<f64>,
    w: Vec<f64>,
    point: Vec<f64>,
    h_point: Vec<f64>,
    /// The region at x: the box intersected with the trust region.
    lo: Vec<f64>,
    hi: Vec<f64>,
    units: Vec<f64>,
    free: Vec<bool>,
    rhs: Vec<f64>,
    face_normal: Vec<f64>,
    face_solution: Vec<f64>,
    diagonal: Vec<f64>,
    trial: Vec<f64>,
    /// Every index (for [`NewtonMatrix::out_of_range`]).
    every: Vec<usize>,
    /// Δ, carried from solve to solve (consecutive time steps are alike), and the
    /// Cauchy point's last t.
    radius: f64,
    cauchy_t: f64,
    /// The last shift that made an indefinite model positive definite (the next
    /// search for one starts below it), and the one of this model step's first round.
    shift: f64,
    round_shift: Option<f64>,
    /// Whether this model step's first round found the model indefinite.
    indefinite: bool,
    slab: Option<Slab>,
    /// The slab multiplier of the last projection of a path point.
    path_tau: f64,
    /// This solve's factorizations.
    factorizations: u32,
    /// This solve's products H v.
    products: u32,
}

impl<M: ModelMatrix> Clone for TrustRegion<M> {
    /// What one solve carries to the next is copied (a clone solves on exactly as the
    /// original: a World cloned mid-run continues bit for bit, tests/world_clone.rs);
    /// the buffers are not.
    fn clone(&self) -> Self {
        self.fresh_with_history()
    }
}

impl<M: ModelMatrix> std::fmt::Debug for TrustRegion<M> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("TrustRegion")
            .field("radius", &self.radius)
            .finish()
    }
}

/// What one call of `minimize` carries from iteration to iteration.
struct State {
    f: f64,
    pg: f64,
    iterations: u32,
    evaluations: u32,
    /// Whether `TrustRegion::h` holds the model at x.
    model_ready: bool,
}

/// How an iteration ends.
enum Next {
    Continue,
    Converged,
    Stop,
}

/// What the model step found: its predicted decrease -m(s) and whether it reaches the
/// region's boundary in some unknown (then Δ may grow).
struct ModelStep {
    predicted: f64,
    on_boundary: bool,
}

impl<M: ModelMatrix> TrustRegion<M> {
    pub fn new() -> Self {
        TrustRegion::default()
    }

    /// A workspace whose next `minimize` runs as this one's would: the values carried
    /// from solve to solve are copied (Δ, the last positive-definite shift, the slab
    /// projection's multiplier it starts from); the buffers and the per-solve values
    /// (the Cauchy t, the round's shift, the slab, the counts) are set by every solve.
    pub fn fresh_with_history(&self) -> Self {
        TrustRegion {
            radius: self.radius,
            shift: self.shift,
            path_tau: self.path_tau,
            ..Self::default()
        }
    }

    /// The current trust-region radius Δ (in the unknowns' units).
    pub fn radius(&self) -> f64 {
        self.radius
    }

    /// Minimize `problem` over the box [lower, upper] and `slab` from `x` (projected
    /// onto them first), writing the minimizer to `x`. The stopping tests are those of
    /// the projected Newton method (`options.reuse_factorization` is not used).
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
        let mut state = self.start(problem, x, lower, upper);
        let initial_pg = state.pg;
        let pgtol = match options.pgtol_relative_to_start {
            Some(factor) => factor * state.pg.max(1e-300),
            None => options.pgtol,
        };
        let mut converged = state.f.is_finite() && state.pg <= pgtol;
        let finite = state.f.is_finite() && state.pg.is_finite();
        while finite && !converged && state.iterations < options.max_iterations {
            match self.iterate(problem, x, lower, upper, options.ftol, pgtol, &mut state) {
                Next::Continue => {}
                Next::Converged => converged = true,
                Next::Stop => break,
            }
        }
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

    /// Size the buffers, project x onto the box and the slab, evaluate f and g there.
    fn start(
        &mut self,
        problem: &mut impl BoxProblem<Matrix = M>,
        x: &mut [f64],
        lower: &[f64],
        upper: &[f64],
    ) -> State {
        let n = problem.dimension();
        for v in [
            &mut self.g,
            &mut self.g_trial,
            &mut self.s,
            &mut self.hs,
            &mut self.best_s,
            &mut self.best_hs,
            &mut self.w,
            &mut self.point,
            &mut self.h_point,
            &mut self.lo,
            &mut self.hi,
            &mut self.units,
            &mut self.rhs,
            &mut self.face_normal,
            &mut self.face_solution,
            &mut self.diagonal,
            &mut self.trial,
        ] {
            v.clear();
            v.resize(n, 0.0);
        }
        self.free.clear();
        self.free.resize(n, false);
        self.every.clear();
        self.every.extend(0..n);
        self.factorizations = 0;
        self.products = 0;
        problem.radius_units(&mut self.units);
        if !(self.radius > 0.0) {
            self.radius = RADIUS_START;
        }
        // a solve that ended on a tiny radius (rejections at round-off) does not make
        // the next one crawl
        self.radius = self.radius.clamp(1e-3, RADIUS_MAX);
        self.cauchy_t = 0.0;
        self.project(x, lower, upper);
        let f = problem.evaluate(x, Some(&mut self.g), None);
        let mut state = State {
            f,
            pg: 0.0,
            iterations: 0,
            evaluations: 1,
            model_ready: false,
        };
        state.pg = self.projected_gradient(x, lower, upper);
        state
    }

    /// `y` projected onto [lower, upper] and the slab.
    fn project(&self, y: &mut [f64], lower: &[f64], upper: &[f64]) {
        project_feasible(self.slab.as_ref(), y, lower, upper);
    }

    /// ||P(x - g) - x||_inf, P onto the box and the slab: zero exactly at a stationary
    /// point of the constrained problem.
    fn projected_gradient(&mut self, x: &[f64], lower: &[f64], upper: &[f64]) -> f64 {
        let mut p = std::mem::take(&mut self.point);
        for i in 0..x.len() {
            p[i] = x[i] - self.g[i];
        }
        self.project(&mut p, lower, upper);
        let norm = p
            .iter()
            .zip(x)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        self.point = p;
        norm
    }

    /// One iteration: the model (built at x if not yet), the model step, the trial.
    #[allow(clippy::too_many_arguments)]
    fn iterate(
        &mut self,
        problem: &mut impl BoxProblem<Matrix = M>,
        x: &mut [f64],
        lower: &[f64],
        upper: &[f64],
        ftol: f64,
        pgtol: f64,
        state: &mut State,
    ) -> Next {
        state.iterations += 1;
        if !state.model_ready {
            // x was the last point evaluated with a gradient (the start or the
            // accepted trial)
            problem.hessian(x, &mut self.h);
            state.model_ready = true;
            if self.h.out_of_range(&self.every) {
                // an absurd force: no model step can be trusted (the caller keeps the
                // last valid state and says so)
                return Next::Stop;
            }
            self.h.diagonal(&mut self.diagonal);
        }
        self.region(x, lower, upper);
        let step = self.model_step(x);
        if !(step.predicted > 0.0) || !step.predicted.is_finite() {
            // no model decrease from a point that is not stationary: the model is
            // useless here (a gradient below the model's round-off)
            return if state.pg <= pgtol {
                Next::Converged
            } else {
                Next::Stop
            };
        }
        if step.predicted <= 1e-15 * state.f.abs() && !step.on_boundary {
            // the Newton step predicts a decrease below the round-off of f: stationary
            return Next::Converged;
        }
        self.trial(problem, x, lower, upper, ftol, pgtol, step, state)
    }

    /// The region at x: lo = max(lower, x - Δ u), hi = min(upper, x + Δ u).
    fn region(&mut self, x: &[f64], lower: &[f64], upper: &[f64]) {
        let r = self.radius;
        for i in 0..x.len() {
            self.lo[i] = lower[i].max(x[i] - r * self.units[i]);
            self.hi[i] = upper[i].min(x[i] + r * self.units[i]);
        }
    }

    /// The one place a trial step is chosen and accepted. The model's step (in
    /// `self.s`, H s in `self.hs`) is first scaled by the problem's largest safe
    /// fraction ([`BoxProblem::max_step_fraction`]: a contact barrier in the objective
    /// clamps every trial by continuous collision detection there), then f is evaluated
    /// at x + s; the ratio of the actual to the predicted decrease accepts it or not and
    /// sets the next radius; the convergence tests follow an accepted step.
    #[allow(clippy::too_many_arguments)]
    fn trial(
        &mut self,
        problem: &mut impl BoxProblem<Matrix = M>,
        x: &mut [f64],
        lower: &[f64],
        upper: &[f64],
        ftol: f64,
        pgtol: f64,
        step: ModelStep,
        state: &mut State,
    ) -> Next {
        let (mut predicted, mut on_boundary) = (step.predicted, step.on_boundary);
        let fraction = problem.max_step_fraction(x, &self.s, lower, upper);
        if fraction < 1.0 {
            let fraction = fraction.max(0.0);
            for (s, hs) in self.s.iter_mut().zip(self.hs.iter_mut()) {
                *s *= fraction;
                *hs *= fraction;
            }
            predicted = -self.model(&self.s, &self.hs);
            on_boundary = false;
            if !(predicted > 0.0) {
                // no safe step along the model's: nothing to try
                return Next::Stop;
            }
        }
        for i in 0..x.len() {
            self.trial[i] = x[i] + self.s[i];
        }
        // (round-off only: the model's step is feasible by construction)
        let mut trial = std::mem::take(&mut self.trial);
        self.project(&mut trial, lower, upper);
        let f_new = problem.evaluate(&trial, Some(&mut self.g_trial), None);
        state.evaluations += 1;
        let ratio = (state.f - f_new) / predicted;
        let length = (0..x.len())
            .map(|i| self.s[i].abs() / self.units[i])
            .fold(0.0, f64::max);
        if !f_new.is_finite() || !(ratio >= ETA1) {
            self.radius = 0.25 * self.radius.min(length);
        } else if ratio > ETA2 && on_boundary {
            self.radius = (RADIUS_GROWTH * self.radius).min(RADIUS_MAX);
        }
        if !(f_new.is_finite() && ratio > ETA0) {
            // rejected: x and its model stay, the smaller region is tried
            self.trial = trial;
            return if self.radius < RADIUS_MIN {
                Next::Stop
            } else {
                Next::Continue
            };
        }
        x.copy_from_slice(&trial);
        self.trial = trial;
        std::mem::swap(&mut self.g, &mut self.g_trial);
        let f_old = state.f;
        state.f = f_new;
        state.model_ready = false;
        state.pg = self.projected_gradient(x, lower, upper);
        if state.pg <= pgtol {
            Next::Converged
        } else if !on_boundary && (f_old - f_new) <= ftol * f_old.abs().max(f_new.abs()).max(1.0) {
            // an accepted step inside the region (the model's own minimizer on its
            // face) that changes f only in its last digits: the L-BFGS-B `factr`
            // test, shared with the projected Newton method (ribbon::step::FTOL)
            Next::Converged
        } else {
            Next::Continue
        }
    }
}
