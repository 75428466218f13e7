//! The gradient: world twists of every coordinate, the adjoint gradient (appendix C,
//! O(n)) and the chain-rule baseline (appendix A, O(n^2)).

use super::{Objective, Vec8, Workspace};
use crate::geometry::{exp_so3, left_jacobian_so3, skew, Matrix3, Point3, Twist, Vector3};
use crate::ribbon::reconstruct::{crease_axis, crease_axis_derivative, crease_transform};

/// How the gradient is evaluated.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GradientMode {
    /// Appendix C: suffix sums of element wrenches, O(n).
    Adjoint,
    /// Appendix A: the explicit Jacobian of every point, O(n^2).
    ChainRule,
}

impl Objective<'_> {
    /// World twists ξ_a of all coordinates (needs `prepare`).
    pub(super) fn compute_twists(&self, q: &[f64], ws: &mut Workspace) {
        let n = self.strip.segments;
        ws.twists.clear();
        if self.layout.floating {
            let w = Vector3::new(q[0], q[1], q[2]);
            let t = Vector3::new(q[3], q[4], q[5]);
            let jl = left_jacobian_so3(&w);
            for i in 0..3 {
                let omega = jl.column(i).into_owned();
                ws.twists.push(Twist {
                    angular: omega,
                    linear: t.cross(&omega),
                });
            }
            for i in 0..3 {
                let mut lin = Vector3::zeros();
                lin[i] = 1.0;
                ws.twists.push(Twist {
                    angular: Vector3::zeros(),
                    linear: lin,
                });
            }
        }
        // One pass over the creases: the c_k twists go to [base, base + n - 1), the
        // psi_k twists after them (the layout's order), with one sin_cos per crease
        // (cached by `reconstruct`) and each crease's data computed once.
        let f = &ws.frames;
        let first = ws.twists.len();
        let zero = Twist {
            angular: Vector3::zeros(),
            linear: Vector3::zeros(),
        };
        ws.twists.resize(first + 2 * (n - 1), zero);
        ws.crease_extra.clear();
        ws.crease_extra
            .push((Vector3::zeros(), Vector3::zeros(), Vector3::zeros()));
        for k in 1..n {
            let r_prev = f.rotation[k - 1];
            let c = ws.coords.crease_direction[k];
            let (sin, cos) = f.bending_sin_cos[k];
            let a = r_prev * Vector3::new(self.strip.crease_station(k), 0.0, 0.0)
                + f.translation[k - 1];
            let d = crease_axis(c);
            let dd = crease_axis_derivative(c);
            let s = 1.0 + c * c;
            let ddd = Vector3::new(-3.0 * c, 2.0 * c * c - 1.0, 0.0) / (s * s * s.sqrt());
            let domega = ddd * sin + d.cross(&ddd) * (1.0 - cos);
            ws.crease_extra.push((a, r_prev * dd, r_prev * domega));
            let axis_point = Point3::from(a);
            // c_k: the derivative of exp(psi d(c)) w.r.t. the axis at fixed angle
            let omega_c = dd * sin + d.cross(&dd) * (1.0 - cos);
            ws.twists[first + k - 1] = Twist::rotation_about(r_prev * omega_c, &axis_point);
            ws.twists[first + n - 1 + k - 1] = Twist::rotation_about(r_prev * d, &axis_point);
        }
    }

    /// Appendix C: gradient by suffix sums of element wrenches, O(n).
    pub(super) fn gradient_adjoint(&self, ws: &mut Workspace, g: &mut [f64]) {
        let n = self.strip.segments;
        ws.suffix.clear();
        ws.suffix.resize(n + 1, Vec8::zeros());
        for e in (0..n).rev() {
            ws.suffix[e] = ws.suffix[e + 1] + ws.element_gradient[e];
        }
        for (a, xi) in ws.twists.iter().enumerate() {
            let s = ws.suffix[self.layout.first_element(a)];
            g[a] += xi.angular.dot(&s.fixed_rows::<3>(0)) + xi.linear.dot(&s.fixed_rows::<3>(3));
        }
        for k in 1..n {
            g[self.layout.c(k)] += ws.element_gradient[k - 1][7] + ws.element_gradient[k][6];
        }
    }

    /// Appendix A: explicit Jacobian of every recorded point, O(n^2). The local
    /// (sliding) terms are shared with the adjoint path.
    pub(super) fn gradient_chain_rule(&self, q: &[f64], ws: &mut Workspace, g: &mut [f64]) {
        let n = self.strip.segments;
        let f = &ws.frames;
        let coords = &ws.coords;
        // prefix products Π_{i<=k} T_i are the element frames; derivative of T_k w.r.t.
        // psi_k / c_k as explicit 3x4 matrices, then ∂p/∂q = F_{k-1} ∂T_k (T_{k+1..e} p̄).
        for pg in &ws.point_gradients {
            let e = pg.element;
            for k in 1..=e {
                let station = self.strip.crease_station(k);
                let (c, psi) = (coords.crease_direction[k], coords.bending_angle[k]);
                // local point in frame k: T_{k+1..e} p̄ = F_k^{-1} F_e p̄
                let p_e = f.rotation[e] * pg.material
                    + if pg.direction {
                        Vector3::zeros()
                    } else {
                        f.translation[e]
                    };
                let p_k = f.rotation[k].transpose()
                    * (p_e
                        - if pg.direction {
                            Vector3::zeros()
                        } else {
                            f.translation[k]
                        });
                for (which, idx) in [(0, self.layout.c(k)), (1, self.layout.psi(k))] {
                    let (dr, dt) = crease_transform_derivative(station, c, psi, which);
                    let local = dr * p_k + if pg.direction { Vector3::zeros() } else { dt };
                    let dp = f.rotation[k - 1] * local;
                    g[idx] += pg.gamma.dot(&dp);
                }
            }
            if self.layout.floating {
                let w = Vector3::new(q[0], q[1], q[2]);
                let p_e = f.rotation[e] * pg.material
                    + if pg.direction {
                        Vector3::zeros()
                    } else {
                        f.translation[e]
                    };
                let base_r = exp_so3(&w);
                let p_0 = base_r.transpose()
                    * (p_e
                        - if pg.direction {
                            Vector3::zeros()
                        } else {
                            Vector3::new(q[3], q[4], q[5])
                        });
                for i in 0..3 {
                    // ∂exp(w)/∂w_i by central differences of Rodrigues' formula would be
                    // approximate; use the closed form skew(J_l e_i) exp(w).
                    let omega = left_jacobian_so3(&w).column(i).into_owned();
                    let dp = skew(&omega) * base_r * p_0;
                    g[i] += pg.gamma.dot(&dp);
                    if !pg.direction {
                        g[3 + i] += pg.gamma[i];
                    }
                }
            }
        }
        for k in 1..n {
            g[self.layout.c(k)] += ws.element_gradient[k - 1][7] + ws.element_gradient[k][6];
        }
    }
}

/// ∂T_k/∂c_k (which = 0) or ∂T_k/∂psi_k (which = 1) as (dR, dt).
fn crease_transform_derivative(station: f64, c: f64, psi: f64, which: usize) -> (Matrix3, Vector3) {
    let (r, _) = crease_transform(station, c, psi);
    let d = crease_axis(c);
    let omega = if which == 1 {
        d
    } else {
        let dd = crease_axis_derivative(c);
        dd * psi.sin() + d.cross(&dd) * (1.0 - psi.cos())
    };
    let dr = skew(&omega) * r;
    let p = Vector3::new(station, 0.0, 0.0);
    (dr, -dr * p)
}
