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

/// A topic for one of the node's writers whose history is bounded by its QoS depth.
///
/// RustDDS keeps every sample a reliable writer published until all matched readers
/// acknowledged it, and with no reader matched it keeps them up to its 8192-sample
/// backstop (rustdds 0.15 `remove_all_acked_changes_but_keep_depth`): 8192 meshes of
/// ~20 kB each, memory that grows for minutes. A `KeepLast(depth)` writer owes nobody
/// more than its last `depth` samples, so the topic carries resource limits of
/// `depth` samples (ros2-client's `QosProfile` has no resource limits; the writer
/// inherits them from the topic).
fn writer_topic(
    context: &Context,
    node_name: &NodeName,
    topic: &Name,
    type_name: MessageTypeName,
    q: Qos,
) -> Result<ros2_client::dds::rustdds::Topic, ros2_client::dds::rustdds::dds::CreateError> {
    use ros2_client::dds::rustdds::{policy, QosPolicies, QosPolicyBuilder, TopicKind};
    let depth = q.depth.max(1) as i32;
    let limits = QosPolicyBuilder::new()
        .resource_limits(policy::ResourceLimits {
            max_samples: depth,
            max_instances: 1,
            max_samples_per_instance: depth,
        })
        .build();
    let dds_qos = QosPolicies::from(qos(q)).modify_by(&limits);
    context.domain_participant().create_topic(
        topic.to_dds_name("rt", node_name, ""),
        type_name.dds_msg_type(),
        &dds_qos,
        TopicKind::NoKey,
    )
}

/// A publisher on `topic` (a resolved ROS name) whose writer history is bounded by its
/// QoS depth (see [`writer_topic`]). `what` names it in errors.
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

/// The DDS QoS of a recorded-QoS description. Reliable writers never block the loop:
/// a full window fails the publication (counted) instead.
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

pub(crate) fn topic_type<M: RosMessage>() -> MessageTypeName {
    let mut parts = M::TYPE.split('/');
    let pkg = parts.next().unwrap_or("");
    let ty = parts.nth(1).unwrap_or("");
    MessageTypeName::new(pkg, ty)
}
