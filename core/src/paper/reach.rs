//! Handle targets a sheet cannot reach isometrically (issue 20).
//!
//! The pattern is convex, so the shortest path between two of its points is the straight
//! segment, of length |m_i - m_j|, and an isometric sheet maps it to a curve of the same
//! length: two held points can never be farther apart in space than in the pattern.
//! Targets that ask for more (two grippers pulling a sheet taut and beyond) cannot be
//! met without stretching it. Schreck et al. are silent on this; what we do: move the
//! targets as little as we can onto the reachable set |t_i - t_j| <= |m_i - m_j| for
//! every pair (each pair's set is convex, so cyclic projection onto them converges to a
//! point of their intersection, which is not empty: the flat pattern itself is in it),
//! hold the sheet there, and report how far each target was moved, as the ribbon
//! reports a target it cannot reach ([`crate::sim::ReachWatch`]).

use crate::geometry::{Point2, Point3, Vector3};

/// A handle point held at a target (world frame, m), at pattern point `material` (m).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HeldTarget {
    pub material: Point2,
    pub target: Point3,
}

/// The reachable targets: each point's correction (reachable target minus target, m),
/// the largest correction's length (m) and its point.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Reach {
    pub corrections: Vec<Vector3>,
    pub excess: f64,
    pub worst: Option<usize>,
}

/// Sweeps of cyclic projection at most; two points need one, a taut chain of k points
/// about k.
const SWEEPS: usize = 200;

/// A pair farther apart than its pattern distance by more than this is projected, m
/// (far below any tolerance of the sheet: it is the round-off of the targets).
const SLACK: f64 = 1e-12;

/// The targets moved onto the reachable set (see the module docs); unchanged (zero
/// corrections) when they are reachable.
pub fn reachable(points: &[HeldTarget]) -> Reach {
    let mut t: Vec<Point3> = points.iter().map(|p| p.target).collect();
    for _ in 0..SWEEPS {
        let mut moved = false;
        for i in 0..t.len() {
            for j in i + 1..t.len() {
                let reach = (points[j].material - points[i].material).norm();
                let r = t[j] - t[i];
                let len = r.norm();
                if len > reach + SLACK {
                    // both ends move by half the excess along the pair's line: the
                    // nearest pair of points at that distance
                    let half = 0.5 * (len - reach) / len * r;
                    t[i] += half;
                    t[j] -= half;
                    moved = true;
                }
            }
        }
        if !moved {
            break;
        }
    }
    let corrections: Vec<Vector3> = t.iter().zip(points).map(|(r, p)| r - p.target).collect();
    let (worst, excess) =
        corrections
            .iter()
            .map(|c| c.norm())
            .enumerate()
            .fold(
                (None, 0.0),
                |(w, e), (i, c)| if c > e { (Some(i), c) } else { (w, e) },
            );
    Reach {
        corrections,
        excess,
        worst,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn held(u: f64, v: f64, x: f64, y: f64, z: f64) -> HeldTarget {
        HeldTarget {
            material: Point2::new(u, v),
            target: Point3::new(x, y, z),
        }
    }

    #[test]
    fn reachable_targets_are_left_alone() {
        // a sheet 0.1 m wide with its bottom corners brought 10 % closer and lifted
        let points = [
            held(0.0, 0.0, 0.005, 0.0, 0.01),
            held(0.1, 0.0, 0.095, 0.0, 0.0),
        ];
        let r = reachable(&points);
        assert_eq!(r.excess, 0.0);
        assert_eq!(r.worst, None);
        assert!(r.corrections.iter().all(|c| c.norm() == 0.0));
    }

    #[test]
    fn two_corners_pulled_apart_meet_their_pattern_distance_halfway() {
        // 12 mm beyond the 0.1 m between the corners: each target moves 6 mm inwards
        let points = [
            held(0.0, 0.0, -0.006, 0.0, 0.0),
            held(0.1, 0.0, 0.106, 0.0, 0.0),
        ];
        let r = reachable(&points);
        assert!((r.excess - 0.006).abs() < 1e-12, "{r:?}");
        assert!((r.corrections[0] - Vector3::new(0.006, 0.0, 0.0)).norm() < 1e-12);
        assert!((r.corrections[1] - Vector3::new(-0.006, 0.0, 0.0)).norm() < 1e-12);
    }

    #[test]
    fn every_pair_of_a_stretched_square_ends_within_its_pattern_distance() {
        // the four corners of a 0.1 m square pulled outwards by 20 % and twisted
        let corners = [(0.0, 0.0), (0.1, 0.0), (0.1, 0.1), (0.0, 0.1)];
        let points: Vec<HeldTarget> = corners
            .iter()
            .enumerate()
            .map(|(k, &(u, v))| held(u, v, 1.2 * (u - 0.05), 1.2 * (v - 0.05), 0.01 * k as f64))
            .collect();
        let r = reachable(&points);
        assert!(r.excess > 0.005, "{r:?}");
        for i in 0..4 {
            for j in i + 1..4 {
                let a = points[i].target + r.corrections[i];
                let b = points[j].target + r.corrections[j];
                let reach = (points[j].material - points[i].material).norm();
                assert!((b - a).norm() <= reach + 1e-9, "pair {i} {j}: {r:?}");
            }
        }
    }
}
