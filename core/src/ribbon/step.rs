//! One implicit-Euler step of a ribbon (Pan et al. algorithm 2).
//!
//! The crease non-intersection constraints (eq. 1) become box constraints after the
//! substitution z_1 = c_1, z_i = c_i - c_{i-1} (sec. 5.1): |z_i| <= Δc_max. The one
//! left, |c_{n-1}| <= Δc_max, and every equality (handles, loops) go to the augmented
//! Lagrangian with penalty μ (1e3 in the paper). The inner problem is solved by
//! L-BFGS-B (the paper) or by our projected Gauss-Newton.
//!
//! Differences from the paper, noted: multipliers are warm-started from the previous
//! step instead of reset to 0 (the fixed point is the same; it saves outer rounds);
//! with our solver mu adapts (raised 10x after a round that did not shrink the
//! residual 4x or while ||Δq|| is below the outer tolerance, capped at 100x the
//! scene's, relaxed 10x after a step that did not raise it), which stiff ribbons
//! under handles and closing a Moebius band from a ring need. The L-BFGS-B baseline
//! keeps the paper's fixed mu.

use nalgebra::DMatrix;

use super::objective::chain::ChainMatrix;
use super::objective::{
    ContactTerms, GradientMode, Layout, Objective, RimHistory, StepTerms, Workspace,
};
use super::params::{SolverKind, SolverSettings};
use super::reconstruct::Strip;
use crate::geometry::Pose;
use crate::optim::{
    BoxProblem, Dense, InteriorPoint, Lbfgsb, LbfgsbOptions, NewtonOptions, ProjectedNewton, Slab,
    TrustRegion,
};

/// Relative objective decrease that ends an inner solve, (f_k - f_k+1)/max(|f|, 1):
/// the resampling operator R is piecewise linear in c (eq. 4), so the gradient jumps
/// where a new vertex crosses an old one and the projected gradient alone can stall
/// above its tolerance near such a kink while f no longer changes. Both solvers share
/// it, so they stop on the same criterion.
pub const FTOL: f64 = 1e-12;

/// Factor by which our solver raises the augmented-Lagrangian penalty mu after a round
/// that stalled (did not shrink the largest constraint residual 4x, or moved q less
/// than the outer tolerance), and by which it relaxes after a step that did not raise
/// it (see `StepSolver::solve`).
pub const PENALTY_GROWTH: f64 = 10.0;

/// Cap of the adaptive penalty, a factor on the scene's mu (`solver.penalty`): 1e5 J/m^2
/// on the default 1e3 (Hessian entries ~1e5 next to the kinetic term's
/// rho w l / (n h^2) = 1e-4 kg / h^2, i.e. 1 at h = 0.01 s), well within what a dense
/// Cholesky in f64 resolves.
pub const MAX_PENALTY_GROWTH: f64 = 100.0;

/// `solver.saddle_free` (issue 47): a chain pivot's eigenvalues are floored at this
/// fraction of its stage's largest entry (pivot and coupling rows) when replaced by
/// their absolute values, which bounds the sweep's feedback gains K = -Q_uu^-1 Q_ux by
/// 1 / 1e-6 (flipped pivots without a floor cascaded to |d| ~ 1e114 on 2026-12-02).
/// Not tuned: the variant is not the default (docs/ribbon_chain_solver.md, 2026-12-07).
const SADDLE_FREE_FLOOR: f64 = 1e-6;

/// What one step's solve did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SolveOutcome {
    pub iterations: u32,
    pub outer_iterations: u32,
    pub converged: bool,
    /// Largest position-constraint residual after the solve, m.
    pub constraint_violation: f64,
    /// Index (in `StepTerms::equalities`) of the equality with that residual.
    pub worst_equality: Option<usize>,
    /// Largest rotation-constraint residual (Frobenius entries), dimensionless.
    pub orientation_violation: f64,
    /// Final objective value, J.
    pub objective: f64,
}

