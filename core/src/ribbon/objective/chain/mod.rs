//! The Newton system of one step solved along the chain in O(n) (see
//! docs/ribbon_chain_solver.md): the Hessian of [`super::hessian`] written as the
//! quadratic model of an articulated chain and factorized by a backward Riccati sweep.
//!
//! The unknowns are the step's own z-coordinates (the base, the crease differences
//! z_k = c_k - c_{k-1} and the bending angles psi_k). The state after crease k is
//! x_k = (V_k, c_k): V_k the twist (rad/unit, m/unit) of element k's frame, c_k its
//! crease direction; crease k's controls (z_k, psi_k) move it by
//! x_k = (V_{k-1} + ξ_c (c_{k-1} + z_k) + ξ_psi psi_k, c_{k-1} + z_k).
//! The model ½ d^T H d (exactly the dense matrix, geometric stiffness included) is
//! - per element e: ½ y_e^T G̃_e y_e, y_e = (V_e, c_e, c_{e+1}), G̃ the Gauss-Newton block
//!   with the sliding geometric terms,
//! - per crease k: the (c_k, psi_k) block L_k (bending, regularizer, the crease's own
//!   geometric stiffness, the end-crease penalty) and the chain's geometric cross term
//!   ω_{k-1} . (W_c c_k + W_psi psi_k), ω_{k-1} the angular part of V_{k-1},
//! - at the root the base's own 6x6 block, and for a loop closure the coupling of the
//!   last element with the first (a rank <= 16 correction, Woodbury).
//!
//! A backward sweep eliminates crease n-1's controls, then n-2's, ... (a 2x2 pivot per
//! crease, a 6x6 one at a floating base): a block LDL^T of the same matrix, so it
//! succeeds exactly when the matrix is positive definite, like the dense Cholesky.

use nalgebra::{Cholesky, Matrix2, SMatrix, SVector, Vector2};

mod barrier;
mod closure;
mod pairs;
mod pivot;
mod product;

use super::hessian::geometric_suffix_sums;
use super::{Mat8, Objective, Vec8, Workspace};
use crate::geometry::{Matrix3, Vector3};

type Vec6 = SVector<f64, 6>;
type Vec7 = SVector<f64, 7>;
type Mat6 = SMatrix<f64, 6, 6>;
type Mat7 = SMatrix<f64, 7, 7>;
type Mat9 = SMatrix<f64, 9, 9>;
type Mat2x7 = SMatrix<f64, 2, 7>;
type Mat8x7 = SMatrix<f64, 8, 7>;
type Mat14 = SMatrix<f64, 14, 14>;
type Vec14 = SVector<f64, 14>;

/// The root unknowns a loop closure couples with the last element: the floating base
/// (6, absent columns for a fixed base) and z_1 (= c_1).
const ROOT: usize = 7;

