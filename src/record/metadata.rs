//! rosbag2's `metadata.yaml` (version 9, ROS 2 Jazzy) and QoS profiles as rosbag2
//! writes them.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use super::RecordError;
pub use crate::wire::qos::Qos;

/// rosbag2 metadata version written (Jazzy).
const VERSION: u32 = 9;

/// How rosbag2 writes a topic's offered QoS.
pub trait QosRecord {
    /// As rosbag2 Jazzy writes it.
    fn entry(&self) -> QosEntry;
    /// The `offered_qos_profiles` channel-metadata string (a YAML list).
    fn yaml(&self) -> String;
}

impl QosRecord for Qos {
    fn entry(&self) -> QosEntry {
        QosEntry {
            history: "keep_last".into(),
            depth: self.depth,
            reliability: if self.reliable {
                "reliable"
            } else {
                "best_effort"
            }
            .into(),
            durability: if self.transient_local {
                "transient_local"
            } else {
                "volatile"
            }
            .into(),
            deadline: RosDuration::INFINITE,
            lifespan: RosDuration::INFINITE,
            liveliness: "automatic".into(),
            liveliness_lease_duration: RosDuration::INFINITE,
            avoid_ros_namespace_conventions: false,
        }
    }

    fn yaml(&self) -> String {
        serde_yaml::to_string(&vec![self.entry()]).unwrap_or_default()
    }
}

/// A duration in rosbag2's QoS notation.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct RosDuration {
    pub sec: i64,
    pub nsec: i64,
}

impl RosDuration {
    /// rmw's "infinite" duration as rosbag2 writes it.
    const INFINITE: RosDuration = RosDuration {
        sec: 9_223_372_036,
        nsec: 854_775_807,
    };
}

#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct QosEntry {
    pub history: String,
    pub depth: u32,
    pub reliability: String,
    pub durability: String,
    pub deadline: RosDuration,
    pub lifespan: RosDuration,
    pub liveliness: String,
    pub liveliness_lease_duration: RosDuration,
    pub avoid_ros_namespace_conventions: bool,
}

#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Nanoseconds {
    pub nanoseconds: u64,
}

#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct SinceEpoch {
    pub nanoseconds_since_epoch: u64,
}

#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct TopicMetadata {
    pub name: String,
    #[serde(rename = "type")]
    pub type_name: String,
    pub serialization_format: String,
    /// A list in version 9 (a YAML string in older versions; we write the list).
    pub offered_qos_profiles: Vec<QosEntry>,
    pub type_description_hash: String,
}

#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct TopicWithCount {
    pub topic_metadata: TopicMetadata,
    pub message_count: u64,
}

#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct FileInfo {
    pub path: String,
    pub starting_time: SinceEpoch,
    pub duration: Nanoseconds,
    pub message_count: u64,
}

#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct BagInfo {
    pub version: u32,
    pub storage_identifier: String,
    pub duration: Nanoseconds,
    pub starting_time: SinceEpoch,
    pub message_count: u64,
    pub topics_with_message_count: Vec<TopicWithCount>,
    pub compression_format: String,
    pub compression_mode: String,
    pub relative_file_paths: Vec<String>,
    pub files: Vec<FileInfo>,
    pub custom_data: Option<BTreeMap<String, String>>,
    pub ros_distro: String,
}

/// The whole `metadata.yaml`.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct MetadataFile {
    pub rosbag2_bagfile_information: BagInfo,
}

/// Per-topic facts needed to write metadata.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct TopicSummary {
    pub name: String,
    pub type_name: String,
    pub qos: Vec<QosEntry>,
    pub type_hash: String,
    pub count: u64,
}

/// Build the metadata of a one-file bag.
pub fn build(
    file_name: &str,
    topics: &[TopicSummary],
    first_ns: Option<u64>,
    last_ns: Option<u64>,
    custom_data: BTreeMap<String, String>,
) -> MetadataFile {
    let count: u64 = topics.iter().map(|t| t.count).sum();
    let start = first_ns.unwrap_or(0);
    let duration = match (first_ns, last_ns) {
        (Some(a), Some(b)) if b >= a => b - a,
        _ => 0,
    };
    MetadataFile {
        rosbag2_bagfile_information: BagInfo {
            version: VERSION,
            storage_identifier: "mcap".into(),
            duration: Nanoseconds {
                nanoseconds: duration,
            },
            starting_time: SinceEpoch {
                nanoseconds_since_epoch: start,
            },
            message_count: count,
            topics_with_message_count: topics
                .iter()
                .map(|t| TopicWithCount {
                    topic_metadata: TopicMetadata {
                        name: t.name.clone(),
                        type_name: t.type_name.clone(),
                        serialization_format: "cdr".into(),
                        offered_qos_profiles: t.qos.clone(),
                        type_description_hash: t.type_hash.clone(),
                    },
                    message_count: t.count,
                })
                .collect(),
            compression_format: String::new(),
            compression_mode: String::new(),
            relative_file_paths: vec![file_name.to_string()],
            files: vec![FileInfo {
                path: file_name.to_string(),
                starting_time: SinceEpoch {
                    nanoseconds_since_epoch: start,
                },
                duration: Nanoseconds {
                    nanoseconds: duration,
                },
                message_count: count,
            }],
            custom_data: if custom_data.is_empty() {
                None
            } else {
                Some(custom_data)
            },
            ros_distro: ros_distro().into(),
        },
    }
}

/// The ROS 2 distribution this build speaks (the ros2-client feature).
fn ros_distro() -> &'static str {
    if cfg!(feature = "humble") && !cfg!(feature = "jazzy") {
        "humble"
    } else {
        "jazzy"
    }
}

/// Write `metadata.yaml` into `dir`.
pub fn write_metadata_file(dir: &std::path::Path, meta: &MetadataFile) -> Result<(), RecordError> {
    let path = dir.join("metadata.yaml");
    let text = serde_yaml::to_string(meta).map_err(|e| RecordError::Bag {
        path: path.clone(),
        message: e.to_string(),
    })?;
    std::fs::write(&path, text).map_err(|source| RecordError::Io { path, source })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn qos_yaml_is_a_list_rosbags_reads() {
        let y = Qos::MARKERS.yaml();
        assert!(y.starts_with("- history: keep_last\n"), "{y}");
        assert!(y.contains("durability: transient_local"));
        assert!(y.contains("sec: 9223372036"));
        let back: Vec<QosEntry> = serde_yaml::from_str(&y).unwrap();
        assert_eq!(back, vec![Qos::MARKERS.entry()]);
    }

    #[test]
    fn metadata_counts_and_times() {
        let t = TopicSummary {
            name: "/a".into(),
            type_name: "rosgraph_msgs/msg/Clock".into(),
            qos: vec![Qos::CLOCK.entry()],
            type_hash: "RIHS01_x".into(),
            count: 3,
        };
        let m = build(
            "b_0.mcap",
            &[t.clone(), t],
            Some(10),
            Some(25),
            BTreeMap::new(),
        );
        let i = &m.rosbag2_bagfile_information;
        assert_eq!((i.message_count, i.duration.nanoseconds), (6, 15));
        assert_eq!(i.files[0].message_count, 6);
        let text = serde_yaml::to_string(&m).unwrap();
        assert!(text.contains("version: 9"));
        assert!(text.contains("custom_data: null"));
        let back: MetadataFile = serde_yaml::from_str(&text).unwrap();
        assert_eq!(back, m);
    }
}
