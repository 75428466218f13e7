//! The command line's logic, kept out of `main.rs` so that it is unit-tested: the
//! subcommands' options (`args`, clap), the node's order of precedence for its
//! settings (`node_launch`), its start-up banner (`banner`), the default bag folder
//! name (`bag_name`), and what the commands print when they finish (`summary`).
//! `main.rs` only parses and dispatches.

pub mod args;
pub mod bag_name;
pub mod banner;
pub mod node_launch;
pub mod summary;
