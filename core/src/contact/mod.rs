//! Collisions and contact (Pan et al. sec. 5.2): after every ribbon's optimization,
//! the reconstructed meshes X~ of all ribbons are made collision-free together by the
//! globally coupled impact-zone QP, and the corrected meshes become the previous state
//! of the next step.
//!
//! - [`collider`]: ground plane, boxes, spheres, capsules, triangle meshes (static or
//!   carried by a handle), with parry for point projection and ray casts.
//! - `ccd`: continuous vertex-face / edge-edge tests and proximity with a thickness.
//! - `detect`: broad phase (sort and sweep over leaves), narrow phase, one constraint
//!   per closest-feature pair.
//! - `metric`: the closeness measure with the artificial edge stiffness K and its
//!   pre-factorized sparse Hessian (faer).
//! - [`qp`]: the dual active-set solver.
//! - [`ContactStage`]: rounds of detection and response until collision-free, zones,
//!   Coulomb friction, the report.
//! - [`barrier`], [`obstacles`]: contact inside the step instead (`contact.method:
//!   barrier`, docs/contact_barrier.md): IPC's barrier, the friction mollifier,
//!   distances and conservative advancement; what one ribbon's step sees of the world.
//!
//! Pure: no I/O, no serde. A scene without colliders and without a `contact:` section
//! builds no stage and pays nothing.

pub mod barrier;
mod ccd;
pub mod collider;
mod detect;
mod metric;
pub mod obstacles;
pub mod qp;
mod stage;

pub use barrier::BarrierSettings;
pub use collider::{Collider, ColliderShape};
pub use obstacles::{CellMesh, ContactEnv, Obstacles, OtherMesh};
pub use stage::{BodyInput, BodyTopology, Closeness, ContactReport, ContactSettings, ContactStage};

/// Why a contact stage could not be built.
#[derive(Debug, thiserror::Error)]
pub enum ContactError {
    #[error("invalid contact setup: {0}")]
    Invalid(String),
    #[error("cannot factorize the closeness Hessian: {0}")]
    Factorization(String),
}
