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

/// Compact limited-memory BFGS matrix `B = θI - W M Wᵀ` with `W = [Y, θS]` and
/// `M = [[-D, Lᵀ], [L, θSᵀS]]⁻¹`, `L` the strict lower triangle and `D` the diagonal of `SᵀY`
/// (paper, section 3). Pairs are indexed logically, `j = 0` being the oldest.
#[derive(Default)]
struct Memory {
    n: usize,
    m: usize,
    /// Ring buffers: physical slot `k` of `S` is `s[k*n..(k+1)*n]`; logical 0 is `head`.
    s: Vec<f64>,
    y: Vec<f64>,
    /// `sy[i*m+j] = s_iᵀy_j` (lower triangle used) and `ss[i*m+j] = s_iᵀs_j`.
    sy: Vec<f64>,
    ss: Vec<f64>,
    /// Lower Cholesky factor `J` of `T = θSᵀS + L D⁻¹ Lᵀ`, used to apply `M`.
    wt: Vec<f64>,
    theta: f64,
    col: usize,
    head: usize,
}

impl Memory {
    fn new(n: usize, m: usize) -> Self {
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
    fn reset(&mut self) {
        (self.col, self.head, self.theta) = (0, 0, 1.0);
    }

    fn s(&self, j: usize) -> &[f64] {
        let k = (self.head + j) % self.m;
        &self.s[k * self.n..(k + 1) * self.n]
    }

    fn y(&self, j: usize) -> &[f64] {
        let k = (self.head + j) % self.m;
        &self.y[k * self.n..(k + 1) * self.n]
    }

    /// `(W v)_i = Σ_j y_j[i] v_j + θ s_j[i] v_{col+j}`.
    fn w_times(&self, i: usize, v: &[f64]) -> f64 {
        let col = self.col;
        (0..col)
            .map(|j| self.y(j)[i] * v[j] + self.theta * self.s(j)[i] * v[col + j])
            .sum()
    }

    /// `p = M v`, with the factorization (reference `bmv`)
    /// `M⁻¹ = [[D^½, 0], [-L D^-½, J]] [[-D^½, D^-½ Lᵀ], [0, Jᵀ]]`.
    fn bmv(&self, v: &[f64], p: &mut [f64]) {
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
    fn push(&mut self, s: &[f64], y: &[f64]) {
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

    /// Generalized Cauchy point (paper, section 4, algorithm CP): the first local minimizer
    /// of the model `m(x) = gᵀ(x - x_k) + ½(x - x_k)ᵀB(x - x_k)` along the projected path
    /// `x(t) = P(x_k - t g)`. Breakpoints are visited in increasing order; on each segment the
    /// derivatives `f' = ∂m/∂t` and `f'' = ∂²m/∂t²` are updated in O(m²) using `p = Wᵀd` and
    /// `c = Wᵀ(x(t) - x_k)` instead of O(n) work. On exit `xcp` = `x^c`, `c = Wᵀ(x^c - x_k)`
    /// and `iwhere` marks the variables at a bound.
    fn cauchy_point(&mut self, x: &[f64], b: &Bounds, pg_norm: f64) {
        let (mem, w) = (&self.mem, &mut self.w);
        let (n, col, theta) = (x.len(), mem.col, mem.theta);
        let col2 = 2 * col;
        w.xcp.copy_from_slice(x);
        w.c[..col2].fill(0.0);
        if pg_norm <= 0.0 {
            return;
        }
        // d = -g on the variables not held at a bound; breakpoints t_i; f' = -dᵀd; p = Wᵀd.
        w.p[..col2].fill(0.0);
        w.breaks.clear();
        let (mut bounded, mut n_unbroken, mut ibkmin, mut bkmin, mut f1) = (true, 0, 0, 0.0, 0.0);
        for (i, &xi) in x.iter().enumerate() {
            let neggi = -w.g[i];
            let status = &mut w.iwhere[i];
            if *status != FIXED && *status != UNBOUNDED {
                let at_lower = w.has_lower[i] && xi <= b.lower[i];
                let at_upper = w.has_upper[i] && xi >= b.upper[i];
                *status = match (at_lower, at_upper) {
                    (true, _) if neggi <= 0.0 => AT_LOWER,
                    (false, true) if neggi >= 0.0 => AT_UPPER,
                    (false, false) if neggi == 0.0 => ZERO_GRADIENT,
                    _ => FREE,
                };
            }
            if *status != FREE && *status != UNBOUNDED {
                w.d[i] = 0.0;
                continue;
            }
            w.d[i] = neggi;
            f1 -= neggi * neggi;
            for j in 0..col {
                w.p[j] += mem.y(j)[i] * neggi;
                w.p[col + j] += mem.s(j)[i] * neggi;
            }
            let t = if w.has_lower[i] && neggi < 0.0 {
                (xi - b.lower[i]) / -neggi
            } else if w.has_upper[i] && neggi > 0.0 {
                (b.upper[i] - xi) / neggi
            } else {
                n_unbroken += 1;
                bounded &= neggi == 0.0;
                continue;
            };
            if w.breaks.is_empty() || t < bkmin {
                (bkmin, ibkmin) = (t, w.breaks.len());
            }
            w.breaks.push((t, i));
        }
        w.p[col..col2].iter_mut().for_each(|pj| *pj *= theta);
        if w.breaks.is_empty() && n_unbroken == 0 {
            return; // d = 0: x^c = x
        }
        // f'' = dᵀBd = θdᵀd - pᵀMp.
        let mut f2 = -theta * f1;
        let f2_org = f2;
        if col > 0 {
            mem.bmv(&w.p[..col2], &mut w.v[..col2]);
            f2 -= dot(&w.v[..col2], &w.p[..col2]);
        }
        let mut dtm = -f1 / f2;
        let (mut tsum, nbreak, mut all_fixed) = (0.0, w.breaks.len(), false);
        let (mut nleft, mut k, mut tj) = (nbreak, 0, 0.0);
        while nleft > 0 {
            // The smallest breakpoint is known; sort the others only if the search goes on
            // (the reference code uses a heap for the same purpose).
            if k == 1 {
                w.breaks.swap(0, ibkmin);
                w.breaks[1..].sort_unstable_by(|a, b| a.0.total_cmp(&b.0));
            }
            let (t, ibp) = w.breaks[if k == 0 { ibkmin } else { k }];
            let dt = t - tj;
            tj = t;
            if dtm < dt {
                break; // the minimizer lies inside the current segment
            }
            // Advance to the breakpoint and fix variable ibp at its bound.
            tsum += dt;
            nleft -= 1;
            k += 1;
            let dibp = std::mem::replace(&mut w.d[ibp], 0.0);
            let (bound, status) = if dibp > 0.0 {
                (b.upper[ibp], AT_UPPER)
            } else {
                (b.lower[ibp], AT_LOWER)
            };
            let zibp = bound - x[ibp];
            (w.xcp[ibp], w.iwhere[ibp]) = (bound, status);
            if nleft == 0 && nbreak == n {
                (dtm, all_fixed) = (dt, true); // every variable fixed: x^c is this breakpoint
                break;
            }
            // Update f' and f'' for the next segment.
            let dibp2 = dibp * dibp;
            f1 += dt * f2 + dibp2 - theta * dibp * zibp;
            f2 -= theta * dibp2;
            if col > 0 {
                for j in 0..col2 {
                    w.c[j] += dt * w.p[j];
                }
                for j in 0..col {
                    (w.wbp[j], w.wbp[col + j]) = (mem.y(j)[ibp], theta * mem.s(j)[ibp]);
                }
                let (wbp, v) = (&w.wbp[..col2], &mut w.v[..col2]);
                mem.bmv(wbp, v);
                let (wmc, wmp, wmw) = (dot(&w.c[..col2], v), dot(&w.p[..col2], v), dot(wbp, v));
                for (pj, &wj) in w.p[..col2].iter_mut().zip(wbp) {
                    *pj -= dibp * wj;
                }
                f1 += dibp * wmc;
                f2 += 2.0 * dibp * wmp - dibp2 * wmw;
            }
            f2 = f2.max(f64::EPSILON * f2_org);
            dtm = if nleft == 0 && bounded { 0.0 } else { -f1 / f2 };
        }
        if !all_fixed {
            tsum += dtm.max(0.0);
            dtm = dtm.max(0.0);
            for (xc, &di) in w.xcp.iter_mut().zip(&w.d) {
                *xc += tsum * di;
            }
        }
        for j in 0..col2 {
            w.c[j] += dtm * w.p[j];
        }
    }

    /// Subspace minimization, direct primal method (paper, section 5.1). With `Z` the free
    /// variables at `x^c`, the reduced gradient is `r = Zᵀ(g + θ(x^c - x) - W M c)` and the
    /// reduced Hessian `B̂ = θI - ZᵀW M WᵀZ`. Sherman–Morrison–Woodbury gives
    /// `B̂⁻¹ = θ⁻¹I + θ⁻² ZᵀW K⁻¹ WᵀZ` with `K = M⁻¹ - θ⁻¹WᵀZZᵀW`, a `2col × 2col` symmetric
    /// indefinite matrix factored as `K = Uᵀ diag(-I, I) U` (reference `formk`). The Newton step
    /// `d^u = -B̂⁻¹r` is backtracked so that `x̄ = x^c + α* d^u` stays in the box.
    /// Returns false if `K` cannot be factored.
    fn subspace_minimization(&mut self, x: &[f64], b: &Bounds) -> bool {
        let (mem, w) = (&self.mem, &mut self.w);
        let (n, col, theta) = (x.len(), mem.col, mem.theta);
        let (mut nfree, mut nact) = (0, 0);
        for i in 0..n {
            if w.iwhere[i] <= 0 {
                w.index[nfree] = i;
                nfree += 1;
            } else {
                nact += 1;
                w.index[n - nact] = i;
            }
        }
        if nfree == 0 || col == 0 {
            return true; // x̄ = x^c
        }
        let (free, active) = w.index.split_at(nfree);
        let col2 = 2 * col;
        // Negative reduced gradient: r = -Zᵀ(g + θ(x^c - x) - W M c).
        mem.bmv(&w.c[..col2], &mut w.v[..col2]);
        for (ri, &k) in w.r.iter_mut().zip(free) {
            *ri = -theta * (w.xcp[k] - x[k]) - w.g[k] + mem.w_times(k, &w.v[..col2]);
        }
        // K = [ -D - YᵀZZᵀY/θ   L_aᵀ - R_zᵀ ]  L_a: strict lower triangle of SᵀAAᵀY,
        //     [ L_a - R_z       θSᵀAAᵀS     ]  R_z: upper triangle (with diagonal) of SᵀZZᵀY.
        // Store A11 = D + YᵀZZᵀY/θ and C = θSᵀAAᵀS (lower triangles) and E = -(L_a - R_z)ᵀ.
        let (ld, kf) = (2 * mem.m, &mut w.kf);
        for a in 0..col {
            for c in 0..col {
                if c <= a {
                    let diag = if a == c { mem.sy[a * mem.m + a] } else { 0.0 };
                    kf[a * ld + c] = diag + dot_on(free, mem.y(a), mem.y(c)) / theta;
                    kf[(col + a) * ld + col + c] = theta * dot_on(active, mem.s(a), mem.s(c));
                }
                kf[a * ld + col + c] = if c > a {
                    -dot_on(active, mem.s(c), mem.y(a))
                } else {
                    dot_on(free, mem.s(c), mem.y(a))
                };
            }
        }
        if !factor_k(kf, ld, col, &mut w.tmp) {
            return false;
        }
        // wv = WᵀZr; wv ← K⁻¹wv; d^u = θ⁻¹r + θ⁻²ZᵀW wv.
        let wv = &mut w.wbp[..col2];
        for j in 0..col {
            wv[j] = dot_on_dense(free, mem.y(j), &w.r);
            wv[col + j] = theta * dot_on_dense(free, mem.s(j), &w.r);
        }
        solve_k(kf, ld, col, wv);
        for (ri, &k) in w.r.iter_mut().zip(free) {
            *ri = (*ri + mem.w_times(k, wv) / theta) / theta;
        }
        // Backtrack: α* = max{α <= 1 : l <= x^c + α d^u <= u} (the first bound met).
        let (mut alpha, mut ibd) = (1.0, None);
        for (ii, &k) in free.iter().enumerate() {
            let dk = w.r[ii];
            let room = if dk < 0.0 && w.has_lower[k] {
                b.lower[k] - w.xcp[k]
            } else if dk > 0.0 && w.has_upper[k] {
                b.upper[k] - w.xcp[k]
            } else {
                continue;
            };
            let limit = if room * dk <= 0.0 { 0.0 } else { room / dk };
            if limit < alpha {
                (alpha, ibd) = (limit, Some(ii));
            }
        }
        if let (true, Some(ii)) = (alpha < 1.0, ibd) {
            // Land the blocking variable exactly on its bound.
            let k = free[ii];
            w.xcp[k] = if w.r[ii] > 0.0 {
                b.upper[k]
            } else {
                b.lower[k]
            };
            w.r[ii] = 0.0;
        }
        for (ri, &k) in w.r.iter().zip(free) {
            w.xcp[k] += alpha * ri;
        }
        true
    }

    /// Line search along `d` (Moré–Thuente, strong Wolfe with `μ = 1e-3`, `η = 0.9`). The step
    /// is capped so that `x + λd` stays in the box; the first iteration of a problem that is
    /// not fully boxed tries `λ = 1/‖d‖`, later ones the quasi-Newton step `λ = 1` (reference
    /// `lnsrlb`). A trial with non-finite `f` or gradient moves the cap halfway back towards the
    /// best step so far and restarts the search below it. Returns the new `f` (with `x`, `g`
    /// updated) or `None` on failure (`x_old`, `g_old` then hold the previous iterate).
    fn line_search(
        &mut self,
        x: &mut [f64],
        b: &Bounds,
        first: bool,
        f0: f64,
        fg: &mut impl FnMut(&[f64], &mut [f64]) -> f64,
    ) -> Option<f64> {
        let w = &mut self.w;
        w.x_old.copy_from_slice(x);
        w.g_old.copy_from_slice(&w.g);
        let mut stpmax = if b.constrained && first {
            1.0
        } else {
            BIG_STEP
        };
        if b.constrained && !first {
            for (i, &di) in w.d.iter().enumerate() {
                let room = if di < 0.0 && w.has_lower[i] {
                    b.lower[i] - x[i]
                } else if di > 0.0 && w.has_upper[i] {
                    b.upper[i] - x[i]
                } else {
                    continue;
                };
                stpmax = if room * di <= 0.0 {
                    0.0
                } else {
                    stpmax.min(room / di)
                };
            }
        }
        let mut stp = if first && !b.boxed {
            (1.0 / dot(&w.d, &w.d).sqrt()).min(stpmax)
        } else {
            stpmax.min(1.0)
        };
        let gd0 = dot(&w.g, &w.d);
        if !(gd0 < 0.0 && stp > 0.0) {
            return None; // not a descent direction (or no room): the caller restarts
        }
        let mut search = MoreThuente::start(f0, gd0, stp, stpmax);
        for _ in 0..self.options.max_line_search {
            if stp == 1.0 {
                x.copy_from_slice(&w.xcp); // lands exactly on the bounds hit by x̄
            } else {
                for (i, xi) in x.iter_mut().enumerate() {
                    // The clamp only guards against rounding: stp <= stpmax keeps x feasible.
                    *xi = (w.x_old[i] + stp * w.d[i]).max(b.lower[i]).min(b.upper[i]);
                }
            }
            let f = fg(x, &mut w.g);
            w.evaluations += 1;
            if !f.is_finite() || !all_finite(&w.g) {
                stp = search.stx + 0.5 * (stp - search.stx);
                search = MoreThuente::start(f0, gd0, stp, stp);
                continue;
            }
            match search.iterate(f, dot(&w.g, &w.d), &mut stp) {
                LsTask::Evaluate => {}
                LsTask::Converged => return Some(f),
                // Interval too small / step at a limit: accept unless f went up (the reference
                // code accepts even then and reports convergence).
                LsTask::Warning => return (f <= f0).then_some(f),
            }
        }
        None
    }
}

/// Factor `K = Uᵀ diag(-I, I) U`, `U = [[L1ᵀ, L1⁻¹E], [0, L2ᵀ]]`, from `A11 = L1L1ᵀ` (always
/// positive definite) and the Schur complement `C + EᵀA11⁻¹E = L2L2ᵀ` (positive definite iff
/// `K` is nonsingular). Returns false if either Cholesky factorization breaks down.
fn factor_k(kf: &mut [f64], ld: usize, col: usize, tmp: &mut [f64]) -> bool {
    if !cholesky(kf, ld, col) {
        return false;
    }
    for j in 0..col {
        (0..col).for_each(|i| tmp[i] = kf[i * ld + col + j]);
        solve_lower(kf, ld, col, &mut tmp[..col]);
        (0..col).for_each(|i| kf[i * ld + col + j] = tmp[i]);
    }
    for a in 0..col {
        for c in 0..=a {
            let e: f64 = (0..col)
                .map(|i| kf[i * ld + col + a] * kf[i * ld + col + c])
                .sum();
            kf[(col + a) * ld + col + c] += e;
        }
    }
    cholesky(&mut kf[col * ld + col..], ld, col)
}

/// `wv ← K⁻¹wv = U⁻¹ diag(-I, I) U⁻ᵀ wv` with the factors of [`factor_k`].
fn solve_k(kf: &[f64], ld: usize, col: usize, wv: &mut [f64]) {
    let l2 = &kf[col * ld + col..];
    let (w1, w2) = wv.split_at_mut(col);
    solve_lower(kf, ld, col, w1);
    for j in 0..col {
        w2[j] -= (0..col).map(|i| kf[i * ld + col + j] * w1[i]).sum::<f64>();
    }
    solve_lower(l2, ld, col, w2);
    w1.iter_mut().for_each(|v| *v = -*v);
    solve_lower_transposed(l2, ld, col, w2);
    for i in 0..col {
        w1[i] -= (0..col).map(|j| kf[i * ld + col + j] * w2[j]).sum::<f64>();
    }
    solve_lower_transposed(kf, ld, col, w1);
}

/// In-place Cholesky `A = LLᵀ` of the leading `k × k` block (row-major, leading dimension
/// `ld`, lower triangle read and written). Returns false if `A` is not positive definite.
fn cholesky(a: &mut [f64], ld: usize, k: usize) -> bool {
    for j in 0..k {
        let s = a[j * ld + j] - (0..j).map(|q| a[j * ld + q].powi(2)).sum::<f64>();
        if s.is_nan() || s <= 0.0 {
            return false;
        }
        a[j * ld + j] = s.sqrt();
        for i in j + 1..k {
            let s = a[i * ld + j] - (0..j).map(|q| a[i * ld + q] * a[j * ld + q]).sum::<f64>();
            a[i * ld + j] = s / a[j * ld + j];
        }
    }
    true
}

/// Solve `Lx = b` in place.
fn solve_lower(l: &[f64], ld: usize, k: usize, b: &mut [f64]) {
    for i in 0..k {
        let s: f64 = (0..i).map(|q| l[i * ld + q] * b[q]).sum();
        b[i] = (b[i] - s) / l[i * ld + i];
    }
}

/// Solve `Lᵀx = b` in place.
fn solve_lower_transposed(l: &[f64], ld: usize, k: usize, b: &mut [f64]) {
    for i in (0..k).rev() {
        let s: f64 = (i + 1..k).map(|q| l[q * ld + i] * b[q]).sum();
        b[i] = (b[i] - s) / l[i * ld + i];
    }
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// `Σ_{k ∈ set} a_k b_k`.
fn dot_on(set: &[usize], a: &[f64], b: &[f64]) -> f64 {
    set.iter().map(|&k| a[k] * b[k]).sum()
}

/// `Σ_i a_{set_i} r_i` for `r` stored compactly over `set`.
fn dot_on_dense(set: &[usize], a: &[f64], r: &[f64]) -> f64 {
    set.iter().zip(r).map(|(&k, ri)| a[k] * ri).sum()
}

fn all_finite(v: &[f64]) -> bool {
    v.iter().all(|x| x.is_finite())
}

enum LsTask {
    Evaluate,
    Converged,
    Warning,
}

/// Moré–Thuente line search (MINPACK-2 `dcsrch`/`dcstep`, as used by the reference code):
/// finds `λ` with `φ(λ) <= φ(0) + μλφ'(0)` and `|φ'(λ)| <= η|φ'(0)|` by safeguarded
/// cubic/quadratic interpolation on an interval of uncertainty `[stx, sty]`.
struct MoreThuente {
    bracketed: bool,
    stage1: bool,
    finit: f64,
    ginit: f64,
    gtest: f64,
    width: f64,
    width1: f64,
    stx: f64,
    fx: f64,
    gx: f64,
    sty: f64,
    fy: f64,
    gy: f64,
    stmin: f64,
    stmax: f64,
    stpmax: f64,
}

impl MoreThuente {
    fn start(finit: f64, ginit: f64, stp: f64, stpmax: f64) -> Self {
        Self {
            bracketed: false,
            stage1: true,
            finit,
            ginit,
            gtest: LS_FTOL * ginit,
            width: stpmax,
            width1: 2.0 * stpmax,
            stx: 0.0,
            fx: finit,
            gx: ginit,
            sty: 0.0,
            fy: finit,
            gy: ginit,
            stmin: 0.0,
            stmax: 5.0 * stp,
            stpmax,
        }
    }

    /// Feed `φ(stp) = f`, `φ'(stp) = g`; on `Evaluate`, `stp` holds the next trial step.
    fn iterate(&mut self, f: f64, g: f64, stp: &mut f64) -> LsTask {
        let s = *stp;
        let ftest = self.finit + s * self.gtest;
        if self.stage1 && f <= ftest && g >= 0.0 {
            self.stage1 = false;
        }
        if f <= ftest && g.abs() <= LS_GTOL * -self.ginit {
            return LsTask::Converged;
        }
        let (lo, hi) = (self.stmin, self.stmax);
        if (self.bracketed && (s <= lo || s >= hi || hi - lo <= LS_XTOL * hi))
            || (s == self.stpmax && f <= ftest && g <= self.gtest)
            || (s == 0.0 && (f > ftest || g >= self.gtest))
        {
            return LsTask::Warning;
        }
        // Stage 1 with a lower but not sufficiently lower f: interpolate the modified function
        // ψ(λ) = φ(λ) - φ(0) - μλφ'(0) instead of φ.
        let mut next = if self.stage1 && f <= self.fx && f > ftest {
            let gt = self.gtest;
            self.shift(-gt);
            let next = self.cstep(s, f - s * gt, g - gt);
            self.shift(gt);
            next
        } else {
            self.cstep(s, f, g)
        };
        if self.bracketed {
            if (self.sty - self.stx).abs() >= 0.66 * self.width1 {
                next = self.stx + 0.5 * (self.sty - self.stx); // force sufficient shrinkage
            }
            self.width1 = self.width;
            self.width = (self.sty - self.stx).abs();
            (self.stmin, self.stmax) = (self.stx.min(self.sty), self.stx.max(self.sty));
        } else {
            self.stmin = next + 1.1 * (next - self.stx);
            self.stmax = next + 4.0 * (next - self.stx);
        }
        next = next.max(0.0).min(self.stpmax);
        let (lo, hi) = (self.stmin, self.stmax);
        if self.bracketed && (next <= lo || next >= hi || hi - lo <= LS_XTOL * hi) {
            next = self.stx; // no further progress possible: fall back to the best step
        }
        *stp = next;
        LsTask::Evaluate
    }

    /// Add `λ·gt` to the stored function values and `gt` to the derivatives.
    fn shift(&mut self, gt: f64) {
        self.fx += self.stx * gt;
        self.fy += self.sty * gt;
        self.gx += gt;
        self.gy += gt;
    }

    /// Safeguarded step (`dcstep`): update the interval `[stx, sty]` with the trial
    /// `(stp, fp, dp)` and return the next trial step.
    fn cstep(&mut self, stp: f64, fp: f64, dp: f64) -> f64 {
        let (stx, fx, dx, sty, fy, dy) = (self.stx, self.fx, self.gx, self.sty, self.fy, self.gy);
        let (stpmin, stpmax) = (self.stmin, self.stmax);
        let sgnd = dp * (dx / dx.abs());
        let stpf = if fp > fx {
            // Case 1: higher f, minimizer bracketed. Cubic step if closer to stx than the
            // quadratic step, else their average.
            let stpc = stx + cubic(stx, fx, dx, stp, fp, dp).0 * (stp - stx);
            let stpq = stx + ((dx / ((fx - fp) / (stp - stx) + dx)) / 2.0) * (stp - stx);
            self.bracketed = true;
            if (stpc - stx).abs() < (stpq - stx).abs() {
                stpc
            } else {
                stpc + (stpq - stpc) / 2.0
            }
        } else if sgnd < 0.0 {
            // Case 2: lower f, derivatives of opposite sign: bracketed; farther of cubic/secant.
            let stpc = stp + cubic(stp, fp, dp, stx, fx, dx).0 * (stx - stp);
            let stpq = stp + (dp / (dp - dx)) * (stx - stp);
            self.bracketed = true;
            if (stpc - stp).abs() > (stpq - stp).abs() {
                stpc
            } else {
                stpq
            }
        } else if dp.abs() < dx.abs() {
            // Case 3: lower f, same sign, |derivative| decreases. The cubic step is used only
            // if the cubic tends to infinity in the step direction.
            let (r, gamma) = cubic(stp, fp, dp, stx, fx, dx);
            let stpc = match (r < 0.0 && gamma != 0.0, stp > stx) {
                (true, _) => stp + r * (stx - stp),
                (false, true) => stpmax,
                (false, false) => stpmin,
            };
            let stpq = stp + (dp / (dp - dx)) * (stx - stp);
            let (dc, dq) = ((stpc - stp).abs(), (stpq - stp).abs());
            if self.bracketed {
                let t = if dc < dq { stpc } else { stpq };
                let lim = stp + 0.66 * (sty - stp);
                if stp > stx {
                    t.min(lim)
                } else {
                    t.max(lim)
                }
            } else {
                let t = if dc > dq { stpc } else { stpq };
                t.min(stpmax).max(stpmin)
            }
        } else if self.bracketed {
            // Case 4: lower f, same sign, |derivative| does not decrease: cubic with sty.
            stp + cubic(stp, fp, dp, sty, fy, dy).0 * (sty - stp)
        } else if stp > stx {
            stpmax
        } else {
            stpmin
        };
        // Update the interval of uncertainty.
        if fp > fx {
            (self.sty, self.fy, self.gy) = (stp, fp, dp);
        } else {
            if sgnd < 0.0 {
                (self.sty, self.fy, self.gy) = (stx, fx, dx);
            }
            (self.stx, self.fx, self.gx) = (stp, fp, dp);
        }
        stpf
    }
}

/// Cubic interpolating `(u, fu, du)` and `(v, fv, dv)` (the `theta`/`gamma` of `dcstep`):
/// returns `(r, γ)` where `u + r(v - u)` is the cubic's minimizer.
fn cubic(u: f64, fu: f64, du: f64, v: f64, fv: f64, dv: f64) -> (f64, f64) {
    let theta = 3.0 * (fu - fv) / (v - u) + du + dv;
    let s = theta.abs().max(du.abs()).max(dv.abs());
    let gamma = s * ((theta / s).powi(2) - (du / s) * (dv / s)).max(0.0).sqrt();
    let gamma = if v < u { -gamma } else { gamma };
    let p = (gamma - du) + theta;
    let q = ((gamma - du) + gamma) + dv;
    (p / q, gamma)
}

#[cfg(test)]
mod tests {
    use super::*;

    const INF: f64 = f64::INFINITY;

    /// Tight tolerances for accuracy tests (the defaults stop at ‖Pg‖∞ <= 1e-5 or earlier).
    fn tight() -> LbfgsbOptions {
        LbfgsbOptions {
            pgtol: 1e-10,
            ftol: 0.0,
            ..LbfgsbOptions::default()
        }
    }

    fn rosenbrock(x: &[f64], g: &mut [f64]) -> f64 {
        let (a, b) = (x[0], x[1]);
        g[0] = -400.0 * a * (b - a * a) - 2.0 * (1.0 - a);
        g[1] = 200.0 * (b - a * a);
        100.0 * (b - a * a).powi(2) + (1.0 - a).powi(2)
    }

    /// Extended Rosenbrock (Moré–Garbow–Hillstrom): independent pairs, start (-1.2, 1, ...).
    fn extended_rosenbrock(x: &[f64], g: &mut [f64]) -> f64 {
        (0..x.len())
            .step_by(2)
            .map(|i| rosenbrock(&x[i..i + 2], &mut g[i..i + 2]))
            .sum()
    }

    fn extended_start(n: usize) -> Vec<f64> {
        (0..n)
            .map(|i| if i % 2 == 0 { -1.2 } else { 1.0 })
            .collect()
    }

    /// The problem of `driver1.f` in the L-BFGS-B distribution.
    fn driver1(x: &[f64], g: &mut [f64]) -> f64 {
        let n = x.len();
        let mut f = 0.25 * (x[0] - 1.0).powi(2);
        for i in 1..n {
            f += (x[i] - x[i - 1].powi(2)).powi(2);
        }
        let mut t1 = x[1] - x[0].powi(2);
        g[0] = 2.0 * (x[0] - 1.0) - 16.0 * x[0] * t1;
        for i in 1..n - 1 {
            let t2 = t1;
            t1 = x[i + 1] - x[i].powi(2);
            g[i] = 8.0 * t2 - 16.0 * x[i] * t1;
        }
        g[n - 1] = 8.0 * t1;
        4.0 * f
    }

    fn projected_gradient(x: &[f64], g: &[f64], l: &[f64], u: &[f64]) -> f64 {
        let pg = |i: usize| ((x[i] - g[i]).max(l[i]).min(u[i]) - x[i]).abs();
        (0..x.len()).map(pg).fold(0.0, f64::max)
    }

    /// Deterministic pseudo-random numbers in [-1, 1).
    struct Rng(u64);
    impl Rng {
        fn next(&mut self) -> f64 {
            self.0 = self
                .0
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((self.0 >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
        }
        fn vec(&mut self, n: usize) -> Vec<f64> {
            (0..n).map(|_| self.next()).collect()
        }
    }

    fn matvec(a: &[f64], v: &[f64]) -> Vec<f64> {
        let n = v.len();
        (0..n).map(|i| dot(&a[i * n..(i + 1) * n], v)).collect()
    }

    /// Gaussian elimination with partial pivoting.
    fn solve_dense(mut a: Vec<f64>, mut b: Vec<f64>) -> Vec<f64> {
        let n = b.len();
        for k in 0..n {
            let p = (k..n).max_by(|&i, &j| a[i * n + k].abs().total_cmp(&a[j * n + k].abs()));
            let p = p.unwrap();
            (0..n).for_each(|j| a.swap(k * n + j, p * n + j));
            b.swap(k, p);
            for i in k + 1..n {
                let f = a[i * n + k] / a[k * n + k];
                (k..n).for_each(|j| a[i * n + j] -= f * a[k * n + j]);
                b[i] -= f * b[k];
            }
        }
        for k in (0..n).rev() {
            let s: f64 = (k + 1..n).map(|j| a[k * n + j] * b[j]).sum();
            b[k] = (b[k] - s) / a[k * n + k];
        }
        b
    }

    type Pair = (Vec<f64>, Vec<f64>);

    /// Dense BFGS matrix by the textbook recursion `B ← B - Bssᵀ B/sᵀBs + yyᵀ/yᵀs` from
    /// `B = θI` over the given pairs; the compact form (paper, section 3) must reproduce it.
    fn dense_bfgs(pairs: &[Pair], theta: f64) -> Vec<f64> {
        let n = pairs[0].0.len();
        let mut b: Vec<f64> = (0..n * n)
            .map(|ij| if ij % (n + 1) == 0 { theta } else { 0.0 })
            .collect();
        for (s, y) in pairs {
            let bs = matvec(&b, s);
            let (sbs, ys) = (dot(s, &bs), dot(y, s));
            for ij in 0..n * n {
                b[ij] += y[ij / n] * y[ij % n] / ys - bs[ij / n] * bs[ij % n] / sbs;
            }
        }
        b
    }

    /// Dense `B = θI - W M Wᵀ` assembled column by column through `bmv`.
    fn compact_b(mem: &Memory) -> Vec<f64> {
        let (n, col) = (mem.n, mem.col);
        let (mut b, mut row, mut mv) = (vec![0.0; n * n], vec![0.0; 2 * col], vec![0.0; 2 * col]);
        for i in 0..n {
            for j in 0..col {
                (row[j], row[col + j]) = (mem.y(j)[i], mem.theta * mem.s(j)[i]);
            }
            mem.bmv(&row, &mut mv);
            for k in 0..n {
                b[k * n + i] = if k == i { mem.theta } else { 0.0 } - mem.w_times(k, &mv);
            }
        }
        b
    }

    /// Workspace whose memory holds `npairs` pairs (`y = As + noise`, A SPD), and those pairs.
    fn with_pairs(rng: &mut Rng, n: usize, m: usize, npairs: usize) -> (Lbfgsb, Vec<Pair>) {
        let opts = LbfgsbOptions {
            memory: m,
            ..LbfgsbOptions::default()
        };
        let mut s = Lbfgsb::new(n, opts);
        let a: Vec<f64> = (0..n * n)
            .map(|ij| if ij % (n + 1) == 0 { 2.0 } else { 0.0 } + 0.3 * rng.next())
            .collect();
        let mut pairs = Vec::new();
        for _ in 0..npairs {
            let sv = rng.vec(n);
            let y: Vec<f64> = matvec(&a, &sv)
                .iter()
                .zip(rng.vec(n))
                .map(|(v, e)| v + 0.1 * e)
                .collect();
            assert!(dot(&sv, &y) > 0.0);
            s.mem.push(&sv, &y);
            pairs.push((sv, y));
        }
        (s, pairs)
    }

    #[test]
    fn compact_representation_matches_bfgs_recursion() {
        let mut rng = Rng(7);
        for npairs in [1, 2, 3, 5, 8] {
            let (s, pairs) = with_pairs(&mut rng, 7, 3, npairs);
            let kept = &pairs[npairs.saturating_sub(3)..];
            assert_eq!(s.mem.col, kept.len());
            let (sl, yl) = kept.last().unwrap();
            let dense = dense_bfgs(kept, dot(yl, yl) / dot(sl, yl));
            let compact = compact_b(&s.mem);
            let scale = dense.iter().fold(0.0, |a: f64, v| a.max(v.abs()));
            for (c, d) in compact.iter().zip(&dense) {
                assert!((c - d).abs() < 1e-12 * scale, "{npairs} pairs: {c} vs {d}");
            }
        }
    }

    /// First local minimizer of `gᵀz + ½zᵀBz`, `z = P(x - tg) - x`, segment by segment.
    fn dense_cauchy_point(x: &[f64], g: &[f64], l: &[f64], u: &[f64], b: &[f64]) -> Vec<f64> {
        let n = x.len();
        let brk = |i: usize| match g[i] {
            gi if gi < 0.0 => (x[i] - u[i]) / gi,
            gi if gi > 0.0 => (x[i] - l[i]) / gi,
            _ => INF,
        };
        let path = |t: f64| -> Vec<f64> {
            (0..n)
                .map(|i| (x[i] - t * g[i]).max(l[i]).min(u[i]))
                .collect()
        };
        let mut ts: Vec<f64> = (0..n)
            .map(brk)
            .filter(|t| *t > 0.0 && t.is_finite())
            .collect();
        ts.sort_by(f64::total_cmp);
        ts.push(INF);
        let mut t0 = 0.0;
        for t1 in ts {
            let z: Vec<f64> = path(t0).iter().zip(x).map(|(p, xi)| p - xi).collect();
            let d: Vec<f64> = (0..n)
                .map(|i| if brk(i) > t0 { -g[i] } else { 0.0 })
                .collect();
            let bd = matvec(b, &d);
            let (f1, f2) = (dot(g, &d) + dot(&z, &bd), dot(&d, &bd));
            if f1 >= 0.0 {
                return path(t0);
            }
            if t0 - f1 / f2 < t1 {
                return path(t0 - f1 / f2);
            }
            t0 = t1;
        }
        unreachable!()
    }

    #[test]
    fn cauchy_point_and_subspace_step_match_dense_computation() {
        let mut rng = Rng(99);
        let n = 6;
        let (mut passed_breakpoints, mut backtracked, mut checked_subspace) = (0, 0, 0);
        for trial in 0..60 {
            let (mut s, _) = with_pairs(&mut rng, n, 3, 1 + trial % 5);
            let b = compact_b(&s.mem);
            let l: Vec<f64> = (0..n)
                .map(|i| {
                    if i == 5 {
                        -INF
                    } else {
                        -0.2 - 0.5 * rng.next().abs()
                    }
                })
                .collect();
            let u: Vec<f64> = (0..n)
                .map(|i| {
                    if i == 4 {
                        INF
                    } else {
                        0.2 + 0.5 * rng.next().abs()
                    }
                })
                .collect();
            let mut x: Vec<f64> = (0..n)
                .map(|i| 0.2 * rng.next() * (i as f64 + 1.0))
                .collect();
            x[0] = l[0]; // at a bound: active or free depending on the sign of g_0
            let g: Vec<f64> = rng.vec(n).iter().map(|v| 3.0 * v).collect();
            let bounds = s.prepare_bounds(&mut x, &l, &u);
            s.w.g.copy_from_slice(&g);
            s.cauchy_point(&x, &bounds, 1.0);
            let expect = dense_cauchy_point(&x, &g, &l, &u, &b);
            for i in 0..n {
                assert!(
                    (s.w.xcp[i] - expect[i]).abs() < 1e-10,
                    "trial {trial}: {:?} vs {expect:?}",
                    s.w.xcp
                );
            }
            passed_breakpoints += (1..n).any(|i| s.w.xcp[i] == l[i] || s.w.xcp[i] == u[i]) as usize;
            // c = Wᵀ(x^c - x), as maintained incrementally by the breakpoint search.
            let z: Vec<f64> = (0..n).map(|i| s.w.xcp[i] - x[i]).collect();
            for j in 0..s.mem.col {
                assert!((s.w.c[j] - dot(s.mem.y(j), &z)).abs() < 1e-10);
                assert!((s.w.c[s.mem.col + j] - s.mem.theta * dot(s.mem.s(j), &z)).abs() < 1e-10);
            }
            // Subspace step: dense reduced Newton step from x^c, then backtracking into the box.
            let free: Vec<usize> = (0..n).filter(|&i| s.w.iwhere[i] <= 0).collect();
            let bz = matvec(&b, &z);
            let rhs: Vec<f64> = free.iter().map(|&i| -(g[i] + bz[i])).collect();
            let red: Vec<f64> = free
                .iter()
                .flat_map(|&i| free.iter().map(move |&j| (i, j)))
                .map(|(i, j)| b[i * n + j])
                .collect();
            let du = if free.is_empty() {
                vec![]
            } else {
                solve_dense(red, rhs)
            };
            let mut alpha: f64 = 1.0;
            for (k, &i) in free.iter().enumerate().filter(|(k, _)| du[*k] != 0.0) {
                let bound = if du[k] > 0.0 { u[i] } else { l[i] };
                alpha = alpha.min(((bound - expect[i]) / du[k]).max(0.0));
            }
            let mut expect = expect.clone();
            free.iter()
                .zip(&du)
                .for_each(|(&i, d)| expect[i] += alpha * d);
            assert!(s.subspace_minimization(&x, &bounds));
            for i in 0..n {
                assert!(
                    (s.w.xcp[i] - expect[i]).abs() < 1e-9,
                    "trial {trial}: {:?} vs {expect:?}",
                    s.w.xcp
                );
            }
            backtracked += (alpha < 1.0) as usize;
            checked_subspace += !free.is_empty() as usize;
        }
        // The random cases must exercise the interesting branches.
        let coverage = (passed_breakpoints, backtracked, checked_subspace);
        assert!(
            coverage.0 > 5 && coverage.1 > 5 && coverage.2 > 30,
            "{coverage:?}"
        );
    }

    #[test]
    fn rosenbrock_2d_unconstrained() {
        let mut x = [-1.2, 1.0];
        let res = Lbfgsb::new(2, tight()).minimize(&mut x, &[-INF; 2], &[INF; 2], rosenbrock);
        assert!(res.converged(), "{res:?}");
        assert!(
            (x[0] - 1.0).abs() < 1e-6 && (x[1] - 1.0).abs() < 1e-6,
            "{x:?}"
        );
    }

    #[test]
    fn rosenbrock_2d_iteration_count() {
        // SciPy 1.17 (L-BFGS-B 3.0): 36 iterations, 44 evaluations, f = 2.8076e-12.
        let mut x = [-1.2, 1.0];
        let mut s = Lbfgsb::new(2, LbfgsbOptions::default());
        let res = s.minimize(&mut x, &[-INF; 2], &[INF; 2], rosenbrock);
        assert!(res.converged() && res.iterations < 60, "{res:?}");
        assert!(res.f < 1e-10 && res.evaluations < 80, "{res:?}");
    }

    #[test]
    fn extended_rosenbrock_10d() {
        let mut x = extended_start(10);
        let mut s = Lbfgsb::new(10, tight());
        let res = s.minimize(&mut x, &[-INF; 10], &[INF; 10], extended_rosenbrock);
        assert!(res.converged(), "{res:?}");
        assert!(x.iter().all(|v| (v - 1.0).abs() < 1e-6), "{x:?}");
    }

    #[test]
    fn diagonal_quadratic_with_active_bounds() {
        // f = ½ Σ a_i (x_i - c_i)²; the minimizer over the box is clamp(c, l, u).
        let a = [1.0, 10.0, 0.5, 100.0, 3.0, 2.0];
        let c = [2.0, -3.0, 0.5, 4.0, -1.0, 7.0];
        let l = [-1.0, -1.0, -INF, 0.0, -5.0, 7.0];
        let u = [1.0, 1.0, 0.0, INF, 5.0, 7.0]; // x_5 fixed (l == u)
        let mut x = [0.3, 0.0, -2.0, 1.0, 4.0, 7.0];
        let res = Lbfgsb::new(6, tight()).minimize(&mut x, &l, &u, |x, g| {
            (0..6)
                .map(|i| {
                    g[i] = a[i] * (x[i] - c[i]);
                    0.5 * a[i] * (x[i] - c[i]).powi(2)
                })
                .sum()
        });
        assert!(res.converged(), "{res:?}");
        for i in 0..6 {
            assert!(
                (x[i] - c[i].max(l[i]).min(u[i])).abs() < 1e-8,
                "i={i} x={x:?}"
            );
        }
        // Bounds active at the solution are hit exactly.
        assert_eq!((x[0], x[1], x[2], x[5]), (1.0, -1.0, 0.0, 7.0));
    }

    #[test]
    fn spd_quadratic_with_bounds_matches_projected_gradient_reference() {
        // f = ½xᵀAx - bᵀx with A = BᵀB + I from a fixed pseudo-random B.
        let n = 8;
        let mut rng = Rng(12345);
        let bm = rng.vec(n * n);
        let mut a: Vec<f64> = (0..n * n)
            .map(|ij| {
                (0..n)
                    .map(|k| bm[k * n + ij / n] * bm[k * n + ij % n])
                    .sum()
            })
            .collect();
        (0..n).for_each(|i| a[i * n + i] += 1.0);
        let b: Vec<f64> = rng.vec(n).iter().map(|v| 4.0 * v).collect();
        let l = vec![-0.5; n];
        let u: Vec<f64> = (0..n).map(|i| if i % 3 == 0 { INF } else { 0.7 }).collect();
        let quad = |x: &[f64], g: &mut [f64]| {
            (0..n)
                .map(|i| {
                    g[i] = (0..n).map(|j| a[i * n + j] * x[j]).sum::<f64>() - b[i];
                    0.5 * x[i] * (g[i] - b[i])
                })
                .sum::<f64>()
        };
        // Reference: projected gradient with step 1/L (L = Gershgorin bound on λ_max).
        let lip = (0..n)
            .map(|i| (0..n).map(|j| a[i * n + j].abs()).sum())
            .fold(0.0, f64::max);
        let (mut xr, mut gr) = (vec![0.0; n], vec![0.0; n]);
        for _ in 0..200_000 {
            quad(&xr, &mut gr);
            (0..n).for_each(|i| xr[i] = (xr[i] - gr[i] / lip).max(l[i]).min(u[i]));
        }
        quad(&xr, &mut gr);
        assert!(projected_gradient(&xr, &gr, &l, &u) < 1e-12);
        let active = (0..n).filter(|&i| xr[i] == l[i] || xr[i] == u[i]).count();
        assert!(
            (2..n - 1).contains(&active),
            "want a mix of active and free: {xr:?}"
        );

        let mut x = vec![0.1; n];
        let res = Lbfgsb::new(n, tight()).minimize(&mut x, &l, &u, quad);
        assert!(res.converged(), "{res:?}");
        for i in 0..n {
            assert!((x[i] - xr[i]).abs() < 1e-8, "i={i}: {x:?} vs {xr:?}");
        }
    }

    #[test]
    fn driver1_bounded_rosenbrock_25() {
        let n = 25;
        let l: Vec<f64> = (0..n)
            .map(|i| if i % 2 == 0 { 1.0 } else { -100.0 })
            .collect();
        let u = vec![100.0; n];
        // driver1 settings (m = 5, factr = 1e7, pgtol = 1e-5). SciPy: 23 iterations, 28
        // evaluations, f = 1.08e-9, stopping on the f-decrease test with ‖Pg‖∞ = 1.7e-4.
        let mut x = vec![3.0; n];
        let opts = LbfgsbOptions {
            memory: 5,
            ..LbfgsbOptions::default()
        };
        let res = Lbfgsb::new(n, opts).minimize(&mut x, &l, &u, driver1);
        assert!(
            res.converged() && res.f < 1e-8 && res.iterations < 40,
            "{res:?}"
        );
        // With the f-decrease test off, the KKT test decides (SciPy: 28 iterations).
        let mut x = vec![3.0; n];
        let opts = LbfgsbOptions { ftol: 0.0, ..opts };
        let res = Lbfgsb::new(n, opts).minimize(&mut x, &l, &u, driver1);
        assert_eq!(res.stop, LbfgsbStop::ProjectedGradient, "{res:?}");
        let mut g = vec![0.0; n];
        assert_eq!(driver1(&x, &mut g), res.f);
        assert!(projected_gradient(&x, &g, &l, &u) < 1e-5, "{res:?}");
        assert!((0..n).all(|i| l[i] <= x[i] && x[i] <= u[i]));
        // (x itself is ill-determined: x_i ≈ x_{i-1}² amplifies errors along the chain.)
        assert!(res.f < 1e-9, "{res:?}");
    }

    #[test]
    fn nan_region_beyond_three() {
        let mut x = [2.9];
        let res = Lbfgsb::new(1, tight()).minimize(&mut x, &[-INF], &[INF], |x, g| {
            let (f, d) = if x[0] < 3.0 {
                ((x[0] - 1.0).powi(2), 2.0 * (x[0] - 1.0))
            } else {
                (f64::NAN, f64::NAN)
            };
            g[0] = d;
            f
        });
        assert!(res.converged(), "{res:?}");
        assert!((x[0] - 1.0).abs() < 1e-6, "{x:?}");
    }

    #[test]
    fn nan_region_hit_by_line_search_is_stepped_back_from() {
        // sqrt(1 + x²) has a nearly constant slope far from 0, so the first line search
        // extrapolates (x = 9, 5, -11) into the NaN region x < -8 before bracketing.
        let mut nan_calls = 0;
        let mut x = [10.0];
        let res = Lbfgsb::new(1, tight()).minimize(&mut x, &[-INF], &[INF], |x, g| {
            if x[0] < -8.0 {
                nan_calls += 1;
                g[0] = f64::NAN;
                return f64::INFINITY;
            }
            let r = (1.0 + x[0] * x[0]).sqrt();
            g[0] = x[0] / r;
            r
        });
        assert!(res.converged() && x[0].abs() < 1e-6, "{x:?} {res:?}");
        assert!(nan_calls > 0, "test did not reach the NaN region");
    }

    #[test]
    fn non_finite_at_start() {
        let mut x = [1.0, 2.0];
        let mut s = Lbfgsb::new(2, LbfgsbOptions::default());
        let res = s.minimize(&mut x, &[-INF; 2], &[INF; 2], |_, g| {
            g.fill(0.0);
            f64::NAN
        });
        assert_eq!(
            (res.stop, res.evaluations, res.converged()),
            (LbfgsbStop::NonFinite, 1, false)
        );
    }

    #[test]
    fn max_iterations_and_workspace_reuse() {
        let opts = LbfgsbOptions {
            max_iterations: 3,
            ..LbfgsbOptions::default()
        };
        let mut s = Lbfgsb::new(2, opts);
        let mut x = [-1.2, 1.0];
        let res = s.minimize(&mut x, &[-INF; 2], &[INF; 2], rosenbrock);
        assert_eq!((res.stop, res.iterations), (LbfgsbStop::MaxIterations, 3));
        // Same workspace with another dimension and memory: buffers are resized.
        *s.options_mut() = LbfgsbOptions {
            memory: 3,
            ..tight()
        };
        let mut x = extended_start(10);
        let res = s.minimize(&mut x, &[-INF; 10], &[INF; 10], extended_rosenbrock);
        assert!(res.converged(), "{res:?}");
        assert!(x.iter().all(|v| (v - 1.0).abs() < 1e-6), "{x:?}");
    }

    #[test]
    fn start_outside_box_is_projected_and_bound_is_active() {
        // Rosenbrock with x0 <= 0.5: the solution is on the bound, (0.5, 0.25).
        let mut x = [3.0, 3.0];
        let res = Lbfgsb::new(2, tight()).minimize(&mut x, &[-INF; 2], &[0.5, INF], rosenbrock);
        assert!(res.converged(), "{res:?}");
        assert!(x[0] == 0.5 && (x[1] - 0.25).abs() < 1e-8, "{x:?}");
    }
}
