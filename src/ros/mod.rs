//! The ROS 2 transport: the DDS node (ros2-client / RustDDS) that joins a domain,
//! subscribes to handle poses, TF and an external clock, serves the services and the
//! parameters, and publishes the session's frames; it drives the recorder and the
//! Foxglove server beside DDS.
//!
//! Architecture invariant: the only module that knows DDS. Messages, encodings and QoS
//! come from `wire`; what a state publishes and how inputs are judged from `session`.

pub mod action;
pub mod dds;
pub mod graph;
pub mod node;
pub mod node_stats;
pub mod param_server;
pub mod reply;
pub mod services;
pub mod tf;
