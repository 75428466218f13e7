//! A loop closure as a well-conditioned update of a softer chain (docs/ribbon_chain_solver.md,
//! "Loop closures"). The closure's term mu/2 |a d - b d|^2 (a = J_last P_{n-1}, the nine
//! closure rows through element n-1; b = J_first G E^T, through element 0 and the root
//! unknowns) is split as H = H_rho + U S U^T with H_rho the chain carrying only rho of
//! the closure's two diagonal blocks (rho (a^T a + b^T b)):
//!
//! - rho = 0: H_open + mu J^T J with J = a - b, a positive rank-9 update, K_1 = I / mu +
//!   J H_open^{-1} J^T >= I / mu (Cholesky);
//! - 0 < rho < mu: with P = a + b (a^T a + b^T b = (J^T J + P^T P) / 2),
//!   H = H_1 - (rho / 2) P^T P, H_1 = H_rho + (mu - rho / 2) J^T J: H_1 by K_1 as above,
//!   then H by K_2 = (2 / rho) I - P H_1^{-1} P^T, positive definite exactly when H is
//!   (Haynsworth's inertia additivity, H_1 being positive definite): two 9 x 9 Cholesky
//!   factors ([`closure_correction`]).
//!
//! Why: the 14-column form (`factor_closure`, rho = mu in effect) keeps mu a^T a and mu
//! b^T b in the chain, stiff (mu = 1e3 and up) where the two ends move together and H is
//! not; its capacitance spanned 2e3 down to 1e-7 in magnitude and the solve's residual
//! |H x - b| was 10 to 100 times |b| on the chains' links (2026-12-07): the damped Newton
//! method took such steps for Newton steps and crawled. A Moebius link's open chain is
//! not positive definite (the closure holds it), hence the smallest rho that makes the
//! chain so, tried in decades up to 1e-2 mu; the 14-column form stays as the last resort.
//!
//! Cost: both forms write U = V D with V = [P_{n-1}^T, E] (the 7 unit loads on element
//! n-1's (V_{n-1}, c_{n-1}) and the 7 root unknowns), so a factorization is the sweep, 14
//! chain solves for Z = H_rho^{-1} V and small dense products with the 14 x 14 V^T Z;
//! a solve is one chain solve and 14 updates of length n.

use nalgebra::{Cholesky, SMatrix};

use super::{product, ChainModel, Mat14, Mat8x7, Vec14, Vec6, Vec7, ROOT};

type Mat9 = SMatrix<f64, 9, 9>;
type Mat14x9 = SMatrix<f64, 14, 9>;