/// Buffers of the step solver (reused across steps).
#[derive(Default)]
pub struct StepSolver {
    pub workspace: Workspace,
    newton: ProjectedNewton<Dense>,
    chain: ProjectedNewton<ChainMatrix>,
    trust: TrustRegion<ChainMatrix>,
    interior: InteriorPoint<ChainMatrix>,
    /// L-BFGS-B workspace and the dimension it was built for.
    lbfgsb: Option<(usize, Lbfgsb)>,
    z: Vec<f64>,
    lower: Vec<f64>,
    upper: Vec<f64>,
    q_prev: Vec<f64>,
    /// The contact hook's last checked path (kept buffers).
    path: CheckedPath,
    /// Buffers of the z-problem (q and its gradient), kept across rounds and steps.
    q_scratch: Vec<f64>,
    gq_scratch: Vec<f64>,
    /// Test-only: the chain matrix's crease blocks off by this relative amount
    /// (`ChainModel::perturb_local_blocks`); 0: exact.
    #[cfg(any(test, feature = "test-hooks"))]
    pub newton_matrix_error: f64,
    /// Test-only: a loop closure always in the 14-column form
    /// (`ChainModel::use_fourteen_column_closure`).
    #[cfg(any(test, feature = "test-hooks"))]
    pub fourteen_column_closure: bool,
    z_scratch: Vec<f64>,
}

impl Clone for StepSolver {
    fn clone(&self) -> Self {
        // Buffers, except what the solvers carry from step to step (the Newton
        // solvers' damping, the trust region's radius and shift): a clone steps on
        // exactly as the original (a World copied mid-run continues bit for bit,
        // tests/world_clone.rs).
        StepSolver {
            newton: self.newton.fresh_with_history(),
            chain: self.chain.fresh_with_history(),
            trust: self.trust.fresh_with_history(),
            interior: self.interior.fresh_with_history(),
            #[cfg(any(test, feature = "test-hooks"))]
            newton_matrix_error: self.newton_matrix_error,
            #[cfg(any(test, feature = "test-hooks"))]
            fourteen_column_closure: self.fourteen_column_closure,
            ..StepSolver::default()
        }
    }
}

impl std::fmt::Debug for StepSolver {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("StepSolver")
    }
}

/// q -> z: crease directions to crease differences.
pub fn q_to_z(layout: &Layout, q: &[f64], z: &mut [f64]) {
    z.copy_from_slice(q);
    let n = layout.segments;
    for k in (2..n).rev() {
        z[layout.c(k)] = q[layout.c(k)] - q[layout.c(k - 1)];
    }
}

/// z -> q: cumulative sums of crease differences.
pub fn z_to_q(layout: &Layout, z: &[f64], q: &mut [f64]) {
    q.copy_from_slice(z);
    let n = layout.segments;
    for k in 2..n {
        q[layout.c(k)] = q[layout.c(k - 1)] + z[layout.c(k)];
    }
}

/// The inner problem in z: f(q(z)) with gradient A^T g and Hessian A^T H A, where A is
/// the cumulative-sum map on the crease block.
struct ZProblem<'o, 'w> {
    objective: &'o Objective<'o>,
    workspace: &'w mut Workspace,
    q: Vec<f64>,
    gq: Vec<f64>,
    mode: GradientMode,
    /// Record second-order data with every gradient (for `BoxProblem::hessian`).
    second_order: bool,
    #[cfg(any(test, feature = "test-hooks"))]
    newton_matrix_error: f64,
    #[cfg(any(test, feature = "test-hooks"))]
    fourteen_column_closure: bool,
    /// A z on the line search's path (contact hook).
    z_scratch: Vec<f64>,
    /// The last path the contact hook checked.
    path: CheckedPath,
    /// The chain matrix's saddle-free pivot floor (`ChainModel::set_saddle_free`); 0:
    /// off.
    saddle_floor: f64,
}

/// The path z(α) = clamp(z0 + α d, lower, upper), α in [0, alpha], that the last line
/// search's collision check covered: evaluations on it may read its candidate pairs.
#[derive(Clone, Debug, Default)]
struct CheckedPath {
    z0: Vec<f64>,
    d: Vec<f64>,
    lower: Vec<f64>,
    upper: Vec<f64>,
    alpha: f64,
    valid: bool,
}

impl CheckedPath {
    fn record(&mut self, z: &[f64], d: &[f64], lower: &[f64], upper: &[f64], alpha: f64) {
        for (v, x) in [
            (&mut self.z0, z),
            (&mut self.d, d),
            (&mut self.lower, lower),
            (&mut self.upper, upper),
        ] {
            v.clear();
            v.extend_from_slice(x);
        }
        self.alpha = alpha;
        self.valid = alpha > 0.0;
    }

