//! DDS plumbing shared by the node, its graph inputs and its services: the node's
//! error type, QoS profiles from the recorded-QoS descriptions, topic type names, and
//! publishers whose writer history is bounded by their QoS depth.

use ros2_client::qos::{Durability, History, WhenFull};
use ros2_client::{Context, MessageTypeName, Name, Node, NodeName, Publisher, QosProfile};
use serde::Serialize;

use super::msgs::RosMessage;
use crate::record::metadata::Qos;

/// A problem starting or running the node.
#[derive(Debug, thiserror::Error)]
pub enum NodeError {
    #[error("DDS: {0}")]
    Dds(String),
    #[error("{0}")]
    Record(#[from] crate::record::RecordError),
    #[error("poll: {0}")]
    Poll(#[from] std::io::Error),
    /// Settings that cannot work together (found before anything starts).
    #[error("{0}")]
    Config(String),
    #[error("{0}")]
    Foxglove(#[from] super::foxglove::FoxgloveStartError),
}

pub(crate) fn dds<E: std::fmt::Debug>(what: &str) -> impl Fn(E) -> NodeError + '_ {
    move |e| NodeError::Dds(format!("{what}: {e:?}"))
}

/// A topic for one of the node's writers, with the writer's QoS.
///
/// The writers are `KeepLast(depth)`: with the patched RustDDS (vendor/rustdds,
/// docs/ros2_interop.md "Patched RustDDS") such a writer keeps its newest `depth`
/// samples plus, for repair, up to 64 a reliable reader has not acknowledged; it
/// never blocks and never fails on a full history, whatever its readers do, and a
/// transient-local late joiner gets the newest `depth` samples only. No resource
/// limits: `max_samples` would also cap that send window (a depth-1 writer would be
/// stop-and-wait again).
fn writer_topic(
    context: &Context,
    node_name: &NodeName,
    topic: &Name,
    type_name: MessageTypeName,
    q: Qos,
) -> Result<ros2_client::dds::rustdds::Topic, ros2_client::dds::rustdds::dds::CreateError> {
    use ros2_client::dds::rustdds::{QosPolicies, TopicKind};
    context.domain_participant().create_topic(
        topic.to_dds_name("rt", node_name, ""),
        type_name.dds_msg_type(),
        &QosPolicies::from(qos(q)),
        TopicKind::NoKey,
    )
}

/// A publisher on `topic` (a resolved ROS name) whose writer keeps its QoS depth and
/// never blocks (see [`writer_topic`]). `what` names it in errors.
pub(crate) fn bounded_publisher<M: RosMessage + Serialize>(
    node: &mut Node,
    context: &Context,
    node_name: &NodeName,
    topic: &str,
    q: Qos,
    what: &str,
) -> Result<Publisher<M>, NodeError> {
    let name = Name::parse(topic).map_err(dds("topic name"))?;
    let t = writer_topic(context, node_name, &name, topic_type::<M>(), q)
        .map_err(|e| NodeError::Dds(format!("{what} topic: {e:?}")))?;
    node.create_publisher(&t, Some(qos(q)))
        .map_err(|e| NodeError::Dds(format!("{what} publisher: {e:?}")))
}

/// The DDS QoS of a recorded-QoS description. Reliable writers never block the loop
/// (KEEP_LAST evicts the oldest sample instead, see [`writer_topic`]); `WhenFull::Fail`
/// only matters for a writer that is not KEEP_LAST.
pub(crate) fn qos(q: Qos) -> QosProfile {
    let p = QosProfile::subscription_default().history(History::KeepLast {
        depth: q.depth as usize,
    });
    let p = if q.reliable {
        p.reliability_reliable(WhenFull::Fail)
    } else {
        p.reliability_best_effort()
    };
    p.durability(if q.transient_local {
        Durability::TransientLocal
    } else {
        Durability::Volatile
    })
}

/// A publication's outcome without its message (a failed write hands the message
/// back; only why it failed is kept).
pub(crate) fn sent<M>(r: ros2_client::WriteResult<(), M>) -> Result<(), String> {
    r.map_err(|e| e.to_string())
}

pub(crate) fn topic_type<M: RosMessage>() -> MessageTypeName {
    let mut parts = M::TYPE.split('/');
    let pkg = parts.next().unwrap_or("");
    let ty = parts.nth(1).unwrap_or("");
    MessageTypeName::new(pkg, ty)
}