/// The chain form of the Newton matrix and, after [`ChainModel::factor`], its factors.
/// Buffers are reused from step to step (no allocation once warm).
#[derive(Clone, Debug, Default)]
pub struct ChainModel {
    pub(super) segments: usize,
    pub(super) floating: bool,
    /// Per crease k (index 0 unused): twists of c_k and psi_k, their geometric cross
    /// vectors W (J per unit of the coordinate and rad), the local 2x2 block.
    pub(super) xi_c: Vec<Vec6>,
    pub(super) xi_psi: Vec<Vec6>,
    w_c: Vec<Vector3>,
    w_psi: Vec<Vector3>,
    local: Vec<Matrix2<f64>>,
    /// Per element: G̃_e over (twist, c_e, c_{e+1}).
    blocks: Vec<Mat8>,
    /// Base twists (columns: w_1..3, t_1..3) and the base's own geometric 3x3 block.
    pub(super) base_twists: Mat6,
    base_local: Matrix3,
    /// Loop closure: B of the term y_{n-1}^T B y_0 (summed over the closures), if any.
    closure: Option<Mat8>,
    /// Its low-rank form (see [`ChainModel::closure_columns`]): A = P_{n-1}^T B G
    /// (ROOT columns of the model's dimension, column-major), U = [A, E] on the free
    /// set and Y = H0^{-1} U (2 ROOT columns), the capacitance S + U^T Y as its
    /// eigendecomposition.
    closure_a: Vec<f64>,
    closure_u: Vec<f64>,
    closure_y: Vec<f64>,
    capacitance: Option<nalgebra::SymmetricEigen<f64, nalgebra::Const<14>>>,
    /// The same closure as an update of a softer chain (`closure`): its rows,
    /// Z = H_rho^{-1} V (14 columns of the model's dimension) and the correction A of
    /// H^{-1} = H_rho^{-1} - Z A V^T; `closure_k` is set when the last factorization
    /// took this form.
    closure_rows: Option<super::ClosureRows>,
    closure_z: Vec<f64>,
    closure_k: Option<Mat14>,
    scratch_rhs: Vec<f64>,
    // --- factors ---
    gain: Vec<Mat2x7>,
    pivot_inverse: Vec<Matrix2<f64>>,
    pub(super) free: Vec<bool>,
    root: Option<Cholesky<f64, nalgebra::Const<6>>>,
    feedforward: Vec<nalgebra::Vector2<f64>>,
    prefix: Vec<Vec6>,
    /// The diagonal of the matrix, once computed for this model (every damping level
    /// of one Newton iteration factorizes the same matrix).
    diagonal: Vec<f64>,
    diagonal_ready: bool,
    /// Contact pairs across the chain (rank one each, `pairs`) and their
    /// solve's buffers.
    pairs: Vec<super::contact_terms::PairTerm>,
    pair_order: Vec<u32>,
    pair_scratch: pairs::PairScratch,
    /// Where the last factorization stopped (for [`Self::negative_curvature`]).
    failure: product::Failure,
    /// rho of a penalty rho dc_{n-1}^2 / 2 on the last crease's change in the
    /// factorization (the trust-region solver's slab face, c_{n-1} = Σ z_k); 0: none.
    terminal_penalty: f64,
    /// Whether a factorization holds the unknowns of a pivot that is not positive
    /// definite instead of failing ([`Self::factor_holding`]), and the pivots it held:
    /// (crease, its 2x2 pivot), and the floating base's 6x6 one.
    hold_failing: bool,
    held_pivots: Vec<(usize, Matrix2<f64>)>,
    /// The creases held so far (by this and earlier factorizations since
    /// [`Self::release_held`]): per crease.
    pinned: Vec<bool>,
    pinned_root: bool,
    held_root: Option<Mat6>,
    closure_mask: Vec<bool>,
    product: product::ProductBuffers,
    /// Saddle-free pivots (issue 47, [`Self::set_saddle_free`]): the floor of a
    /// modified pivot's eigenvalues relative to its stage's scale; 0: off.
    saddle_floor: f64,
}

impl Objective<'_> {
    /// Fill `model` with the Newton matrix at the q of the last evaluation that
    /// recorded second-order data (what [`Self::assemble_newton_hessian`] would
    /// assemble densely, in z-coordinates), in O(n).
    pub fn chain_model(&self, ws: &mut Workspace, model: &mut ChainModel) {
        assert!(
            ws.second_order_recorded,
            "chain_model needs an evaluation that recorded second-order data"
        );
        let n = self.strip.segments;
        let lay = self.layout;
        geometric_suffix_sums(
            &ws.element_gradient,
            &ws.element_second,
            &ws.contact.wrench,
            &mut ws.scratch_psuf,
        );
        model.segments = n;
        model.floating = lay.floating;
        model.diagonal_ready = false;
        self.crease_blocks(ws, model);
        element_blocks(ws, model);
        model.base_twists = Mat6::zeros();
        model.base_local = Matrix3::zeros();
        if lay.base_len() == 6 {
            base_blocks(ws, model);
        }
        model.closure = None;
        model.closure_rows = None;
        for (e1, e2, b, rows) in &ws.cross_blocks {
            assert!(
                (*e1, *e2) == (n - 1, 0),
                "a cross block other than the loop closure's"
            );
            *model.closure.get_or_insert_with(Mat8::zeros) += b;
            model.closure_rows = *rows;
        }
        if ws.cross_blocks.len() > 1 {
            // (one closure's rows only: more than one keep the 14-column Woodbury)
            model.closure_rows = None;
        }
        pairs::merge_pairs(&ws.contact.pairs, &mut model.pair_order, &mut model.pairs);
    }

    /// Per crease k = 1..n-1: the twists ξ and geometric terms W of c_k and psi_k, and
    /// the 2x2 local block (bending, regularizer, the crease's own second-order terms,
    /// the end-crease penalty on the last); entry 0 of each is a zero placeholder.
    fn crease_blocks(&self, ws: &Workspace, model: &mut ChainModel) {
        let n = self.strip.segments;
        let lay = self.layout;
        let t = self.terms;
        model.xi_c.clear();
        model.xi_psi.clear();
        model.w_c.clear();
        model.w_psi.clear();
        model.local.clear();
        model.xi_c.push(Vec6::zeros());
        model.xi_psi.push(Vec6::zeros());
        model.w_c.push(Vector3::zeros());
        model.w_psi.push(Vector3::zeros());
        model.local.push(Matrix2::zeros());
        for k in 1..n {
            let (ic, ip) = (lay.c(k), lay.psi(k));
            let (wc, wp) = (geometric(ws, ic, k), geometric(ws, ip, k));
            let (a_k, dd_world, domega_world) = ws.crease_extra[k];
            let (_, f, m) = &ws.scratch_psuf[k];
            let arm = m - a_k.cross(f);
            let (oc, op) = (ws.twists[ic].angular, ws.twists[ip].angular);
            let mut local =
                self.bending_block(ws.coords.crease_direction[k], ws.coords.bending_angle[k], k);
            local[(0, 0)] += 2.0 * t.crease_regularizer + oc.dot(&wc) + domega_world.dot(&arm);
            let cross = op.dot(&wc) + dd_world.dot(&arm);
            local[(0, 1)] += cross;
            local[(1, 0)] += cross;
            local[(1, 1)] += op.dot(&wp);
            model.xi_c.push(twist(ws, ic));
            model.xi_psi.push(twist(ws, ip));
            model.w_c.push(wc);
            model.w_psi.push(wp);
            model.local.push(local);
        }
        if n >= 2 {
            let c_last = ws.coords.crease_direction[n - 1];
            for (_, shifted) in self.end_crease_shifts(c_last) {
                if shifted < 0.0 {
                    model.local[n - 1][(0, 0)] += t.penalty;
                }
            }
        }
    }
}

