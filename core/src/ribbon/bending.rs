//! Per-crease bending weights (Pan et al. sec. 4, V_bend) and the clamp rule.
//!
//! Crease k carries the energy `weight_k (1 + c_k^2) psi_k^2` with
//! `weight_k = alpha w / d_k`, where d_k (m) is the length of centerline whose
//! curvature the crease stands for (psi_k ~ kappa d_k, so the energy is
//! alpha w kappa^2 d_k = (B/2) kappa^2 d_k with B = 2 alpha w). Away from clamps
//! d_k = l/n (the paper's `alpha n w / l`), the distance between the midpoints of the
//! two elements the crease joins. Next to a clamp (a fixed or driven base, a handle
//! that holds an element's orientation) the held element is rigid, and the paper's
//! uniform d_k acts as if the strip were clamped half an element away from its clamp
//! point: first order in n ([`ClampRule::Paper`]). [`ClampRule::DualLength`] gives the
//! crease next to a clamp at s_c the length from s_c to the midpoint of its free
//! neighbour (the crease sum becomes a consistent quadrature of the curvature from
//! the clamp on: second order); [`ClampRule::MomentMatched`] (the default) also
//! makes the first moment of the first two creases exact, which removes the leading
//! h^2 error of that quadrature and of the rigid held element. Derivation and measured
//! errors: docs/accuracy.md.

use super::params::ClampRule;
use super::BaseMode;
use crate::sim::{HandleSpec, OrientationMode};

/// Fill `out[k]` (k = 1..n-1; entries 0 and n are 0) with the bending weight of crease k,
/// J: `alpha w / d_k` (see the module doc). `clamps` are the centerline stations s_c
/// (m, clamped into [0, l]) of every clamp; ignored by [`ClampRule::Paper`].
pub fn crease_bending_weights(
    alpha: f64,
    strip: &super::Strip,
    rule: ClampRule,
    clamps: &[f64],
    out: &mut Vec<f64>,
) {
    let d = dual_lengths(strip, rule, clamps);
    out.clear();
    out.extend(d.iter().map(|&dk| {
        if dk > 0.0 {
            alpha * strip.width / dk
        } else {
            0.0
        }
    }));
}

/// The length d_k (m) each crease k = 1..n-1 stands for (entries 0 and n are 0).
pub fn dual_lengths(strip: &super::Strip, rule: ClampRule, clamps: &[f64]) -> Vec<f64> {
    let n = strip.segments;
    let h = strip.length / n as f64;
    // dual interval of crease k: from the midpoint of element k-1 to that of k, cut
    // at a clamp in element k-1 (on the left) or k (on the right), the nearest one
    // where there are several
    let mut lo: Vec<f64> = (0..=n).map(|k| (k as f64 - 0.5) * h).collect();
    let mut hi: Vec<f64> = (0..=n).map(|k| (k as f64 + 0.5) * h).collect();
    let mut cut_lo = vec![false; n + 1];
    let mut cut_hi = vec![false; n + 1];
    if rule != ClampRule::Paper {
        for &s in clamps {
            let s = s.clamp(0.0, strip.length);
            let e = ((s / h).floor().max(0.0) as usize).min(n - 1);
            if e + 1 < n && (!cut_lo[e + 1] || s > lo[e + 1]) {
                (lo[e + 1], cut_lo[e + 1]) = (s, true);
            }
            if e >= 1 && (!cut_hi[e] || s < hi[e]) {
                (hi[e], cut_hi[e]) = (s, true);
            }
        }
    }
    // a clamp exactly on a crease from both sides leaves nothing to bend: keep a tiny
    // positive length so the weight stays finite (the crease is held anyway)
    let mut d: Vec<f64> = (0..=n)
        .map(|k| match k {
            0 => 0.0,
            k if k == n => 0.0,
            k => (hi[k] - lo[k]).max(1e-9 * h),
        })
        .collect();
    if rule == ClampRule::MomentMatched {
        moment_match(&mut d, &lo, &hi, &cut_lo, &cut_hi, h);
    }
    d
}

/// Beside each clamp, trade length between the first crease (cut by the clamp) and the
/// second (uncut) so that d_1 + d_2 keeps the dual total D and the first moment about
/// the clamp is exact: d_1 b + d_2 (b + h) = D^2 / 2, b the first crease's distance
/// from the clamp, i.e. d_2 = D (D/2 - b) / h (positive for b in [0, h]: d_2 in
/// [0.625 h, 1.125 h]). Where the second crease is cut too (two clamps within three
/// elements) the dual lengths stay.
fn moment_match(d: &mut [f64], lo: &[f64], hi: &[f64], cut_lo: &[bool], cut_hi: &[bool], h: f64) {
    let n = d.len() - 1;
    let uncut = |k: usize| k >= 1 && k < n && !cut_lo[k] && !cut_hi[k];
    let mut pairs = Vec::new();
    for k in 1..n {
        // clamp on the left of k (cuts lo): the second crease is k + 1
        if cut_lo[k] && !cut_hi[k] && uncut(k + 1) {
            pairs.push((k, k + 1, (k as f64) * h - lo[k]));
        }
        // clamp on the right of k (cuts hi): the second crease is k - 1
        if cut_hi[k] && !cut_lo[k] && k >= 2 && uncut(k - 1) {
            pairs.push((k, k - 1, hi[k] - (k as f64) * h));
        }
    }
    // a second crease claimed by two clamps keeps its dual length
    for &(first, second, b) in &pairs {
        if pairs.iter().filter(|p| p.1 == second).count() > 1 {
            continue;
        }
        let total = d[first] + d[second];
        let d2 = total * (0.5 * total - b) / h;
        d[second] = d2;
        d[first] = total - d2;
    }
}

