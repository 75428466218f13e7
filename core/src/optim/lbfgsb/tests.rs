//! Tests of L-BFGS-B: the compact matrix against the BFGS recursion, the Cauchy point and
//! subspace step against dense computations, the reference problems (Rosenbrock, driver1).

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
