//! Projected Gauss-Newton / Levenberg-Marquardt for box-constrained minimization with a
//! dense positive semi-definite Hessian model (Bertsekas' projected Newton): variables
//! at a bound whose gradient pushes outward are held; the rest take a damped Newton
//! step solved by a dense Cholesky factorization (faer); a projected Armijo search keeps
//! the iterate in the box.

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::cholesky::llt;
use faer::{MatMut, Par};
use nalgebra::DMatrix;

use super::slab::Slab;

mod face;

/// A box-constrained problem with a Hessian model.
pub trait BoxProblem {
    /// How its Hessian is stored and factorized ([`Dense`], or a structured one).
    type Matrix: NewtonMatrix;
    fn dimension(&self) -> usize;
    /// f(x); writes the gradient if asked and the Hessian model (PSD) if asked.
    fn evaluate(
        &mut self,
        x: &[f64],
        gradient: Option<&mut [f64]>,
        hessian: Option<&mut Self::Matrix>,
    ) -> f64;
    /// The Hessian model at `x`, called only right after `evaluate(x, Some(g), None)`
    /// at that same `x`: a problem that keeps what that evaluation computed can
    /// assemble the Hessian without a second pass. The solver asks for it only when it
    /// takes another step, so the last iterate never pays for one.
    fn hessian(&mut self, x: &[f64], hessian: &mut Self::Matrix) {
        self.evaluate(x, None, Some(hessian));
    }
    /// The largest fraction α in [0, 1] of the step `direction` from `x` the problem
    /// admits: every point clamp(x + s direction, lower, upper), s in [0, α], must be
    /// a valid iterate (contact: no pair crosses or comes closer than its minimum
    /// separation on the way, docs/contact_barrier.md). The projected Newton line
    /// search starts there; the trust-region solver scales each trial step by it before
    /// evaluating (`TrustRegion::trial`, the one place a step is chosen; its steps lie
    /// in the box). 1.0 by default.
    fn max_step_fraction(
        &mut self,
        _x: &[f64],
        _direction: &[f64],
        _lower: &[f64],
        _upper: &[f64],
    ) -> f64 {
        1.0
    }
    /// The unit of each unknown in the trust region's l-infinity norm (`out`, one per
    /// unknown): the region is |s_i| <= Δ u_i. The default, 1, suits unknowns that are
    /// angles and dimensionless ratios.
    fn radius_units(&self, out: &mut [f64]) {
        out.fill(1.0);
    }
}

/// The Newton matrix H of a problem and its factorization: what the projected Newton
/// method needs of it, so that the line search, the held variables and the damping are
/// shared between a dense matrix and a structured one (the ribbon's chain sweep).
pub trait NewtonMatrix: Default {
    /// The diagonal of H into `out` (one entry per unknown).
    fn diagonal(&mut self, out: &mut [f64]);
    /// Whether an entry of H on the free set is beyond 1e150 in magnitude or not a
    /// number: it would square past f64's range in a factorization.
    fn out_of_range(&self, free: &[usize]) -> bool;
    /// Factorize H_FF + diag(s) on the free set F, s_i = damping max(|H_ii|, floor) +
    /// floor with floor = 1e-14 max_F |H_ii| (see [`damped_diagonal`]); false where
    /// that is not positive definite.
    fn factor(&mut self, free: &[usize], damping: f64) -> bool;
    /// Solve with the last factorization: `reduced` holds the right-hand side on the
    /// free set (in `free`'s order) and receives the solution. False if not finite.
    fn solve(&mut self, free: &[usize], reduced: &mut [f64]) -> bool;
}

/// The floor of the Levenberg-Marquardt shift for the largest free diagonal entry
/// `max_diag`: 1e-14 of it (a zero diagonal entry still gets a positive pivot).
pub fn damping_floor(max_diag: f64) -> f64 {
    1e-14 * max_diag.max(1e-300)
}

/// A diagonal entry `d` of H with the Levenberg-Marquardt shift for `damping` and
/// `floor` (from [`damping_floor`]): d + damping max(|d|, floor) + floor.
#[inline]
pub fn damped_diagonal(d: f64, damping: f64, floor: f64) -> f64 {
    d + damping * d.abs().max(floor) + floor
}