/// The centerline stations (m) of the clamps acting on ribbon `index`: s = 0 for a
/// fixed base, the grasp point's u for a base driven by a handle, and the grasp point's
/// u for every handle that holds an element's orientation (`orientation: full`).
pub fn clamp_stations(base: &BaseMode, handles: &[HandleSpec], index: usize) -> Vec<f64> {
    let mut out = Vec::new();
    let driven_by = match base {
        BaseMode::Prescribed {
            driven_by: Some(h), ..
        } => {
            out.push(handles.get(*h).map_or(0.0, |spec| spec.material_point.x));
            Some(*h)
        }
        BaseMode::Prescribed {
            driven_by: None, ..
        } => {
            out.push(0.0);
            None
        }
        BaseMode::Floating { .. } => None,
    };
    for (h, spec) in handles.iter().enumerate() {
        if spec.holds(index)
            && Some(h) != driven_by
            && matches!(spec.orientation, OrientationMode::Full)
        {
            out.push(spec.material_point.x);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ribbon::Strip;

    fn strip(n: usize) -> Strip {
        Strip {
            length: 1.0,
            width: 0.05,
            segments: n,
        }
    }

    /// Without clamps, or with the paper's rule, every crease has the paper's
    /// alpha n w / l.
    #[test]
    fn unclamped_and_paper_weights_are_the_papers() {
        let mut w = Vec::new();
        for (rule, clamps) in [
            (ClampRule::DualLength, &[][..]),
            (ClampRule::Paper, &[0.0, 0.33][..]),
        ] {
            crease_bending_weights(0.1, &strip(10), rule, clamps, &mut w);
            assert_eq!(w.len(), 11);
            assert_eq!((w[0], w[10]), (0.0, 0.0));
            for &wk in &w[1..10] {
                assert!((wk - 0.1 * 10.0 * 0.05).abs() < 1e-15);
            }
        }
    }

    /// An end clamp at s = 0 gives crease 1 the dual length 1.5 l/n; a clamp at the far
    /// end the same for crease n-1; a grasp at s inside element E gives its two
    /// creases |m_{E-1} - s| and |m_{E+1} - s|.
    #[test]
    fn clamped_creases_get_their_dual_length() {
        let (alpha, wid, h) = (0.1, 0.05, 0.1);
        let mut w = Vec::new();
        let d = |wk: f64| alpha * wid / wk;
        let dual = ClampRule::DualLength;
        crease_bending_weights(alpha, &strip(10), dual, &[0.0, 1.0], &mut w);
        assert!((d(w[1]) - 1.5 * h).abs() < 1e-12);
        assert!((d(w[9]) - 1.5 * h).abs() < 1e-12);
        assert!((d(w[5]) - h).abs() < 1e-12);
        // grasp at 0.33 in element 3 [0.3, 0.4]: crease 3 from m_2 = 0.25, crease 4 to
        // m_4 = 0.45
        crease_bending_weights(alpha, &strip(10), dual, &[0.33], &mut w);
        assert!((d(w[3]) - 0.08).abs() < 1e-12);
        assert!((d(w[4]) - 0.12).abs() < 1e-12);
        assert!((d(w[2]) - h).abs() < 1e-12 && (d(w[5]) - h).abs() < 1e-12);
    }

    /// Moment matching keeps each pair's total and makes the first moment about the
    /// clamp exact: end clamp d = (1.875, 0.625) l/n; a grasp at an element's middle
    /// keeps the paper's l/n; two clamps too close for a pair keep their dual lengths.
    #[test]
    fn moment_matched_pairs_integrate_linear_curvature_exactly() {
        let h = 0.1;
        let mm = ClampRule::MomentMatched;
        let d = dual_lengths(&strip(10), mm, &[0.0, 1.0]);
        for (k, want) in [
            (1, 1.875),
            (2, 0.625),
            (3, 1.0),
            (7, 1.0),
            (8, 0.625),
            (9, 1.875),
        ] {
            assert!((d[k] - want * h).abs() < 1e-12, "crease {k}: {}", d[k] / h);
        }
        // the first moment about the clamp at 0: nodes at h, 2h over [0, 2.5 h]
        let moment = d[1] * h + d[2] * 2.0 * h;
        assert!((moment - 0.5 * (2.5 * h) * (2.5 * h)).abs() < 1e-14);
        let mid = dual_lengths(&strip(10), mm, &[0.35]);
        for k in 1..10 {
            assert!((mid[k] - h).abs() < 1e-12, "crease {k}: {}", mid[k] / h);
        }
        // clamps in elements 3 and 5: crease 4 and 5 lie between them, crease 5 is
        // also cut: every cut crease keeps its dual length
        let near = dual_lengths(&strip(10), mm, &[0.3, 0.5]);
        let dual = dual_lengths(&strip(10), ClampRule::DualLength, &[0.3, 0.5]);
        assert_eq!(near[4], dual[4]);
        assert_eq!(near[5], dual[5]);
        for k in 1..10 {
            assert!(near[k] > 0.0);
        }
    }
}
