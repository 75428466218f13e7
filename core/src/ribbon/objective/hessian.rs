//! The dense Newton matrix of the objective: the Gauss-Newton part of the least-squares
//! terms from 8x8 per-element blocks and their suffix sums, the geometric stiffness,
//! and the (c, psi) terms, assembled in O(n^2) into an N x N matrix (the dense
//! projected Newton baseline).

use nalgebra::{DMatrix, SMatrix, SVector};

use super::accumulate::SecondOrder;
use super::layout::Layout;
use super::{Mat8, Objective, Vec8, Workspace};
use crate::geometry::{Matrix3, Twist, Vector3};

type Vec6 = SVector<f64, 6>;
type Mat6 = SMatrix<f64, 6, 6>;

#[inline(always)]
fn dot6(a: &[f64; 6], b: &[f64]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3] + a[4] * b[4] + a[5] * b[5]
}

/// Projection of a symmetric 2x2 matrix onto the PSD cone (negative eigenvalues
/// clamped to zero), in closed form.
fn psd_2x2(m: &nalgebra::Matrix2<f64>) -> nalgebra::Matrix2<f64> {
    let (a, b, d) = (m[(0, 0)], m[(0, 1)], m[(1, 1)]);
    let mean = 0.5 * (a + d);
    let radius = (0.25 * (a - d) * (a - d) + b * b).sqrt();
    let (hi, lo) = (mean + radius, mean - radius);
    if lo >= 0.0 {
        return *m;
    }
    if hi <= 0.0 {
        return nalgebra::Matrix2::zeros();
    }
    // eigenvector of `hi`: the larger of the two candidate columns of (M - lo I)
    let v1 = nalgebra::Vector2::new(a - lo, b);
    let v2 = nalgebra::Vector2::new(b, d - lo);
    let v = if v1.norm_squared() >= v2.norm_squared() {
        v1
    } else {
        v2
    };
    let v = v / v.norm();
    v * v.transpose() * hi
}