/// A dense Newton matrix, factorized by a sequential dense Cholesky (faer; systems
/// here are at most a few hundred rows, where threads cost more than they save).
#[derive(Default)]
pub struct Dense {
    pub matrix: DMatrix<f64>,
    /// Reduced system matrix (column-major), then its Cholesky factor.
    system: Vec<f64>,
    scratch: Option<(usize, MemBuffer)>,
    /// Its last factorization as a trust-region model ([`super::ModelMatrix`]).
    pub(crate) model: super::trust_region::DenseModel,
    /// Its last factorization for the interior-point method
    /// (`optim::interior_point::BarrierMatrix`).
    pub(crate) barrier: Option<nalgebra::Cholesky<f64, nalgebra::Dyn>>,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NewtonOptions {
    pub max_iterations: u32,
    /// Stop when the projected-gradient infinity norm is at most this.
    pub pgtol: f64,
    /// Stop when (f_k - f_{k+1}) / max(|f_k|, |f_{k+1}|, 1) is at most this after an
    /// accepted step (the L-BFGS-B `factr` test, so both solvers share one criterion).
    pub ftol: f64,
    /// When set, the projected-gradient tolerance is this factor times the projected
    /// gradient at the (clamped) start instead of `pgtol`; the start value is returned
    /// in [`NewtonResult::initial_projected_gradient_inf`].
    pub pgtol_relative_to_start: Option<f64>,
    /// Start with chord steps on the factorization the last call ended with (if its
    /// free set still applies): for a sequence of nearby problems, such as the rounds
    /// of an augmented Lagrangian, whose Hessians differ only by the multiplier terms.
    pub reuse_factorization: bool,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NewtonResult {
    pub f: f64,
    pub iterations: u32,
    pub evaluations: u32,
    pub projected_gradient_inf: f64,
    /// Factorizations of the Newton matrix, rejected (not positive definite) ones
    /// included: the cost of an iteration beyond its evaluations.
    pub factorizations: u32,
    /// Projected gradient (infinity norm) at the clamped start.
    pub initial_projected_gradient_inf: f64,
    pub converged: bool,
}

/// Workspace of the projected Newton method; buffers are reused between calls.
#[derive(Default)]
pub struct ProjectedNewton<M: NewtonMatrix = Dense> {
    g: Vec<f64>,
    /// Gradient at the first (full-step) trial point of the line search.
    g_trial: Vec<f64>,
    /// The Hessian model and its factorization.
    h: M,
    /// Its diagonal (for the scaled-gradient fallback).
    diagonal: Vec<f64>,
    free: Vec<usize>,
    reduced: Vec<f64>,
    trial: Vec<f64>,
    /// The direction over all variables (zero where held), for
    /// [`BoxProblem::max_step_fraction`].
    step: Vec<f64>,
    /// Levenberg-Marquardt damping relative to the Hessian diagonal, adapted per step.
    damping: f64,
    /// The damping the first iteration of the last solve needed.
    first_damping: f64,
    /// The largest damping at which a factorization of this solve failed (not positive
    /// definite), divided by 10 after every full step that needed no escalation.
    indefinite_at: f64,
    /// The free set of the factorization in `h`, when `factor_valid`.
    factor_free: Vec<usize>,
    factor_valid: bool,
    /// Factorizations in this solve.
    factorizations: u32,
    /// Where the last line search started ([`BoxProblem::max_step_fraction`]).
    first_alpha: f64,
    /// One slab |Σ_S x_i| <= b besides the box, held exactly ([`Self::set_slab`]).
    slab: Option<Slab>,
    /// The slab's multiplier τ in P(x - g) at the current x (0 without a slab): a
    /// variable of S on a bound is held where g_i + τ pushes it out.
    slab_tau: f64,
    /// H_FF^{-1} a (a the slab's indicator on the free set), for the face's step.
    face_w: Vec<f64>,
    /// P(x - g) (the projected gradient's point).
    point: Vec<f64>,
    /// Whether a line-search cut (alpha < 1) leaves the damping as it is instead of
    /// raising it 10x ([`Self::set_cut_keeps_damping`]).
    cut_keeps_damping: bool,
}

/// Relative tolerance of "on a bound": x_i <= lower_i + eps (1 + |lower_i|).
const BOUND_EPS: f64 = 1e-12;

/// What one call of `minimize` carries from iteration to iteration.
struct IterationState {
    f: f64,
    /// Projected-gradient infinity norm at x.
    pg: f64,
    iterations: u32,
    evaluations: u32,
    /// Whether `ProjectedNewton::h` holds the Hessian at x (assembled on demand: see
    /// [`BoxProblem::hessian`]).
    hessian_ready: bool,
    /// Whether this iteration steps on the stored factorization (chord step).
    chord: bool,
    /// Whether no iteration has found a direction yet (its damping is remembered in
    /// `ProjectedNewton::first_damping`).
    first: bool,
}

/// When `minimize` stops: the two tests of [`NewtonOptions`], `pgtol` resolved.
struct Stopping {
    /// Projected-gradient infinity norm to reach.
    pgtol: f64,
    /// Relative decrease of f below which an accepted Newton step ends the solve.
    ftol: f64,
}

/// How an iteration of `minimize` ends.
enum Iteration {
    /// Go on (if iterations are left).
    Continue,
    Converged,
    /// No progress possible: return what we have, not converged.
    Stop,
}

/// How an iteration's direction was found.
struct Direction {
    ok: bool,
    /// The damping had to be raised to make the model positive definite.
    escalated: bool,
    /// The scaled-gradient fallback instead of a Newton step.
    fallback: bool,
}

impl<M: NewtonMatrix> Clone for ProjectedNewton<M> {
    /// Buffers only: a fresh workspace behaves identically.
    fn clone(&self) -> Self {
        ProjectedNewton::new()
    }
}

impl<M: NewtonMatrix> std::fmt::Debug for ProjectedNewton<M> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ProjectedNewton")
            .field("damping", &self.damping)
            .finish()
    }
}

impl<M: NewtonMatrix> ProjectedNewton<M> {
    pub fn new() -> Self {
        ProjectedNewton {
            damping: 1e-9,
            ..Default::default()
        }
    }

