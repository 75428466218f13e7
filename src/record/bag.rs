//! The bag folder writer: `<folder>/<folder>_0.mcap` plus `metadata.yaml`.
//!
//! Messages go into MCAP chunks; the open chunk is closed and flushed to the OS at
//! least every `flush_period`, so after a crash (or `kill -9`) a streaming reader
//! reads everything up to the last flush, and `developable_sim bag reindex` rebuilds
//! the rest. A write error (disk full, folder removed) stops the recording: the
//! error is returned once, later writes are ignored, and [`BagWriter::close`] still
//! writes `metadata.yaml` counting what is readable.

use std::collections::BTreeMap;
use std::fs::File;
use std::io::{BufWriter, Seek, Write};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use super::metadata::{self, write_metadata_file, Qos, QosRecord, TopicSummary};
use super::RecordError;
use crate::wire::msgs::RosMessage;

/// MCAP chunk compression.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Compression {
    /// No compression (rosbag2's default storage preset).
    #[default]
    None,
    /// LZ4 frames (fast; readable by rosbag2, Foxglove, rosbags and mcap).
    Lz4,
}

impl std::str::FromStr for Compression {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "none" | "" => Ok(Compression::None),
            "lz4" => Ok(Compression::Lz4),
            other => Err(format!(
                "unknown compression `{other}`, expected none or lz4"
            )),
        }
    }
}

/// How a bag is written.
#[derive(Clone, Debug, PartialEq)]
pub struct BagOptions {
    pub compression: Compression,
    /// Target uncompressed chunk size, bytes (rosbag2: 768 KiB).
    pub chunk_size: u64,
    /// The open chunk is flushed at least this often.
    pub flush_period: Duration,
    /// Extra `custom_data` for metadata.yaml.
    pub custom_data: BTreeMap<String, String>,
    /// Record the cameras' images and clouds too (`--record-cameras`; 6.4 MB a 640 x 480
    /// frame). Their camera_info is recorded regardless.
    pub record_cameras: bool,
}

impl Default for BagOptions {
    fn default() -> Self {
        BagOptions {
            compression: Compression::None,
            chunk_size: 768 * 1024,
            flush_period: Duration::from_secs(1),
            custom_data: BTreeMap::new(),
            record_cameras: false,
        }
    }
}

/// Something the MCAP can be written to (a file; tests inject failing sinks).
pub trait Sink: Write + Seek + Send {}
impl<T: Write + Seek + Send> Sink for T {}

/// A recorded topic.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct TopicId(usize);

struct TopicState {
    name: String,
    type_name: String,
    qos: Qos,
    type_hash: String,
    channel: u16,
    count: u64,
}

/// Writes one bag folder.
pub struct BagWriter {
    dir: PathBuf,
    file_name: String,
    mcap: Option<mcap::Writer<Box<dyn Sink>>>,
    topics: Vec<TopicState>,
    schemas: BTreeMap<String, u16>,
    first_ns: Option<u64>,
    last_ns: Option<u64>,
    last_flush: Instant,
    options: BagOptions,
    /// Set on the first write error; the recording stops there.
    failed: Option<String>,
    closed: bool,
}

impl BagWriter {
    /// Create `dir` (and its parents) and the MCAP file in it. Fails if `dir` exists and
    /// is not an empty folder (a bag is never overwritten).
    pub fn create(dir: &Path, options: BagOptions) -> Result<BagWriter, RecordError> {
        let folder = |message: String| RecordError::Folder {
            path: dir.to_path_buf(),
            message,
        };
        if dir.exists() {
            if !dir.is_dir() {
                return Err(folder("exists and is not a folder".into()));
            }
            let empty = std::fs::read_dir(dir)
                .map_err(|e| folder(format!("cannot list it: {e}")))?
                .next()
                .is_none();
            if !empty {
                return Err(folder(
                    "already exists and is not empty (bags are never overwritten: choose a new folder)"
                        .into(),
                ));
            }
        }
        std::fs::create_dir_all(dir).map_err(|e| folder(format!("cannot create it: {e}")))?;
        let file_name = format!("{}_0.mcap", folder_name(dir));
        let path = dir.join(&file_name);
        let file = File::create(&path).map_err(|source| RecordError::Io {
            path: path.clone(),
            source,
        })?;
        Self::with_sink(dir, &file_name, Box::new(BufWriter::new(file)), options)
    }

