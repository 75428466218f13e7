//! A loop closure as a well-conditioned update of a softer chain (docs/ribbon_chain_solver.md,
//! "Loop closures"). The closure's term mu/2 |a d - b d|^2 (a = J_last P_{n-1}, the nine
//! closure rows through element n-1; b = J_first G E^T, through element 0 and the root
//! unknowns) is split as H = H_rho + U S U^T with H_rho the chain carrying only rho of
//! the closure's two diagonal blocks (rho (a^T a + b^T b)):
//!
//! - rho = 0: H_open + mu (a - b)^T (a - b), a positive rank-9 update, K = I / mu + J
//!   H_open^{-1} J^T >= I / mu (Cholesky);
//! - 0 < rho < mu: U = [a^T, b^T], S = [[(mu - rho) I, -mu I], [-mu I, (mu - rho) I]]
//!   (eigenvalues -rho and 2 mu - rho), K = S^{-1} + U^T H_rho^{-1} U; by Haynsworth's
//!   inertia additivity H is positive definite (H_rho being so) exactly when K has 9
//!   positive and 9 negative eigenvalues, as S^{-1} has.
//!
//! Why: the 14-column form (`factor_closure`, rho = mu in effect) keeps mu a^T a and mu
//! b^T b in the chain, stiff (mu = 1e3 and up) where the two ends move together and H is
//! not; its capacitance spanned 2e3 down to 1e-7 in magnitude and the solve's residual
//! |H x - b| was 10 to 100 times |b| on the chains' links (2026-12-07): the damped Newton
//! method took such steps for Newton steps and crawled. A Moebius link's open chain is
//! not positive definite (the closure holds it), hence the smallest rho that makes the
//! chain so, tried in decades; the 14-column form stays as the last resort.

use nalgebra::{Cholesky, SMatrix, SVector};

use super::{ChainModel, Vec6, ROOT};

type Mat9 = SMatrix<f64, 9, 9>;
type Mat18 = SMatrix<f64, 18, 18>;

/// rho / mu tried in turn.
const RHO: [f64; 4] = [0.0, 1e-3, 1e-2, 1e-1];

impl ChainModel {
    /// Factorize H + diag(shift) on `free` with the closure split as above, the first
    /// rho of [`RHO`] that works. False where there is no closure with rows, in the
    /// holding factorization of the trust region, or where no rho works (the caller
    /// then tries the 14-column form).
    pub(super) fn factor_open_closure(&mut self, free: &[bool], shift: &[f64]) -> bool {
        self.closure_k = None;
        let Some(rows) = self.closure_rows else {
            return false;
        };
        let mu = rows.penalty;
        if self.hold_failing || !(mu > 0.0 && mu.is_finite()) {
            return false;
        }
        let n = self.segments;
        let (last, first) = (self.blocks[n - 1], self.blocks[0]);
        let (block_a, block_b) = (
            rows.last.transpose() * rows.last,
            rows.first.transpose() * rows.first,
        );
        for rho in RHO.map(|r| r * mu) {
            self.blocks[n - 1] -= block_a * (mu - rho);
            self.blocks[0] -= block_b * (mu - rho);
            let ok = self.factor_chain(free, shift);
            // (copies, not additions back: the model's matrix stays bit for bit)
            self.blocks[0] = first;
            self.blocks[n - 1] = last;
            if ok && self.closure_capacitance(&rows, mu, rho) {
                return true;
            }
        }
        self.closure_k = None;
        false
    }

    /// The rows of U (9 for rho = 0, else 18) on the free unknowns, Y = H_rho^{-1} U and
    /// K^{-1} after a successful sweep of H_rho; false where K is not as it must be.
    fn closure_capacitance(
        &mut self,
        rows: &crate::ribbon::objective::ClosureRows,
        mu: f64,
        rho: f64,
    ) -> bool {
        let count = if rho == 0.0 { 9 } else { 18 };
        self.closure_rows_on_free(rows, count);
        let nq = self.dimension();
        let mut y = std::mem::take(&mut self.closure_jy);
        y.clear();
        y.resize(count * nq, 0.0);
        let mut rhs = std::mem::take(&mut self.scratch_rhs);
        let mut ok = true;
        for i in 0..count {
            rhs.clear();
            rhs.extend_from_slice(&self.closure_j[i * nq..(i + 1) * nq]);
            if !self.solve_chain(&rhs, &mut y[i * nq..(i + 1) * nq]) {
                ok = false;
                break;
            }
        }
        self.scratch_rhs = rhs;
        let mut uy = Mat18::zeros();
        for i in 0..count {
            let ui = &self.closure_j[i * nq..(i + 1) * nq];
            for j in 0..count {
                let yj = &y[j * nq..(j + 1) * nq];
                uy[(i, j)] = ui.iter().zip(yj).map(|(a, b)| a * b).sum::<f64>();
            }
        }
        self.closure_jy = y;
        if !ok {
            return false;
        }
        let uy = (uy + uy.transpose()) * 0.5;
        self.closure_k = if count == 9 {
            let k: Mat9 = Mat9::identity() / mu + uy.fixed_view::<9, 9>(0, 0);
            Cholesky::new(k).map(|c| {
                let mut inverse = Mat18::zeros();
                inverse.fixed_view_mut::<9, 9>(0, 0).copy_from(&c.inverse());
                inverse
            })
        } else {
            split_inverse(mu, rho, &uy)
        };
        self.closure_k.is_some()
    }