    /// Whether z lies on the path (to 1e-12 relative: the solvers form their trial
    /// points with the same operations, a line search exactly, a trust region as
    /// z0 + α d within the box). α is read off the largest move not on a bound.
    fn contains(&self, z: &[f64]) -> bool {
        if !self.valid || z.len() != self.z0.len() {
            return false;
        }
        let inside = |i: usize| z[i] > self.lower[i] && z[i] < self.upper[i];
        let (mut largest, mut alpha) = (0.0, 0.0);
        for i in 0..z.len() {
            if self.d[i].abs() > largest && inside(i) {
                largest = self.d[i].abs();
                alpha = (z[i] - self.z0[i]) / self.d[i];
            }
        }
        if !(-1e-12..=self.alpha * (1.0 + 1e-12)).contains(&alpha) {
            return false;
        }
        (0..z.len()).all(|i| {
            let on = (self.z0[i] + alpha * self.d[i]).clamp(self.lower[i], self.upper[i]);
            (z[i] - on).abs() <= 1e-12 * (1.0 + z[i].abs())
        })
    }
}

impl ZProblem<'_, '_> {
    fn gradient_to_z(&self, g: &mut [f64]) {
        let lay = &self.objective.layout;
        g.copy_from_slice(&self.gq);
        let n = lay.segments;
        // suffix sums over the crease block
        for k in (1..n - 1).rev() {
            g[lay.c(k)] += g[lay.c(k + 1)];
        }
    }
}

impl ZProblem<'_, '_> {
    /// f(q(z)) and, if asked, its z-gradient, recording the second-order data a Newton
    /// matrix is built from when `hessian` (or `second_order` with a gradient): the
    /// dense and the chain matrix read it from the workspace.
    fn evaluate_second_order(
        &mut self,
        z: &[f64],
        gradient: Option<&mut [f64]>,
        hessian: bool,
    ) -> f64 {
        let lay = self.objective.layout;
        z_to_q(&lay, z, &mut self.q);
        let on_path = self.path.contains(z);
        self.workspace.set_on_checked_path(on_path);
        let want_g = gradient.is_some();
        let second_order = hessian || (want_g && self.second_order);
        let f = if want_g {
            self.objective.evaluate_recording(
                &self.q,
                self.workspace,
                Some((&mut self.gq, self.mode)),
                second_order,
            )
        } else {
            self.objective
                .evaluate_recording(&self.q, self.workspace, None, second_order)
        };
        self.workspace.set_on_checked_path(false);
        if let Some(g) = gradient {
            self.gradient_to_z(g);
        }
        f
    }

    fn dimension(&self) -> usize {
        self.q.len()
    }

    /// The contact hook of the line search ([`BoxProblem::max_step_fraction`]): the
    /// safe fraction of the path z(α) = clamp(z + α d) mapped to q.
    fn max_step_fraction(&mut self, z: &[f64], d: &[f64], lower: &[f64], upper: &[f64]) -> f64 {
        let lay = self.objective.layout;
        let mut zs = std::mem::take(&mut self.z_scratch);
        let fraction = self
            .objective
            .safe_step_fraction(self.workspace, &mut |alpha, q| {
                zs.clear();
                zs.extend((0..z.len()).map(|i| (z[i] + alpha * d[i]).clamp(lower[i], upper[i])));
                z_to_q(&lay, &zs, q);
            });
        self.z_scratch = zs;
        self.path.record(z, d, lower, upper, fraction);
        fraction
    }
    /// f(q(z)) and, if asked, its z-gradient (second-order data as `second_order`).
    fn evaluate(&mut self, z: &[f64], gradient: Option<&mut [f64]>) -> f64 {
        self.evaluate_second_order(z, gradient, false)
    }
}