impl ChainModel {
    /// The slab's face held in the next factorization: `face` is the crease
    /// differences' index range with the penalty rho on their sum (None: no face).
    /// The slab's face is the last crease's change, c_{n-1} = Σ_k z_k, so rho (Σ d_z)^2
    /// is rho dc_{n-1}^2 on the sweep's terminal value.
    pub(crate) fn hold_slab_face(&mut self, face: Option<(std::ops::Range<usize>, f64)>) {
        let n = self.segments;
        self.terminal_penalty = match face {
            Some((range, rho)) => {
                assert_eq!(
                    range,
                    self.c_index(1)..self.c_index(n - 1) + 1,
                    "the chain's only slab is the crease differences' sum"
                );
                rho
            }
            None => 0.0,
        };
    }

    /// Test-only: the loop closure in the 14-column form only (the split of `closure`
    /// not tried), until the next [`Objective::chain_model`].
    #[cfg(any(test, feature = "test-hooks"))]
    pub fn use_fourteen_column_closure(&mut self) {
        self.closure_rows = None;
    }

    /// Test-only: every crease's local 2x2 block (bending, regularizer, its own
    /// geometric terms) scaled by 1 + `relative`, a subtly wrong Newton matrix for the
    /// negative controls of the solver comparisons.
    #[cfg(any(test, feature = "test-hooks"))]
    pub fn perturb_local_blocks(&mut self, relative: f64) {
        for block in self.local.iter_mut() {
            *block *= 1.0 + relative;
        }
        self.diagonal_ready = false;
    }
}

/// The twist ξ_a of coordinate a as a 6-vector (angular, linear).
fn twist(ws: &Workspace, a: usize) -> Vec6 {
    Vec6::from(ws.twists[a].to_array())
}

/// W_b = P Ω_b - tr(P) Ω_b + v_b × F at the first element b moves (`s`: the suffix
/// sums P, F from element s on).
fn geometric(ws: &Workspace, a: usize, s: usize) -> Vector3 {
    let (p, f, _) = &ws.scratch_psuf[s];
    let o = ws.twists[a].angular;
    p * o - o * p.trace() + ws.twists[a].linear.cross(f)
}

/// The 8x8 block of each element (its Hessian with the slide terms of its crease
/// columns added), symmetric from the columns the dense assembly reads.
fn element_blocks(ws: &Workspace, model: &mut ChainModel) {
    let n = model.segments;
    model.blocks.clear();
    for e in 0..n {
        let mut g = ws.element_hessian[e];
        for col in 0..2 {
            let s = ws.element_second[e].slide[col];
            for i in 0..3 {
                g[(i, 6 + col)] += s[i];
            }
        }
        // symmetric from the columns the dense assembly reads
        for j in 6..8 {
            for i in 0..j {
                g[(j, i)] = g[(i, j)];
            }
        }
        model.blocks.push(g);
    }
}