    /// Create a writer on `sink` (named `file_name` in metadata) in folder `dir`.
    pub fn with_sink(
        dir: &Path,
        file_name: &str,
        sink: Box<dyn Sink>,
        options: BagOptions,
    ) -> Result<BagWriter, RecordError> {
        let path = dir.join(file_name);
        let compression = match options.compression {
            Compression::None => None,
            Compression::Lz4 => Some(mcap::Compression::Lz4),
        };
        let mcap = mcap::WriteOptions::new()
            .profile("ros2")
            .library(format!("developable_sim {}", env!("CARGO_PKG_VERSION")))
            .compression(compression)
            .chunk_size(Some(options.chunk_size))
            .create(sink)
            .map_err(|error| RecordError::Mcap { path, error })?;
        Ok(BagWriter {
            dir: dir.to_path_buf(),
            file_name: file_name.to_string(),
            mcap: Some(mcap),
            topics: Vec::new(),
            schemas: BTreeMap::new(),
            first_ns: None,
            last_ns: None,
            last_flush: Instant::now(),
            options,
            failed: None,
            closed: false,
        })
    }

    /// The bag folder.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// The MCAP file.
    fn mcap_path(&self) -> PathBuf {
        self.dir.join(&self.file_name)
    }

    /// Why the recording stopped, if it did.
    pub fn failure(&self) -> Option<&str> {
        self.failed.as_deref()
    }

    fn mcap_error(&self, error: mcap::McapError) -> RecordError {
        RecordError::Mcap {
            path: self.mcap_path(),
            error,
        }
    }

    fn fail(&mut self, e: RecordError) -> RecordError {
        if self.failed.is_none() {
            self.failed = Some(e.to_string());
        }
        e
    }

    fn writer(&mut self) -> Result<&mut mcap::Writer<Box<dyn Sink>>, RecordError> {
        if let Some(f) = &self.failed {
            return Err(RecordError::Bag {
                path: self.mcap_path(),
                message: format!("recording stopped earlier: {f}"),
            });
        }
        let path = self.mcap_path();
        self.mcap.as_mut().ok_or(RecordError::Bag {
            path,
            message: "the bag is closed".into(),
        })
    }

    /// Add a topic of message type `M` offered with `qos`.
    pub fn add_topic<M: RosMessage>(
        &mut self,
        name: &str,
        qos: Qos,
    ) -> Result<TopicId, RecordError> {
        self.add_topic_of(name, (M::TYPE, M::HASH, &M::schema), qos)
    }

    /// Add a topic of message type `type_name` (`pkg/msg/Type`) with its REP-2011 hash
    /// and `ros2msg` schema (made only for the first topic of the type), offered with
    /// `qos`.
    pub fn add_topic_of(
        &mut self,
        name: &str,
        (type_name, type_hash, schema): (&str, &str, &dyn Fn() -> String),
        qos: Qos,
    ) -> Result<TopicId, RecordError> {
        let schema = match self.schemas.get(type_name) {
            Some(id) => *id,
            None => {
                let text = schema();
                let r = self
                    .writer()?
                    .add_schema(type_name, "ros2msg", text.as_bytes());
                let id = match r {
                    Ok(id) => id,
                    Err(e) => {
                        let e = self.mcap_error(e);
                        return Err(self.fail(e));
                    }
                };
                self.schemas.insert(type_name.to_string(), id);
                id
            }
        };
        let mut meta = BTreeMap::new();
        meta.insert("offered_qos_profiles".to_string(), qos.yaml());
        meta.insert("topic_type_hash".to_string(), type_hash.to_string());
        let r = self.writer()?.add_channel(schema, name, "cdr", &meta);
        let channel = match r {
            Ok(c) => c,
            Err(e) => {
                let e = self.mcap_error(e);
                return Err(self.fail(e));
            }
        };
        self.topics.push(TopicState {
            name: name.to_string(),
            type_name: type_name.to_string(),
            qos,
            type_hash: type_hash.to_string(),
            channel,
            count: 0,
        });
        Ok(TopicId(self.topics.len() - 1))
    }

    /// Write one message (already CDR-encoded with its encapsulation header).
    /// `log_time_ns`: when it was received / produced; `publish_time_ns`: when it was
    /// sent (both ns since the Unix epoch).
    pub fn write_raw(
        &mut self,
        topic: TopicId,
        log_time_ns: u64,
        publish_time_ns: u64,
        data: &[u8],
    ) -> Result<(), RecordError> {
        let t = self.topics.get(topic.0).ok_or(RecordError::Bag {
            path: self.dir.clone(),
            message: format!("unknown topic id {}", topic.0),
        })?;
        let header = mcap::records::MessageHeader {
            channel_id: t.channel,
            sequence: (t.count + 1) as u32,
            log_time: log_time_ns,
            publish_time: publish_time_ns,
        };
        let r = self.writer()?.write_to_known_channel(&header, data);
        if let Err(e) = r {
            let e = self.mcap_error(e);
            return Err(self.fail(e));
        }
        self.topics[topic.0].count += 1;
        self.first_ns = Some(self.first_ns.map_or(log_time_ns, |f| f.min(log_time_ns)));
        self.last_ns = Some(self.last_ns.map_or(log_time_ns, |l| l.max(log_time_ns)));
        if self.last_flush.elapsed() >= self.options.flush_period {
            self.flush()?;
        }
        Ok(())
    }

