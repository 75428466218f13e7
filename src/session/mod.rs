//! The session layer: a simulation as the node runs it, with no transport. The scene,
//! the handle-input filter ([`input`]), the commands that change it ([`command`]), the
//! outputs it produces as a table ([`outputs`]: markers, statuses, singular points,
//! clock, colliders, the grasp and end frames on `/tf`), the resolved names of every
//! topic and service ([`names`]) and the parameters ([`params`]).
//!
//! Architecture invariant: nothing here opens a socket, a file or a clock of its own:
//! the node (`ros`), the recorder and `replay` (`record`) and Foxglove drive a
//! [`Session`] the same way, so a replay reproduces what the node did.

pub mod camera;
pub mod command;
pub mod frames;
pub mod grasping;
pub mod input;
mod markers;
pub mod names;
pub mod outputs;
pub mod params;
pub mod produce;
pub mod robot;
pub mod sensor;
pub mod sim_clock;
mod state;
mod status;
pub mod style;

pub use command::Command;
pub use outputs::{Frame, OutputRow, OutputTable, RunOutputs, Scope};
pub use state::{Applied, Content, Session};
pub use style::MarkerStyle;