/// A floating base's twists (the columns of `base_twists`) and the symmetric
/// geometric block of its rotation (`base_local`).
fn base_blocks(ws: &Workspace, model: &mut ChainModel) {
    for a in 0..6 {
        model.base_twists.set_column(a, &twist(ws, a));
    }
    for j in 0..3 {
        for i in 0..3 {
            let (wi, wj) = (geometric(ws, i, 0), geometric(ws, j, 0));
            model.base_local[(i, j)] =
                0.5 * (ws.twists[i].angular.dot(&wj) + ws.twists[j].angular.dot(&wi));
        }
    }
}

impl ChainModel {
    /// Number of unknowns (the layout's length).
    pub fn dimension(&self) -> usize {
        let base = if self.floating { 6 } else { 0 };
        base + 2 * (self.segments - 1)
    }

    pub(super) fn c_index(&self, k: usize) -> usize {
        (if self.floating { 6 } else { 0 }) + k - 1
    }
    pub(super) fn psi_index(&self, k: usize) -> usize {
        (if self.floating { 6 } else { 0 }) + self.segments - 1 + k - 1
    }

    /// The diagonal of the matrix (what the dense solver scales its damping by), in
    /// O(n) with suffix sums: a unit step of psi_k moves elements k.. rigidly by ξ_psi;
    /// one of z_k turns every crease from k on, moving element e >= k by C_e - C_{k-1}
    /// with C_e = Σ_{i<=e} ξ_{c_i} (prefix sums), which expands into suffix sums of
    /// C^T G C, G C and G.
    pub fn diagonal(&mut self, out: &mut [f64]) {
        let n = self.segments;
        // prefix twists C_e of the crease directions
        let mut prefix = std::mem::take(&mut self.prefix);
        prefix.clear();
        prefix.resize(n, Vec6::zeros());
        for e in 1..n {
            prefix[e] = prefix[e - 1] + self.xi_c[e];
        }
        let mut s = Mat6::zeros();
        let mut alpha = 0.0;
        let mut beta = Vec6::zeros();
        let mut local_c = 0.0;
        let mut w_sum = Vector3::zeros();
        let mut w_moment = 0.0;
        for k in (1..n).rev() {
            // element k (it is moved by crease k and slid by c_k, c_{k+1})
            let g = &self.blocks[k];
            let tt = Mat6::from_fn(|i, j| g[(i, j)]);
            let inner = k + 1 < n;
            let mut gv = Vec6::from_fn(|i, _| g[(i, 6)]);
            let mut l = g[(6, 6)];
            if inner {
                gv += Vec6::from_fn(|i, _| g[(i, 7)]);
                l += 2.0 * g[(6, 7)] + g[(7, 7)];
            }
            let c = &prefix[k];
            s += tt;
            alpha += c.dot(&(tt * c)) + 2.0 * c.dot(&gv) + l;
            beta += tt * c + gv;
            local_c += self.local[k][(0, 0)];
            let ang = |v: &Vec6| Vector3::new(v[0], v[1], v[2]);
            w_sum += self.w_c[k];
            w_moment += ang(&prefix[k - 1]).dot(&self.w_c[k]);
            let xp = &self.xi_psi[k];
            out[self.psi_index(k)] = xp.dot(&(s * xp)) + self.local[k][(1, 1)];
            let cb = &prefix[k - 1];
            let previous = self.blocks[k - 1][(7, 7)];
            out[self.c_index(k)] = alpha - 2.0 * cb.dot(&beta)
                + cb.dot(&(s * cb))
                + previous
                + local_c
                + 2.0 * (w_moment - ang(cb).dot(&w_sum));
        }
        if self.floating {
            let g0 = Mat6::from_fn(|i, j| self.blocks[0][(i, j)]);
            let s0 = s + g0;
            for (a, o) in out.iter_mut().enumerate().take(6) {
                let x = self.base_twists.column(a);
                *o = x.dot(&(s0 * x)) + if a < 3 { self.base_local[(a, a)] } else { 0.0 };
            }
        }
        self.prefix = prefix;
    }

