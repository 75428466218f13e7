//! Streaming bag reading (file order, constant memory) that survives a file cut short
//! by a crash, and `reindex`: rebuild `metadata.yaml` from the MCAP files of a bag
//! folder, repairing a truncated MCAP first (as `ros2 bag reindex` does for the
//! metadata; the repair makes indexed readers such as `rosbags` open it too).

use std::collections::BTreeMap;
use std::fs::File;
use std::io::{BufReader, BufWriter, Read};
use std::path::{Path, PathBuf};

use mcap::records::Record;
use mcap::sans_io::{LinearReadEvent, LinearReader, LinearReaderOptions};

use super::metadata::write_metadata_file;
use super::metadata::{self, MetadataFile, QosEntry, TopicSummary};
use super::RecordError;

/// A recorded channel.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ChannelInfo {
    pub id: u16,
    pub topic: String,
    /// `package/msg/Type` (the schema name).
    pub type_name: String,
    pub schema_encoding: String,
    pub schema: Vec<u8>,
    pub message_encoding: String,
    pub metadata: BTreeMap<String, String>,
}

/// One message of a bag.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct BagMessage {
    pub channel: u16,
    pub topic: String,
    pub type_name: String,
    pub sequence: u32,
    pub log_time: u64,
    pub publish_time: u64,
    /// CDR payload with its encapsulation header.
    pub data: Vec<u8>,
}

/// What a bag holds, in file order.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum BagEvent {
    Message(BagMessage),
    /// An MCAP metadata record.
    Metadata {
        name: String,
        values: BTreeMap<String, String>,
    },
}

/// Reads an MCAP file record by record. Ends quietly at the end of the data (complete
/// file) or at the first unreadable record (truncated file: see [`McapStream::truncated`]).
pub struct McapStream {
    path: PathBuf,
    file: BufReader<File>,
    reader: LinearReader,
    schemas: BTreeMap<u16, (String, String, Vec<u8>)>,
    channels: BTreeMap<u16, ChannelInfo>,
    done: bool,
    /// Why reading stopped early (None: the data section was read to its end).
    pub truncated: Option<String>,
    /// True once the data-end record was reached.
    pub reached_data_end: bool,
    /// The MCAP header's `library` (who wrote the file), once read.
    pub library: Option<String>,
    /// The records of a chunk the writer never closed, read after the reader stopped at
    /// it (see [`open_chunk_records`]), and why it stopped.
    open_chunk: Option<(std::collections::VecDeque<RawRecord>, String)>,
}

/// How `reindex` ends the `library` of the files it rewrites: such a file was cut short
/// (crash, full disk) before it was repaired, so its last state may be incomplete.
pub const REINDEX_LIBRARY_SUFFIX: &str = "(reindex)";

impl McapStream {
    pub fn open(path: &Path) -> Result<McapStream, RecordError> {
        let file = File::open(path).map_err(|source| RecordError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        Ok(McapStream {
            path: path.to_path_buf(),
            file: BufReader::with_capacity(1 << 16, file),
            reader: LinearReader::new_with_options(
                LinearReaderOptions::default().with_skip_end_magic(true),
            ),
            schemas: BTreeMap::new(),
            channels: BTreeMap::new(),
            done: false,
            truncated: None,
            reached_data_end: false,
            library: None,
            open_chunk: None,
        })
    }

    /// Channels seen so far, by id.
    fn channels(&self) -> &BTreeMap<u16, ChannelInfo> {
        &self.channels
    }

    /// The channel `id`, once its record was read.
    pub fn channel(&self, id: u16) -> Option<&ChannelInfo> {
        self.channels.get(&id)
    }

    fn stop(&mut self, why: String) -> Option<Result<BagEvent, RecordError>> {
        self.done = true;
        self.truncated = Some(why);
        None
    }
}

impl Iterator for McapStream {
    type Item = Result<BagEvent, RecordError>;

