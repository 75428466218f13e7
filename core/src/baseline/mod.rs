//! Conventional simulators the papers compare against, run on the same scenes so the
//! report can say where the reduced models win and by how much.
//!
//! Pure core: no I/O, no clocks.

pub mod conforming_fem;

pub use conforming_fem::{BaselineError, ConformingFem, ConformingFemParams};
