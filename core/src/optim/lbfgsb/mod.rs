//! L-BFGS-B: limited-memory BFGS for bound-constrained minimization.
//!
//! Implementation of R. H. Byrd, P. Lu, J. Nocedal, C. Zhu, "A limited memory algorithm for
//! bound constrained optimization", SIAM J. Sci. Comput. 16(5), 1995 ("the paper"). Where the
//! paper leaves implementation freedom we follow the reference Fortran code (Zhu, Byrd, Lu,
//! Nocedal, ACM TOMS Algorithm 778, "the reference code"), so iterates, iteration counts and
//! stopping behaviour are comparable with SciPy's `L-BFGS-B`.
//!
//! One iteration (paper, section 2):
//! 1. `cauchy_point`: generalized Cauchy point, the first local minimizer of the
//!    quadratic model along the projected steepest-descent path (section 4);
//! 2. `subspace_minimization`: minimize the model over the variables free at the
//!    Cauchy point, direct primal method with backtracking into the box (section 5.1);
//! 3. `line_search`: Moré–Thuente line search for the strong Wolfe conditions along
//!    `d = x̄ - x`, with the step limited so that the iterate stays feasible;
//! 4. update of the compact limited-memory matrix `B = θI - W M Wᵀ` (section 3).
//!
//! All buffers are sized in `new` (or when `minimize` sees another dimension or memory), so an
//! iteration performs no heap allocation.

/// Options; defaults match SciPy's `L-BFGS-B`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LbfgsbOptions {
    /// Number of correction pairs `m` kept in the limited memory.
    pub memory: usize,
    /// Maximum number of (successful) iterations.
    pub max_iterations: usize,
    /// Stop when `‖P(x - g) - x‖∞ <= pgtol`.
    pub pgtol: f64,
    /// Stop when `(f_k - f_{k+1}) / max(|f_k|, |f_{k+1}|, 1) <= ftol` (SciPy: `factr * eps`).
    pub ftol: f64,
    /// Maximum number of function evaluations in one line search.
    pub max_line_search: usize,
}

impl Default for LbfgsbOptions {
    fn default() -> Self {
        Self {
            memory: 10,
            max_iterations: 15000,
            pgtol: 1e-5,
            ftol: 1e7 * f64::EPSILON,
            max_line_search: 20,
        }
    }
}

/// Why [`Lbfgsb::minimize`] stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LbfgsbStop {
    /// `‖P(x - g) - x‖∞ <= pgtol`.
    ProjectedGradient,
    /// Relative reduction of `f` in the last iteration was `<= ftol`.
    FunctionDecrease,
    /// `max_iterations` reached.
    MaxIterations,
    /// The line search failed with an empty memory (restarting did not help).
    LineSearchFailed,
    /// `f` or the gradient was not finite at the starting point.
    NonFinite,
}

/// Outcome of [`Lbfgsb::minimize`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LbfgsbResult {
    /// `f` at the returned `x`.
    pub f: f64,
    /// Completed iterations (accepted line searches).
    pub iterations: usize,
    /// Calls of `fg`, including line-search trials.
    pub evaluations: usize,
    /// `‖P(x - g) - x‖∞` at the returned `x` (infinite for `NonFinite`).
    pub projected_gradient_inf: f64,
    pub stop: LbfgsbStop,
}

impl LbfgsbResult {
    /// True when one of the two convergence tests fired.
    pub fn converged(&self) -> bool {
        matches!(
            self.stop,
            LbfgsbStop::ProjectedGradient | LbfgsbStop::FunctionDecrease
        )
    }
}

/// Line-search constants of the reference code: sufficient decrease `μ = 1e-3`, curvature
/// `η = 0.9` (strong Wolfe), relative interval tolerance 0.1; step cap without bounds.
const LS_FTOL: f64 = 1e-3;
const LS_GTOL: f64 = 0.9;
const LS_XTOL: f64 = 0.1;
const BIG_STEP: f64 = 1e10;

// Variable status (the reference code's `iwhere`); `<= 0` means free at the Cauchy point.
/// No finite bound: always free.
const UNBOUNDED: i8 = -1;
/// Free with zero gradient component (does not move along the Cauchy path).
const ZERO_GRADIENT: i8 = -3;
const FREE: i8 = 0;
/// At a bound with the gradient pushing outward, or fixed there by the Cauchy search.
const AT_LOWER: i8 = 1;
const AT_UPPER: i8 = 2;
/// `lower == upper`: always fixed.
const FIXED: i8 = 3;

