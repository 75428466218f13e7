//! What a trust-region method needs of the chain model besides the Newton solve, in
//! O(n) each (docs/ribbon_chain_solver.md, "The trust-region solver"):
//!
//! - H v by one forward sweep (the twists V_e and crease changes dc_e that v makes) and
//!   one adjoint sweep (the gradient of ½ v^T H v, written in the sum of the module
//!   documentation);
//! - where the factorization met a pivot that is not positive definite, a direction d
//!   with d^T (H + diag(shift)) d <= 0: the failing crease k moved along its pivot's
//!   least eigenvector e, every crease before it and the base held still, every crease
//!   after it by the feedback of the (successful) sweep beyond k, so that
//!   d^T (H + S) d = e^T Q_uu e exactly (the tail's value matrix is the minimum of the
//!   tail's quadratic over its controls).

use nalgebra::{Matrix2, Vector2};

use super::{ChainModel, Mat2x7, Mat6, Mat7, Mat9, Vec6, Vec7};
use crate::geometry::Vector3;

/// Where the last factorization stopped, if it did. (One value per model, written at
/// every failed factorization: boxing the 6x6 pivot would allocate there.)
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Copy, Debug, Default)]
pub(super) enum Failure {
    /// It succeeded (or was never run).
    #[default]
    None,
    /// The 2x2 pivot of crease k (held rows replaced by the identity).
    Crease { k: usize, pivot: Matrix2<f64> },
    /// The floating base's 6x6 pivot (held rows replaced by the identity).
    Root(Mat6),
    /// The loop closure's capacitance had the wrong inertia: no direction from the sweep.
    Closure,
}

/// Buffers of [`ChainModel::multiply`] (kept: no allocation once warm).
#[derive(Clone, Debug, Default)]
pub(super) struct ProductBuffers {
    /// Per element e: V_e and dc_e of the vector.
    twist: Vec<Vec6>,
    crease: Vec<f64>,
    /// Per element: ∂(½ v^T H v)/∂V_e and ∂/∂dc_e (direct), per crease ∂/∂dpsi_k.
    twist_bar: Vec<Vec6>,
    crease_bar: Vec<f64>,
    psi_bar: Vec<f64>,
}

fn angular(v: &Vec6) -> Vector3 {
    Vector3::new(v[0], v[1], v[2])
}

impl ChainModel {
    /// `out` = H v (full length, the model's dimension), exactly the dense matrix's
    /// product (loop closure included), in O(n).
    pub fn multiply(&mut self, v: &[f64], out: &mut [f64]) {
        let n = self.segments;
        let mut b = std::mem::take(&mut self.product);
        b.twist.clear();
        b.twist.resize(n, Vec6::zeros());
        b.crease.clear();
        b.crease.resize(n, 0.0);
        // forward: V_0 = Ξ_base v_base, V_e = V_{e-1} + ξ_c dc_e + ξ_psi dpsi_e
        if self.floating {
            b.twist[0] = self.base_twists * Vec6::from_column_slice(&v[..6]);
        }
        for e in 1..n {
            let (dz, dpsi) = (v[self.c_index(e)], v[self.psi_index(e)]);
            b.crease[e] = b.crease[e - 1] + dz;
            b.twist[e] = b.twist[e - 1] + self.xi_c[e] * b.crease[e] + self.xi_psi[e] * dpsi;
        }
        b.twist_bar.clear();
        b.twist_bar.resize(n, Vec6::zeros());
        b.crease_bar.clear();
        b.crease_bar.resize(n + 1, 0.0);
        b.psi_bar.clear();
        b.psi_bar.resize(n, 0.0);
        // the element blocks ½ y_e^T G̃_e y_e, y_e = (V_e, dc_e, dc_{e+1}), dc_n = 0
        for e in 0..n {
            let next = if e + 1 < n { b.crease[e + 1] } else { 0.0 };
            let y = super::Vec8::from_fn(|i, _| match i {
                0..=5 => b.twist[e][i],
                6 => b.crease[e],
                _ => next,
            });
            let a = self.blocks[e] * y;
            b.twist_bar[e] += a.fixed_rows::<6>(0);
            b.crease_bar[e] += a[6];
            b.crease_bar[e + 1] += a[7];
        }
        // the creases' own blocks and the geometric cross terms ω_{k-1}.(W_c dc_k + W_psi dpsi_k)
        for k in 1..n {
            let u = Vector2::new(b.crease[k], v[self.psi_index(k)]);
            let l = self.local[k] * u;
            let omega = angular(&b.twist[k - 1]);
            let pull = self.w_c[k] * u[0] + self.w_psi[k] * u[1];
            for i in 0..3 {
                b.twist_bar[k - 1][i] += pull[i];
            }
            b.crease_bar[k] += l[0] + omega.dot(&self.w_c[k]);
            b.psi_bar[k] += l[1] + omega.dot(&self.w_psi[k]);
        }
        if let Some(closure) = self.closure {
            // y_{n-1}^T B y_0: y_0 = (V_0, 0, dc_1), y_{n-1} = (V_{n-1}, dc_{n-1}, 0)
            let c1 = if n > 1 { b.crease[1] } else { 0.0 };
            let y0 = super::Vec8::from_fn(|i, _| match i {
                0..=5 => b.twist[0][i],
                6 => 0.0,
                _ => c1,
            });
            let yl = super::Vec8::from_fn(|i, _| match i {
                0..=5 => b.twist[n - 1][i],
                6 => b.crease[n - 1],
                _ => 0.0,
            });
            let (to_last, to_first) = (closure * y0, closure.transpose() * yl);
            b.twist_bar[n - 1] += to_last.fixed_rows::<6>(0);
            b.crease_bar[n - 1] += to_last[6];
            b.twist_bar[0] += to_first.fixed_rows::<6>(0);
            b.crease_bar[1] += to_first[7];
        }
        // adjoint: V_e feeds every later twist, dc_e every later crease change
        let mut twist_acc = Vec6::zeros();
        let mut crease_acc = 0.0;
        for e in (1..n).rev() {
            twist_acc += b.twist_bar[e];
            crease_acc += b.crease_bar[e] + self.xi_c[e].dot(&twist_acc);
            out[self.c_index(e)] = crease_acc;
            out[self.psi_index(e)] = b.psi_bar[e] + self.xi_psi[e].dot(&twist_acc);
        }
        if self.floating {
            twist_acc += b.twist_bar[0];
            let wrench = self.base_twists.transpose() * twist_acc;
            let w = Vector3::new(v[0], v[1], v[2]);
            let own = self.base_local * w;
            for i in 0..6 {
                out[i] = wrench[i] + if i < 3 { own[i] } else { 0.0 };
            }
        }
        self.product = b;
    }

