//! Pairs across the chain in the chain solver (docs/contact_barrier.md): a contact pair
//! between elements e1 and e2 of one ribbon adds B'' g g^T to the Newton matrix, with
//! g = P_{e1}^T u1 + P_{e2}^T u2 (P_e the map from the unknowns to y_e = (V_e, c_e,
//! c_{e+1})). With m pairs, H = M + G D G^T, M the chain's own matrix (with its loop
//! closure and damping shift) that the sweep factorizes. Woodbury's identity with the
//! scaled columns U = G D^{1/2}:
//!
//!     H^{-1} b = x0 - Y K^{-1} U^T x0,   x0 = M^{-1} b,  Y = M^{-1} U,
//!     K = I + U^T Y   (m x m, symmetric positive definite when M is),
//!
//! factorized once per Newton matrix (m chain solves, m forward sweeps, a dense
//! Cholesky of K) and applied per solve (one chain solve, one sweep, O(n m)). K's
//! eigenvalues are at least 1, so its Cholesky cannot fail where M's did not: H is
//! positive definite exactly when M is. A stiff pair makes K ill-conditioned (up to
//! B'' |g|^2 / |M|), which a direct factorization takes and conjugate gradients did not
//! (tried first: on the falling ribbon at n = 600, 500 pairs at gaps of 4 µm, CG on K
//! stalled short of a descent direction, 2026-12-07). No dense n x n matrix: G^T v is
//! one forward sweep of the twists V_e of v read at the pairs' elements, G w one
//! adjoint sweep of the pairs' wrenches.

use nalgebra::SVector;

use super::ChainModel;
use crate::ribbon::objective::contact_terms::PairTerm;
use crate::ribbon::objective::{Objective, Vec8, Workspace};

type Vec6 = SVector<f64, 6>;

/// The pairs' Woodbury factors and buffers (no allocation once warm at a given m).
#[derive(Clone, Debug, Default)]
pub(super) struct PairScratch {
    /// Per element: the twist V_e and c_e of a step (forward sweep).
    twist: Vec<(Vec6, f64)>,
    /// Per element: the pairs' summed wrenches (adjoint sweep).
    wrench: Vec<Vec8>,
    /// D^{1/2} per pair.
    sqrt_d: Vec<f64>,
    /// Y = M^{-1} U, column-major (m columns of the unknowns' length).
    y: Vec<f64>,
    /// K, then its Cholesky factor (lower, column-major m x m).
    k: Vec<f64>,
    unit: Vec<f64>,
    gy: Vec<f64>,
    column: Vec<f64>,
    x0: Vec<f64>,
    t: Vec<f64>,
}

impl ChainModel {
    /// G^T v: per pair, u1 . y_{e1} + u2 . y_{e2} for the step v (held entries 0).
    fn pairs_forward(&self, twist: &mut Vec<(Vec6, f64)>, v: &[f64], out: &mut [f64]) {
        let n = self.segments;
        twist.clear();
        let mut tw = Vec6::zeros();
        if self.floating {
            tw = self.base_twists * Vec6::from_column_slice(&v[..6]);
        }
        let mut c = 0.0;
        twist.push((tw, 0.0));
        for k in 1..n {
            c += v[self.c_index(k)];
            tw += self.xi_c[k] * c + self.xi_psi[k] * v[self.psi_index(k)];
            twist.push((tw, c));
        }
        let y = |e: usize| -> Vec8 {
            let (tw, c_e) = twist[e];
            let c_next = if e + 1 < n { twist[e + 1].1 } else { 0.0 };
            let mut y = Vec8::zeros();
            y.fixed_rows_mut::<6>(0).copy_from(&tw);
            y[6] = c_e;
            y[7] = c_next;
            y
        };
        for (o, p) in out.iter_mut().zip(&self.pairs) {
            *o = p.u1.dot(&y(p.e1 as usize)) + p.u2.dot(&y(p.e2 as usize));
        }
    }

    /// G w: the gradient over the unknowns of Σ_p w_p (u1 . y_{e1} + u2 . y_{e2}), by
    /// suffix sums of the pairs' wrenches (every entry, held ones too).
    fn pairs_adjoint(&self, wrench: &mut Vec<Vec8>, w: &[f64], out: &mut [f64]) {
        let n = self.segments;
        wrench.clear();
        wrench.resize(n, Vec8::zeros());
        for (p, &wp) in self.pairs.iter().zip(w) {
            wrench[p.e1 as usize] += p.u1 * wp;
            wrench[p.e2 as usize] += p.u2 * wp;
        }
        out.iter_mut().for_each(|o| *o = 0.0);
        let mut suffix = Vec6::zeros();
        // ∂/∂c_k: the twist of c_k moves elements k.., and c_k is the local c of
        // elements k (column 6) and k-1 (column 7); z_k moves every c_j, j >= k
        let mut dz = 0.0;
        for k in (1..n).rev() {
            suffix += wrench[k].fixed_rows::<6>(0);
            dz += self.xi_c[k].dot(&suffix) + wrench[k][6] + wrench[k - 1][7];
            out[self.c_index(k)] = dz;
            out[self.psi_index(k)] = self.xi_psi[k].dot(&suffix);
        }
        if self.floating {
            suffix += wrench[0].fixed_rows::<6>(0);
            let base = self.base_twists.transpose() * suffix;
            out[..6].copy_from_slice(base.as_slice());
        }
    }