impl Objective<'_> {
    /// The Hessian (N x N, N = layout.len()) at the q of the last
    /// [`Self::evaluate_recording`] with `second_order`, whose data `ws` still holds.
    pub fn assemble_newton_hessian(&self, ws: &mut Workspace, hm: &mut DMatrix<f64>) {
        assert!(
            ws.second_order_recorded,
            "assemble_newton_hessian needs an evaluation that recorded second-order data"
        );
        let n = self.strip.segments;
        let nq = self.layout.len();
        if hm.nrows() != nq || hm.ncols() != nq {
            *hm = DMatrix::zeros(nq, nq);
        } else {
            // one memset (nalgebra's fill walks the matrix entry by entry)
            hm.as_mut_slice().fill(0.0);
        }
        let t = self.terms;
        for k in 1..n {
            let (ic, ip) = (self.layout.c(k), self.layout.psi(k));
            let clamped =
                self.bending_block(ws.coords.crease_direction[k], ws.coords.bending_angle[k], k);
            hm[(ic, ic)] += clamped[(0, 0)] + 2.0 * t.crease_regularizer;
            // (each unordered pair once: the matrix is symmetrized at the end)
            hm[(ic, ip)] += clamped[(0, 1)];
            hm[(ip, ip)] += clamped[(1, 1)];
        }
        // the end-crease inequality term, where active (see `evaluate_recording`)
        if n >= 2 {
            let c_last = ws.coords.crease_direction[n - 1];
            for (_, shifted) in self.end_crease_shifts(c_last) {
                if shifted < 0.0 {
                    let ic = self.layout.c(n - 1);
                    hm[(ic, ic)] += t.penalty;
                }
            }
        }
        self.assemble_hessian(ws, hm);
        // contact pairs across the chain (rank one each, dense here)
        self.add_dense_pairs(ws, hm);
    }

    /// Hessian of the bending energy k_k (1+c^2) psi^2 of crease k in (c_k, psi_k),
    /// clamped to PSD (it is indefinite for c^2 > 1/3).
    pub(crate) fn bending_block(&self, c: f64, psi: f64, k: usize) -> nalgebra::Matrix2<f64> {
        let bend_k = self.bending_weight(k);
        let s = 1.0 + c * c;
        let block = nalgebra::Matrix2::new(
            2.0 * bend_k * psi * psi,
            4.0 * bend_k * c * psi,
            4.0 * bend_k * c * psi,
            2.0 * bend_k * s,
        );
        psd_2x2(&block)
    }

    /// Hessian of the objective: the Gauss-Newton part P^T (blockdiag G_e + cross
    /// blocks) P plus the geometric stiffness Σ_p γ_p · ∂²p/∂q_a∂q_b.
    ///
    /// Twist-twist entries: with S_m = Σ_{e>=m} G_e[tw,tw], the Gauss-Newton part is
    /// H_ab = ξ_a^T S_max(s_a,s_b) ξ_b. Geometric stiffness: for a before b in the chain
    /// (s_a < s_b, or the base translation before the base rotation)
    /// ∂²p/∂q_a∂q_b = Ω_a × ξ_b(p) (Jacobi identity), so with suffix sums P = Σ p γ^T and
    /// F = Σ γ over the elements b moves, Σ γ·(Ω_a × ξ_b(p)) =
    /// Ω_a · (P Ω_b - tr(P) Ω_b + v_b × F). The pair (c_k, psi_k) of one crease adds
    /// the terms of the c-dependence of the axis; a vertex sliding with c_j adds
    /// Ω_a · (s × γ). Both parts share one pass: O(n^2) 6-vector dot products written
    /// down contiguous columns, each unordered pair once, then one symmetrizing pass.
    fn assemble_hessian(&self, ws: &mut Workspace, h: &mut DMatrix<f64>) {
        let lay = self.layout;
        let nq = lay.len();
        let Workspace {
            twists,
            element_hessian,
            element_gradient,
            element_second,
            crease_extra,
            cross_blocks,
            hessian_suffix,
            scratch_first,
            scratch_u,
            scratch_psuf,
            scratch_twists,
            scratch_columns,
            scratch_left,
            scratch_right,
            contact,
            ..
        } = ws;
        // first element moved by each coordinate, and the twists as 6-vectors
        scratch_first.clear();
        scratch_first.extend((0..nq).map(|a| lay.first_element(a)));
        suffix_sums(
            element_hessian,
            element_gradient,
            element_second,
            &contact.wrench,
            hessian_suffix,
            scratch_psuf,
        );
        let mut pass = Assembly {
            layout: lay,
            first: scratch_first,
            twists,
            xs: &[],
            u: &[],
            columns: &[],
            suffix: hessian_suffix,
            psuf: scratch_psuf,
            element_hessian,
            element_second,
            crease_extra,
        };
        // U_b = S ξ_b + [P Ω_b - tr(P) Ω_b + v_b × F; 0] at s_b: H_ab = ξ_a · U_b for
        // s_a < s_b (the geometric part pairs with Ω_a only: zero-padded)
        scratch_u.clear();
        scratch_u.extend((0..nq).map(|b| pass.column_before(b)));
        pass.u = scratch_u;
        scratch_twists.clear();
        scratch_twists.extend(twists.iter().map(|t| t.to_array()));
        pass.xs = scratch_twists;
        scratch_columns.clear();
        scratch_columns.extend((0..nq).map(|b| pass.column_with_sliding(b)));
        pass.columns = scratch_columns;
        let hs = h.as_mut_slice();
        pass.pairs_along_the_chain(hs);
        pass.same_element_pairs(hs);
        pass.base_rotation_geometric(hs);
        pass.crease_geometric(hs);
        pass.twist_local(hs);
        for (e1, e2, block, _) in cross_blocks.iter() {
            pass.cross_block(hs, *e1, *e2, block, scratch_left, scratch_right);
        }
        symmetrize_upper(hs, nq);
    }
}