    /// After a [`Self::factor`] that returned false: the least eigenvalue of the pivot
    /// it stopped at (the shift included), or None (it succeeded, or the loop closure's
    /// capacitance failed).
    pub fn failed_pivot(&self) -> Option<f64> {
        match self.failure {
            Failure::None | Failure::Closure => None,
            Failure::Crease { pivot, .. } => Some(pivot.symmetric_eigen().eigenvalues.min()),
            Failure::Root(r) => Some(r.symmetric_eigen().eigenvalues.min()),
        }
    }

    /// After a [`Self::factor`] that returned false: a direction d (full length, held
    /// unknowns 0) with d^T (H + diag(shift)) d = the returned curvature <= 0, of unit
    /// length in the failing pivot's own unknowns. None where the factorization did not
    /// fail in the sweep (it succeeded, or the loop closure's capacitance failed).
    pub fn negative_curvature(&self, out: &mut [f64]) -> Option<f64> {
        out.fill(0.0);
        let n = self.segments;
        let (mut x, first, curvature) = match self.failure {
            Failure::None | Failure::Closure => return None,
            Failure::Crease { k, pivot } => {
                let eigen = pivot.symmetric_eigen();
                let i = eigen.eigenvalues.imin();
                let e = eigen.eigenvectors.column(i);
                let u = [e[0], e[1]];
                out[self.c_index(k)] = u[0];
                out[self.psi_index(k)] = u[1];
                // x_k = M (0, u): V_k = ξ_c dc_k + ξ_psi dpsi_k, dc_k = dz_k
                let v = self.xi_c[k] * u[0] + self.xi_psi[k] * u[1];
                let x = Vec7::from_fn(|r, _| if r < 6 { v[r] } else { u[0] });
                (x, k + 1, eigen.eigenvalues[i])
            }
            Failure::Root(r) => {
                let eigen = r.symmetric_eigen();
                let i = eigen.eigenvalues.imin();
                let u: Vec6 = eigen.eigenvectors.column(i).into_owned();
                out[..6].copy_from_slice(u.as_slice());
                let v = self.base_twists * u;
                let x = Vec7::from_fn(|r, _| if r < 6 { v[r] } else { 0.0 });
                (x, 1, eigen.eigenvalues[i])
            }
        };
        // the tail follows by its feedback u_j = K_j x_{j-1} (no feedforward)
        for j in first..n {
            let u = self.gain[j] * x;
            let c = x[6] + u[0];
            for i in 0..6 {
                x[i] += self.xi_c[j][i] * c + self.xi_psi[j][i] * u[1];
            }
            x[6] = c;
            out[self.c_index(j)] = u[0];
            out[self.psi_index(j)] = u[1];
        }
        Some(curvature)
    }
}

