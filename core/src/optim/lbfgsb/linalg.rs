//! Small dense factorizations of the `2m x 2m` middle matrices (column-major in flat
//! slices with a leading dimension `ld`).

/// Factor `K = Uᵀ diag(-I, I) U`, `U = [[L1ᵀ, L1⁻¹E], [0, L2ᵀ]]`, from `A11 = L1L1ᵀ` (always
/// positive definite) and the Schur complement `C + EᵀA11⁻¹E = L2L2ᵀ` (positive definite iff
/// `K` is nonsingular). Returns false if either Cholesky factorization breaks down.
pub(super) fn factor_k(kf: &mut [f64], ld: usize, col: usize, tmp: &mut [f64]) -> bool {
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
pub(super) fn solve_k(kf: &[f64], ld: usize, col: usize, wv: &mut [f64]) {
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
pub(super) fn cholesky(a: &mut [f64], ld: usize, k: usize) -> bool {
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
pub(super) fn solve_lower(l: &[f64], ld: usize, k: usize, b: &mut [f64]) {
    for i in 0..k {
        let s: f64 = (0..i).map(|q| l[i * ld + q] * b[q]).sum();
        b[i] = (b[i] - s) / l[i * ld + i];
    }
}

/// Solve `Lᵀx = b` in place.
pub(super) fn solve_lower_transposed(l: &[f64], ld: usize, k: usize, b: &mut [f64]) {
    for i in (0..k).rev() {
        let s: f64 = (i + 1..k).map(|q| l[q * ld + i] * b[q]).sum();
        b[i] = (b[i] - s) / l[i * ld + i];
    }
}

pub(super) fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// `Σ_{k ∈ set} a_k b_k`.
pub(super) fn dot_on(set: &[usize], a: &[f64], b: &[f64]) -> f64 {
    set.iter().map(|&k| a[k] * b[k]).sum()
}

/// `Σ_i a_{set_i} r_i` for `r` stored compactly over `set`.
pub(super) fn dot_on_dense(set: &[usize], a: &[f64], r: &[f64]) -> f64 {
    set.iter().zip(r).map(|(&k, ri)| a[k] * ri).sum()
}

pub(super) fn all_finite(v: &[f64]) -> bool {
    v.iter().all(|x| x.is_finite())
}