/// rho / mu tried in turn. Not 1e-1: there K_2 = (2 / rho) I - P H_1^{-1} P^T loses
/// digits to cancellation (H_rho is stiff along P by rho), and mobius_band's closure
/// violation rose from 2e-8 to 9e-7 m with more Newton iterations (1 504 against the
/// dense solver's 1 006 over 1 s; 1 024 without it), 2026-12-07.
const RHO: [f64; 3] = [0.0, 1e-3, 1e-2];

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

    /// After a successful sweep of H_rho: Z = H_rho^{-1} V and the correction A of
    /// [`closure_correction`]; false where H is not positive definite.
    ///
    /// V = [P_{n-1}^T, E] (14 columns: the unit loads on element n-1's (V_{n-1},
    /// c_{n-1}) and the root unknowns, zero on held unknowns); the closure's rows are
    /// combinations of them, so the capacitances need only the 14 x 14 compliance
    /// V^T Z, whose element-n-1 rows are the forward sweep's end states: 14 chain
    /// solves and no product over the unknowns.
    fn closure_capacitance(
        &mut self,
        rows: &crate::ribbon::objective::ClosureRows,
        mu: f64,
        rho: f64,
    ) -> bool {
        let nq = self.dimension();
        let mut z = std::mem::take(&mut self.closure_z);
        z.clear();
        z.resize(14 * nq, 0.0);
        let mut rhs = std::mem::take(&mut self.scratch_rhs);
        rhs.clear();
        rhs.resize(14 * nq, 0.0);
        for j in 0..14 {
            let column = &mut rhs[j * nq..(j + 1) * nq];
            if j < 7 {
                let pv = Vec6::from_fn(|r, _| if r == j { 1.0 } else { 0.0 });
                self.last_element_adjoint(&pv, if j == 6 { 1.0 } else { 0.0 }, column);
            } else if let Some(r) = self.root_index(j - 7) {
                column[r] = 1.0;
            }
            for (v, &f) in column.iter_mut().zip(&self.free) {
                if !f {
                    *v = 0.0;
                }
            }
        }
        let mut ends = [Vec7::zeros(); 14];
        let ok = self.solve_chain_columns(&rhs, &mut z, &mut ends);
        let mut compliance = Mat14::zeros();
        for (j, end) in ends.iter().enumerate() {
            let column = &z[j * nq..(j + 1) * nq];
            for i in 0..7 {
                compliance[(i, j)] = end[i];
                compliance[(7 + i, j)] = self.root_index(i).map_or(0.0, |r| column[r]);
            }
        }
        self.scratch_rhs = rhs;
        self.closure_z = z;
        if !ok {
            return false;
        }
        let compliance = (compliance + compliance.transpose()) * 0.5;
        self.closure_k = closure_correction(rows, &self.root_map(), &compliance, mu, rho);
        self.closure_k.is_some()
    }

    /// x = x0 - Z A V^T x0, x0 = H_rho^{-1} rhs (V^T x0: the forward
    /// sweep's end state and x0 on the root unknowns).
    pub(super) fn solve_open_closure(&mut self, rhs: &[f64], out: &mut [f64]) -> bool {
        let (solved, end) = self.solve_chain_to_end(rhs, out);
        if !solved {
            return false;
        }
        let Some(correction) = self.closure_k.as_ref() else {
            return false;
        };
        let mut t = Vec14::zeros();
        for i in 0..7 {
            t[i] = end[i];
            t[7 + i] = self.root_index(i).map_or(0.0, |r| out[r]);
        }
        let w = correction * t;
        let nq = self.dimension();
        for (j, wj) in w.iter().enumerate() {
            let zj = &self.closure_z[j * nq..(j + 1) * nq];
            for (o, z) in out.iter_mut().zip(zj) {
                *o -= z * wj;
            }
        }
        out.iter().all(|v| v.is_finite())
    }
}

/// The correction A of H^{-1} = H_rho^{-1} - Z A V^T (so that a solve is
/// x = x0 - Z A V^T x0), from the 14 x 14 compliance C = V^T Z; None where H is not
/// positive definite (H_rho being so).
///
/// With J = a - b and P = a + b (the closure's rows; a^T a + b^T b = (J^T J + P^T P) / 2)
/// H = H_1 - (rho / 2) P^T P, H_1 = H_rho + (mu - rho / 2) J^T J: first H_1 by K_1 =
/// I / (mu - rho / 2) + J H_rho^{-1} J^T (positive definite: a Cholesky factor), then,
/// for rho > 0, H by K_2 = (2 / rho) I - P H_1^{-1} P^T, positive definite exactly when
/// H is (Woodbury's determinant identity with H_1 positive definite). In the
/// 14-column terms J = D_J^T V^T and P = D_P^T V^T.
fn closure_correction(
    rows: &crate::ribbon::objective::ClosureRows,
    root_map: &Mat8x7,
    compliance: &Mat14,
    mu: f64,
    rho: f64,
) -> Option<Mat14> {
    let first_g = rows.first * root_map;
    let (mut d_j, mut d_p) = (Mat14x9::zeros(), Mat14x9::zeros());
    for i in 0..9 {
        for r in 0..7 {
            d_j[(r, i)] = rows.last[(i, r)];
            d_p[(r, i)] = rows.last[(i, r)];
            d_j[(7 + r, i)] = -first_g[(i, r)];
            d_p[(7 + r, i)] = first_g[(i, r)];
        }
    }
    let gamma = mu - 0.5 * rho;
    let k1 = Mat9::identity() / gamma + d_j.transpose() * compliance * d_j;
    let k1_inverse = Cholesky::new((k1 + k1.transpose()) * 0.5)?.inverse();
    // H_1^{-1} = H_rho^{-1} - Z A_1 V^T
    let a1 = d_j * k1_inverse * d_j.transpose();
    if rho == 0.0 {
        return Some(a1);
    }
    // H_1^{-1} P^T = Z E_P, E_P = (I - A_1 C) D_P
    let e_p = (Mat14::identity() - a1 * compliance) * d_p;
    let k2 = Mat9::identity() * (2.0 / rho) - d_p.transpose() * compliance * e_p;
    let k2_inverse = Cholesky::new((k2 + k2.transpose()) * 0.5)?.inverse();
    // H^{-1} = H_1^{-1} + H_1^{-1} P^T K_2^{-1} P H_1^{-1}, P H_1^{-1} = E_P^T V^T
    Some(a1 - e_p * k2_inverse * e_p.transpose())
}