    fn next(&mut self) -> Option<Self::Item> {
        while !self.done {
            if let Some((records, why)) = self.open_chunk.as_mut() {
                let Some((opcode, data)) = records.pop_front() else {
                    let why = why.clone();
                    return self.stop(why);
                };
                match mcap::parse_record(opcode, &data) {
                    Ok(record) => match self.handle(record) {
                        Some(event) => return Some(event),
                        None => continue,
                    },
                    Err(e) => return self.stop(e.to_string()),
                }
            }
            let event = match self.reader.next_event() {
                None => {
                    self.done = true;
                    return None;
                }
                Some(Err(e)) => {
                    self.reader_failed(e.to_string());
                    continue;
                }
                Some(Ok(e)) => e,
            };
            match event {
                LinearReadEvent::ReadRequest(n) => {
                    let buf = self.reader.insert(n);
                    let read = loop {
                        match self.file.read(buf) {
                            Ok(r) => break r,
                            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
                            Err(e) => {
                                let path = self.path.clone();
                                self.done = true;
                                return Some(Err(RecordError::Io { path, source: e }));
                            }
                        }
                    };
                    self.reader.notify_read(read);
                }
                LinearReadEvent::Record { data, opcode } => {
                    let record = match mcap::parse_record(opcode, data) {
                        Ok(r) => r,
                        Err(e) => {
                            let why = e.to_string();
                            return self.stop(why);
                        }
                    };
                    let taken = take_record(
                        &mut self.schemas,
                        &mut self.channels,
                        &mut self.library,
                        record,
                    );
                    if let Some(event) = self.outcome(taken) {
                        return Some(event);
                    }
                }
            }
        }
        None
    }
}

impl McapStream {
    /// The reader stopped (`why`): when at a chunk its writer never closed (a crash, a
    /// full disk), read on inside it; otherwise stop.
    fn reader_failed(&mut self, why: String) {
        match open_chunk_records(&self.path) {
            Some(records) if !records.is_empty() => {
                let why = format!(
                    "{why}; the last chunk was never closed: its {} complete records were read",
                    records.len()
                );
                self.open_chunk = Some((records.into(), why));
            }
            _ => {
                self.stop(why);
            }
        }
    }

    /// Take one record's outcome (see [`take_record`]).
    fn handle(&mut self, record: Record) -> Option<Result<BagEvent, RecordError>> {
        let taken = take_record(
            &mut self.schemas,
            &mut self.channels,
            &mut self.library,
            record,
        );
        self.outcome(taken)
    }

