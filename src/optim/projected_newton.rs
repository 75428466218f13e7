//! Projected Gauss-Newton / Levenberg-Marquardt for box-constrained minimization with a
//! dense positive semi-definite Hessian model (Bertsekas' projected Newton): variables
//! at a bound whose gradient pushes outward are held; the rest take a damped Newton
//! step solved by a dense Cholesky factorization (faer); a projected Armijo search keeps
//! the iterate in the box.

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::cholesky::llt;
use faer::{MatMut, Par};
use nalgebra::DMatrix;

use super::projected_gradient_inf;

/// A box-constrained problem with a Hessian model.
pub trait BoxProblem {
    fn dimension(&self) -> usize;
    /// f(x); writes the gradient if asked and the Hessian model (PSD) if asked.
    fn evaluate(
        &mut self,
        x: &[f64],
        gradient: Option<&mut [f64]>,
        hessian: Option<&mut DMatrix<f64>>,
    ) -> f64;
    /// The Hessian model at `x`, called only right after `evaluate(x, Some(g), None)`
    /// at that same `x`: a problem that keeps what that evaluation computed can
    /// assemble the Hessian without a second pass. The solver asks for it only when it
    /// takes another step, so the last iterate never pays for one.
    fn hessian(&mut self, x: &[f64], hessian: &mut DMatrix<f64>) {
        self.evaluate(x, None, Some(hessian));
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NewtonOptions {
    pub max_iterations: u32,
    /// Stop when the projected-gradient infinity norm is at most this.
    pub pgtol: f64,
    /// Stop when (f_k - f_{k+1}) / max(|f_k|, |f_{k+1}|, 1) is at most this after a full
    /// step (the L-BFGS-B `factr` test, so both solvers share one criterion).
    pub ftol: f64,
    /// When set, the projected-gradient tolerance is this factor times the projected
    /// gradient at the (clamped) start instead of `pgtol`; the start value is returned
    /// in [`NewtonResult::initial_projected_gradient_inf`].
    pub pgtol_relative_to_start: Option<f64>,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NewtonResult {
    pub f: f64,
    pub iterations: u32,
    pub evaluations: u32,
    pub projected_gradient_inf: f64,
    /// Projected gradient (infinity norm) at the clamped start.
    pub initial_projected_gradient_inf: f64,
    pub converged: bool,
}

/// Workspace of the projected Newton method; buffers are reused between calls.
#[derive(Default)]
pub struct ProjectedNewton {
    g: Vec<f64>,
    /// Gradient at the first (full-step) trial point of the line search.
    g_trial: Vec<f64>,
    h: DMatrix<f64>,
    free: Vec<usize>,
    reduced: Vec<f64>,
    trial: Vec<f64>,
    /// Reduced system matrix (column-major) and factorization scratch.
    system: Vec<f64>,
    scratch: Option<(usize, MemBuffer)>,
    /// Levenberg-Marquardt damping relative to the Hessian diagonal, adapted per step.
    damping: f64,
    /// The damping the first iteration of the last solve needed.
    first_damping: f64,
}

impl Clone for ProjectedNewton {
    /// Buffers only: a fresh workspace behaves identically.
    fn clone(&self) -> Self {
        ProjectedNewton::new()
    }
}

impl std::fmt::Debug for ProjectedNewton {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ProjectedNewton")
            .field("damping", &self.damping)
            .finish()
    }
}

impl ProjectedNewton {
    pub fn new() -> Self {
        ProjectedNewton {
            damping: 1e-9,
            ..Default::default()
        }
    }

    pub fn minimize(
        &mut self,
        problem: &mut impl BoxProblem,
        x: &mut [f64],
        lower: &[f64],
        upper: &[f64],
        options: &NewtonOptions,
    ) -> NewtonResult {
        let n = problem.dimension();
        self.g.resize(n, 0.0);
        self.g_trial.resize(n, 0.0);
        self.trial.resize(n, 0.0);
        for i in 0..n {
            x[i] = x[i].clamp(lower[i], upper[i]);
        }
        let mut evaluations = 1;
        let mut f = problem.evaluate(x, Some(&mut self.g), None);
        let mut pg = projected_gradient_inf(x, &self.g, lower, upper);
        let initial_pg = pg;
        let pgtol = match options.pgtol_relative_to_start {
            Some(factor) => factor * pg.max(1e-300),
            None => options.pgtol,
        };
        if !f.is_finite() || !pg.is_finite() {
            return NewtonResult {
                f,
                iterations: 0,
                evaluations,
                projected_gradient_inf: pg,
                initial_projected_gradient_inf: initial_pg,
                converged: false,
            };
        }
        let mut iterations = 0;
        let mut converged = pg <= pgtol;
        // Whether self.h holds the Hessian at x (assembled on demand: see
        // BoxProblem::hessian).
        let mut hessian_ready = false;
        // Start from a tenth of the damping the last solve's first iteration needed:
        // consecutive time steps have similar curvature, and every rejected
        // factorization costs as much as an accepted one.
        self.damping = (self.first_damping * 0.1).max(1e-9);
        let mut first = true;
        while !converged && iterations < options.max_iterations {
            iterations += 1;
            // Active set: at a bound with the gradient pointing out of the box.
            let eps = 1e-12;
            self.free.clear();
            for i in 0..n {
                let at_lower = x[i] <= lower[i] + eps * (1.0 + lower[i].abs()) && self.g[i] > 0.0;
                let at_upper = x[i] >= upper[i] - eps * (1.0 + upper[i].abs()) && self.g[i] < 0.0;
                if !(at_lower || at_upper) {
                    self.free.push(i);
                }
            }
            let m = self.free.len();
            if m == 0 {
                converged = true;
                break;
            }
            if !hessian_ready {
                // x was the last point evaluated with a gradient (the start or the
                // accepted trial)
                problem.hessian(x, &mut self.h);
                hessian_ready = true;
            }
            // Newton step on the Hessian; where it is indefinite, the PSD fallback
            // model; then more damping.
            let mut step_ok = self.solve_reduced(m);
            while !step_ok && self.damping < 1e2 {
                self.damping = (self.damping * 10.0).max(1e-8);
                step_ok = self.solve_reduced(m);
            }
            if first {
                self.first_damping = self.damping;
                first = false;
            }
            if !step_ok {
                break;
            }
            // Stationary to round-off: the model predicts a decrease no larger than the
            // rounding error of f itself, so no step can be verified. Converged.
            let predicted: f64 = -self
                .free
                .iter()
                .zip(&self.reduced)
                .map(|(&i, d)| self.g[i] * d)
                .sum::<f64>();
            if predicted <= 1e-14 * f.abs() {
                converged = true;
                break;
            }
            // Projected Armijo line search along the Newton direction. The full step is
            // evaluated with its gradient: it is accepted almost always, and then that
            // evaluation is the next iterate's.
            let mut alpha = 1.0;
            let mut accepted = false;
            let mut f_new = f;
            for trial in 0..40 {
                self.trial.copy_from_slice(x);
                for (k, &i) in self.free.iter().enumerate() {
                    self.trial[i] = (x[i] + alpha * self.reduced[k]).clamp(lower[i], upper[i]);
                }
                evaluations += 1;
                f_new = if trial == 0 {
                    problem.evaluate(&self.trial, Some(&mut self.g_trial), None)
                } else {
                    problem.evaluate(&self.trial, None, None)
                };
                let decrease: f64 = self
                    .free
                    .iter()
                    .map(|&i| self.g[i] * (self.trial[i] - x[i]))
                    .sum();
                if f_new.is_finite() && f_new <= f + 1e-4 * decrease {
                    accepted = true;
                    break;
                }
                alpha *= 0.5;
            }
            if !accepted {
                // No decrease along the model direction: more damping next time (the
                // Hessian at x is kept); stop if the model is already heavily damped
                // (we are at the noise floor).
                if self.damping > 1e2 {
                    break;
                }
                self.damping = (self.damping * 100.0).max(1e-6);
                continue;
            }
            if alpha == 1.0 {
                // a full step: trust the model more (Levenberg-Marquardt update)
                self.damping = (self.damping / 1000.0).max(1e-12);
            } else {
                self.damping = (self.damping * 10.0).min(1e6);
            }
            x.copy_from_slice(&self.trial);
            let f_old = f;
            if alpha == 1.0 {
                // the full-step trial was evaluated with its gradient
                f = f_new;
                std::mem::swap(&mut self.g, &mut self.g_trial);
            } else {
                evaluations += 1;
                f = problem.evaluate(x, Some(&mut self.g), None);
            }
            hessian_ready = false;
            pg = projected_gradient_inf(x, &self.g, lower, upper);
            if pg <= pgtol {
                converged = true;
            } else if alpha == 1.0
                && (f_old - f) <= options.ftol * f_old.abs().max(f.abs()).max(1.0)
            {
                converged = true;
            }
        }
        NewtonResult {
            f,
            iterations,
            evaluations,
            projected_gradient_inf: pg,
            initial_projected_gradient_inf: initial_pg,
            converged,
        }
    }

    /// Solve (H_FF + damping * diag(H_FF) + tiny I) d = -g_F into `self.reduced` by a
    /// sequential dense Cholesky (faer; systems here are at most a few hundred rows,
    /// where threads cost more than they save).
    fn solve_reduced(&mut self, m: usize) -> bool {
        let n = self.h.nrows();
        self.system.clear();
        let mut max_diag: f64 = 0.0;
        if m == n {
            // nothing held at a bound: the whole (column-major) Hessian
            self.system.extend_from_slice(self.h.as_slice());
        } else {
            let h = self.h.as_slice();
            for &j in &self.free {
                let col = &h[j * n..(j + 1) * n];
                self.system.extend(self.free.iter().map(|&i| col[i]));
            }
        }
        for k in 0..m {
            max_diag = max_diag.max(self.system[k * m + k].abs());
        }
        let floor = 1e-14 * max_diag.max(1e-300);
        for k in 0..m {
            let d = self.system[k * m + k];
            self.system[k * m + k] = d + self.damping * d.abs().max(floor) + floor;
        }
        self.reduced.clear();
        self.reduced.extend(self.free.iter().map(|&i| -self.g[i]));
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
        if llt::factor::cholesky_in_place(
            a,
            Default::default(),
            Par::Seq,
            stack,
            Default::default(),
        )
        .is_err()
        {
            return false;
        }
        // L L^T d = rhs by forward and back substitution on the column-major factor
        // (contiguous column sweeps; one right-hand side)
        let l = &self.system;
        let d = &mut self.reduced;
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
            let dot: f64 = d[j + 1..]
                .iter()
                .zip(&col[j + 1..])
                .map(|(x, y)| x * y)
                .sum();
            d[j] = (d[j] - dot) / col[j];
        }
        self.reduced.iter().all(|v| v.is_finite())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Rosenbrock as least squares r = (10 (y - x^2), 1 - x): GN Hessian J^T J.
    struct Rosen;
    impl BoxProblem for Rosen {
        fn dimension(&self) -> usize {
            2
        }
        fn evaluate(
            &mut self,
            x: &[f64],
            g: Option<&mut [f64]>,
            h: Option<&mut DMatrix<f64>>,
        ) -> f64 {
            let r = [10.0 * (x[1] - x[0] * x[0]), 1.0 - x[0]];
            let j = [[-20.0 * x[0], 10.0], [-1.0, 0.0]];
            if let Some(g) = g {
                for i in 0..2 {
                    g[i] = r[0] * j[0][i] + r[1] * j[1][i];
                }
            }
            if let Some(h) = h {
                *h = DMatrix::from_fn(2, 2, |a, b| j[0][a] * j[0][b] + j[1][a] * j[1][b]);
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
        };
        let r = ProjectedNewton::new().minimize(&mut Rosen, &mut x, &[-10.0; 2], &[10.0; 2], &opts);
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
        };
        let r = ProjectedNewton::new().minimize(
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
}