    /// Encode and write one message.
    pub fn write<M: RosMessage>(
        &mut self,
        topic: TopicId,
        log_time_ns: u64,
        msg: &M,
    ) -> Result<(), RecordError> {
        let data = crate::wire::cdr::encode(msg)?;
        self.write_raw(topic, log_time_ns, log_time_ns, &data)
    }

    /// Close the open chunk and hand everything to the OS: a streaming reader can read
    /// every message written so far.
    pub fn flush(&mut self) -> Result<(), RecordError> {
        self.last_flush = Instant::now();
        let r = self.writer()?.flush();
        if let Err(e) = r {
            let e = self.mcap_error(e);
            return Err(self.fail(e));
        }
        Ok(())
    }

    /// Add an MCAP metadata record (name, key/value map).
    pub fn write_metadata(
        &mut self,
        name: &str,
        values: BTreeMap<String, String>,
    ) -> Result<(), RecordError> {
        let r = self.writer()?.write_metadata(&mcap::records::Metadata {
            name: name.to_string(),
            metadata: values,
        });
        if let Err(e) = r {
            let e = self.mcap_error(e);
            return Err(self.fail(e));
        }
        Ok(())
    }

    /// Messages written per topic.
    pub fn counts(&self) -> Vec<(String, u64)> {
        self.topics
            .iter()
            .map(|t| (t.name.clone(), t.count))
            .collect()
    }

    /// Finish the MCAP (summary, footer) and write `metadata.yaml`. After a write
    /// error the MCAP is left as written and the metadata counts what a streaming
    /// reader can read from it. Returns the metadata written.
    pub fn close(&mut self) -> Result<metadata::MetadataFile, RecordError> {
        if self.closed {
            return Err(RecordError::Bag {
                path: self.dir.clone(),
                message: "the bag is already closed".into(),
            });
        }
        self.closed = true;
        let mut finish_error = None;
        if let Some(mut w) = self.mcap.take() {
            if self.failed.is_none() {
                let mut rosbag2 = BTreeMap::new();
                let meta = self.metadata();
                rosbag2.insert(
                    "serialized_metadata".to_string(),
                    serde_yaml::to_string(&meta).unwrap_or_default(),
                );
                let r = w
                    .write_metadata(&mcap::records::Metadata {
                        name: "rosbag2".into(),
                        metadata: rosbag2,
                    })
                    .and_then(|_| w.finish().map(|_| ()));
                if let Err(e) = r {
                    finish_error = Some(self.mcap_error(e));
                } else {
                    let mut sink = w.into_inner();
                    if let Err(e) = sink.flush() {
                        finish_error = Some(RecordError::Io {
                            path: self.mcap_path(),
                            source: e,
                        });
                    }
                }
            } else {
                // dropping a failed writer does not write any more
                drop(w);
            }
        }
        if let Some(e) = &finish_error {
            self.failed.get_or_insert_with(|| e.to_string());
        }
        let meta = if self.failed.is_some() {
            // count what is actually readable
            match super::read::scan(&self.mcap_path()) {
                Ok(scan) => scan.metadata(&self.file_name, self.custom_data()),
                Err(_) => self.metadata(),
            }
        } else {
            self.metadata()
        };
        write_metadata_file(&self.dir, &meta)?;
        match finish_error {
            Some(e) => Err(e),
            None => Ok(meta),
        }
    }

    fn custom_data(&self) -> BTreeMap<String, String> {
        self.options.custom_data.clone()
    }

    fn metadata(&self) -> metadata::MetadataFile {
        let topics: Vec<TopicSummary> = self
            .topics
            .iter()
            .map(|t| TopicSummary {
                name: t.name.clone(),
                type_name: t.type_name.clone(),
                qos: vec![t.qos.entry()],
                type_hash: t.type_hash.clone(),
                count: t.count,
            })
            .collect();
        metadata::build(
            &self.file_name,
            &topics,
            self.first_ns,
            self.last_ns,
            self.custom_data(),
        )
    }
}

impl Drop for BagWriter {
    fn drop(&mut self) {
        if !self.closed {
            let _ = self.close();
        }
    }
}

/// The folder's last path component (`bags/demo` -> `demo`).
fn folder_name(dir: &Path) -> String {
    dir.file_name()
        .map(|s| s.to_string_lossy().into_owned())
        .filter(|s| !s.is_empty() && s != "." && s != "..")
        .unwrap_or_else(|| "bag".into())
}
