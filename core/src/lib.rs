//! developable_core: the pure simulation core of developable_sim.
//!
//! Developable ribbons (Pan et al., ruling-bending coordinates: [`ribbon`]) and sheets
//! of paper (Schreck et al., non-smooth developable geometry: [`paper`]), their contact
//! ([`contact`]), the solvers they share ([`optim`]), the world that steps them
//! ([`sim`]), error measures ([`metrics`]) and the conforming-FEM baseline
//! ([`baseline`]).
//!
//! Architecture invariant: no I/O, no ROS, no serde, no clocks. It takes a scene's
//! objects and handle targets and returns a state; the `developable_sim` crate holds
//! the edges (scene files, the wire format, the ROS 2 node, bags, the CLI). The
//! compiler enforces it: this crate's dependency list is in its Cargo.toml.

// Index loops over several parallel arrays read as the papers' formulas (sum over k of
// a_k b_k), and `!(x < y)` is how the solvers catch NaN along with the failed test: both
// are meant, so clippy's style lints against them are off for the whole crate.
#![allow(clippy::needless_range_loop, clippy::neg_cmp_op_on_partial_ord)]

pub mod baseline;
pub mod camera;
pub mod contact;
pub mod geometry;
pub mod metrics;
pub mod optim;
pub mod paper;
pub mod ribbon;
pub mod sim;