/// Transform a q-space Hessian into z-space in place: H_z = A^T H A.
fn hessian_to_z(layout: &Layout, h: &mut DMatrix<f64>) {
    let n = layout.segments;
    let rows = h.nrows();
    let data = h.as_mut_slice();
    // columns: column c_k += column c_{k+1}, from the end (contiguous vector adds)
    for k in (1..n - 1).rev() {
        let (a, b) = (layout.c(k), layout.c(k + 1));
        let (head, tail) = data.split_at_mut(b * rows);
        for (x, y) in head[a * rows..(a + 1) * rows].iter_mut().zip(&tail[..rows]) {
            *x += y;
        }
    }
    // rows: the same suffix sums down each column, eight columns side by side so that
    // their independent dependency chains overlap (one column alone waits on every add)
    for block in data.chunks_mut(rows * 8) {
        let columns = block.len() / rows;
        for k in (1..n - 1).rev() {
            let (a, b) = (layout.c(k), layout.c(k + 1));
            for col in 0..columns {
                block[col * rows + a] += block[col * rows + b];
            }
        }
    }
}

struct ZNewton<'p, 'o, 'w>(&'p mut ZProblem<'o, 'w>);
impl BoxProblem for ZNewton<'_, '_, '_> {
    type Matrix = Dense;
    fn dimension(&self) -> usize {
        self.0.dimension()
    }
    fn evaluate(
        &mut self,
        z: &[f64],
        gradient: Option<&mut [f64]>,
        hessian: Option<&mut Dense>,
    ) -> f64 {
        let f = self.0.evaluate_second_order(z, gradient, hessian.is_some());
        if let Some(h) = hessian {
            self.hessian(z, h);
        }
        f
    }
    fn max_step_fraction(&mut self, z: &[f64], d: &[f64], lo: &[f64], hi: &[f64]) -> f64 {
        self.0.max_step_fraction(z, d, lo, hi)
    }
    fn hessian(&mut self, _z: &[f64], h: &mut Dense) {
        // the workspace holds the second-order data of the evaluation at z
        let problem = &mut *self.0;
        problem
            .objective
            .assemble_newton_hessian(problem.workspace, &mut h.matrix);
        hessian_to_z(&problem.objective.layout, &mut h.matrix);
    }
}

/// The same problem with the Newton system in chain form (O(n), already in z).
struct ZChain<'p, 'o, 'w>(&'p mut ZProblem<'o, 'w>);
impl BoxProblem for ZChain<'_, '_, '_> {
    type Matrix = ChainMatrix;
    fn dimension(&self) -> usize {
        self.0.dimension()
    }
    fn evaluate(
        &mut self,
        z: &[f64],
        gradient: Option<&mut [f64]>,
        hessian: Option<&mut ChainMatrix>,
    ) -> f64 {
        let f = self.0.evaluate_second_order(z, gradient, hessian.is_some());
        if let Some(h) = hessian {
            self.hessian(z, h);
        }
        f
    }
    fn max_step_fraction(&mut self, z: &[f64], d: &[f64], lo: &[f64], hi: &[f64]) -> f64 {
        self.0.max_step_fraction(z, d, lo, hi)
    }
    fn hessian(&mut self, _z: &[f64], h: &mut ChainMatrix) {
        let problem = &mut *self.0;
        problem
            .objective
            .chain_model(problem.workspace, &mut h.model);
        h.model.set_saddle_free(problem.saddle_floor);
        #[cfg(any(test, feature = "test-hooks"))]
        if problem.newton_matrix_error != 0.0 {
            h.model.perturb_local_blocks(problem.newton_matrix_error);
        }
        #[cfg(any(test, feature = "test-hooks"))]
        if problem.fourteen_column_closure {
            h.model.use_fourteen_column_closure();
        }
    }
    /// The trust region's units: 1 for crease differences (crease-direction units),
    /// bending angles and the base rotation (rad); the strip's length l for the base
    /// translation (m), which moves the far end as far as a base rotation of 1 rad.
    fn radius_units(&self, out: &mut [f64]) {
        out.fill(1.0);
        if self.0.objective.layout.floating {
            out[3..6].fill(self.0.objective.strip.length);
        }
    }
}

/// What one round's multiplier update (algorithm 2) gives: the new multipliers and the
/// residuals at the round's q.
struct MultiplierUpdate {
    /// λ - μ C per equality (`StepTerms::multipliers` layout), J/m for positions.
    multipliers: Vec<Vec<f64>>,
    /// min(0, λ + μ (Δc_max -+ c_{n-1})) of the two end-crease inequalities.
    end_crease_multipliers: [f64; 2],
    /// Whether an end-crease inequality is active (before or after the update).
    end_active: bool,
    /// Largest position residual, m, and the index of its equality.
    max_position: f64,
    worst: Option<usize>,
    /// Largest rotation residual, dimensionless.
    max_rotation: f64,
    /// c_{n-1} at the round's q.
    c_last: f64,
}