impl ChainModel {
    /// [`Self::factor`], but a pivot that is not positive definite does not end it: its
    /// crease is held (c_k and psi_k keep their values in [`Self::solve`], see
    /// [`Self::hold_crease`]; the floating base's: the base is held) and the sweep goes
    /// on, as do the creases held since [`Self::release_held`]. One O(n) sweep, which
    /// factorizes H on what is left (false only where the loop closure's capacitance
    /// fails) and finds every crease whose pivot, given the tail beyond it, has negative
    /// curvature ([`Self::held_direction`], [`Self::newly_held`]).
    pub fn factor_holding(&mut self, free: &[bool], shift: &[f64]) -> bool {
        self.hold_failing = true;
        let ok = self.factor(free, shift);
        self.hold_failing = false;
        ok
    }

    /// How many pivots the last factorization held that were not held before.
    pub fn newly_held(&self) -> usize {
        self.held_pivots.len() + usize::from(self.held_root.is_some())
    }

    /// Forget the held creases: the next [`Self::factor_holding`] starts from none.
    pub fn release_held(&mut self) {
        self.pinned.clear();
        self.pinned_root = false;
    }

    /// Hold crease k in the sweep: its crease direction c_k and bending angle psi_k
    /// keep their values (dz_k = -dc_{k-1}, dpsi_k = 0: the feedback u = K x with
    /// K = [[0 .. 0, -1], [0 .. 0]], no feedforward), so that the tail's value before
    /// it is the stage's quadratic on w = T x, T = [I; K]: P = T^T Q T. Holding c_k,
    /// not z_k: a crease difference held at 0 still lets every crease before it move
    /// c_k (c_k = c_{k-1} + z_k), and the negative curvature with it, which made every
    /// pivot before fail in turn (2026-12-07). `z_free`: whether z_k is free (a z_k on
    /// its bound is held at 0 instead).
    pub(super) fn hold_crease(&mut self, k: usize, q: &Mat9, z_free: bool, p: &mut Mat7) {
        let mut gain = Mat2x7::zeros();
        if z_free {
            gain[(0, 6)] = -1.0;
        }
        // P = Q_xx + Q_xu K + K^T Q_ux + K^T Q_uu K with K's one entry at (0, 6)
        let k06 = gain[(0, 6)];
        for j in 0..7 {
            for i in 0..7 {
                let mut v = q[(i, j)];
                if j == 6 {
                    v += q[(i, 7)] * k06;
                }
                if i == 6 {
                    v += k06 * q[(7, j)];
                }
                if i == 6 && j == 6 {
                    v += k06 * q[(7, 7)] * k06;
                }
                p[(i, j)] = v;
            }
        }
        self.gain[k] = gain;
        self.pivot_inverse[k] = Matrix2::zeros();
    }

    /// After [`Self::factor_holding`] held pivots: the superposition of one direction
    /// of non-positive curvature per held pivot, each its pivot's least eigenvector
    /// (scaled to 1 in its largest entry, turned so that its entries of `downhill`
    /// have a non-negative dot product with it) followed by the tail's feedback (the
    /// other held pivots' unknowns at 0), into `out`. O(n). For one held pivot,
    /// d^T (H + S) d is its eigenvalue (<= 0), as for [`Self::negative_curvature`].
    pub fn held_direction(&self, downhill: &[f64], out: &mut [f64]) {
        out.fill(0.0);
        let n = self.segments;
        let least = |m: &Matrix2<f64>| -> Vector2<f64> {
            let eigen = m.symmetric_eigen();
            let e = eigen
                .eigenvectors
                .column(eigen.eigenvalues.imin())
                .into_owned();
            e / e.amax()
        };
        let mut x = Vec7::zeros();
        if let Some(r) = self.held_root {
            let eigen = r.symmetric_eigen();
            let mut u: Vec6 = eigen
                .eigenvectors
                .column(eigen.eigenvalues.imin())
                .into_owned();
            u /= u.amax();
            if u.dot(&Vec6::from_column_slice(&downhill[..6])) < 0.0 {
                u = -u;
            }
            out[..6].copy_from_slice(u.as_slice());
            let v = self.base_twists * u;
            x.fixed_rows_mut::<6>(0).copy_from(&v);
        }
        let mut held = self.held_pivots.iter().rev().peekable();
        for k in 1..n {
            let mut u = self.gain[k] * x;
            if let Some(&(_, pivot)) = held.next_if(|(j, _)| *j == k) {
                let (ic, ip) = (self.c_index(k), self.psi_index(k));
                let mut e = least(&pivot);
                if e[0] * downhill[ic] + e[1] * downhill[ip] < 0.0 {
                    e = -e;
                }
                u += e;
            }
            let c = x[6] + u[0];
            for i in 0..6 {
                x[i] += self.xi_c[k][i] * c + self.xi_psi[k][i] * u[1];
            }
            x[6] = c;
            out[self.c_index(k)] = u[0];
            out[self.psi_index(k)] = u[1];
        }
    }
}