    /// A solver whose next `minimize` runs as this one's would: the one value carried
    /// from solve to solve, the damping the last solve's first iteration needed, is
    /// copied; the rest (the gradient, the matrix and its factorization) is rebuilt by
    /// every solve (a factorization is reused only within a solve's rounds, when the
    /// caller asks, never across a fresh start).
    pub fn fresh_with_history(&self) -> Self {
        ProjectedNewton {
            first_damping: self.first_damping,
            slab: self.slab.clone(),
            cut_keeps_damping: self.cut_keeps_damping,
            ..Self::new()
        }
    }

    /// Whether a line-search cut (alpha < 1) leaves the damping as it is (true) or
    /// raises it 10x (false, the default).
    pub fn set_cut_keeps_damping(&mut self, keep: bool) {
        self.cut_keeps_damping = keep;
    }

    /// Minimize `problem` over the box [lower, upper] from `x` (clamped into the box),
    /// writing the minimizer to `x`.
    pub fn minimize(
        &mut self,
        problem: &mut impl BoxProblem<Matrix = M>,
        x: &mut [f64],
        lower: &[f64],
        upper: &[f64],
        options: &NewtonOptions,
    ) -> NewtonResult {
        let mut state = self.start(problem, x, lower, upper);
        let initial_pg = state.pg;
        let stopping = Stopping {
            pgtol: match options.pgtol_relative_to_start {
                Some(factor) => factor * state.pg.max(1e-300),
                None => options.pgtol,
            },
            ftol: options.ftol,
        };
        let result = |state: &IterationState, converged: bool, factorizations: u32| NewtonResult {
            f: state.f,
            iterations: state.iterations,
            evaluations: state.evaluations,
            projected_gradient_inf: state.pg,
            factorizations,
            initial_projected_gradient_inf: initial_pg,
            converged,
        };
        if !state.f.is_finite() || !state.pg.is_finite() {
            return result(&state, false, 0);
        }
        let mut converged = state.pg <= stopping.pgtol;
        // Start from a tenth of the damping the last solve's first iteration needed:
        // consecutive time steps have similar curvature, and every rejected
        // factorization costs as much as an accepted one.
        self.damping = (self.first_damping * 0.1).max(1e-9);
        // Chord steps (the stored factorization, no new Hessian) while they contract
        // the projected gradient at least 4x per step: each saves an assembly and a
        // factorization (about half an iteration's cost at 100 unknowns).
        state.chord = options.reuse_factorization && self.factor_valid;
        if !state.chord {
            self.factor_valid = false;
        }
        while !converged && state.iterations < options.max_iterations {
            match self.iterate(problem, x, lower, upper, &stopping, &mut state) {
                Iteration::Continue => {}
                Iteration::Converged => converged = true,
                Iteration::Stop => break,
            }
        }
        result(&state, converged, self.factorizations)
    }

    /// Size the buffers for `problem`, clamp `x` into [lower, upper] and evaluate f and
    /// its gradient there: the state before the first iteration.
    fn start(
        &mut self,
        problem: &mut impl BoxProblem<Matrix = M>,
        x: &mut [f64],
        lower: &[f64],
        upper: &[f64],
    ) -> IterationState {
        let n = problem.dimension();
        self.g.resize(n, 0.0);
        self.g_trial.resize(n, 0.0);
        self.factorizations = 0;
        self.indefinite_at = 0.0;
        self.trial.resize(n, 0.0);
        self.project(x, lower, upper);
        let mut state = IterationState {
            f: problem.evaluate(x, Some(&mut self.g), None),
            pg: 0.0,
            iterations: 0,
            evaluations: 1,
            hessian_ready: false,
            chord: false,
            first: true,
        };
        state.pg = self.projected_gradient(x, lower, upper);
        state
    }

    /// One iteration: the free set, a direction on it, the line search along it, and
    /// the convergence tests after an accepted step.
    fn iterate(
        &mut self,
        problem: &mut impl BoxProblem<Matrix = M>,
        x: &mut [f64],
        lower: &[f64],
        upper: &[f64],
        stopping: &Stopping,
        state: &mut IterationState,
    ) -> Iteration {
        state.iterations += 1;
        self.free_set(x, lower, upper);
        if self.free.is_empty() {
            return Iteration::Converged;
        }
        let pg_before = state.pg;
        let direction = self.direction(problem, x, lower, upper, state);
        if state.first && !state.chord {
            self.first_damping = self.damping;
        }
        state.first = false;
        if !direction.ok {
            return Iteration::Stop;
        }
        // Stationary to round-off: the model predicts a decrease no larger than the
        // rounding error of f itself, so no step can be verified. Converged.
        let predicted: f64 = -self
            .free
            .iter()
            .zip(&self.reduced)
            .map(|(&i, d)| self.g[i] * d)
            .sum::<f64>();
        if predicted <= 1e-14 * state.f.abs() {
            return Iteration::Converged;
        }
        // (a chord step gets no line search: if its full step fails, the factorization
        // is stale)
        let trials = if state.chord { 1 } else { 40 };
        let (accepted, alpha, f_new) = self.line_search(problem, x, lower, upper, state, trials);
        if let Some(next) = self.after_search(problem, x, state, accepted, alpha) {
            return next;
        }
        // a step cut short by the problem's admissible fraction is as full as it can be
        self.adapt_damping(alpha / self.first_alpha, direction.escalated);
        let f_old = state.f;
        self.accept(problem, x, alpha, f_new, state);
        state.pg = self.projected_gradient(x, lower, upper);
        // (chord steps only at the start of a call: within one, Newton steps
        // converge in fewer evaluations)
        state.chord &= state.pg <= 0.25 * pg_before;
        let f = state.f;
        if state.pg <= stopping.pgtol {
            Iteration::Converged
        } else if !direction.fallback
            && self.first_alpha >= 1.0
            && (f_old - f) <= stopping.ftol * f_old.abs().max(f.abs()).max(1.0)
        {
            // After any accepted Newton step, as L-BFGS-B applies `factr`: where the
            // resampling operator's kinks stall the projected gradient above its
            // tolerance, the line search keeps passing steps of alpha ~1e-3 that
            // change f only in its last digits (17 iterations for nothing on a
            // Moebius loop before this). Not after a fallback step: a gradient
            // step's small decrease says nothing about stationarity.
            Iteration::Converged
        } else {
            Iteration::Continue
        }
    }