/// Suffix sums over the elements e >= m: S_m (6x6 Gauss-Newton twist blocks) and, for
/// the geometric stiffness, P_m = Σ p γ^T, F_m = Σ force, M_m = Σ moment.
pub(super) fn suffix_sums(
    element_hessian: &[Mat8],
    element_gradient: &[Vec8],
    element_second: &[SecondOrder],
    excluded: &[Vec8],
    hessian_suffix: &mut Vec<Mat6>,
    psuf: &mut Vec<(Matrix3, Vector3, Vector3)>,
) {
    let n = element_hessian.len();
    hessian_suffix.clear();
    hessian_suffix.resize(n + 1, Mat6::zeros());
    for e in (0..n).rev() {
        let g = &element_hessian[e];
        hessian_suffix[e] = hessian_suffix[e + 1] + Mat6::from_fn(|i, j| g[(i, j)]);
    }
    geometric_suffix_sums(element_gradient, element_second, excluded, psuf);
}

/// The geometric part of [`suffix_sums`] alone (P_m, F_m, M_m): all the chain model
/// needs, since it folds the twist blocks along its own sweep.
/// `excluded`: per element, a wrench left out of the force and moment sums (the
/// contact forces when their geometric stiffness is left out; empty: none).
pub(super) fn geometric_suffix_sums(
    element_gradient: &[Vec8],
    element_second: &[SecondOrder],
    excluded: &[Vec8],
    psuf: &mut Vec<(Matrix3, Vector3, Vector3)>,
) {
    let n = element_gradient.len();
    psuf.clear();
    psuf.resize(
        n + 1,
        (Matrix3::zeros(), Vector3::zeros(), Vector3::zeros()),
    );
    for e in (0..n).rev() {
        let (p, f, m) = psuf[e + 1];
        let mut g = element_gradient[e];
        if let Some(x) = excluded.get(e) {
            g -= x;
        }
        psuf[e] = (
            p + element_second[e].p_gamma,
            f + Vector3::new(g[3], g[4], g[5]),
            m + Vector3::new(g[0], g[1], g[2]),
        );
    }
}

/// Every unordered pair was written once at (a, b) or (b, a): H = A + A^T - diag, in
/// 8 x 8 tiles so that the transposed reads stay in a few cache lines.
fn symmetrize_upper(hs: &mut [f64], nq: usize) {
    const TILE: usize = 8;
    for jb in (0..nq).step_by(TILE) {
        for ib in (jb..nq).step_by(TILE) {
            for j in jb..(jb + TILE).min(nq) {
                for i in ib.max(j + 1)..(ib + TILE).min(nq) {
                    let v = hs[i + j * nq] + hs[j + i * nq];
                    hs[i + j * nq] = v;
                    hs[j + i * nq] = v;
                }
            }
        }
    }
}

/// The data the passes of the dense assembly share (all borrowed from the workspace).
struct Assembly<'w> {
    layout: Layout,
    first: &'w [usize],
    twists: &'w [Twist],
    /// The twists as 6-arrays.
    xs: &'w [[f64; 6]],
    /// Per column b: U_b (see `column_before`).
    u: &'w [Vec6],
    /// Per column b: U_b plus the sliding columns of c_m (see `column_with_sliding`).
    columns: &'w [[f64; 6]],
    suffix: &'w [Mat6],
    psuf: &'w [(Matrix3, Vector3, Vector3)],
    element_hessian: &'w [Mat8],
    element_second: &'w [SecondOrder],
    crease_extra: &'w [(Vector3, Vector3, Vector3)],
}

