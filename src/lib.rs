//! developable_sim: developable ribbons (Pan et al.) and paper (Schreck et al.) for robots.
//!
//! The simulation core (`geometry`, `ribbon`, `paper`, `contact`, `optim`, `sim`, `metrics`)
//! is pure: no I/O, no ROS, no serde. `scene` (configs), `ros` (the ROS 2 node and
//! messages), `record` (bags, replay) and the CLI are the edges around it. See
//! ARCHITECTURE.md.

pub mod baseline;
pub mod cli;
pub mod contact;
pub mod geometry;
pub mod metrics;
pub mod optim;
pub mod paper;
pub mod record;
pub mod render;
pub mod report;
pub mod ribbon;
pub mod ros;
pub mod runner;
pub mod scene;
pub mod sim;
pub mod stats;
pub mod stress;