    /// What follows a line search that was not a passed full chord step or an accepted
    /// Newton step: a failed chord step falls back to Newton steps from x; a rejected
    /// Newton step raises the damping (or stops at the noise floor). `None`: accept the
    /// step at `alpha`.
    fn after_search(
        &mut self,
        problem: &mut impl BoxProblem<Matrix = M>,
        x: &[f64],
        state: &mut IterationState,
        accepted: bool,
        alpha: f64,
    ) -> Option<Iteration> {
        if state.chord && !(accepted && alpha == self.first_alpha) {
            // the old factorization no longer models f here: a Newton step from x
            state.chord = false;
            if !accepted {
                // the workspace holds the trial's data: evaluate x again for its
                // Hessian
                state.evaluations += 1;
                state.f = problem.evaluate(x, Some(&mut self.g), None);
                state.iterations -= 1;
                return Some(Iteration::Continue);
            }
        }
        if !accepted {
            // No decrease along the model direction: more damping next time (the
            // Hessian at x is kept); stop if the model is already heavily damped
            // (we are at the noise floor).
            if self.damping > 1e2 {
                return Some(Iteration::Stop);
            }
            self.damping = (self.damping * 100.0).max(1e-6);
            return Some(Iteration::Continue);
        }
        None
    }

    /// The free set at x: every variable except those at a bound with the gradient
    /// pointing out of the box.
    ///
    /// With a slab, on its range the gradient is g_i + τ (τ the slab's multiplier in
    /// P(x - g)): what the projection onto box and slab moves it by.
    fn free_set(&mut self, x: &[f64], lower: &[f64], upper: &[f64]) {
        self.free.clear();
        let range = self.slab.as_ref().map(|s| s.range.clone()).unwrap_or(0..0);
        for i in 0..x.len() {
            let g = self.g[i]
                + if range.contains(&i) {
                    self.slab_tau
                } else {
                    0.0
                };
            let at_lower = x[i] <= lower[i] + BOUND_EPS * (1.0 + lower[i].abs()) && g > 0.0;
            let at_upper = x[i] >= upper[i] - BOUND_EPS * (1.0 + upper[i].abs()) && g < 0.0;
            if !(at_lower || at_upper) {
                self.free.push(i);
            }
        }
    }

    /// The step direction on the free set into `self.reduced`: a chord step on the
    /// stored factorization, a damped Newton step, or the scaled-gradient fallback.
    ///
    /// At most a few rounds of binding: each drops from the free set the variables
    /// that sit on a bound while the Newton step points out of the box, and solves
    /// again. The projected search would clamp them at every trial, bending the path
    /// until only tiny steps pass Armijo (seen as runs of alpha ~1e-4 on the loops of
    /// the Moebius chain); held, they are freed again next iteration if the step turns
    /// inward (it does when H is positive definite and they are the only ones left
    /// with a gradient).
    fn direction(
        &mut self,
        problem: &mut impl BoxProblem<Matrix = M>,
        x: &[f64],
        lower: &[f64],
        upper: &[f64],
        state: &mut IterationState,
    ) -> Direction {
        let mut direction = Direction {
            ok: false,
            escalated: false,
            fallback: false,
        };
        for binding in 0..4 {
            let m = self.free.len();
            state.chord &= self.factor_valid && self.factor_free == self.free;
            direction.ok = if state.chord {
                self.reduced.clear();
                self.reduced.extend(self.free.iter().map(|&i| -self.g[i]));
                self.h.solve(&self.free, &mut self.reduced)
            } else {
                if !state.hessian_ready {
                    // x was the last point evaluated with a gradient (the start or the
                    // accepted trial)
                    problem.hessian(x, &mut self.h);
                    state.hessian_ready = true;
                }
                self.damped_newton_step(m, &mut direction)
            };
            if direction.ok && !direction.fallback {
                direction.ok = self.hold_face(x);
            }
            if !direction.ok || binding == 3 {
                break;
            }
            if !self.drop_binding(x, lower, upper) {
                // every free variable was binding: no step
                if self.free.is_empty() {
                    direction.ok = false;
                }
                break;
            }
        }
        direction
    }

