//! The ribbon simulator of Pan, Huang, Bao: "Modelling Developable Ribbons Using Ruling
//! Bending Coordinates".
//!
//! - [`reconstruct`]: eqs. (2), (3), element frames, rims, normals.
//! - [`bending`]: the per-crease bending weights and how a clamp sets them.
//! - [`mass`]: the crease-dependent consistent mass of a trapezoid (appendix B).
//! - [`objective`]: the implicit-Euler objective (sec. 4), its adjoint gradient
//!   (appendix C), the chain-rule baseline (appendix A) and a Gauss-Newton Hessian.
//! - [`step`]: one time step (algorithm 2): box constraints after the variable
//!   substitution, augmented Lagrangian, and the two inner solvers.
//! - [`contact`]: a step with contact inside it (the barrier, docs/contact_barrier.md).

pub mod bending;
mod body_friction;
pub mod contact;
mod handle_terms;
mod handles;
pub mod mass;
pub mod objective;
pub mod params;
pub mod reconstruct;
mod sim;
pub mod step;
#[cfg(any(test, feature = "test-hooks"))]
mod test_hooks;

pub use handle_terms::HandleRef;
pub use params::{
    BaseMode, ChainVariant, ClampRule, KineticModel, LoopKind, RibbonParams, SolverKind,
    SolverSettings,
};
pub use reconstruct::{Coordinates, Frames, Strip};
pub use sim::{Imperfection, RibbonForce, RibbonInitialShape, RibbonSim};