    /// `out` += G D G^T v: the pairs' part of the product H v
    /// ([`ChainModel::multiply`], the trust region's model).
    pub(super) fn add_pairs_product(&mut self, v: &[f64], out: &mut [f64]) {
        if self.pairs.is_empty() {
            return;
        }
        let mut ps = std::mem::take(&mut self.pair_scratch);
        ps.t.clear();
        ps.t.resize(self.pairs.len(), 0.0);
        self.pairs_forward(&mut ps.twist, v, &mut ps.t);
        for (t, p) in ps.t.iter_mut().zip(&self.pairs) {
            *t *= p.weight.max(0.0);
        }
        ps.column.clear();
        ps.column.resize(v.len(), 0.0);
        self.pairs_adjoint(&mut ps.wrench, &ps.t, &mut ps.column);
        for (o, c) in out.iter_mut().zip(&ps.column) {
            *o += c;
        }
        self.pair_scratch = ps;
    }

    /// The Woodbury factors of the pairs on top of the chain just factorized (true
    /// without pairs). False where a chain solve fails.
    pub(super) fn factor_pairs(&mut self) -> bool {
        if self.pairs.is_empty() {
            return true;
        }
        let mut ps = std::mem::take(&mut self.pair_scratch);
        let ok = self.woodbury_factor(&mut ps);
        self.pair_scratch = ps;
        ok
    }

    fn woodbury_factor(&mut self, ps: &mut PairScratch) -> bool {
        let (nq, m) = (self.dimension(), self.pairs.len());
        ps.sqrt_d.clear();
        ps.sqrt_d
            .extend(self.pairs.iter().map(|p| p.weight.max(0.0).sqrt()));
        ps.y.clear();
        ps.y.resize(nq * m, 0.0);
        ps.unit.clear();
        ps.unit.resize(m, 0.0);
        ps.column.clear();
        ps.column.resize(nq, 0.0);
        ps.gy.clear();
        ps.gy.resize(m, 0.0);
        ps.k.clear();
        ps.k.resize(m * m, 0.0);
        for j in 0..m {
            // column j of U = G D^{1/2} e_j, then Y_j = M^{-1} U_j
            ps.unit[j] = ps.sqrt_d[j];
            self.pairs_adjoint(&mut ps.wrench, &ps.unit, &mut ps.column);
            for (c, &f) in ps.column.iter_mut().zip(&self.free) {
                if !f {
                    *c = 0.0;
                }
            }
            ps.unit[j] = 0.0;
            if !self.solve_chain_only(&ps.column, &mut ps.y[j * nq..(j + 1) * nq]) {
                return false;
            }
            // column j of U^T Y = D^{1/2} G^T Y_j
            self.pairs_forward(&mut ps.twist, &ps.y[j * nq..(j + 1) * nq], &mut ps.gy);
            for i in 0..m {
                ps.k[j * m + i] = ps.sqrt_d[i] * ps.gy[i] + if i == j { 1.0 } else { 0.0 };
            }
        }
        cholesky_in_place(&mut ps.k, m)
    }

    /// Solve (M + G D G^T) x = rhs with the factors of [`Self::factor_pairs`].
    pub(super) fn solve_with_pairs(&mut self, rhs: &[f64], out: &mut [f64]) -> bool {
        let mut ps = std::mem::take(&mut self.pair_scratch);
        let ok = self.woodbury_solve(&mut ps, rhs, out);
        self.pair_scratch = ps;
        ok
    }

    fn woodbury_solve(&mut self, ps: &mut PairScratch, rhs: &[f64], out: &mut [f64]) -> bool {
        let (nq, m) = (self.dimension(), self.pairs.len());
        ps.x0.clear();
        ps.x0.resize(nq, 0.0);
        ps.t.clear();
        ps.t.resize(m, 0.0);
        if !self.solve_chain_only(rhs, &mut ps.x0) {
            return false;
        }
        if ps.k.len() != m * m {
            return false;
        }
        self.pairs_forward(&mut ps.twist, &ps.x0, &mut ps.t);
        for (t, d) in ps.t.iter_mut().zip(&ps.sqrt_d) {
            *t *= d;
        }
        cholesky_solve(&ps.k, m, &mut ps.t);
        out.copy_from_slice(&ps.x0);
        for (j, s) in ps.t.iter().enumerate() {
            for (o, y) in out.iter_mut().zip(&ps.y[j * nq..(j + 1) * nq]) {
                *o -= y * s;
            }
        }
        out.iter().all(|v| v.is_finite())
    }
}