    /// The diagonal of the whole matrix (the chain's, [`Self::diagonal`], plus the
    /// loop closure's), computed once per model.
    pub fn cached_diagonal(&mut self) -> &[f64] {
        if !self.diagonal_ready {
            let mut d = std::mem::take(&mut self.diagonal);
            d.resize(self.dimension(), 0.0);
            self.diagonal(&mut d);
            if self.closure.is_some() {
                self.closure_columns();
                // C = A E^T + E A^T: 2 A[r_j, j] on the diagonal at root unknown r_j
                let nq = self.dimension();
                for j in 0..ROOT {
                    if let Some(r) = self.root_index(j) {
                        d[r] += 2.0 * self.closure_a[j * nq + r];
                    }
                }
            }
            self.diagonal = d;
            self.diagonal_ready = true;
        }
        &self.diagonal
    }

    /// Factorize H + diag(shift) restricted to the unknowns with `free[i]` (the others
    /// are held at a zero step). False where it is not positive definite.
    ///
    /// With a loop closure H = H0 + U S U^T (U = [A, E], S = [[0, I], [I, 0]]), H0 the
    /// chain: H0 is factorized by the sweep and H by Woodbury's identity with the
    /// 14 x 14 capacitance K = S + U^T H0^{-1} U. By Haynsworth's inertia additivity
    /// (on [[H0, U], [U^T, -S]]), In(H) = In(H0) + In(-K) - In(-S): with H0 positive
    /// definite, H is exactly when K has ROOT positive and ROOT negative eigenvalues.
    ///
    /// Contact pairs across the chain come on top (`pairs`).
    pub fn factor(&mut self, free: &[bool], shift: &[f64]) -> bool {
        self.factor_chain_only(free, shift) && self.factor_pairs()
    }

    /// [`Self::factor`] without the contact pairs.
    fn factor_chain_only(&mut self, free: &[bool], shift: &[f64]) -> bool {
        self.failure = product::Failure::None;
        self.held_pivots.clear();
        self.held_root = None;
        if self.factor_open_closure(free, shift) {
            self.capacitance = None;
            return true;
        }
        self.failure = product::Failure::None;
        self.held_pivots.clear();
        self.held_root = None;
        if !self.factor_chain(free, shift) {
            return false;
        }
        // (the sweep may have held more unknowns: the closure's columns use its mask)
        let mut mask = std::mem::take(&mut self.closure_mask);
        mask.clear();
        mask.extend_from_slice(&self.free);
        let ok = self.factor_closure(&mask);
        self.closure_mask = mask;
        ok
    }

