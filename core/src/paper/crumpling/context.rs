//! What the remeshing of step 2 shares between its parts (crumpling/mod.rs and
//! singular.rs): the context, the band of imaginary rulings and the seeded normal
//! deviate. A file of its own so that neither part imports the other back.

use nalgebra::Vector2;
use rand::Rng;

use crate::geometry::{Point2, Point3};
use crate::paper::geometric::GVertexKind;
use crate::paper::params::PaperParams;
use crate::paper::pattern::Pattern;

/// Everything the remeshing needs besides the structure.
pub struct CrumpleContext<'a> {
    pub pattern: &'a Pattern,
    pub params: &'a PaperParams,
    /// World position of an S_G vertex from its kind and pattern position (the S_P of
    /// step 1, interpolated; cubic along the boundary).
    pub position: &'a dyn Fn(&GVertexKind, &Point2) -> Point3,
}

/// The band of imaginary rulings through T_comp: offsets along v (m).
#[derive(Clone, Copy, Debug)]
pub(super) struct Band {
    pub(super) v: Vector2<f64>,
    pub(super) v_perp: Vector2<f64>,
    pub(super) t_min: f64,
    pub(super) t_max: f64,
}

impl Band {
    pub(super) fn line(&self, t: f64) -> (Point2, Vector2<f64>) {
        (Point2::from(self.v * t), self.v_perp)
    }
    /// Parameter range [u0, u1] of segment [p, q] inside the band, if any.
    pub(super) fn clip_segment(&self, p: &Point2, q: &Point2) -> Option<(f64, f64)> {
        let tp = p.coords.dot(&self.v);
        let tq = q.coords.dot(&self.v);
        if (tq - tp).abs() < 1e-15 {
            return (tp >= self.t_min && tp <= self.t_max).then_some((0.0, 1.0));
        }
        let u_a = (self.t_min - tp) / (tq - tp);
        let u_b = (self.t_max - tp) / (tq - tp);
        let (lo, hi) = (u_a.min(u_b).max(0.0), u_a.max(u_b).min(1.0));
        (hi > lo).then_some((lo, hi))
    }
}

/// A standard normal deviate (Box-Muller) from the seeded generator.
pub(super) fn normal(rng: &mut impl Rng) -> f64 {
    let u1: f64 = 1.0 - rng.random::<f64>();
    let u2: f64 = rng.random::<f64>();
    (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
}