/// The residuals at the round's new `q` and the multiplier update they give (algorithm
/// 2), read from `objective.terms`; the caller stores them once the objective is done.
fn multiplier_update(
    objective: &Objective,
    workspace: &mut Workspace,
    q: &[f64],
) -> MultiplierUpdate {
    let terms = objective.terms;
    let layout = objective.layout;
    objective.prepare(q, workspace);
    let mut residual = [0.0; 9];
    let mut max_pos: f64 = 0.0;
    let mut max_rot: f64 = 0.0;
    let mut worst: Option<usize> = None;
    let mut updates: Vec<Vec<f64>> = Vec::with_capacity(terms.equalities.len());
    for (index, (eq, lambda)) in terms.equalities.iter().zip(&terms.multipliers).enumerate() {
        let rows = eq.rows();
        objective.equality_residual(workspace, eq, &mut residual[..rows]);
        for (i, r) in residual[..rows].iter().enumerate() {
            if eq.is_rotation_row(i) {
                max_rot = max_rot.max(r.abs());
            } else if r.abs() > max_pos {
                max_pos = r.abs();
                worst = Some(index);
            }
        }
        updates.push(
            lambda
                .iter()
                .zip(&residual[..rows])
                .map(|(l, c)| l - terms.penalty * c)
                .collect(),
        );
    }
    let bound = terms.crease_bound;
    let c_last = q[layout.c(layout.segments - 1)];
    let mu = terms.penalty;
    let end = [
        (terms.end_crease_multipliers[0] + mu * (bound - c_last)).min(0.0),
        (terms.end_crease_multipliers[1] + mu * (bound + c_last)).min(0.0),
    ];
    let end_active = !terms.end_crease_exact
        && (end.iter().any(|&l| l < 0.0) || terms.end_crease_multipliers.iter().any(|&l| l < 0.0));
    let end = if terms.end_crease_exact {
        [0.0; 2]
    } else {
        end
    };
    MultiplierUpdate {
        multipliers: updates,
        end_crease_multipliers: end,
        end_active,
        max_position: max_pos,
        worst,
        max_rotation: max_rot,
        c_last,
    }
}

/// Our Newton solvers' options for round `outer`: the gradient tolerance relative to
/// the first round's start (`pg0`; the solver measures it at its first evaluation
/// when unset), and chord steps on the last round's final factorization in later
/// rounds (they differ from it only by the multiplier update).
fn newton_options(settings: &SolverSettings, pg0: Option<f64>, outer: u32) -> NewtonOptions {
    NewtonOptions {
        max_iterations: settings.max_iterations,
        pgtol: settings.tolerance * pg0.unwrap_or(0.0),
        ftol: FTOL,
        pgtol_relative_to_start: match pg0 {
            Some(_) => None,
            None => Some(settings.tolerance),
        },
        reuse_factorization: outer > 0,
    }
}

/// The next step's starting mu after a step that did not raise it: relaxed toward the
/// scene's (a large mu makes the inner problems stiffer), but not below |lambda| / (l/n)
/// for the position rows, J/m^2. The shifted penalty mu/2 (C - lambda/mu)^2 pulls toward
/// a point lambda/mu away from the target; with the large multiplier that holds a stiff
/// ribbon (~1e3 N) and the scene's mu that point is ~1 m away, and the next step's first
/// round ran off to it (a 0.97 m violation on a 1000 J ribbon). One element length
/// keeps it on the ribbon's own scale.
fn relaxed_penalty(strip: Strip, terms: &StepTerms, settings: &SolverSettings) -> f64 {
    let element = strip.length / strip.segments as f64;
    let mut largest_force: f64 = 0.0;
    for (eq, lambda) in terms.equalities.iter().zip(&terms.multipliers) {
        for (i, l) in lambda.iter().enumerate() {
            if !eq.is_rotation_row(i) {
                largest_force = largest_force.max(l.abs());
            }
        }
    }
    let floor = (largest_force / element)
        .min(MAX_PENALTY_GROWTH * settings.penalty)
        .max(settings.penalty);
    (terms.penalty / PENALTY_GROWTH).max(floor)
}