    /// The chain's own factorization (no loop closure): see [`Self::factor`].
    fn factor_chain(&mut self, free: &[bool], shift: &[f64]) -> bool {
        let n = self.segments;
        self.free.clear();
        self.free.extend_from_slice(free);
        self.gain.clear();
        self.gain.resize(n, Mat2x7::zeros());
        self.pivot_inverse.clear();
        self.pivot_inverse.resize(n, Matrix2::zeros());
        // value Hessian after the last crease: element n-1 with c_n = 0
        let mut p = Mat7::from_fn(|i, j| self.blocks[n - 1][(i, j)]);
        p[(6, 6)] += self.terminal_penalty;
        for k in (1..n).rev() {
            let q = self.stage_matrix(k, &p, shift);
            let (ic, ip) = (self.c_index(k), self.psi_index(k));
            let mask = [free[ic], free[ip]];
            let mut quu = Matrix2::from_fn(|i, j| q[(7 + i, 7 + j)]);
            let mut qux = Mat2x7::from_fn(|i, j| q[(7 + i, j)]);
            for (r, &f) in mask.iter().enumerate() {
                if !f {
                    // a held control: its row and column drop out, its step is 0
                    quu.row_mut(r).fill(0.0);
                    quu.column_mut(r).fill(0.0);
                    quu[(r, r)] = 1.0;
                    qux.row_mut(r).fill(0.0);
                }
            }
            let pinned = self.hold_failing && self.pinned.get(k).copied().unwrap_or(false);
            let inverse = if self.saddle_floor > 0.0 && !self.hold_failing {
                let scale = quu.amax().max(qux.amax());
                pivot::saddle_free_inverse_2x2(&quu, self.saddle_floor * scale)
            } else {
                pivot::spd_inverse_2x2(&quu)
            };
            let inv = match (pinned, inverse) {
                (false, Some(inv)) => inv,
                (_, _) if self.hold_failing => {
                    if !pinned {
                        self.held_pivots.push((k, quu));
                        self.pinned.resize(n, false);
                        self.pinned[k] = true;
                    }
                    self.hold_crease(k, &q, mask[0], &mut p);
                    continue;
                }
                _ => {
                    self.failure = product::Failure::Crease { k, pivot: quu };
                    return false;
                }
            };
            let gain = -(inv * qux);
            // p = Q_xx + Q_ux^T K, symmetric (= Q_xx - Q_ux^T Q_uu^-1 Q_ux): the upper
            // triangle, mirrored
            for j in 0..7 {
                for i in 0..=j {
                    let v = q[(i, j)] + qux[(0, i)] * gain[(0, j)] + qux[(1, i)] * gain[(1, j)];
                    p[(i, j)] = v;
                    p[(j, i)] = v;
                }
            }
            self.gain[k] = gain;
            self.pivot_inverse[k] = inv;
        }
        self.root = None;
        if self.floating {
            let pv = Mat6::from_fn(|i, j| p[(i, j)]);
            let x = self.base_twists;
            let mut r = x.transpose() * pv * x;
            for i in 0..3 {
                for j in 0..3 {
                    r[(i, j)] += self.base_local[(i, j)];
                }
            }
            for i in 0..6 {
                if free[i] {
                    r[(i, i)] += shift[i];
                } else {
                    r.row_mut(i).fill(0.0);
                    r.column_mut(i).fill(0.0);
                    r[(i, i)] = 1.0;
                }
            }
            let r = (r + r.transpose()) * 0.5;
            match Cholesky::new(r).filter(|_| !(self.hold_failing && self.pinned_root)) {
                Some(chol) => self.root = Some(chol),
                None if self.hold_failing => {
                    self.pinned_root = true;
                    self.held_root = Some(r);
                    self.free[..6].fill(false);
                    self.root = Cholesky::new(Mat6::identity());
                }
                None => {
                    self.failure = product::Failure::Root(r);
                    return false;
                }
            }
        }
        true
    }

    /// The 9x9 quadratic of stage k over w = (V_{k-1}, c_{k-1}, z_k, psi_k): what
    /// crease k, element k-1 and the value after crease k (Hessian `p`) contribute.
    fn stage_matrix(&self, k: usize, p: &Mat7, shift: &[f64]) -> Mat9 {
        // x_k = M w, M = [e_0 .. e_5, a, a, b] with a = (ξ_c, 1), b = (ξ_psi, 0): M is
        // the identity but for its last three columns, so M^T P M needs only P a and P b
        // (about 200 flops instead of the 2000 of the dense product)
        let (xc, xp) = (&self.xi_c[k], &self.xi_psi[k]);
        let a = Vec7::from_fn(|i, _| if i < 6 { xc[i] } else { 1.0 });
        let b = Vec7::from_fn(|i, _| if i < 6 { xp[i] } else { 0.0 });
        let (pa, pb) = (p * a, p * b);
        let (aa, ab, bb) = (a.dot(&pa), a.dot(&pb), b.dot(&pb));
        let mut q = Mat9::zeros();
        for i in 0..6 {
            for j in 0..6 {
                q[(i, j)] = p[(i, j)];
            }
            for (j, v) in [(6, pa[i]), (7, pa[i]), (8, pb[i])] {
                q[(i, j)] = v;
                q[(j, i)] = v;
            }
        }
        for (i, j, v) in [
            (6, 6, aa),
            (6, 7, aa),
            (7, 7, aa),
            (6, 8, ab),
            (7, 8, ab),
            (8, 8, bb),
        ] {
            q[(i, j)] = v;
            q[(j, i)] = v;
        }
        // element k-1 over y = (V_{k-1}, c_{k-1}, c_k = c_{k-1} + z_k): y_r = w_r for
        // r < 7 and y_7 = w_6 + w_7, so row and column 7 of G add to both 6 and 7
        let g = &self.blocks[k - 1];
        for s in 0..7 {
            for r in 0..7 {
                q[(r, s)] += g[(r, s)];
            }
        }
        for r in 0..7 {
            let (v, h) = (g[(r, 7)], g[(7, r)]);
            q[(r, 6)] += v;
            q[(r, 7)] += v;
            q[(6, r)] += h;
            q[(7, r)] += h;
        }
        let corner = g[(7, 7)];
        q[(6, 6)] += corner;
        q[(6, 7)] += corner;
        q[(7, 6)] += corner;
        q[(7, 7)] += corner;
        // crease k's own block over (c_k, psi_k)
        let l = &self.local[k];
        let rows = [[6usize, 7], [8, 8]];
        for (a, ra) in rows.iter().enumerate() {
            for (b, rb) in rows.iter().enumerate() {
                let v = l[(a, b)];
                for &i in ra.iter().take(if a == 0 { 2 } else { 1 }) {
                    for &j in rb.iter().take(if b == 0 { 2 } else { 1 }) {
                        q[(i, j)] += v;
                    }
                }
            }
        }
        // the chain's geometric cross term ω_{k-1} . (W_c c_k + W_psi psi_k)
        let (wc, wp) = (&self.w_c[k], &self.w_psi[k]);
        for i in 0..3 {
            for (j, v) in [(6, wc[i]), (7, wc[i]), (8, wp[i])] {
                q[(i, j)] += v;
                q[(j, i)] += v;
            }
        }
        q[(7, 7)] += shift[self.c_index(k)];
        q[(8, 8)] += shift[self.psi_index(k)];
        q
    }