/// Per-iteration work buffers (all sized once).
#[derive(Default)]
struct Work {
    g: Vec<f64>,
    x_old: Vec<f64>,
    g_old: Vec<f64>,
    /// Steepest-descent direction in the Cauchy search, then the search direction `x̄ - x`.
    d: Vec<f64>,
    /// Cauchy point `x^c`, then overwritten with the subspace minimizer `x̄`.
    xcp: Vec<f64>,
    /// Reduced gradient, then the subspace step, on the free variables.
    r: Vec<f64>,
    has_lower: Vec<bool>,
    has_upper: Vec<bool>,
    iwhere: Vec<i8>,
    /// Free variables first (`index[..nfree]`), then the active ones.
    index: Vec<usize>,
    breaks: Vec<(f64, usize)>,
    /// `2m` vectors: `p = Wᵀd`, `c = Wᵀ(x^c - x)`, `v = M·(…)`, row of `W`, scratch.
    p: Vec<f64>,
    c: Vec<f64>,
    v: Vec<f64>,
    wbp: Vec<f64>,
    tmp: Vec<f64>,
    /// `2m × 2m` factorization of `K` (subspace step), leading dimension `2m`.
    kf: Vec<f64>,
    evaluations: usize,
}

/// Reusable workspace: all buffers allocated in new()/resize, nothing allocated per iteration.
pub struct Lbfgsb {
    options: LbfgsbOptions,
    mem: Memory,
    w: Work,
}

/// Bounds of one `minimize` call.
struct Bounds<'a> {
    lower: &'a [f64],
    upper: &'a [f64],
    constrained: bool,
    boxed: bool,
}

impl Lbfgsb {
    /// Workspace for problems of dimension `n` (other dimensions are accepted later too, at the
    /// cost of one reallocation in `minimize`).
    pub fn new(n: usize, options: LbfgsbOptions) -> Self {
        let mut s = Self {
            options,
            mem: Memory::default(),
            w: Work::default(),
        };
        s.resize(n);
        s
    }

    /// Options for subsequent `minimize` calls (a new `memory` resizes the buffers there).
    pub fn options_mut(&mut self) -> &mut LbfgsbOptions {
        &mut self.options
    }

    /// (Re)allocate every buffer for dimension `n` and the current memory; no-op if unchanged.
    fn resize(&mut self, n: usize) {
        let m = self.options.memory.max(1);
        if n == self.mem.n && m == self.mem.m {
            return;
        }
        self.mem = Memory::new(n, m);
        let z = |len| vec![0.0; len];
        self.w = Work {
            g: z(n),
            x_old: z(n),
            g_old: z(n),
            d: z(n),
            xcp: z(n),
            r: z(n),
            has_lower: vec![false; n],
            has_upper: vec![false; n],
            iwhere: vec![FREE; n],
            index: vec![0; n],
            breaks: Vec::with_capacity(n),
            p: z(2 * m),
            c: z(2 * m),
            v: z(2 * m),
            wbp: z(2 * m),
            tmp: z(2 * m),
            kf: z(4 * m * m),
            evaluations: 0,
        };
    }

