//! developable_sim: developable ribbons (Pan et al.) and paper (Schreck et al.) for robots.
//!
//! The simulation core (`geometry`, `ribbon`, `paper`, `contact`, `optim`, `sim`, `metrics`)
//! is pure: no I/O, no ROS, no serde. `scene` (configs), `ros` (the ROS 2 node and
//! messages), `record` (bags, replay) and the CLI are the edges around it. See
//! ARCHITECTURE.md.

// Index loops over several parallel arrays read as the papers' formulas (sum over k of
// a_k b_k), and `!(x < y)` is how the solvers catch NaN along with the failed test: both
// are meant, so clippy's style lints against them are off for the whole crate.
#![allow(clippy::needless_range_loop, clippy::neg_cmp_op_on_partial_ord)]

// The simulation core, its own crate (core/): re-exported so that `crate::ribbon::...`
// reads the same in the edges and in a library user's code.
pub use developable_core::{
    baseline, camera, contact, geometry, metrics, optim, paper, ribbon, sim,
};

// The edges, in layers (ARCHITECTURE.md, "Layers"; tests/layers.rs): each module
// imports only the core and the modules of the layers below its own. Those that speak
// a protocol, write a bag or drive the command line need the `node` feature, the
// report and the stress suite `tools` (both on by default; the Python wheel builds
// neither: Cargo.toml, `[features]`).
#[cfg(all(feature = "node", feature = "tools"))]
pub mod cli;
#[cfg(feature = "node")]
pub mod foxglove; //      4: transports
#[cfg(feature = "tools")]
pub mod plot; //          1: plots and self-contained pages (no scene, no run)
#[cfg(feature = "node")]
pub mod record; //        4
pub mod render; //        1: offline pictures
#[cfg(feature = "tools")]
pub mod report; //        6: tools built on runs
#[cfg(feature = "node")]
pub mod ros; //           5: the node (DDS), driving the recorder and Foxglove
pub mod runner; //        3: headless runs
pub mod scene; //         1: scene files
#[cfg(feature = "node")]
pub mod session; //       3: a simulation as the node runs it, without transport
pub mod stats; //         1: run statistics
#[cfg(feature = "tools")]
pub mod stress; //        6
#[cfg(feature = "node")]
pub mod wire; //          2: messages, CDR, schemas, QoS //           7: the command line
