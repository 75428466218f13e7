//! Solvers shared by the simulators: a projected (Gauss-)Newton method for
//! box-constrained problems with a damped Newton matrix, a trust-region projected
//! Newton method (TRON / LANCELOT family) with one optional slab besides the box, a
//! primal-dual interior-point method (IPOPT family) for the same constraints, and
//! L-BFGS-B (Byrd et al. 1995), the baseline the ribbon paper uses.

pub mod interior_point;
pub mod lbfgsb;
pub mod projected_newton;
pub mod slab;
pub mod trust_region;

pub use interior_point::{BarrierMatrix, InteriorPoint};
pub use lbfgsb::{Lbfgsb, LbfgsbOptions, LbfgsbResult, LbfgsbStop};
pub use projected_newton::{
    damped_diagonal, damping_floor, BoxProblem, Dense, NewtonMatrix, NewtonOptions, NewtonResult,
    ProjectedNewton,
};
pub use slab::Slab;
pub use trust_region::{ModelMatrix, TrustRegion};

/// Infinity norm of the projected gradient P(x - g) - x on the box [lower, upper].
pub fn projected_gradient_inf(x: &[f64], g: &[f64], lower: &[f64], upper: &[f64]) -> f64 {
    x.iter()
        .zip(g)
        .zip(lower.iter().zip(upper))
        .map(|((&xi, &gi), (&lo, &hi))| ((xi - gi).clamp(lo, hi) - xi).abs())
        .fold(0.0, f64::max)
}