    fn outcome(&mut self, taken: Taken) -> Option<Result<BagEvent, RecordError>> {
        match taken {
            Taken::Event(e) => Some(Ok(e)),
            Taken::Stop(why) => self.stop(why),
            Taken::DataEnd => {
                self.reached_data_end = true;
                self.done = true;
                None
            }
            Taken::Nothing => None,
        }
    }
}

/// What one record means to the stream.
enum Taken {
    Event(BagEvent),
    Stop(String),
    DataEnd,
    Nothing,
}

/// Take one record: remember schemas and channels (and the writing library), turn
/// messages and metadata into events.
fn take_record(
    schemas: &mut BTreeMap<u16, (String, String, Vec<u8>)>,
    channels: &mut BTreeMap<u16, ChannelInfo>,
    library: &mut Option<String>,
    record: Record,
) -> Taken {
    match record {
        Record::Header(h) => *library = Some(h.library),
        Record::Schema { header, data } => {
            schemas.insert(header.id, (header.name, header.encoding, data.into_owned()));
        }
        Record::Channel(c) => {
            let (type_name, schema_encoding, schema) =
                schemas.get(&c.schema_id).cloned().unwrap_or_default();
            channels.insert(
                c.id,
                ChannelInfo {
                    id: c.id,
                    topic: c.topic,
                    type_name,
                    schema_encoding,
                    schema,
                    message_encoding: c.message_encoding,
                    metadata: c.metadata,
                },
            );
        }
        Record::Message { header, data } => {
            let Some(ch) = channels.get(&header.channel_id) else {
                return Taken::Stop(format!("message on unknown channel {}", header.channel_id));
            };
            return Taken::Event(BagEvent::Message(BagMessage {
                channel: ch.id,
                topic: ch.topic.clone(),
                type_name: ch.type_name.clone(),
                sequence: header.sequence,
                log_time: header.log_time,
                publish_time: header.publish_time,
                data: data.into_owned(),
            }));
        }
        Record::Metadata(m) => {
            return Taken::Event(BagEvent::Metadata {
                name: m.name,
                values: m.metadata,
            })
        }
        Record::DataEnd(_) => return Taken::DataEnd,
        _ => {}
    }
    Taken::Nothing
}

/// An MCAP record as (opcode, body).
type RawRecord = (u8, Vec<u8>);

/// The complete records inside the first chunk of `path` that its writer never closed:
/// an uncompressed chunk whose length is still the writer's placeholder (all ones),
/// because the recorder died (or its disk filled) while the chunk was open. The MCAP
/// reader cannot size such a chunk; its records up to the first one cut short are
/// intact. None when the file has no such chunk.
fn open_chunk_records(path: &Path) -> Option<Vec<RawRecord>> {
    let bytes = std::fs::read(path).ok()?;
    let u64_at = |at: usize| -> Option<u64> {
        Some(u64::from_le_bytes(bytes.get(at..at + 8)?.try_into().ok()?))
    };
    let mut at = mcap::MAGIC.len();
    loop {
        let opcode = *bytes.get(at)?;
        let len = u64_at(at + 1)?;
        if opcode == mcap::records::op::CHUNK && len == u64::MAX {
            break;
        }
        at = at.checked_add(9)?.checked_add(usize::try_from(len).ok()?)?;
    }
    // the chunk header: start, end, uncompressed size (u64 each), crc (u32),
    // compression (u32 length + text), records length (u64)
    let mut k = at + 9 + 8 * 3 + 4;
    let name_len = u32::from_le_bytes(bytes.get(k..k + 4)?.try_into().ok()?) as usize;
    if name_len != 0 {
        return None; // compressed: its records cannot be read without the whole frame
    }
    k += 4 + 8;
    let mut records = Vec::new();
    while let (Some(&opcode), Some(len)) = (bytes.get(k), u64_at(k + 1)) {
        let start = k + 9;
        let Some(end) = usize::try_from(len).ok().and_then(|l| start.checked_add(l)) else {
            break;
        };
        let Some(data) = bytes.get(start..end) else {
            break; // cut short
        };
        records.push((opcode, data.to_vec()));
        k = end;
    }
    Some(records)
}

/// The MCAP files of a bag folder, in name order.
pub fn mcap_files(dir: &Path) -> Result<Vec<PathBuf>, RecordError> {
    let folder = |message: String| RecordError::Folder {
        path: dir.to_path_buf(),
        message,
    };
    let entries = std::fs::read_dir(dir).map_err(|e| folder(format!("cannot read it: {e}")))?;
    let mut files: Vec<PathBuf> = entries
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "mcap"))
        .collect();
    files.sort();
    if files.is_empty() {
        return Err(folder("holds no .mcap file".into()));
    }
    Ok(files)
}

/// Message counts and times of one MCAP file, read in a streaming pass.
#[derive(Clone, Debug, Default)]
pub struct Scan {
    /// Per channel id.
    pub channels: BTreeMap<u16, ChannelInfo>,
    pub counts: BTreeMap<u16, u64>,
    pub first_ns: Option<u64>,
    pub last_ns: Option<u64>,
    /// Why reading stopped early, if it did.
    pub truncated: Option<String>,
    /// The file ends with a valid footer and magic.
    pub complete: bool,
    pub metadata_records: Vec<(String, BTreeMap<String, String>)>,
}

impl Scan {
    pub fn message_count(&self) -> u64 {
        self.counts.values().sum()
    }

