//! Service replies held until the client can receive them (and [`receive_request`],
//! the request side every server and the action share).
//!
//! A client on the Cyclone DDS service mapping (rclpy on rmw_cyclonedds) creates its
//! request writer and its reply reader together and may send a request as soon as its
//! writer has matched our request reader. Our reply writer delivers only to readers it
//! has already matched, and with volatile durability a reader matched later never
//! receives earlier samples: a reply written before the node has matched the client's
//! reply reader is lost and the client waits forever. rmw_cyclonedds holds such a reply
//! until the client's reader is matched; so do we.
//!
//! The test is the reply writer's own matches (the patched ros2-client's
//! `Node::matched_remote_readers`, from RustDDS's match events, sent once the writer has
//! added the reader). The request id carries the client writer's GUID, whose first 8
//! bytes (host and application id of the GUID prefix) the client's reply reader shares.
//! A client creates its request writer and reply reader as a pair, so the reply waits
//! until that participant has at least as many matched reply readers as request writers
//! in the discovery database (a client that just replaced its endpoints is then not
//! mistaken for its predecessor); with one matched reader but fewer readers than writers
//! (a predecessor's disposed writer still in the database) the reply goes after
//! [`PAIR_WAIT`]; with none, after [`GIVE_UP`] it is sent anyway and counted.

use std::collections::HashMap;
use std::time::{Duration, Instant};

use ros2_client::dds::rustdds::{DomainParticipant, GUID};
use ros2_client::{Message, Node, RmwRequestId, Server};

/// How often the node re-checks held replies while any is waiting.
pub const RECHECK: Duration = Duration::from_millis(5);
/// How long a reply waits for the reader count to catch up with the writer count once
/// the client's participant has at least one matched reply reader: the discovery
/// database may keep a predecessor's disposed endpoint for a while, so the counts alone
/// could hold a reply until [`GIVE_UP`].
const PAIR_WAIT: Duration = Duration::from_millis(200);
/// How long a reply waits for the client's reader before it is sent regardless.
pub const GIVE_UP: Duration = Duration::from_secs(5);

/// The request writers of remote participants (service clients).
#[derive(Default)]
pub struct ClientWriters {
    /// (DDS topic, host and app id) -> number of writers.
    writers: HashMap<(String, [u8; 8]), usize>,
}

impl ClientWriters {
    /// Re-read the discovery database; writers that left are forgotten.
    pub fn refresh(&mut self, participant: &DomainParticipant) {
        self.writers.clear();
        for w in participant.discovered_writers() {
            let guid = w.writer_proxy.remote_writer_guid;
            let topic = w.publication_topic_data.topic_name.clone();
            *self
                .writers
                .entry((topic, host_app(guid.prefix.as_ref())))
                .or_default() += 1;
        }
    }

    /// Whether the client that sent `id` on `request_topic` at `received` can receive
    /// its reply, given the readers `matched` to the reply writer: its participant has
    /// as many of them as request writers, or at least one and the reply has waited
    /// [`PAIR_WAIT`] (see the module doc).
    fn settled(
        &self,
        request_topic: &str,
        matched: &[GUID],
        id: &RmwRequestId,
        received: Instant,
        now: Instant,
    ) -> bool {
        let client = host_app(&id.writer_gid.to_bytes16());
        let readers = matched
            .iter()
            .filter(|g| host_app(g.prefix.as_ref()) == client)
            .count();
        let writers = self
            .writers
            .get(&(request_topic.to_owned(), client))
            .copied()
            .unwrap_or(0);
        readers >= writers.max(1) || (readers >= 1 && now.duration_since(received) >= PAIR_WAIT)
    }
}

fn host_app(guid_bytes: &[u8]) -> [u8; 8] {
    let mut out = [0; 8];
    out.copy_from_slice(&guid_bytes[..8]);
    out
}

/// The replies of one server that wait for their client's reader.
pub struct HeldReplies<Resp> {
    /// DDS name of the request topic (`rq/.../<service>Request`).
    request_topic: String,
    waiting: Vec<(RmwRequestId, Resp, Instant)>,
}

/// What one [`HeldReplies::flush`] did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Flushed {
    pub sent: u64,
    /// Sent after [`GIVE_UP`] without the client's reader in sight.
    pub sent_unseen: u64,
    pub failed: u64,
}

impl<Resp: Message + 'static> HeldReplies<Resp> {
    pub fn new(request_topic: String) -> Self {
        HeldReplies {
            request_topic,
            waiting: Vec::new(),
        }
    }

    pub fn hold(&mut self, id: RmwRequestId, response: Resp) {
        self.waiting.push((id, response, Instant::now()));
    }

    pub fn is_empty(&self) -> bool {
        self.waiting.is_empty()
    }

    /// Send every reply whose client can receive it (in request order per client).
    pub fn flush<Req: Message + 'static>(
        &mut self,
        server: &Server<Req, Resp>,
        node: &Node,
        writers: &ClientWriters,
        now: Instant,
    ) -> Flushed {
        let mut done = Flushed::default();
        let mut keep = Vec::new();
        let matched = node.matched_remote_readers(server.response_writer_guid());
        for (id, response, received) in self.waiting.drain(..) {
            let ready = writers.settled(&self.request_topic, &matched, &id, received, now);
            let expired = now.duration_since(received) >= GIVE_UP;
            if !(ready || expired) {
                keep.push((id, response, received));
                continue;
            }
            match server.send_response(id, response) {
                Ok(()) if ready => done.sent += 1,
                Ok(()) => done.sent_unseen += 1,
                Err(_) => done.failed += 1,
            }
        }
        self.waiting = keep;
        done
    }
}

/// Requests a single `receive` skips past when they fail to read (deserialize or
/// unwrap), so one bad sample does not stall the good ones queued behind it until
/// the next wake, yet a reader that fails forever cannot spin the loop.
const MAX_UNREADABLE_PER_CALL: usize = 16;

/// The next request of `server`, if any. A request that cannot be read is reported on
/// stderr (once per run of failures, naming the service `name`; `failing` keeps the run)
/// and skipped, never dropped silently: a client waiting on it would otherwise see only
/// a missing reply.
pub fn receive_request<Req: Message + 'static, Resp: Message + 'static>(
    server: &Server<Req, Resp>,
    name: &str,
    failing: &mut bool,
) -> Option<(RmwRequestId, Req)> {
    for _ in 0..MAX_UNREADABLE_PER_CALL {
        match server.receive_request() {
            Ok(next) => {
                *failing = false;
                return next;
            }
            Err(e) => {
                if !*failing {
                    eprintln!("warning: service {name}: unreadable request dropped: {e:?}");
                }
                *failing = true;
            }
        }
    }
    None
}