/// The 14-column form and the pieces both forms share.
impl ChainModel {
    /// Root unknown j (0..6 the floating base, 6 z_1) as an index of the unknowns.
    pub(super) fn root_index(&self, j: usize) -> Option<usize> {
        match j {
            6 => Some(self.c_index(1)),
            _ if self.floating => Some(j),
            _ => None,
        }
    }

    /// The loop closure's coupling y_{n-1}^T B y_0 as a low-rank matrix. Element 0
    /// moves only with the root unknowns r: y_0 = G r, G = [[Ξ_base, 0], [0, 0],
    /// [0, 1]] (8 x ROOT). So the coupling's matrix is C = A E^T + E A^T, with E the
    /// columns of the unit vectors of r and A = P_{n-1}^T B G, P_{n-1} the map from
    /// the unknowns to y_{n-1} = (V_{n-1}, c_{n-1}, c_n = 0). Column j of A is the
    /// gradient of the linear function (B G)_j . y_{n-1}, by the adjoint sweep of
    /// [`Self::solve_chain`]: O(n) per column.
    pub(super) fn closure_columns(&mut self) {
        let Some(b) = self.closure else { return };
        let nq = self.dimension();
        let bg = b * self.root_map();
        let mut a = std::mem::take(&mut self.closure_a);
        a.clear();
        a.resize(ROOT * nq, 0.0);
        for j in 0..ROOT {
            let pv: Vec6 = bg.fixed_view::<6, 1>(0, j).into_owned();
            self.last_element_adjoint(&pv, bg[(6, j)], &mut a[j * nq..(j + 1) * nq]);
        }
        self.closure_a = a;
    }

    /// G: element 0's y_0 = (V_0, c_0 = 0, c_1 = z_1) = G r from the root unknowns r
    /// (8 x ROOT; the base columns are zero for a fixed base).
    pub(super) fn root_map(&self) -> Mat8x7 {
        let mut g = Mat8x7::zeros();
        for j in 0..6 {
            g.fixed_view_mut::<6, 1>(0, j)
                .copy_from(&self.base_twists.column(j));
        }
        g[(7, 6)] = 1.0;
        g
    }

    /// P_{n-1}^T w into `col` (every unknown's entry written): the gradient of the
    /// linear function w . y_{n-1} = pv . V_{n-1} + pc c_{n-1} (c_n = 0 is no unknown),
    /// by the adjoint sweep of [`Self::solve_chain`], O(n).
    pub(super) fn last_element_adjoint(&self, pv: &Vec6, pc: f64, col: &mut [f64]) {
        let n = self.segments;
        let base = if self.floating { 6 } else { 0 };
        let mut pc = pc;
        for k in (1..n).rev() {
            let (xc, xp) = (&self.xi_c[k], &self.xi_psi[k]);
            let (c, psi) = (base + k - 1, base + n - 1 + k - 1);
            col[psi] = xp.dot(pv);
            pc += xc.dot(pv);
            col[c] = pc;
        }
        if self.floating {
            let wrench = self.base_twists.transpose() * pv;
            col[..6].copy_from_slice(wrench.as_slice());
        }
    }