    /// Per-topic summaries (channel order).
    pub fn topics(&self) -> Vec<TopicSummary> {
        self.channels
            .values()
            .map(|c| TopicSummary {
                name: c.topic.clone(),
                type_name: c.type_name.clone(),
                qos: c
                    .metadata
                    .get("offered_qos_profiles")
                    .and_then(|q| serde_yaml::from_str::<Vec<QosEntry>>(q).ok())
                    .unwrap_or_default(),
                type_hash: c
                    .metadata
                    .get("topic_type_hash")
                    .cloned()
                    .unwrap_or_default(),
                count: self.counts.get(&c.id).copied().unwrap_or(0),
            })
            .collect()
    }

    /// metadata.yaml for a bag of this one file.
    pub fn metadata(&self, file_name: &str, custom: BTreeMap<String, String>) -> MetadataFile {
        metadata::build(
            file_name,
            &self.topics(),
            self.first_ns,
            self.last_ns,
            custom,
        )
    }
}

/// Read a whole MCAP file (streaming) and count its messages.
pub fn scan(path: &Path) -> Result<Scan, RecordError> {
    let mut stream = McapStream::open(path)?;
    let mut s = Scan::default();
    for event in stream.by_ref() {
        match event? {
            BagEvent::Message(m) => {
                *s.counts.entry(m.channel).or_insert(0) += 1;
                s.first_ns = Some(s.first_ns.map_or(m.log_time, |f| f.min(m.log_time)));
                s.last_ns = Some(s.last_ns.map_or(m.log_time, |l| l.max(m.log_time)));
            }
            BagEvent::Metadata { name, values } => s.metadata_records.push((name, values)),
        }
    }
    s.channels = stream.channels().clone();
    s.truncated = stream.truncated.clone();
    s.complete = stream.reached_data_end && has_footer(path);
    Ok(s)
}

fn has_footer(path: &Path) -> bool {
    let Ok(bytes) = std::fs::metadata(path).map(|m| m.len()) else {
        return false;
    };
    if bytes < 8 + 37 {
        return false;
    }
    let Ok(mut f) = File::open(path) else {
        return false;
    };
    use std::io::{Seek, SeekFrom};
    let mut tail = [0u8; 8];
    f.seek(SeekFrom::End(-8)).is_ok() && f.read_exact(&mut tail).is_ok() && tail == mcap::MAGIC[..]
}

/// What `reindex` did.
#[derive(Clone, Debug)]
pub struct ReindexReport {
    pub metadata: MetadataFile,
    /// Files that were truncated and rewritten complete: (file, original kept as).
    pub repaired: Vec<(PathBuf, PathBuf)>,
    /// Why each repaired file's reading stopped.
    pub truncation: Vec<String>,
}

/// Rebuild `metadata.yaml` of the bag folder `dir` from its MCAP files. A truncated
/// MCAP (a killed recorder) is rewritten complete with every readable message; the
/// original is kept next to it as `<file>.incomplete`.
pub fn reindex(dir: &Path) -> Result<ReindexReport, RecordError> {
    let files = mcap_files(dir)?;
    let mut report = ReindexReport {
        metadata: metadata::build("", &[], None, None, BTreeMap::new()),
        repaired: Vec::new(),
        truncation: Vec::new(),
    };
    let mut all_topics: Vec<TopicSummary> = Vec::new();
    let mut file_infos = Vec::new();
    let (mut first, mut last): (Option<u64>, Option<u64>) = (None, None);
    let mut custom = BTreeMap::new();
    // keep custom_data of an existing metadata.yaml
    if let Ok(text) = std::fs::read_to_string(dir.join("metadata.yaml")) {
        if let Ok(old) = serde_yaml::from_str::<MetadataFile>(&text) {
            custom = old
                .rosbag2_bagfile_information
                .custom_data
                .unwrap_or_default();
        }
    }
    for path in &files {
        let mut s = scan(path)?;
        if !s.complete {
            let kept = repair(path)?;
            report.repaired.push((path.clone(), kept));
            report
                .truncation
                .push(s.truncated.clone().unwrap_or_else(|| "no footer".into()));
            s = scan(path)?;
        }
        if custom.is_empty() {
            if let Some((_, v)) = s
                .metadata_records
                .iter()
                .find(|(n, _)| n == "developable_sim")
            {
                if let Some(name) = v.get("scene_name") {
                    custom.insert("developable_sim.scene".to_string(), name.clone());
                }
            }
        }
        let name = path
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        let m = s.metadata(&name, BTreeMap::new());
        file_infos.extend(m.rosbag2_bagfile_information.files);
        for t in s.topics() {
            match all_topics
                .iter_mut()
                .find(|a| a.name == t.name && a.type_name == t.type_name)
            {
                Some(a) => a.count += t.count,
                None => all_topics.push(t),
            }
        }
        if let Some(f) = s.first_ns {
            first = Some(first.map_or(f, |x| x.min(f)));
        }
        if let Some(l) = s.last_ns {
            last = Some(last.map_or(l, |x| x.max(l)));
        }
    }
    let mut meta = metadata::build("", &all_topics, first, last, custom);
    meta.rosbag2_bagfile_information.relative_file_paths =
        file_infos.iter().map(|f| f.path.clone()).collect();
    meta.rosbag2_bagfile_information.files = file_infos;
    write_metadata_file(dir, &meta)?;
    report.metadata = meta;
    Ok(report)
}

