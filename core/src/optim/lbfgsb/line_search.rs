//! Moré–Thuente line search for the strong Wolfe conditions along `d = x̄ - x`, the
//! step limited so that the iterate stays feasible (reference `lnsrlb`, `dcsrch`, `dcstep`).

use super::*;

impl Lbfgsb {
    /// Line search along `d` (Moré–Thuente, strong Wolfe with `μ = 1e-3`, `η = 0.9`). The step
    /// is capped so that `x + λd` stays in the box; the first iteration of a problem that is
    /// not fully boxed tries `λ = 1/‖d‖`, later ones the quasi-Newton step `λ = 1` (reference
    /// `lnsrlb`). A trial with non-finite `f` or gradient moves the cap halfway back towards the
    /// best step so far and restarts the search below it. Returns the new `f` (with `x`, `g`
    /// updated) or `None` on failure (`x_old`, `g_old` then hold the previous iterate).
    pub(super) fn line_search(
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