    /// Solve the factorized system for the right-hand side `rhs` (full length; held
    /// entries ignored), writing the step to `out` (held entries 0). With contact
    /// pairs across the chain, their low-rank solve around the chain's
    /// (`pairs`).
    pub fn solve(&mut self, rhs: &[f64], out: &mut [f64]) -> bool {
        if self.pairs.is_empty() {
            self.solve_chain_only(rhs, out)
        } else {
            self.solve_with_pairs(rhs, out)
        }
    }

    /// The chain's solve (H0, no loop closure) with the last factorization.
    fn solve_chain(&mut self, rhs: &[f64], out: &mut [f64]) -> bool {
        self.solve_chain_to_end(rhs, out).0
    }

    /// [`Self::solve_chain`] and the forward sweep's end state (V_{n-1}, c_{n-1}) =
    /// P_{n-1} out.
    fn solve_chain_to_end(&mut self, rhs: &[f64], out: &mut [f64]) -> (bool, Vec7) {
        let mut end = [Vec7::zeros(); 1];
        let ok = self.solve_chain_columns(rhs, out, &mut end);
        (ok, end[0])
    }

    /// The chain's solve of the B columns of `rhs` (each of the model's dimension; held
    /// entries ignored) into `out` (held entries 0) at once: each stage's factors are
    /// read once for all B (the loop closure's factorization solves 14 every Newton
    /// iteration), the arithmetic column by column that of a single solve. `ends`: each
    /// column's end state (V_{n-1}, c_{n-1}) = P_{n-1} out.
    pub(super) fn solve_chain_columns<const B: usize>(
        &mut self,
        rhs: &[f64],
        out: &mut [f64],
        ends: &mut [Vec7; B],
    ) -> bool {
        let n = self.segments;
        let nq = self.dimension();
        let mut feedforward = std::mem::take(&mut self.feedforward);
        feedforward.clear();
        feedforward.resize(B * n, Vector2::zeros());
        let mut p = [Vec7::zeros(); B];
        for k in (1..n).rev() {
            let (ic, ip) = (self.c_index(k), self.psi_index(k));
            let (xc, xp) = (&self.xi_c[k], &self.xi_psi[k]);
            let (free_c, free_p) = (self.free[ic], self.free[ip]);
            let (inverse, gain) = (self.pivot_inverse[k], self.gain[k].transpose());
            for (j, pj) in p.iter_mut().enumerate() {
                let pv = Vec6::from_fn(|i, _| pj[i]);
                let along_c = xc.dot(&pv) + pj[6];
                let r = &rhs[j * nq..];
                let mut qu = Vector2::new(along_c - r[ic], xp.dot(&pv) - r[ip]);
                if !free_c {
                    qu[0] = 0.0;
                }
                if !free_p {
                    qu[1] = 0.0;
                }
                let mut qx = *pj;
                qx[6] = along_c;
                feedforward[j * n + k] = -(inverse * qu);
                *pj = qx + gain * qu;
            }
        }
        let mut ok = true;
        for (j, (pj, x)) in p.iter().zip(ends.iter_mut()).enumerate() {
            *x = Vec7::zeros();
            if self.floating {
                let r = &rhs[j * nq..];
                let pv = Vec6::from_fn(|i, _| pj[i]);
                let force = self.base_twists.transpose() * pv;
                let v = Vec6::from_fn(|i, _| if self.free[i] { r[i] - force[i] } else { 0.0 });
                let Some(root) = self.root.as_ref() else {
                    self.feedforward = feedforward;
                    return false;
                };
                let u = root.solve(&v);
                out[j * nq..j * nq + 6].copy_from_slice(u.as_slice());
                let twist = self.base_twists * u;
                x.fixed_rows_mut::<6>(0).copy_from(&twist);
            }
        }
        for k in 1..n {
            let (xc, xp) = (&self.xi_c[k], &self.xi_psi[k]);
            let (ic, ip) = (self.c_index(k), self.psi_index(k));
            let gain = self.gain[k];
            for (j, x) in ends.iter_mut().enumerate() {
                let u = gain * *x + feedforward[j * n + k];
                let c = x[6] + u[0];
                for i in 0..6 {
                    x[i] += xc[i] * c + xp[i] * u[1];
                }
                x[6] = c;
                out[j * nq + ic] = u[0];
                out[j * nq + ip] = u[1];
            }
        }
        self.feedforward = feedforward;
        ok &= out.iter().all(|v| v.is_finite());
        ok
    }
}