/// Rewrite a truncated MCAP complete (every readable record, then a summary); keep
/// the original as `<file>.incomplete`. Returns the kept original's path.
fn repair(path: &Path) -> Result<PathBuf, RecordError> {
    let tmp = path.with_extension("mcap.repairing");
    let kept = path.with_extension("mcap.incomplete");
    let io = |p: &Path, source| RecordError::Io {
        path: p.to_path_buf(),
        source,
    };
    {
        let out = File::create(&tmp).map_err(|e| io(&tmp, e))?;
        let mut w = mcap::WriteOptions::new()
            .profile("ros2")
            .library(format!(
                "developable_sim {} {REINDEX_LIBRARY_SUFFIX}",
                env!("CARGO_PKG_VERSION")
            ))
            .compression(None)
            .create(BufWriter::new(out))
            .map_err(|error| RecordError::Mcap {
                path: tmp.clone(),
                error,
            })?;
        let mcap_err = |error| RecordError::Mcap {
            path: tmp.clone(),
            error,
        };
        let mut stream = McapStream::open(path)?;
        let mut channel_map: BTreeMap<u16, u16> = BTreeMap::new();
        let mut schema_map: BTreeMap<String, u16> = BTreeMap::new();
        while let Some(event) = stream.next() {
            match event? {
                BagEvent::Message(m) => {
                    let id = match channel_map.get(&m.channel) {
                        Some(id) => *id,
                        None => {
                            let Some(c) = stream.channels().get(&m.channel).cloned() else {
                                continue;
                            };
                            let schema = match schema_map.get(&c.type_name) {
                                Some(s) => *s,
                                None => {
                                    let s = w
                                        .add_schema(&c.type_name, &c.schema_encoding, &c.schema)
                                        .map_err(mcap_err)?;
                                    schema_map.insert(c.type_name.clone(), s);
                                    s
                                }
                            };
                            let id = w
                                .add_channel(schema, &c.topic, &c.message_encoding, &c.metadata)
                                .map_err(mcap_err)?;
                            channel_map.insert(m.channel, id);
                            id
                        }
                    };
                    w.write_to_known_channel(
                        &mcap::records::MessageHeader {
                            channel_id: id,
                            sequence: m.sequence,
                            log_time: m.log_time,
                            publish_time: m.publish_time,
                        },
                        &m.data,
                    )
                    .map_err(mcap_err)?;
                }
                BagEvent::Metadata { name, values } => {
                    w.write_metadata(&mcap::records::Metadata {
                        name,
                        metadata: values,
                    })
                    .map_err(mcap_err)?;
                }
            }
        }
        w.finish().map_err(mcap_err)?;
        let mut sink = w.into_inner();
        std::io::Write::flush(&mut sink).map_err(|e| io(&tmp, e))?;
    }
    std::fs::rename(path, &kept).map_err(|e| io(path, e))?;
    std::fs::rename(&tmp, path).map_err(|e| io(path, e))?;
    Ok(kept)
}
