//! Errors of a run against the reference and what the summary derives from them:
//! RMS over time, the order in time, the Pareto front. Pure: meshes in, numbers out.

use crate::geometry::{Point2, SurfaceMesh};
use crate::metrics::rms_distance_where_defined;

/// A run's distance to the reference at the sample times.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RunError {
    /// sqrt(mean over sample times of the squared RMS distance at matched material
    /// points), m.
    pub rms_over_time: f64,
    /// The RMS distance at the last sample time, m.
    pub at_end: f64,
    /// Fewest material points compared at one sample time (all of them unless a
    /// remeshed pattern left some uncovered).
    pub points_used_min: usize,
}

/// Compare two runs sampled at the same times (`run[k]` and `reference[k]`) at the
/// material `points`; points outside either pattern are skipped. None when a sample is
/// missing or no point is covered.
pub fn error_against(
    run: &[SurfaceMesh],
    reference: &[SurfaceMesh],
    points: &[Point2],
) -> Option<RunError> {
    if run.len() != reference.len() || run.is_empty() {
        return None;
    }
    let mut sum = 0.0;
    let mut used_min = usize::MAX;
    let mut last = 0.0;
    for (a, b) in run.iter().zip(reference) {
        let (d, used) = rms_distance_where_defined(a, b, points)?;
        sum += d * d;
        used_min = used_min.min(used);
        last = d;
    }
    Some(RunError {
        rms_over_time: (sum / run.len() as f64).sqrt(),
        at_end: last,
        points_used_min: used_min,
    })
}

/// Least-squares slope of ln y against ln x over the pairs with both positive and
/// finite (the convergence order when x is the time step); None with fewer than 2.
pub fn log_log_slope(points: &[(f64, f64)]) -> Option<f64> {
    let p: Vec<(f64, f64)> = points
        .iter()
        .filter(|(x, y)| *x > 0.0 && *y > 0.0 && x.is_finite() && y.is_finite())
        .map(|(x, y)| (x.ln(), y.ln()))
        .collect();
    if p.len() < 2 {
        return None;
    }
    let n = p.len() as f64;
    let mx = p.iter().map(|q| q.0).sum::<f64>() / n;
    let my = p.iter().map(|q| q.1).sum::<f64>() / n;
    let sxx: f64 = p.iter().map(|q| (q.0 - mx).powi(2)).sum();
    let sxy: f64 = p.iter().map(|q| (q.0 - mx) * (q.1 - my)).sum();
    (sxx > 0.0).then(|| sxy / sxx)
}

/// Local order of a run's own halvings: log2(far / near), where `near` is the distance
/// between the runs at h and 2h and `far` between the runs at 2h and 4h (1 for a first-
/// order method in its asymptotic range, ~0 when halving h no longer brings the runs
/// closer). None unless both are positive and finite.
pub fn halving_order(near: f64, far: f64) -> Option<f64> {
    (near > 0.0 && far > 0.0 && near.is_finite() && far.is_finite()).then(|| (far / near).log2())
}

/// The error of the run at h implied by the distance `near` to its run at 2h and the
/// local `order` of its halvings: `near` in the first-order range (order >= 0.8, or no
/// order known: e(2h) - e(h) ~ e(h)); near / (2^p - 1) for an order p in (0.2, 0.8)
/// (the error left if the halvings kept shrinking at that rate); None when p <= 0.2 (the
/// halvings do not converge, so the error is not bounded).
pub fn error_from_halvings(near: f64, order: Option<f64>) -> Option<f64> {
    match order {
        None => Some(near),
        Some(p) if p >= 0.8 => Some(near),
        Some(p) if p > 0.2 => Some(near / (p.exp2() - 1.0)),
        Some(_) => None,
    }
}

/// Relative improvement in error below which a costlier point does not join the Pareto
/// front: a tie. Two solvers that share their iterates (chain and the dense
/// gauss_newton) differ by round-off (2e-13 relative on the heavy cantilever), and a
/// tighter tolerance on a converged run changes its error by ~1e-6 relative (the
/// buckled strip at n = 50, tolerances 1e-4 to 1e-10; measured 2026-12-07): a run
/// better by less than 0.1 % is not a better run to pick.
pub const FRONT_TIE: f64 = 1e-3;

/// Indices of the points (cost, error) no other point beats in both (lower is better),
/// sorted by cost; a costlier point must lower the error by more than [`FRONT_TIE`]
/// (relative) to count.
pub fn pareto_front(points: &[(f64, f64)]) -> Vec<usize> {
    let mut idx: Vec<usize> = (0..points.len())
        .filter(|&i| points[i].0.is_finite() && points[i].1.is_finite())
        .collect();
    idx.sort_by(|&a, &b| {
        points[a]
            .0
            .total_cmp(&points[b].0)
            .then(points[a].1.total_cmp(&points[b].1))
    });
    let mut front = Vec::new();
    let mut best = f64::INFINITY;
    for i in idx {
        if points[i].1 < best * (1.0 - FRONT_TIE) {
            best = points[i].1;
            front.push(i);
        }
    }
    front
}

/// The smallest error among points costing at most `budget` (the error a method reaches
/// within a run-time budget): its index.
pub fn best_within(points: &[(f64, f64)], budget: f64) -> Option<usize> {
    (0..points.len())
        .filter(|&i| points[i].0 <= budget && points[i].1.is_finite())
        .min_by(|&a, &b| points[a].1.total_cmp(&points[b].1))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slope_of_a_power_law_is_its_exponent() {
        let p: Vec<(f64, f64)> = [0.1, 0.05, 0.025]
            .iter()
            .map(|&h| (h, 3.0 * h * h))
            .collect();
        assert!((log_log_slope(&p).unwrap() - 2.0).abs() < 1e-12);
        assert_eq!(log_log_slope(&p[..1]), None);
    }

    #[test]
    fn halvings_bound_the_error_only_while_they_converge() {
        // first order: the runs at h, 2h, 4h are 1, 2 apart -> e(h) ~ 1
        let p = halving_order(1.0, 2.0).unwrap();
        assert!((p - 1.0).abs() < 1e-12);
        assert_eq!(error_from_halvings(1.0, Some(p)), Some(1.0));
        // order 0.5: e(h) = d / (sqrt 2 - 1)
        let e = error_from_halvings(1.0, halving_order(1.0, 2f64.sqrt())).unwrap();
        assert!((e - 1.0 / (2f64.sqrt() - 1.0)).abs() < 1e-12);
        // not converging: equal distances (order 0), or the coarser pair closer
        assert_eq!(error_from_halvings(1.0, halving_order(1.0, 1.0)), None);
        assert_eq!(error_from_halvings(1.0, halving_order(1.0, 0.5)), None);
        assert_eq!(error_from_halvings(1.0, None), Some(1.0));
        assert_eq!(halving_order(0.0, 1.0), None);
    }

    #[test]
    fn pareto_front_drops_dominated_points() {
        let p = [(1.0, 1.0), (2.0, 0.5), (1.5, 2.0), (3.0, 0.6), (0.5, 3.0)];
        assert_eq!(pareto_front(&p), vec![4, 0, 1]);
        // a costlier run better by round-off, or by 0.05 %, is not on the front
        let twins = [
            (1.0, 1e-3),
            (2.0, 1e-3 * (1.0 - 1e-13)),
            (2.5, 0.9995e-3),
            (3.0, 0.9e-3),
        ];
        assert_eq!(pareto_front(&twins), vec![0, 3]);
        assert_eq!(best_within(&p, 2.0), Some(1));
        assert_eq!(best_within(&p, 0.1), None);
    }
}