    /// Newton step on the Hessian; where it is indefinite, more damping; where even
    /// 100x its diagonal is not enough, the scaled-gradient fallback.
    fn damped_newton_step(&mut self, m: usize, direction: &mut Direction) -> bool {
        let mut ok = self.solve_reduced(m);
        while !ok && self.damping < 1e2 {
            self.indefinite_at = self.indefinite_at.max(self.damping);
            self.damping = (self.damping * 10.0).max(1e-8);
            direction.escalated = true;
            ok = self.solve_reduced(m);
        }
        self.factor_valid = ok;
        if ok {
            // (copied into a kept buffer: no allocation per iteration once warm)
            self.factor_free.clear();
            self.factor_free.extend_from_slice(&self.free);
        }
        if !ok {
            // Not positive definite even at 100x its diagonal: a projected gradient
            // step scaled by the diagonal instead, a descent direction the line search
            // can always shorten to a decrease. Giving up here would return the start,
            // i.e. the previous state, and zero the velocity (seen once in a helix run
            // at dt 78 us: kinetic energy 0.62 J -> 0 in one step).
            ok = self.scaled_gradient_step();
            direction.fallback = true;
        }
        ok
    }

    /// Drop from the free set the variables on a bound that the direction in
    /// `self.reduced` pushes out of the box. Whether to solve again: some were
    /// dropped and some are left (with none left, the step is void: `self.free` empty).
    fn drop_binding(&mut self, x: &[f64], lower: &[f64], upper: &[f64]) -> bool {
        let before = self.free.len();
        let mut k = 0;
        let reduced = &self.reduced;
        self.free.retain(|&i| {
            let d = reduced[k];
            k += 1;
            let on_lower = x[i] <= lower[i] + BOUND_EPS * (1.0 + lower[i].abs());
            let on_upper = x[i] >= upper[i] - BOUND_EPS * (1.0 + upper[i].abs());
            !((on_lower && d < 0.0) || (on_upper && d > 0.0))
        });
        self.free.len() != before && !self.free.is_empty()
    }

    /// Projected Armijo line search along the direction in `self.reduced`, at most
    /// `trials` halvings. The full step is evaluated with its gradient (into
    /// `g_trial`): it is accepted almost always, and then that evaluation is the next
    /// iterate's. Returns (accepted, alpha, f at the last trial).
    fn line_search(
        &mut self,
        problem: &mut impl BoxProblem<Matrix = M>,
        x: &[f64],
        lower: &[f64],
        upper: &[f64],
        state: &mut IterationState,
        trials: u32,
    ) -> (bool, f64, f64) {
        self.step.clear();
        self.step.resize(x.len(), 0.0);
        for (k, &i) in self.free.iter().enumerate() {
            self.step[i] = self.reduced[k];
        }
        let mut alpha = problem.max_step_fraction(x, &self.step, lower, upper);
        self.first_alpha = alpha;
        let mut f_new = state.f;
        if !(alpha > 0.0) {
            // no step admissible at all: as a rejected step (more damping, a shorter
            // direction)
            return (false, 0.0, f_new);
        }
        for trial in 0..trials {
            self.trial.copy_from_slice(x);
            for (k, &i) in self.free.iter().enumerate() {
                self.trial[i] = (x[i] + alpha * self.reduced[k]).clamp(lower[i], upper[i]);
            }
            if let Some(slab) = &self.slab {
                // onto box and slab, not onto the face the step is held on: a step
                // whose clamps pull Σ inside may leave the face (projecting onto the face
                // instead shifts every z_k of S alike, a stiff global motion of c, and
                // took 10-20x the iterations, docs/ribbon_chain_solver.md 2026-12-07)
                slab.project(&mut self.trial, lower, upper, 0.0);
            }
            state.evaluations += 1;
            f_new = if trial == 0 {
                problem.evaluate(&self.trial, Some(&mut self.g_trial), None)
            } else {
                problem.evaluate(&self.trial, None, None)
            };
            let decrease: f64 = if self.slab.is_some() {
                // the slab's projection may move held variables of S too
                (0..x.len())
                    .map(|i| self.g[i] * (self.trial[i] - x[i]))
                    .sum()
            } else {
                self.free
                    .iter()
                    .map(|&i| self.g[i] * (self.trial[i] - x[i]))
                    .sum()
            };
            if f_new.is_finite() && f_new <= state.f + 1e-4 * decrease {
                return (true, alpha, f_new);
            }
            alpha *= 0.5;
        }
        (false, alpha, f_new)
    }

    /// Levenberg-Marquardt update after an accepted step of length `alpha`.
    fn adapt_damping(&mut self, alpha: f64, escalated: bool) {
        if alpha == 1.0 {
            // a full step: trust the model more, unless this iteration had to raise
            // the damping to make the model positive definite: then the next Hessian,
            // a step away, is likely indefinite at a lower damping too, and every
            // rejected factorization costs as much as an accepted one
            //
            // Nor below the damping at which this solve last found the model
            // indefinite (times 10, the level that worked): on the twisted ribbons of
            // ribbon_extreme_torsion the exact Hessian stays indefinite below ~1e-2 of
            // its diagonal for many iterations, and dividing by 1000 after each full
            // step made every other iteration escalate back through three rejected
            // factorizations (994 factorizations for 438 iterations at n = 400,
            // 2026-12-02). That bound decays 10x per such step, so the damping still
            // falls where the model turns positive definite.
            if !escalated {
                self.damping = (self.damping / 1000.0)
                    .max(10.0 * self.indefinite_at)
                    .max(1e-12);
                self.indefinite_at *= 0.1;
            }
        } else if !self.cut_keeps_damping {
            self.damping = (self.damping * 10.0).min(1e6);
        }
    }

