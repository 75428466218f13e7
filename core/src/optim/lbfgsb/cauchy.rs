//! The generalized Cauchy point (paper, section 4) and the subspace minimization
//! over the variables free there (section 5.1).

use super::*;

impl Lbfgsb {
    /// Generalized Cauchy point (paper, section 4, algorithm CP): the first local minimizer
    /// of the model `m(x) = gᵀ(x - x_k) + ½(x - x_k)ᵀB(x - x_k)` along the projected path
    /// `x(t) = P(x_k - t g)`. Breakpoints are visited in increasing order; on each segment the
    /// derivatives `f' = ∂m/∂t` and `f'' = ∂²m/∂t²` are updated in O(m²) using `p = Wᵀd` and
    /// `c = Wᵀ(x(t) - x_k)` instead of O(n) work. On exit `xcp` = `x^c`, `c = Wᵀ(x^c - x_k)`
    /// and `iwhere` marks the variables at a bound.
    pub(super) fn cauchy_point(&mut self, x: &[f64], b: &Bounds, pg_norm: f64) {
        let (mem, w) = (&self.mem, &mut self.w);
        let (n, col, theta) = (x.len(), mem.col, mem.theta);
        let col2 = 2 * col;
        w.xcp.copy_from_slice(x);
        w.c[..col2].fill(0.0);
        if pg_norm <= 0.0 {
            return;
        }
        let start = steepest_descent_path(mem, w, x, b);
        if w.breaks.is_empty() && start.n_unbroken == 0 {
            return; // d = 0: x^c = x
        }
        // f'' = dᵀBd = θdᵀd - pᵀMp.
        let mut slope = PathDerivatives {
            f1: start.f1,
            f2: -theta * start.f1,
        };
        let f2_org = slope.f2;
        if col > 0 {
            mem.bmv(&w.p[..col2], &mut w.v[..col2]);
            slope.f2 -= dot(&w.v[..col2], &w.p[..col2]);
        }
        let mut dtm = -slope.f1 / slope.f2;
        let (mut tsum, nbreak, mut all_fixed) = (0.0, w.breaks.len(), false);
        let (mut nleft, mut k, mut tj) = (nbreak, 0, 0.0);
        while nleft > 0 {
            // The smallest breakpoint is known; sort the others only if the search goes on
            // (the reference code uses a heap for the same purpose).
            if k == 1 {
                w.breaks.swap(0, start.ibkmin);
                w.breaks[1..].sort_unstable_by(|a, b| a.0.total_cmp(&b.0));
            }
            let (t, ibp) = w.breaks[if k == 0 { start.ibkmin } else { k }];
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
            next_segment(mem, w, ibp, dibp, zibp, dt, &mut slope);
            slope.f2 = slope.f2.max(f64::EPSILON * f2_org);
            dtm = if nleft == 0 && start.bounded {
                0.0
            } else {
                -slope.f1 / slope.f2
            };
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
    pub(super) fn subspace_minimization(&mut self, x: &[f64], b: &Bounds) -> bool {
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
}

/// The derivatives of the model along the projected path on the current segment:
/// `f1 = ∂m/∂t`, `f2 = ∂²m/∂t²`.
struct PathDerivatives {
    f1: f64,
    f2: f64,
}

/// What [`steepest_descent_path`] found besides the direction and breakpoints it
/// writes to the workspace.
struct PathStart {
    /// f' = -dᵀd at t = 0.
    f1: f64,
    /// Index in `breaks` of the smallest breakpoint.
    ibkmin: usize,
    /// Variables of d ≠ 0 that meet no bound along the path.
    n_unbroken: usize,
    /// Every variable without a breakpoint has a zero direction.
    bounded: bool,
}

/// The start of algorithm CP: marks each variable's status (`iwhere`), writes
/// d = -g on the variables not held at a bound (`w.d`), the breakpoints t_i
/// (`w.breaks`) and p = Wᵀd (`w.p`, its second half times θ).
fn steepest_descent_path(mem: &Memory, w: &mut Work, x: &[f64], b: &Bounds) -> PathStart {
    let (col, theta) = (mem.col, mem.theta);
    w.p[..2 * col].fill(0.0);
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
    w.p[col..2 * col].iter_mut().for_each(|pj| *pj *= theta);
    PathStart {
        f1,
        ibkmin,
        n_unbroken,
        bounded,
    }
}

/// Past breakpoint `ibp` (its direction component `dibp` just zeroed, `zibp` = its
/// bound - x): update f' and f'' for the next segment after a step `dt` on this one,
/// and c and p in O(m²) through W's row `ibp`.
fn next_segment(
    mem: &Memory,
    w: &mut Work,
    ibp: usize,
    dibp: f64,
    zibp: f64,
    dt: f64,
    slope: &mut PathDerivatives,
) {
    let (col, theta) = (mem.col, mem.theta);
    let col2 = 2 * col;
    let dibp2 = dibp * dibp;
    slope.f1 += dt * slope.f2 + dibp2 - theta * dibp * zibp;
    slope.f2 -= theta * dibp2;
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
        slope.f1 += dibp * wmc;
        slope.f2 += 2.0 * dibp * wmp - dibp2 * wmw;
    }
}