impl Assembly<'_> {
    fn xi(&self, a: usize) -> Vec6 {
        Vec6::from(self.twists[a].to_array())
    }
    fn omega(&self, a: usize) -> Vector3 {
        self.twists[a].angular
    }
    fn dot(&self, a: usize, v: &Vec6) -> f64 {
        dot6(&self.xs[a], v.as_slice())
    }
    fn base(&self) -> usize {
        self.layout.base_len()
    }
    /// Index of psi_1: the end of the crease-direction block.
    fn psi0(&self) -> usize {
        self.base() + self.layout.segments - 1
    }

    /// U_b = S ξ_b + [P Ω_b - tr(P) Ω_b + v_b × F; 0] at s_b.
    fn column_before(&self, b: usize) -> Vec6 {
        let sb = self.first[b];
        let (p, f, _) = &self.psuf[sb];
        let ob = self.omega(b);
        let w = p * ob - ob * p.trace() + self.twists[b].linear.cross(f);
        let mut u = self.suffix[sb] * self.xi(b);
        u[0] += w.x;
        u[1] += w.y;
        u[2] += w.z;
        u
    }

    /// Twist-local column of element e: c_m slides vertices of element m-1 (local
    /// column 7) and m (6): the Gauss-Newton column of G plus the geometric Σ s × γ on
    /// the angular part.
    fn local(&self, e: usize, col: usize) -> Vec6 {
        let mut v: Vec6 = self.element_hessian[e]
            .fixed_view::<6, 1>(0, 6 + col)
            .into_owned();
        let s = self.element_second[e].slide[col];
        v[0] += s.x;
        v[1] += s.y;
        v[2] += s.z;
        v
    }

    /// U_b, plus for c_m both elements' sliding columns: for rows a with s_a <= m-1
    /// both elements count; they share the row range of the twist-twist pass of
    /// column c_m, so they join its vector.
    fn column_with_sliding(&self, b: usize) -> [f64; 6] {
        let (base, psi0) = (self.base(), self.psi0());
        let mut v = self.u[b];
        if b >= base && b < psi0 {
            let m = b - base + 1;
            v += self.local(m - 1, 1) + self.local(m, 0);
        }
        let mut out = [0.0; 6];
        out.copy_from_slice(v.as_slice());
        out
    }

    /// Pairs with a strictly before b in the chain (s_a < s_b): ξ_a · column_b.
    fn pairs_along_the_chain(&self, hs: &mut [f64]) {
        let (base, psi0) = (self.base(), self.psi0());
        let nq = self.layout.len();
        let xs = self.xs;
        for b in 0..nq {
            let sb = self.first[b];
            // rows strictly before b in the chain: base, c_1..c_{sb-1}, psi_1..psi_{sb-1}
            if sb > 0 {
                let m = sb - 1;
                let ub = &self.columns[b];
                let col = &mut hs[b * nq..(b + 1) * nq];
                for range in [0..base, base..base + m, psi0..psi0 + m] {
                    for (h_ab, x_a) in col[range.clone()].iter_mut().zip(&xs[range]) {
                        *h_ab += dot6(x_a, ub);
                    }
                }
            }
        }
    }

    /// Same-element pairs: Gauss-Newton ξ_a^T S ξ_b (each unordered pair once, a <= b).
    fn same_element_pairs(&self, hs: &mut [f64]) {
        let lay = self.layout;
        let (nq, base) = (lay.len(), self.base());
        for b in 0..nq {
            let sb = self.first[b];
            let gn_b = self.suffix[sb] * self.xi(b);
            let same = if sb == 0 { 0..base } else { 0..0 };
            for a in same.chain(if sb > 0 {
                [lay.c(sb), lay.psi(sb)].into_iter().take(2)
            } else {
                [0, 0].into_iter().take(0)
            }) {
                if a <= b {
                    hs[a + b * nq] += self.xi(a).dot(&gn_b);
                }
            }
        }
    }

    /// Geometric terms of the rotation-vector coordinates of the base: exact at w = 0,
    /// symmetrized elsewhere (the translation comes before the rotation: no t-w terms).
    fn base_rotation_geometric(&self, hs: &mut [f64]) {
        if self.base() != 6 {
            return;
        }
        let nq = self.layout.len();
        let u = self.u;
        for j in 0..3 {
            for i in 0..=j {
                let wi = u[i].fixed_rows::<3>(0) - (self.suffix[0] * self.xi(i)).fixed_rows::<3>(0);
                let wj = u[j].fixed_rows::<3>(0) - (self.suffix[0] * self.xi(j)).fixed_rows::<3>(0);
                hs[i + j * nq] += 0.5 * (self.omega(i).dot(&wj) + self.omega(j).dot(&wi));
            }
        }
    }

    /// Geometric terms within one crease (c_k, psi_k), with those of the
    /// c-dependence of its axis.
    fn crease_geometric(&self, hs: &mut [f64]) {
        let lay = self.layout;
        let nq = lay.len();
        for k in 1..lay.segments {
            let (ic, ip) = (lay.c(k), lay.psi(k));
            let (a_k, dd_world, domega_world) = self.crease_extra[k];
            let (_, f, m) = &self.psuf[k];
            let arm = m - a_k.cross(f);
            let gn = |b: usize| self.suffix[k] * self.xi(b);
            let geo = |b: usize| self.u[b].fixed_rows::<3>(0) - gn(b).fixed_rows::<3>(0);
            hs[ip + ip * nq] += self.omega(ip).dot(&geo(ip));
            hs[ic + ip * nq] += self.omega(ip).dot(&geo(ic)) + dd_world.dot(&arm);
            hs[ic + ic * nq] += self.omega(ic).dot(&geo(ic)) + domega_world.dot(&arm);
        }
    }

    /// Twist-local entries of rows with s_a == m (c_m itself and psi_m).
    fn twist_local(&self, hs: &mut [f64]) {
        let lay = self.layout;
        let (n, nq) = (lay.segments, lay.len());
        let eh = self.element_hessian;
        for m in 1..n {
            let cm = lay.c(m);
            let only_m = self.local(m, 0);
            // c_m with itself: twice Ω·(s×γ) and twice ξ·G[tw, c_m], plus G's local
            // diagonal from both elements
            let s_self = self.element_second[m].slide[0];
            let g_self: Vec6 = eh[m].fixed_view::<6, 1>(0, 6).into_owned();
            hs[cm + cm * nq] += eh[m - 1][(7, 7)]
                + eh[m][(6, 6)]
                + 2.0 * self.omega(cm).dot(&s_self)
                + 2.0 * self.dot(cm, &g_self);
            let ip = lay.psi(m);
            hs[cm + ip * nq] += self.dot(ip, &only_m);
            if m + 1 < n {
                let cn = lay.c(m + 1);
                hs[cm + cn * nq] += eh[m][(6, 7)];
            }
        }
    }

    /// A cross block B between elements e1, e2 (loop closure): H += M + M^T with
    /// M_ab = P_e1(a)^T B P_e2(b). Column b of P_e2 is zero unless b moves element e2
    /// (for e2 = 0 only the base and c_1), so only those columns are visited: O(N)
    /// per block instead of O(N^2). M_ab goes to (a, b) and the symmetrizing pass
    /// adds M_ba from (b, a); the diagonal, which that pass keeps as is, takes both
    /// halves here.
    fn cross_block(
        &self,
        hs: &mut [f64],
        e1: usize,
        e2: usize,
        block: &Mat8,
        scratch_left: &mut Vec<Vec8>,
        scratch_right: &mut Vec<(usize, Vec8)>,
    ) {
        let (base, psi0) = (self.base(), self.psi0());
        let nq = self.layout.len();
        let p = |e: usize, a: usize| -> Vec8 {
            let mut v = Vec8::zeros();
            if self.first[a] <= e {
                v.fixed_rows_mut::<6>(0).copy_from(&self.xi(a));
            }
            if a >= base && a < psi0 {
                let k = a - base + 1;
                if k == e {
                    v[6] = 1.0;
                } else if k == e + 1 {
                    v[7] = 1.0;
                }
            }
            v
        };
        scratch_right.clear();
        scratch_right.extend(
            (0..nq)
                .map(|b| (b, p(e2, b)))
                .filter(|(_, v)| v.iter().any(|x| *x != 0.0))
                .map(|(b, v)| (b, block * v)),
        );
        scratch_left.clear();
        scratch_left.extend((0..nq).map(|a| p(e1, a)));
        for (b, right_b) in scratch_right.iter() {
            let col = &mut hs[b * nq..(b + 1) * nq];
            for (h_ab, left_a) in col.iter_mut().zip(scratch_left.iter()) {
                *h_ab += left_a.dot(right_b);
            }
            col[*b] += scratch_left[*b].dot(right_b);
        }
    }
}
