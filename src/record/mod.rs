//! rosbag2-compatible recording and the offline checks built on it.
//!
//! - [`bag`]: a bag folder writer: one MCAP file (profile `ros2`, `ros2msg` schemas with
//!   dependencies, `cdr` messages, channel metadata `offered_qos_profiles` and
//!   `topic_type_hash`), chunked and flushed periodically, and `metadata.yaml`
//!   (rosbag2 version 9) written on close.
//! - [`read`]: a streaming reader that also reads a bag cut short by a crash, and
//!   [`read::reindex`] (rebuild `metadata.yaml`, repair a truncated MCAP).
//! - [`recorder`]: which topics a session records and how frames are written.
//! - [`replay`]: re-simulate a bag from its recorded handle inputs and compare.
//!
//! An edge module: it knows files and the ROS wire format, the simulation core knows
//! neither.

pub mod bag;
pub mod metadata;
pub mod read;
pub mod recorder;
pub mod replay;

use std::path::PathBuf;

/// A recording problem, with the file it concerns.
#[derive(Debug, thiserror::Error)]
pub enum RecordError {
    #[error("bag folder {path}: {message}")]
    Folder { path: PathBuf, message: String },
    #[error("{path}: {source}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// The MCAP writer's or reader's error with its OS cause (`File too large (os error
    /// 27)`), which the MCAP crate's own message leaves out: the node logs this line.
    #[error("{path}: MCAP: {}", mcap_cause(.error))]
    Mcap {
        path: PathBuf,
        error: mcap::McapError,
    },
    #[error("{path}: {message}")]
    Bag { path: PathBuf, message: String },
    #[error("encoding a message: {0}")]
    Cdr(#[from] crate::wire::cdr::CdrError),
}

/// An MCAP error and, for an I/O error, the OS error under it.
fn mcap_cause(e: &mcap::McapError) -> String {
    match e {
        mcap::McapError::Io(io) => format!("{e}: {io}"),
        _ => e.to_string(),
    }
}
