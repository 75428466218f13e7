//! The ROS 2 edge: message structs mirroring `msg/*.msg` and the standard interfaces,
//! their CDR encoding and schemas, names, parameters, the handle-input filter, the
//! session (frames of messages per simulation state) and the DDS node itself.
//!
//! The only module that knows ROS. The simulation core never imports it; conversions
//! from core types happen here ([`convert`], [`session`]).

pub mod cdr;
pub mod convert;
pub mod foxglove;
pub mod frames;
pub mod graph;
pub mod input;
pub mod introspect;
pub mod msgs;
pub mod names;
pub mod node;
pub mod node_stats;
pub mod param_msgs;
pub mod param_server;
pub mod params;
pub mod reply;
pub mod schema;
pub mod services;
pub mod session;
pub mod tf;