    /// Minimize f over lower <= x <= upper (entries may be -inf/+inf). x is the start (projected
    /// onto the box first) and receives the result.
    ///
    /// `fg(x, grad)` returns f(x) and writes the gradient. A non-finite value at a line-search
    /// trial shrinks the step; at the start it stops with [`LbfgsbStop::NonFinite`].
    pub fn minimize(
        &mut self,
        x: &mut [f64],
        lower: &[f64],
        upper: &[f64],
        mut fg: impl FnMut(&[f64], &mut [f64]) -> f64,
    ) -> LbfgsbResult {
        let n = x.len();
        self.resize(n);
        let opts = self.options;
        let bounds = self.prepare_bounds(x, lower, upper);
        self.mem.reset();

        let mut f = fg(x, &mut self.w.g);
        self.w.evaluations = 1;
        let mut iterations = 0;
        let finish = |s: &Self, f, iterations, projected_gradient_inf, stop| LbfgsbResult {
            f,
            iterations,
            evaluations: s.w.evaluations,
            projected_gradient_inf,
            stop,
        };
        if !f.is_finite() || !all_finite(&self.w.g) {
            return finish(self, f, 0, f64::INFINITY, LbfgsbStop::NonFinite);
        }
        let mut pg = self.projected_gradient_norm(x, &bounds);
        if pg <= opts.pgtol {
            return finish(self, f, 0, pg, LbfgsbStop::ProjectedGradient);
        }
        loop {
            if iterations >= opts.max_iterations {
                return finish(self, f, iterations, pg, LbfgsbStop::MaxIterations);
            }
            // Without bounds and with a nonempty memory the reference code skips the Cauchy
            // point (x^c = x, c = 0), so x̄ - x is the plain L-BFGS direction.
            if !bounds.constrained && self.mem.col > 0 {
                self.w.xcp.copy_from_slice(x);
                self.w.c.fill(0.0);
            } else {
                self.cauchy_point(x, &bounds, pg);
            }
            if !self.subspace_minimization(x, &bounds) {
                self.mem.reset(); // K could not be factored: restart from B = I
                continue;
            }
            for ((di, &zi), &xi) in self.w.d.iter_mut().zip(&self.w.xcp).zip(x.iter()) {
                *di = zi - xi;
            }
            let Some(f_new) = self.line_search(x, &bounds, iterations == 0, f, &mut fg) else {
                // Restore the iterate; drop the memory and retry along the projected gradient,
                // or give up if the memory was already empty (reference code).
                x.copy_from_slice(&self.w.x_old);
                self.w.g.copy_from_slice(&self.w.g_old);
                if self.mem.col == 0 {
                    return finish(self, f, iterations, pg, LbfgsbStop::LineSearchFailed);
                }
                self.mem.reset();
                continue;
            };
            let f_old = std::mem::replace(&mut f, f_new);
            iterations += 1;
            pg = self.projected_gradient_norm(x, &bounds);
            if pg <= opts.pgtol {
                return finish(self, f, iterations, pg, LbfgsbStop::ProjectedGradient);
            }
            if f_old - f <= opts.ftol * f_old.abs().max(f.abs()).max(1.0) {
                return finish(self, f, iterations, pg, LbfgsbStop::FunctionDecrease);
            }
            // s = x_{k+1} - x_k into d, y = g_{k+1} - g_k into r (both free now).
            let w = &mut self.w;
            for (i, &xi) in x.iter().enumerate() {
                (w.d[i], w.r[i]) = (xi - w.x_old[i], w.g[i] - w.g_old[i]);
            }
            self.mem.push(&w.d, &w.r);
        }
    }

    /// Project `x` onto the box and classify the variables (reference code `active`).
    fn prepare_bounds<'a>(
        &mut self,
        x: &mut [f64],
        lower: &'a [f64],
        upper: &'a [f64],
    ) -> Bounds<'a> {
        let n = x.len();
        assert!(
            lower.len() == n && upper.len() == n,
            "bounds length mismatch"
        );
        let (mut constrained, mut boxed) = (false, true);
        for i in 0..n {
            assert!(lower[i] <= upper[i], "invalid bounds at index {i}");
            let (hl, hu) = (lower[i] > f64::NEG_INFINITY, upper[i] < f64::INFINITY);
            (self.w.has_lower[i], self.w.has_upper[i]) = (hl, hu);
            if x[i] < lower[i] || x[i] > upper[i] {
                x[i] = x[i].clamp(lower[i], upper[i]);
            }
            boxed &= hl && hu;
            constrained |= hl || hu;
            self.w.iwhere[i] = match (hl, hu) {
                (false, false) => UNBOUNDED,
                (true, true) if upper[i] <= lower[i] => FIXED,
                _ => FREE,
            };
        }
        Bounds {
            lower,
            upper,
            constrained,
            boxed,
        }
    }

    /// `‖P(x - g) - x‖∞`, the first-order optimality measure for the box.
    fn projected_gradient_norm(&self, x: &[f64], b: &Bounds) -> f64 {
        let w = &self.w;
        (0..x.len()).fold(0.0, |norm: f64, i| {
            let gi = match w.g[i] {
                gi if gi < 0.0 && w.has_upper[i] => gi.max(x[i] - b.upper[i]),
                gi if gi >= 0.0 && w.has_lower[i] => gi.min(x[i] - b.lower[i]),
                gi => gi,
            };
            norm.max(gi.abs())
        })
    }
}

mod cauchy;
mod linalg;
mod line_search;
mod memory;

use linalg::{all_finite, dot, dot_on, dot_on_dense, factor_k, solve_k};
use memory::Memory;

#[cfg(test)]
mod tests;
