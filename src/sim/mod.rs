//! The simulated world: objects, handles, one time step for all of them.
//!
//! This is the API every edge (CLI, ROS node, recorder, report) drives:
//! build a [`World`] from a scene, call [`World::step`] with the newest handle targets,
//! read meshes, singular points and the [`StepReport`]. Pure: no I/O, no ROS, no serde.

pub mod handle;
pub mod reach;
mod world;

pub use handle::{HandleSpec, Motion, OrientationMode, Trajectory};
pub use reach::{ReachMessage, ReachWatch};
pub use world::{
    ContactStepReport, Energies, NoClock, ObjectKind, ObjectStepReport, Phase, PhaseClock,
    SimObject, SingularPoint, StepReport, World,
};
