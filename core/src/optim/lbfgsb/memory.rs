//! The compact limited-memory BFGS matrix (paper, section 3).

use super::linalg::{cholesky, dot, solve_lower, solve_lower_transposed};

/// Compact limited-memory BFGS matrix `B = θI - W M Wᵀ` with `W = [Y, θS]` and
/// `M = [[-D, Lᵀ], [L, θSᵀS]]⁻¹`, `L` the strict lower triangle and `D` the diagonal of `SᵀY`
/// (paper, section 3). Pairs are indexed logically, `j = 0` being the oldest.
#[derive(Default)]
pub(super) struct Memory {
    pub(super) n: usize,
    pub(super) m: usize,
    /// Ring buffers: physical slot `k` of `S` is `s[k*n..(k+1)*n]`; logical 0 is `head`.
    pub(super) s: Vec<f64>,
    pub(super) y: Vec<f64>,
    /// `sy[i*m+j] = s_iᵀy_j` (lower triangle used) and `ss[i*m+j] = s_iᵀs_j`.
    pub(super) sy: Vec<f64>,
    pub(super) ss: Vec<f64>,
    /// Lower Cholesky factor `J` of `T = θSᵀS + L D⁻¹ Lᵀ`, used to apply `M`.
    pub(super) wt: Vec<f64>,
    pub(super) theta: f64,
    pub(super) col: usize,
    pub(super) head: usize,
}

impl Memory {
    pub(super) fn new(n: usize, m: usize) -> Self {
        let z = |len| vec![0.0; len];
        let (s, y, sy, ss, wt) = (z(n * m), z(n * m), z(m * m), z(m * m), z(m * m));
        Self {
            n,
            m,
            s,
            y,
            sy,
            ss,
            wt,
            theta: 1.0,
            col: 0,
            head: 0,
        }
    }

    /// Drop all pairs: `B = I` (the reference code's restart).
    pub(super) fn reset(&mut self) {
        (self.col, self.head, self.theta) = (0, 0, 1.0);
    }

    pub(super) fn s(&self, j: usize) -> &[f64] {
        let k = (self.head + j) % self.m;
        &self.s[k * self.n..(k + 1) * self.n]
    }

    pub(super) fn y(&self, j: usize) -> &[f64] {
        let k = (self.head + j) % self.m;
        &self.y[k * self.n..(k + 1) * self.n]
    }

    /// `(W v)_i = Σ_j y_j[i] v_j + θ s_j[i] v_{col+j}`.
    pub(super) fn w_times(&self, i: usize, v: &[f64]) -> f64 {
        let col = self.col;
        (0..col)
            .map(|j| self.y(j)[i] * v[j] + self.theta * self.s(j)[i] * v[col + j])
            .sum()
    }

    /// `p = M v`, with the factorization (reference `bmv`)
    /// `M⁻¹ = [[D^½, 0], [-L D^-½, J]] [[-D^½, D^-½ Lᵀ], [0, Jᵀ]]`.
    pub(super) fn bmv(&self, v: &[f64], p: &mut [f64]) {
        let (m, col, sy) = (self.m, self.col, &self.sy);
        let (p1, p2) = p.split_at_mut(col);
        for i in 0..col {
            let sum: f64 = (0..i).map(|k| sy[i * m + k] * v[k] / sy[k * m + k]).sum();
            p2[i] = v[col + i] + sum;
        }
        solve_lower(&self.wt, m, col, p2);
        solve_lower_transposed(&self.wt, m, col, p2);
        for i in 0..col {
            let dii = sy[i * m + i];
            let sum: f64 = (i + 1..col).map(|k| sy[k * m + i] * p2[k]).sum();
            p1[i] = (sum - v[i]) / dii;
        }
    }

    /// Add the pair `(s, y)`, dropping the oldest when full; update `θ = yᵀy / sᵀy`, `SᵀY`,
    /// `SᵀS` and refactor `T = θSᵀS + L D⁻¹ Lᵀ`. As in the paper, the pair is skipped unless
    /// the curvature condition `sᵀy > ε‖y‖²` (ε = machine epsilon) holds, which keeps `B`
    /// positive definite. (The reference code tests `sᵀy > ε·(-gᵀs)` instead.)
    pub(super) fn push(&mut self, s: &[f64], y: &[f64]) {
        let (sty, yty) = (dot(s, y), dot(y, y));
        if sty <= f64::EPSILON * yty {
            return;
        }
        let (n, m) = (self.n, self.m);
        let k = if self.col < m {
            self.col += 1;
            (self.head + self.col - 1) % m
        } else {
            for i in 0..m - 1 {
                for j in 0..m - 1 {
                    self.sy[i * m + j] = self.sy[(i + 1) * m + j + 1];
                    self.ss[i * m + j] = self.ss[(i + 1) * m + j + 1];
                }
            }
            self.head = (self.head + 1) % m;
            (self.head + m - 1) % m
        };
        self.s[k * n..(k + 1) * n].copy_from_slice(s);
        self.y[k * n..(k + 1) * n].copy_from_slice(y);
        self.theta = yty / sty;
        let (col, last) = (self.col, self.col - 1);
        for j in 0..last {
            let (sy, ss) = (dot(s, self.y(j)), dot(s, self.s(j)));
            self.sy[last * m + j] = sy;
            (self.ss[last * m + j], self.ss[j * m + last]) = (ss, ss);
        }
        (self.sy[last * m + last], self.ss[last * m + last]) = (sty, dot(s, s));
        for i in 0..col {
            for j in 0..=i {
                let sy = &self.sy;
                let ld: f64 = (0..j)
                    .map(|k| sy[i * m + k] * sy[j * m + k] / sy[k * m + k])
                    .sum();
                self.wt[i * m + j] = self.theta * self.ss[i * m + j] + ld;
            }
        }
        if !cholesky(&mut self.wt, m, col) {
            self.reset(); // nearly dependent pairs: the reference code restarts too
        }
    }
}