/// The chain model as the projected Newton method's matrix: the damping and the held
/// variables of [`crate::optim::NewtonMatrix`] on top of [`ChainModel`].
#[derive(Clone, Debug, Default)]
pub struct ChainMatrix {
    pub model: ChainModel,
    mask: Vec<bool>,
    shift: Vec<f64>,
    rhs: Vec<f64>,
    out: Vec<f64>,
}

impl crate::optim::NewtonMatrix for ChainMatrix {
    fn diagonal(&mut self, out: &mut [f64]) {
        out.copy_from_slice(self.model.cached_diagonal());
    }

    fn out_of_range(&self, _free: &[usize]) -> bool {
        let m = &self.model;
        let bad = |x: f64| !x.is_finite() || x.abs() >= 1e150;
        m.blocks.iter().any(|b| b.iter().any(|&x| bad(x)))
            || m.local.iter().any(|b| b.iter().any(|&x| bad(x)))
            || m.w_c
                .iter()
                .chain(&m.w_psi)
                .any(|w| w.iter().any(|&x| bad(x)))
            || m.closure.iter().any(|b| b.iter().any(|&x| bad(x)))
    }

    fn factor(&mut self, free: &[usize], damping: f64) -> bool {
        self.model.terminal_penalty = 0.0;
        let nq = self.model.dimension();
        self.mask.clear();
        self.mask.resize(nq, false);
        let diagonal = self.model.cached_diagonal();
        let mut max_diag: f64 = 0.0;
        for &i in free {
            self.mask[i] = true;
            max_diag = max_diag.max(diagonal[i].abs());
        }
        let floor = crate::optim::damping_floor(max_diag);
        self.shift.clear();
        self.shift.extend(
            diagonal
                .iter()
                .map(|&d| crate::optim::damped_diagonal(d, damping, floor) - d),
        );
        self.model.factor(&self.mask, &self.shift)
    }

    fn solve(&mut self, free: &[usize], reduced: &mut [f64]) -> bool {
        let nq = self.model.dimension();
        self.rhs.clear();
        self.rhs.resize(nq, 0.0);
        self.out.clear();
        self.out.resize(nq, 0.0);
        for (k, &i) in free.iter().enumerate() {
            self.rhs[i] = reduced[k];
        }
        if !self.model.solve(&self.rhs, &mut self.out) {
            return false;
        }
        for (k, &i) in free.iter().enumerate() {
            reduced[k] = self.out[i];
        }
        true
    }
}

impl crate::optim::ModelMatrix for ChainMatrix {
    fn multiply(&mut self, v: &[f64], out: &mut [f64]) {
        self.model.multiply(v, out);
    }

    /// The slab's face as the sweep's terminal penalty ([`ChainModel::hold_slab_face`]).
    fn factor_free(
        &mut self,
        free: &[bool],
        shift: f64,
        face: Option<(std::ops::Range<usize>, f64)>,
    ) -> bool {
        let model = &mut self.model;
        model.hold_slab_face(face);
        self.shift.clear();
        self.shift.resize(model.dimension(), shift);
        model.factor(free, &self.shift)
    }

    fn failed_pivot(&self) -> Option<f64> {
        self.model.failed_pivot()
    }

    fn solve_free(&mut self, rhs: &[f64], out: &mut [f64]) -> bool {
        self.model.solve(rhs, out)
    }
}