    /// U's rows on the unknowns, zero on those the last sweep held: for `count` 9, row i
    /// is a_i - b_i; for 18, the a_i then the b_i (a_i = P_{n-1}^T (row i of J_last),
    /// b_i = E G^T (row i of J_first)).
    fn closure_rows_on_free(&mut self, rows: &crate::ribbon::objective::ClosureRows, count: usize) {
        let nq = self.dimension();
        let first_g = rows.first * self.root_map();
        let mut j = std::mem::take(&mut self.closure_j);
        j.clear();
        j.resize(count * nq, 0.0);
        for i in 0..9 {
            let w = rows.last.row(i);
            let pv = Vec6::from_fn(|r, _| w[r]);
            self.last_element_adjoint(&pv, w[6], &mut j[i * nq..(i + 1) * nq]);
            let (b_row, sign) = if count == 9 { (i, -1.0) } else { (9 + i, 1.0) };
            for c in 0..ROOT {
                if let Some(r) = self.root_index(c) {
                    j[b_row * nq + r] += sign * first_g[(i, c)];
                }
            }
        }
        for row in j.chunks_mut(nq) {
            for (v, &f) in row.iter_mut().zip(&self.free) {
                if !f {
                    *v = 0.0;
                }
            }
        }
        self.closure_j = j;
    }

    /// x = x0 - Y K^{-1} U^T x0, x0 = H_rho^{-1} rhs.
    pub(super) fn solve_open_closure(&mut self, rhs: &[f64], out: &mut [f64]) -> bool {
        if !self.solve_chain(rhs, out) {
            return false;
        }
        let Some(k_inverse) = self.closure_k.as_ref() else {
            return false;
        };
        let nq = self.dimension();
        let count = self.closure_j.len() / nq.max(1);
        let mut t = SVector::<f64, 18>::zeros();
        for (i, ti) in t.iter_mut().enumerate().take(count) {
            let ui = &self.closure_j[i * nq..(i + 1) * nq];
            *ti = ui.iter().zip(out.iter()).map(|(a, b)| a * b).sum::<f64>();
        }
        let s = k_inverse * t;
        for (i, si) in s.iter().enumerate().take(count) {
            let yi = &self.closure_jy[i * nq..(i + 1) * nq];
            for (o, y) in out.iter_mut().zip(yi) {
                *o -= y * si;
            }
        }
        out.iter().all(|v| v.is_finite())
    }
}

/// K^{-1} for 0 < rho < mu: K = S^{-1} + U^T Y with S = [[alpha I, beta I], [beta I,
/// alpha I]] (alpha = mu - rho, beta = -mu), so S^{-1} = [[alpha I, -beta I], [-beta I,
/// alpha I]] / (alpha^2 - beta^2); None unless K has 9 positive and 9 negative
/// eigenvalues (told from zero down to the eigensolver's backward error).
fn split_inverse(mu: f64, rho: f64, uy: &Mat18) -> Option<Mat18> {
    let (alpha, beta) = (mu - rho, -mu);
    let det = alpha * alpha - beta * beta;
    let mut k = *uy;
    for i in 0..9 {
        k[(i, i)] += alpha / det;
        k[(9 + i, 9 + i)] += alpha / det;
        k[(i, 9 + i)] -= beta / det;
        k[(9 + i, i)] -= beta / det;
    }
    let eigen = nalgebra::SymmetricEigen::new(k);
    let scale = eigen.eigenvalues.amax();
    let tiny = 32.0 * f64::EPSILON * scale.max(1.0);
    let positive = eigen.eigenvalues.iter().filter(|&&l| l > tiny).count();
    let negative = eigen.eigenvalues.iter().filter(|&&l| l < -tiny).count();
    if positive != 9 || negative != 9 || !scale.is_finite() {
        return None;
    }
    let inverse_values = eigen.eigenvalues.map(|l| 1.0 / l);
    Some(eigen.eigenvectors * Mat18::from_diagonal(&inverse_values) * eigen.eigenvectors.transpose())
}