    /// Move x to the accepted trial point, with its value and gradient.
    fn accept(
        &mut self,
        problem: &mut impl BoxProblem<Matrix = M>,
        x: &mut [f64],
        alpha: f64,
        f_new: f64,
        state: &mut IterationState,
    ) {
        x.copy_from_slice(&self.trial);
        if alpha == self.first_alpha {
            // the full-step trial was evaluated with its gradient
            state.f = f_new;
            std::mem::swap(&mut self.g, &mut self.g_trial);
        } else {
            state.evaluations += 1;
            state.f = problem.evaluate(x, Some(&mut self.g), None);
        }
        state.hessian_ready = false;
    }

    /// Solve (H_FF + damping * diag(H_FF) + tiny I) d = -g_F into `self.reduced`.
    fn solve_reduced(&mut self, _m: usize) -> bool {
        self.factorizations += 1;
        if !self.h.factor(&self.free, self.damping) {
            return false;
        }
        self.reduced.clear();
        self.reduced.extend(self.free.iter().map(|&i| -self.g[i]));
        self.h.solve(&self.free, &mut self.reduced)
    }

    /// d_F = -g_F / |diag H_FF| into `self.reduced` (entries of a vanishing diagonal
    /// scaled by the largest one).
    fn scaled_gradient_step(&mut self) -> bool {
        // A Hessian beyond 1e150 squares past f64's range in the factorization: the
        // objective itself is out of range (an absurd force), not merely indefinite,
        // and no step is taken (the caller keeps the last valid state and says so).
        if self.h.out_of_range(&self.free) {
            return false;
        }
        self.diagonal.resize(self.g.len(), 0.0);
        self.h.diagonal(&mut self.diagonal);
        let d = &self.diagonal;
        let scale = self
            .free
            .iter()
            .map(|&i| d[i].abs())
            .fold(0.0, f64::max)
            .max(1e-300);
        self.reduced.clear();
        self.reduced.extend(
            self.free
                .iter()
                .map(|&i| -self.g[i] / d[i].abs().max(1e-12 * scale)),
        );
        self.reduced.iter().all(|v| v.is_finite())
    }
}

impl NewtonMatrix for Dense {
    fn diagonal(&mut self, out: &mut [f64]) {
        let n = self.matrix.nrows();
        let h = self.matrix.as_slice();
        for (i, o) in out.iter_mut().enumerate().take(n) {
            *o = h[i * n + i];
        }
    }

    fn out_of_range(&self, free: &[usize]) -> bool {
        let n = self.matrix.nrows();
        let h = self.matrix.as_slice();
        free.iter().any(|&j| {
            free.iter().any(|&i| {
                let x = h[j * n + i];
                !x.is_finite() || x.abs() >= 1e150
            })
        })
    }

    fn factor(&mut self, free: &[usize], damping: f64) -> bool {
        let n = self.matrix.nrows();
        let m = free.len();
        self.system.clear();
        let mut max_diag: f64 = 0.0;
        if m == n {
            // nothing held at a bound: the whole (column-major) Hessian
            self.system.extend_from_slice(self.matrix.as_slice());
        } else {
            let h = self.matrix.as_slice();
            for &j in free {
                let col = &h[j * n..(j + 1) * n];
                self.system.extend(free.iter().map(|&i| col[i]));
            }
        }
        for k in 0..m {
            max_diag = max_diag.max(self.system[k * m + k].abs());
        }
        let floor = damping_floor(max_diag);
        for k in 0..m {
            let d = self.system[k * m + k];
            self.system[k * m + k] = damped_diagonal(d, damping, floor);
        }
        if self.scratch.as_ref().map(|(n, _)| *n) != Some(m) {
            let req = StackReq::any_of(&[
                llt::factor::cholesky_in_place_scratch::<f64>(m, Par::Seq, Default::default()),
                llt::solve::solve_in_place_scratch::<f64>(m, 1, Par::Seq),
            ]);
            self.scratch = Some((m, MemBuffer::new(req)));
        }
        let (_, buffer) = self.scratch.as_mut().expect("allocated above");
        let stack = MemStack::new(buffer);
        let a = MatMut::from_column_major_slice_mut(&mut self.system, m, m);
        llt::factor::cholesky_in_place(a, Default::default(), Par::Seq, stack, Default::default())
            .is_ok()
    }