/// The lower Cholesky factor of the symmetric m x m matrix `a` (column-major; its upper
/// triangle read as the lower one's mirror) in place; false if it is not positive
/// definite.
fn cholesky_in_place(a: &mut [f64], m: usize) -> bool {
    for j in 0..m {
        let mut d = a[j * m + j];
        for k in 0..j {
            d -= a[k * m + j] * a[k * m + j];
        }
        if !(d > 0.0 && d.is_finite()) {
            return false;
        }
        let d = d.sqrt();
        a[j * m + j] = d;
        for i in j + 1..m {
            // symmetric input: entry (i, j) is taken from the upper triangle (j, i)
            let mut v = 0.5 * (a[j * m + i] + a[i * m + j]);
            for k in 0..j {
                v -= a[k * m + i] * a[k * m + j];
            }
            a[j * m + i] = v / d;
        }
    }
    true
}

/// Solve L L^T x = b in place with the factor of [`cholesky_in_place`].
fn cholesky_solve(l: &[f64], m: usize, b: &mut [f64]) {
    for j in 0..m {
        b[j] /= l[j * m + j];
        let bj = b[j];
        for i in j + 1..m {
            b[i] -= l[j * m + i] * bj;
        }
    }
    for j in (0..m).rev() {
        let mut v = b[j];
        for i in j + 1..m {
            v -= l[j * m + i] * b[i];
        }
        b[j] = v / l[j * m + j];
    }
}

/// The pairs of the last evaluation into the chain model, merged per pair of elements:
/// the pairs between elements e1 < e2 sum to one 16 x 16 positive semidefinite matrix
/// over (y_{e1}, y_{e2}) whose rank (its eigenvalues above 1e-12 of the largest) is
/// what the Woodbury step needs, usually far fewer columns than pairs (a vertex-
/// triangle and the edge-edge pairs around it push along one normal).
pub(super) fn merge_pairs(from: &[PairTerm], order: &mut Vec<u32>, to: &mut Vec<PairTerm>) {
    to.clear();
    order.clear();
    order.extend(0..from.len() as u32);
    let key = |p: &PairTerm| (p.e1.min(p.e2), p.e1.max(p.e2));
    order.sort_unstable_by_key(|&i| (key(&from[i as usize]), i));
    let mut start = 0;
    while start < order.len() {
        let k = key(&from[order[start] as usize]);
        let mut end = start;
        let mut w = nalgebra::SMatrix::<f64, 16, 16>::zeros();
        while end < order.len() && key(&from[order[end] as usize]) == k {
            let p = &from[order[end] as usize];
            let (a, b) = if p.e1 == k.0 {
                (&p.u1, &p.u2)
            } else {
                (&p.u2, &p.u1)
            };
            let mut u = nalgebra::SVector::<f64, 16>::zeros();
            u.fixed_rows_mut::<8>(0).copy_from(a);
            u.fixed_rows_mut::<8>(8).copy_from(b);
            w += u * u.transpose() * p.weight.max(0.0);
            end += 1;
        }
        let eigen = nalgebra::SymmetricEigen::new(w);
        let top = eigen.eigenvalues.max();
        for (i, &l) in eigen.eigenvalues.iter().enumerate() {
            if l > 1e-12 * top && l > 0.0 {
                let v = eigen.eigenvectors.column(i);
                to.push(PairTerm {
                    e1: k.0,
                    e2: k.1,
                    u1: v.fixed_rows::<8>(0).into_owned(),
                    u2: v.fixed_rows::<8>(8).into_owned(),
                    weight: l,
                });
            }
        }
        start = end;
    }
}

impl Objective<'_> {
    /// The pairs' B'' g g^T added to the dense Newton matrix `h` (q-coordinates, the
    /// baseline solver's): g_a = ξ_a . u[twist] for every coordinate moving the pair's
    /// element, plus u's local columns at c_e and c_{e+1}. O(N^2) per pair.
    pub(in crate::ribbon::objective) fn add_dense_pairs(
        &self,
        ws: &mut Workspace,
        h: &mut nalgebra::DMatrix<f64>,
    ) {
        let lay = self.layout;
        let (n, nq) = (self.strip.segments, lay.len());
        let mut g = std::mem::take(&mut ws.contact.dense_g);
        for p in &ws.contact.pairs {
            g.clear();
            g.resize(nq, 0.0);
            for (e, u) in [(p.e1 as usize, &p.u1), (p.e2 as usize, &p.u2)] {
                let wrench: Vec6 = u.fixed_rows::<6>(0).into_owned();
                for (a, xi) in ws.twists.iter().enumerate() {
                    if lay.first_element(a) <= e {
                        g[a] += Vec6::from(xi.to_array()).dot(&wrench);
                    }
                }
                if e >= 1 {
                    g[lay.c(e)] += u[6];
                }
                if e + 1 < n {
                    g[lay.c(e + 1)] += u[7];
                }
            }
            for j in 0..nq {
                if g[j] == 0.0 {
                    continue;
                }
                let gj = g[j] * p.weight;
                for i in 0..nq {
                    h[(i, j)] += g[i] * gj;
                }
            }
        }
        ws.contact.dense_g = g;
    }
}