impl StepSolver {
    /// Solve one step starting from (and writing to) `q`. `terms` multipliers are
    /// updated in place (augmented Lagrangian).
    #[allow(clippy::too_many_arguments)]
    pub fn solve(
        &mut self,
        strip: Strip,
        floating: bool,
        history: &RimHistory,
        base: Pose,
        objective_terms: &mut StepTerms,
        settings: &SolverSettings,
        contact: Option<&ContactTerms>,
        q: &mut [f64],
    ) -> SolveOutcome {
        let mut outcome = SolveOutcome {
            converged: true,
            ..Default::default()
        };
        let has_equalities = !objective_terms.equalities.is_empty();
        let mut pg0: Option<f64> = None;
        // Adaptive penalty (ours; the paper's solver keeps the scene's fixed mu): mu
        // carries over from the last step, relaxed at its end (below).
        let adaptive = matches!(
            settings.kind,
            SolverKind::GaussNewton
                | SolverKind::Chain
                | SolverKind::TrustRegion
                | SolverKind::InteriorPoint
        );
        if !adaptive {
            objective_terms.penalty = settings.penalty;
        }
        // The trust-region solver holds the end crease exactly (a slab), so it has no
        // augmented-Lagrangian term, and no multiplier, there.
        objective_terms.end_crease_exact = settings.kind == SolverKind::TrustRegion
            || settings.kind == SolverKind::InteriorPoint
            || (settings.kind == SolverKind::Chain && settings.chain_variant.end_crease_exact);
        if objective_terms.end_crease_exact {
            objective_terms.end_crease_multipliers = [0.0, 0.0];
        }
        let mut last_residual = f64::INFINITY;
        let mut grew = false;
        for outer in 0..settings.max_outer_iterations.max(1) {
            self.q_prev.clear();
            self.q_prev.extend_from_slice(q);
            let objective = Objective::new(strip, floating, objective_terms, history, base)
                .with_contact(contact);
            let layout = objective.layout;
            let bound = objective_terms.crease_bound;
            self.start_round(&layout, q, bound);
            let (iterations, converged, f) =
                self.inner_solve(&objective, settings, outer, &mut pg0);
            outcome.iterations += iterations;
            outcome.outer_iterations = outer + 1;
            outcome.converged &= converged;
            outcome.objective = f;
            z_to_q(&layout, &self.z, q);
            let update = multiplier_update(&objective, &mut self.workspace, q);
            let (max_pos, max_rot, c_last) =
                (update.max_position, update.max_rotation, update.c_last);
            objective_terms.multipliers = update.multipliers;
            objective_terms.end_crease_multipliers = update.end_crease_multipliers;
            outcome.constraint_violation = max_pos;
            outcome.worst_equality = update.worst;
            outcome.orientation_violation = max_rot;
            let change = q
                .iter()
                .zip(&self.q_prev)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max);
            // The paper stops on ||Δq|| < outer_tolerance; we also stop as soon as every
            // constraint holds to `constraint_tolerance` (with multipliers warm-started
            // from the previous step this usually saves the second round).
            let end_ok = c_last.abs() <= bound + settings.constraint_tolerance;
            let satisfied = max_pos <= settings.constraint_tolerance
                && max_rot <= settings.constraint_tolerance
                && end_ok;
            // Ours: a round that did not shrink the largest residual 4x raises mu 10x
            // (up to MAX_PENALTY_GROWTH x the scene's). A stiff ribbon barely moves under
            // one round's multiplier update mu C, so ||Δq|| falls below the paper's
            // outer tolerance while the grasp point still lags its target (a 1000 J
            // ribbon under two grippers: 0.33 m behind, 110 of 300 steps on the round
            // limit); a small ||Δq|| ends the step only once mu has stopped growing.
            let residual = max_pos.max(max_rot);
            let cap = MAX_PENALTY_GROWTH * settings.penalty;
            let stalled = residual > 0.25 * last_residual || change < settings.outer_tolerance;
            let grow = adaptive && !satisfied && stalled && objective_terms.penalty < cap;
            last_residual = residual;
            if !(has_equalities || update.end_active)
                || satisfied
                || (change < settings.outer_tolerance && !grow)
            {
                break;
            }
            if outer + 1 == settings.max_outer_iterations {
                outcome.converged = false;
            }
            if grow {
                objective_terms.penalty = (objective_terms.penalty * PENALTY_GROWTH).min(cap);
                grew = true;
            }
        }
        if adaptive && !grew {
            // No round of this step needed a larger mu: relax it for the next step.
            objective_terms.penalty = relaxed_penalty(strip, objective_terms, settings);
        }
        outcome
    }

    /// A round's start in z (q -> z) and its box: |z_k| <= Δc_max on the crease
    /// differences k = 1..n-1 (dimensionless), the rest unbounded; the start is
    /// clamped into the box so that it is feasible.
    fn start_round(&mut self, layout: &Layout, q: &[f64], bound: f64) {
        let nq = q.len();
        self.z.resize(nq, 0.0);
        q_to_z(layout, q, &mut self.z);
        self.lower.clear();
        self.upper.clear();
        self.lower.resize(nq, f64::NEG_INFINITY);
        self.upper.resize(nq, f64::INFINITY);
        for k in 1..layout.segments {
            self.lower[layout.c(k)] = -bound;
            self.upper[layout.c(k)] = bound;
        }
        // keep the start feasible
        for i in 0..nq {
            self.z[i] = self.z[i].clamp(self.lower[i], self.upper[i]);
        }
    }

    /// One round's inner problem in z from `self.z` (written back): our projected
    /// Newton (dense or chain matrix) or L-BFGS-B, with the gradient tolerance relative
    /// to the first round's start (`pg0`, set by the first round). Returns (iterations,
    /// converged, final objective in J).
    fn inner_solve(
        &mut self,
        objective: &Objective,
        settings: &SolverSettings,
        outer: u32,
        pg0: &mut Option<f64>,
    ) -> (u32, bool, f64) {
        let nq = self.z.len();
        self.q_scratch.resize(nq, 0.0);
        self.gq_scratch.resize(nq, 0.0);
        let mut problem = ZProblem {
            objective,
            workspace: &mut self.workspace,
            q: std::mem::take(&mut self.q_scratch),
            gq: std::mem::take(&mut self.gq_scratch),
            mode: GradientMode::Adjoint,
            second_order: false,
            #[cfg(any(test, feature = "test-hooks"))]
            newton_matrix_error: self.newton_matrix_error,
            #[cfg(any(test, feature = "test-hooks"))]
            fourteen_column_closure: self.fourteen_column_closure,
            z_scratch: std::mem::take(&mut self.z_scratch),
            path: std::mem::take(&mut self.path),
            saddle_floor: 0.0,
        };
        problem.path.valid = false;
        let result = match settings.kind {
            SolverKind::GaussNewton
            | SolverKind::Chain
            | SolverKind::TrustRegion
            | SolverKind::InteriorPoint => {
                let opts = newton_options(settings, *pg0, outer);
                problem.second_order = true;
                let n = objective.layout.segments;
                // |c_{n-1}| = |Σ_k z_k| <= Δc_max, held exactly
                let slab = (n >= 2).then(|| Slab {
                    range: objective.layout.c(1)..objective.layout.c(n - 1) + 1,
                    bound: objective.terms.crease_bound,
                });
                let (z, lower, upper) = (&mut self.z, &self.lower[..], &self.upper[..]);
                let r = match settings.kind {
                    SolverKind::InteriorPoint => {
                        let chain = &mut ZChain(&mut problem);
                        self.interior.minimize(chain, z, lower, upper, slab, &opts)
                    }
                    SolverKind::TrustRegion => {
                        let chain = &mut ZChain(&mut problem);
                        self.trust.minimize(chain, z, lower, upper, slab, &opts)
                    }
                    SolverKind::Chain => {
                        let variant = settings.chain_variant;
                        self.chain
                            .set_slab(slab.filter(|_| variant.end_crease_exact));
                        self.chain.set_cut_keeps_damping(variant.cut_keeps_shift);
                        if variant.saddle_free {
                            problem.saddle_floor = SADDLE_FREE_FLOOR;
                        }
                        let chain = &mut ZChain(&mut problem);
                        self.chain.minimize(chain, z, lower, upper, &opts)
                    }
                    _ => self
                        .newton
                        .minimize(&mut ZNewton(&mut problem), z, lower, upper, &opts),
                };
                pg0.get_or_insert(r.initial_projected_gradient_inf.max(1e-300));
                (r.iterations, r.converged, r.f)
            }
            SolverKind::Lbfgsb => {
                // relative gradient tolerance against the first round's start
                let scale = *pg0.get_or_insert_with(|| {
                    let mut g = vec![0.0; nq];
                    problem.evaluate(&self.z, Some(&mut g));
                    crate::optim::projected_gradient_inf(&self.z, &g, &self.lower, &self.upper)
                        .max(1e-300)
                });
                let pgtol = settings.tolerance * scale;
                let options = LbfgsbOptions {
                    max_iterations: settings.max_iterations as usize,
                    pgtol,
                    ftol: FTOL,
                    ..LbfgsbOptions::default()
                };
                if self.lbfgsb.as_ref().map(|(n, _)| *n) != Some(nq) {
                    self.lbfgsb = Some((nq, Lbfgsb::new(nq, options)));
                }
                let (_, solver) = self.lbfgsb.as_mut().expect("created above");
                *solver.options_mut() = options;
                let r = solver.minimize(&mut self.z, &self.lower, &self.upper, |z, g| {
                    problem.evaluate(z, Some(g))
                });
                (r.iterations as u32, r.converged(), r.f)
            }
        };
        self.q_scratch = std::mem::take(&mut problem.q);
        self.gq_scratch = std::mem::take(&mut problem.gq);
        self.z_scratch = std::mem::take(&mut problem.z_scratch);
        self.path = std::mem::take(&mut problem.path);
        result
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_checked_path_holds_its_points_and_no_others() {
        // z0 + α d clamped into the box, α up to 0.5; coordinate 2 reaches its bound
        let (z0, d) = ([0.1, -0.2, 0.9, 0.0], [1.0, 0.5, 1.0, 0.0]);
        let (lower, upper) = ([-1.0; 4], [1.0; 4]);
        let mut path = CheckedPath::default();
        path.record(&z0, &d, &lower, &upper, 0.5);
        let at = |a: f64| -> Vec<f64> {
            (0..4)
                .map(|i| (z0[i] + a * d[i]).clamp(lower[i], upper[i]))
                .collect()
        };
        for a in [0.0, 0.05, 0.25, 0.5] {
            assert!(path.contains(&at(a)), "α = {a}");
        }
        assert!(!path.contains(&at(0.6)), "beyond the checked fraction");
        assert!(!path.contains(&at(-0.1)), "behind the start");
        let mut off = at(0.25);
        off[3] += 1e-9;
        assert!(!path.contains(&off), "off the line");
        path.record(&z0, &d, &lower, &upper, 0.0);
        assert!(!path.contains(&z0), "no step was checked");
    }

    #[test]
    fn substitution_round_trips_and_hessian_transform_is_a_congruence() {
        let lay = Layout {
            segments: 6,
            floating: true,
        };
        let q: Vec<f64> = (0..lay.len()).map(|i| (i as f64 * 0.37).sin()).collect();
        let mut z = vec![0.0; q.len()];
        let mut back = vec![0.0; q.len()];
        q_to_z(&lay, &q, &mut z);
        z_to_q(&lay, &z, &mut back);
        for (a, b) in q.iter().zip(&back) {
            assert!((a - b).abs() < 1e-15);
        }
        // A^T H A with A = dq/dz built explicitly
        let n = lay.len();
        let h = DMatrix::from_fn(n, n, |i, j| {
            ((i * 7 + j * 3) % 5) as f64 + if i == j { 10.0 } else { 0.0 }
        });
        let h = &h + h.transpose();
        let mut a = DMatrix::<f64>::identity(n, n);
        for k in 1..6 {
            for j in 1..k {
                a[(lay.c(k), lay.c(j))] = 1.0;
            }
        }
        let expected = a.transpose() * &h * &a;
        let mut got = h.clone();
        hessian_to_z(&lay, &mut got);
        assert!((expected - got).amax() < 1e-12);
    }
}
