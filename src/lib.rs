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

pub mod cli;
pub mod record;
pub mod render;
pub mod report;
pub mod ros;
pub mod runner;
pub mod scene;
pub mod stats;
pub mod stress;
