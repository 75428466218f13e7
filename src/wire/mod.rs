//! The wire layer: what a message is, independent of how it travels. Rust mirrors of
//! every ROS 2 message and service the node speaks ([`msgs`], [`param_msgs`]; the
//! standard definitions in `interfaces/`, ours in `msg/`), their CDR encoding
//! ([`cdr`]), `ros2msg` schemas ([`schema`]), a field-by-field view for comparisons
//! ([`introspect`]), the QoS of each kind of topic ([`qos`]), the clock inputs are
//! stamped with ([`clock`]) and the conversions from the core's geometry ([`convert`]).
//!
//! Architecture invariant: DDS (`ros`), the bags (`record`) and Foxglove (`foxglove`)
//! all sit on this module and never define a message, an encoding or a QoS of their
//! own. It imports the core and nothing of the edges above it.

pub mod cdr;
pub mod clock;
pub mod convert;
pub mod introspect;
pub mod msgs;
pub mod param_msgs;
pub mod qos;
pub mod schema;
