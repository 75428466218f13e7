//! DDS plumbing shared by the node, its graph inputs and its services: the node's
//! error type, QoS profiles from the recorded-QoS descriptions, topic type names, and
//! publishers whose writer history is bounded by their QoS depth.

use bytes::Bytes;
use ros2_client::dds::rustdds::no_key::{DataWriter, SerializerAdapter};
use ros2_client::dds::rustdds::RepresentationIdentifier;
use ros2_client::qos::{Durability, History, WhenFull};
use ros2_client::{Context, MessageTypeName, Name, Node, NodeName, QosProfile};

use crate::wire::msgs::RosMessage;
use crate::wire::qos::Qos;

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
    Foxglove(#[from] crate::foxglove::FoxgloveStartError),
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

/// A message already encoded as CDR (with its 4-byte encapsulation header), as the
/// session's frames hold it: DDS, the bags and Foxglove send the same bytes, encoded
/// once.
#[derive(Clone, Debug)]
pub struct RawCdr(pub Bytes);

/// RustDDS's serializer adapter for [`RawCdr`]: the payload is the bytes after the
/// encapsulation header (RustDDS writes the header from [`Self::output_encoding`]).
pub struct RawCdrAdapter;

impl SerializerAdapter<RawCdr> for RawCdrAdapter {
    type Error = std::io::Error;

    fn output_encoding() -> RepresentationIdentifier {
        RepresentationIdentifier::CDR_LE
    }

    fn to_bytes(value: &RawCdr) -> Result<Bytes, std::io::Error> {
        // the session encodes little endian (`wire::cdr::encode`): 00 01 00 00
        match value.0.get(..4) {
            Some([0x00, 0x01, _, _]) => Ok(value.0.slice(4..)),
            _ => Err(std::io::Error::new(
                std::io::ErrorKind::InvalidData,
                "not a CDR little-endian payload",
            )),
        }
    }
}

/// A writer of pre-encoded messages of one type.
pub type RawPublisher = DataWriter<RawCdr, RawCdrAdapter>;

/// A writer on `topic` (a resolved ROS name) of messages of type `type_name`
/// (`pkg/msg/Type`) that keeps its QoS depth and never blocks (see [`writer_topic`]).
/// `what` names it in errors.
pub(crate) fn raw_publisher(
    node: &mut Node,
    context: &Context,
    node_name: &NodeName,
    (topic, type_name): (&str, &str),
    q: Qos,
    what: &str,
) -> Result<RawPublisher, NodeError> {
    let name = Name::parse(topic).map_err(dds("topic name"))?;
    let t = writer_topic(context, node_name, &name, message_type_name(type_name), q)
        .map_err(|e| NodeError::Dds(format!("{what} topic: {e:?}")))?;
    node.create_datawriter::<RawCdr, RawCdrAdapter>(&t, Some(qos(q)))
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
pub(crate) fn sent<M>(
    r: ros2_client::dds::rustdds::dds::result::WriteResult<(), M>,
) -> Result<(), String> {
    r.map_err(|e| e.to_string())
}

pub(crate) fn topic_type<M: RosMessage>() -> MessageTypeName {
    message_type_name(M::TYPE)
}

/// `pkg/msg/Type` as ros2-client names it.
fn message_type_name(type_name: &str) -> MessageTypeName {
    let mut parts = type_name.split('/');
    let pkg = parts.next().unwrap_or("");
    let ty = parts.nth(1).unwrap_or("");
    MessageTypeName::new(pkg, ty)
}