    /// d = (L L^T)^{-1} rhs in place in `reduced`, L the column-major m x m
    /// Cholesky factor in `self.system` (contiguous column sweeps; one right-hand side).
    fn solve(&mut self, free: &[usize], reduced: &mut [f64]) -> bool {
        let m = free.len();
        let l = &self.system;
        let d = reduced;
        for j in 0..m {
            let col = &l[j * m..(j + 1) * m];
            d[j] /= col[j];
            let dj = d[j];
            for (di, lij) in d[j + 1..].iter_mut().zip(&col[j + 1..]) {
                *di -= lij * dj;
            }
        }
        for j in (0..m).rev() {
            let col = &l[j * m..(j + 1) * m];
            // four partial sums: one running sum waits ~4 cycles on every add, which
            // made this O(m^2) sweep cost a third of the O(m^3/3) factorization at
            // m ~ 100
            let (tail, lij) = (&d[j + 1..], &col[j + 1..]);
            let mut acc = [0.0; 4];
            let chunks = tail.len() / 4 * 4;
            for (x, y) in tail[..chunks]
                .chunks_exact(4)
                .zip(lij[..chunks].chunks_exact(4))
            {
                for k in 0..4 {
                    acc[k] += x[k] * y[k];
                }
            }
            let rest: f64 = tail[chunks..]
                .iter()
                .zip(&lij[chunks..])
                .map(|(x, y)| x * y)
                .sum();
            let dot = (acc[0] + acc[1]) + (acc[2] + acc[3]) + rest;
            d[j] = (d[j] - dot) / col[j];
        }
        d.iter().all(|v| v.is_finite())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Rosenbrock as least squares r = (10 (y - x^2), 1 - x): GN Hessian J^T J.
    struct Rosen;
    impl BoxProblem for Rosen {
        type Matrix = Dense;
        fn dimension(&self) -> usize {
            2
        }
        fn evaluate(&mut self, x: &[f64], g: Option<&mut [f64]>, h: Option<&mut Dense>) -> f64 {
            let r = [10.0 * (x[1] - x[0] * x[0]), 1.0 - x[0]];
            let j = [[-20.0 * x[0], 10.0], [-1.0, 0.0]];
            if let Some(g) = g {
                for i in 0..2 {
                    g[i] = r[0] * j[0][i] + r[1] * j[1][i];
                }
            }
            if let Some(h) = h {
                h.matrix = DMatrix::from_fn(2, 2, |a, b| j[0][a] * j[0][b] + j[1][a] * j[1][b]);
            }
            0.5 * (r[0] * r[0] + r[1] * r[1])
        }
    }

    #[test]
    fn gauss_newton_solves_rosenbrock() {
        let mut x = [-1.2, 1.0];
        let opts = NewtonOptions {
            max_iterations: 100,
            pgtol: 1e-10,
            ftol: 0.0,
            pgtol_relative_to_start: None,
            reuse_factorization: false,
        };
        let r = ProjectedNewton::<Dense>::new().minimize(
            &mut Rosen,
            &mut x,
            &[-10.0; 2],
            &[10.0; 2],
            &opts,
        );
        assert!(r.converged, "{r:?}");
        assert!(
            (x[0] - 1.0).abs() < 1e-8 && (x[1] - 1.0).abs() < 1e-8,
            "{x:?}"
        );
    }

    #[test]
    fn active_bound_is_respected_and_kkt_holds() {
        // minimum of Rosenbrock with x <= 0.5: on the bound, y = x^2.
        let mut x = [-1.2, 1.0];
        let opts = NewtonOptions {
            max_iterations: 200,
            pgtol: 1e-10,
            ftol: 0.0,
            pgtol_relative_to_start: None,
            reuse_factorization: false,
        };
        let r = ProjectedNewton::<Dense>::new().minimize(
            &mut Rosen,
            &mut x,
            &[-10.0, -10.0],
            &[0.5, 10.0],
            &opts,
        );
        assert!(r.converged, "{r:?}");
        assert!((x[0] - 0.5).abs() < 1e-12);
        assert!((x[1] - 0.25).abs() < 1e-8);
    }

    /// f = 1/2 x^T H x + b^T x with strongly coupled H.
    struct Quadratic {
        h: [[f64; 2]; 2],
        b: [f64; 2],
    }
    impl BoxProblem for Quadratic {
        type Matrix = Dense;
        fn dimension(&self) -> usize {
            2
        }
        fn evaluate(&mut self, x: &[f64], g: Option<&mut [f64]>, h: Option<&mut Dense>) -> f64 {
            let hx = [
                self.h[0][0] * x[0] + self.h[0][1] * x[1],
                self.h[1][0] * x[0] + self.h[1][1] * x[1],
            ];
            if let Some(g) = g {
                g[0] = hx[0] + self.b[0];
                g[1] = hx[1] + self.b[1];
            }
            if let Some(h) = h {
                h.matrix = DMatrix::from_fn(2, 2, |a, c| self.h[a][c]);
            }
            0.5 * (x[0] * hx[0] + x[1] * hx[1]) + self.b[0] * x[0] + self.b[1] * x[1]
        }
    }

    fn tight() -> NewtonOptions {
        NewtonOptions {
            max_iterations: 20,
            // above the 1e-9 relative Levenberg-Marquardt damping's residue
            pgtol: 1e-8,
            ftol: 0.0,
            pgtol_relative_to_start: None,
            reuse_factorization: false,
        }
    }

    #[test]
    fn a_bound_variable_the_newton_step_pushes_out_is_held_not_clamped() {
        // Unconstrained minimum (-0.7, 1); x0 >= 0. At the start (0, 0) the gradient
        // (-0.2, -0.37) points into the box for x0 but the Newton step (-0.7, 1) points
        // out of it: clamped, the full step overshoots in y (f = 0.13 > 0) and Armijo
        // would need halving. Held, x0 stays and y solves exactly: one iteration to the
        // constrained minimum (0, 0.37).
        let mut problem = Quadratic {
            h: [[1.0, 0.9], [0.9, 1.0]],
            b: [-0.2, -0.37],
        };
        let mut x = [0.0, 0.0];
        let r = ProjectedNewton::<Dense>::new().minimize(
            &mut problem,
            &mut x,
            &[0.0, -10.0],
            &[10.0, 10.0],
            &tight(),
        );
        assert!(r.converged, "{r:?}");
        assert_eq!(r.iterations, 1, "{r:?}");
        assert_eq!(x[0], 0.0);
        assert!((x[1] - 0.37).abs() < 1e-8, "{x:?}");
        // the start and the one full step
        assert_eq!(r.evaluations, 2, "{r:?}");
    }

    #[test]
    fn chord_steps_on_the_last_factorization_reach_the_new_minimum() {
        // two problems with the same Hessian (as AL rounds nearly are): the second call
        // reuses the first's factorization and still lands on its own minimum
        let h = [[2.0, 0.5], [0.5, 1.0]];
        let mut newton = ProjectedNewton::<Dense>::new();
        let mut x = [0.3, -0.2];
        let bounds = ([-10.0; 2], [10.0; 2]);
        let first = newton.minimize(
            &mut Quadratic { h, b: [1.0, -1.0] },
            &mut x,
            &bounds.0,
            &bounds.1,
            &tight(),
        );
        assert!(first.converged);
        let b = [0.4, -0.9];
        let opts = NewtonOptions {
            reuse_factorization: true,
            ..tight()
        };
        let second = newton.minimize(&mut Quadratic { h, b }, &mut x, &bounds.0, &bounds.1, &opts);
        assert!(second.converged, "{second:?}");
        // H x = -b
        let det = h[0][0] * h[1][1] - h[0][1] * h[1][0];
        let expected = [
            (-b[0] * h[1][1] + b[1] * h[0][1]) / det,
            (-b[1] * h[0][0] + b[0] * h[1][0]) / det,
        ];
        // |x - x*| <= pg / lambda_min(H) (~0.8) with pg <= 1e-8
        assert!(
            (x[0] - expected[0]).abs() < 2e-8 && (x[1] - expected[1]).abs() < 2e-8,
            "{x:?}"
        );
        assert!(second.iterations <= 2, "{second:?}");
    }

    #[test]
    fn an_indefinite_hessian_beyond_damping_ends_on_a_vertex_minimizer() {
        // H = [[1, 1e6], [1e6, 1]] stays indefinite at 100x its diagonal (eigenvalues
        // 1 +- 1e6): the solver must fall back to a scaled gradient step and follow the
        // negative curvature (1, -1) to the box. Both vertices (1, -1) and (-1, 1) are
        // strict local minimizers (the gradient points out of the box at each: checked
        // by pg = 0 below); f there is 1.5 - 1e6 and 0.5 - 1e6.
        let mut problem = Quadratic {
            h: [[1.0, 1e6], [1e6, 1.0]],
            b: [1.0, 0.5],
        };
        let mut x = [0.2, -0.1];
        let r = ProjectedNewton::<Dense>::new().minimize(
            &mut problem,
            &mut x,
            &[-1.0, -1.0],
            &[1.0, 1.0],
            &tight(),
        );
        assert!(r.converged, "{r:?} at {x:?}");
        assert!(
            x == [1.0, -1.0] || x == [-1.0, 1.0],
            "not a vertex minimizer: {x:?}"
        );
        assert_eq!(r.projected_gradient_inf, 0.0, "{r:?}");
        let expected = if x[0] == 1.0 { 1.5 - 1e6 } else { 0.5 - 1e6 };
        assert_eq!(r.f, expected, "{r:?}");
    }

    #[test]
    fn a_clone_is_a_fresh_workspace() {
        // A solve whose model needs heavy damping leaves `first_damping` high; the next
        // solve of the used workspace starts from a tenth of it. A clone must not: it
        // behaves exactly like `new()` (issue 18), while the used original does not.
        let mut used = ProjectedNewton::<Dense>::new();
        let mut x = [0.2, -0.1];
        let indefinite = || Quadratic {
            h: [[1.0, 3.0], [3.0, 1.0]],
            b: [1.0, 0.5],
        };
        used.minimize(&mut indefinite(), &mut x, &[-1.0; 2], &[1.0; 2], &tight());
        assert!(used.first_damping > 1e-3, "{}", used.first_damping);
        let convex = || Quadratic {
            h: [[2.0, 0.5], [0.5, 1.0]],
            b: [1.0, -1.0],
        };
        let solve = |newton: &mut ProjectedNewton<Dense>| {
            let mut x = [0.3, -0.2];
            let r = newton.minimize(&mut convex(), &mut x, &[-10.0; 2], &[10.0; 2], &tight());
            (r, x)
        };
        let fresh = solve(&mut ProjectedNewton::new());
        let cloned = solve(&mut used.clone());
        assert_eq!(cloned, fresh);
        let original = solve(&mut used);
        assert_ne!(original, fresh, "the check cannot see a kept first_damping");
    }
}
