//! The simulated world: objects, handles, one time step for all of them.
//!
//! This is the API every edge (CLI, ROS node, recorder, report) drives:
//! build a [`World`] from a scene, call [`World::step`] with the newest handle targets,
//! read meshes, singular points and the [`StepReport`]. Pure: no I/O, no ROS, no serde.
//! Every object meets one contract, [`ObjectSim`] (`object`, a leaf: the simulators
//! import it, not the world).

mod barrier_steps;
mod dependency_order;
mod grasp;
pub mod handle;
pub mod object;
pub mod reach;
mod world;

pub use grasp::{GraspAt, Grasped};
pub use handle::{
    GraspError, GraspEvent, HandleSpec, Hold, Motion, OrientationMode, ScriptedChange, Trajectory,
};
pub use object::{
    CompressionStats, ContactBody, Energies, ObjectSim, ObjectStepReport, Phase, PhaseClock,
    SingularPoint, StepContext, Wrench,
};
pub use reach::ReachWatch;
pub use world::{ContactStepReport, StepReport, World};