    /// The loop closure's part of [`Self::factor`] after the chain's sweep: Woodbury's
    /// capacitance on the free unknowns `free` and its inertia.
    pub(super) fn factor_closure(&mut self, free: &[bool]) -> bool {
        self.capacitance = None;
        if self.closure.is_none() {
            return true;
        }
        if !self.diagonal_ready {
            self.cached_diagonal();
        }
        let nq = self.dimension();
        self.closure_u.clear();
        self.closure_u.resize(2 * ROOT * nq, 0.0);
        for j in 0..ROOT {
            let (u, a) = (
                &mut self.closure_u[j * nq..(j + 1) * nq],
                &self.closure_a[j * nq..(j + 1) * nq],
            );
            for ((u, a), &f) in u.iter_mut().zip(a).zip(free) {
                if f {
                    *u = *a;
                }
            }
            if let Some(r) = self.root_index(j).filter(|&r| free[r]) {
                self.closure_u[(ROOT + j) * nq + r] = 1.0;
            }
        }
        let mut y = std::mem::take(&mut self.closure_y);
        y.clear();
        y.resize(2 * ROOT * nq, 0.0);
        for j in 0..2 * ROOT {
            let column = &self.closure_u[j * nq..(j + 1) * nq];
            let mut rhs = std::mem::take(&mut self.scratch_rhs);
            rhs.clear();
            rhs.extend_from_slice(column);
            let ok = self.solve_chain(&rhs, &mut y[j * nq..(j + 1) * nq]);
            self.scratch_rhs = rhs;
            if !ok {
                self.closure_y = y;
                return false;
            }
        }
        let mut k = Mat14::zeros();
        for i in 0..ROOT {
            k[(i, ROOT + i)] = 1.0;
            k[(ROOT + i, i)] = 1.0;
        }
        for i in 0..2 * ROOT {
            let ui = &self.closure_u[i * nq..(i + 1) * nq];
            for j in 0..2 * ROOT {
                let yj = &y[j * nq..(j + 1) * nq];
                k[(i, j)] += ui.iter().zip(yj).map(|(a, b)| a * b).sum::<f64>();
            }
        }
        self.closure_y = y;
        let k = (k + k.transpose()) * 0.5;
        let eigen = nalgebra::SymmetricEigen::new(k);
        let scale = eigen.eigenvalues.amax();
        // an eigenvalue is told from zero down to the eigensolver's backward error,
        // a few eps |K|: a fixed 1e-13 |K| called eigenvalues of -1.9e-9 (|K| 2e4, 500x
        // that error) zero on the Moebius chain's links, rejected a positive definite H
        // and escalated the damping where the dense Cholesky did not (24 of 40 steps
        // unconverged against none, 2026-12-02)
        let tiny = 32.0 * f64::EPSILON * scale.max(1.0);
        let positive = eigen.eigenvalues.iter().filter(|&&l| l > tiny).count();
        let negative = eigen.eigenvalues.iter().filter(|&&l| l < -tiny).count();
        if positive != ROOT || negative != ROOT || !scale.is_finite() {
            self.failure = product::Failure::Closure;
            return false;
        }
        self.capacitance = Some(eigen);
        true
    }

    /// The chain's solve with its loop closure (no contact pairs). With a loop
    /// closure, Woodbury: x = x0 - Y K^{-1} U^T x0, x0 = H0^{-1} rhs.
    pub(super) fn solve_chain_only(&mut self, rhs: &[f64], out: &mut [f64]) -> bool {
        if self.closure_k.is_some() {
            return self.solve_open_closure(rhs, out);
        }
        if !self.solve_chain(rhs, out) {
            return false;
        }
        let Some(eigen) = self.capacitance.as_ref() else {
            return self.closure.is_none();
        };
        let nq = self.dimension();
        let mut t = Vec14::zeros();
        for (i, ti) in t.iter_mut().enumerate() {
            let ui = &self.closure_u[i * nq..(i + 1) * nq];
            *ti = ui.iter().zip(out.iter()).map(|(a, b)| a * b).sum();
        }
        // K^{-1} t = Q Λ^{-1} Q^T t
        let mut s = eigen.eigenvectors.transpose() * t;
        for (si, l) in s.iter_mut().zip(eigen.eigenvalues.iter()) {
            *si /= l;
        }
        let s = eigen.eigenvectors * s;
        for (j, sj) in s.iter().enumerate() {
            let yj = &self.closure_y[j * nq..(j + 1) * nq];
            for (o, y) in out.iter_mut().zip(yj) {
                *o -= y * sj;
            }
        }
        out.iter().all(|v| v.is_finite())
    }
}
