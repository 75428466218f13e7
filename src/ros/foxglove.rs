//! The live Foxglove view (`--foxglove PORT`, parameter `foxglove_port`): a Foxglove
//! WebSocket server (the Foxglove SDK, subprotocol `foxglove.sdk.v1`: protocol v1) that
//! advertises the node's output topics under their ROS names, each with its `ros2msg`
//! schema (the text the bags carry, [`RosMessage::schema`]) and `cdr` message encoding,
//! and sends the CDR bytes the DDS writers and the bags send ([`super::cdr::encode`]).
//! Foxglove's 3D panel then shows the meshes live with no ROS installation.
//!
//! The node never waits for a WebSocket client: the SDK queues each client's data in a
//! bounded queue and, when it is full, drops the oldest message (foxglove 0.30
//! `websocket/connected_client/send_lossy.rs`: `try_send`, then `try_recv` of the oldest);
//! the sending happens on the SDK's own tokio threads. A message is encoded only when a
//! client subscribed to its topic.

use std::sync::Arc;

use foxglove::{
    ChannelBuilder, Context, FoxgloveError, RawChannel, Schema, WebSocketServer,
    WebSocketServerHandle,
};

use super::msgs::{MarkerArray, RosMessage, SimStatus, SingularPoints, TFMessage};
use super::names::NodeNames;
use super::session::{Frame, FrameContent};

/// The address the server binds unless told otherwise: this machine only (the stream
/// has no authentication; `--foxglove-bind 0.0.0.0` opens it to the network).
pub const DEFAULT_BIND: &str = "127.0.0.1";

/// Messages queued per client before the oldest is dropped. Foxglove shows the newest
/// mesh; 64 meshes of a 150-segment ribbon are ~4 MB per stalled client, where the
/// SDK's default of 1024 would be ~60 MB.
const CLIENT_BACKLOG: usize = 64;

/// Where the server listens.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct FoxgloveConfig {
    /// IP address to bind (e.g. 127.0.0.1, 0.0.0.0).
    pub bind: String,
    /// TCP port, > 0.
    pub port: u16,
}

/// A problem starting the server.
#[derive(Debug, thiserror::Error)]
#[error("Foxglove WebSocket server on {bind}:{port}: {source}")]
pub struct FoxgloveStartError {
    pub bind: String,
    pub port: u16,
    #[source]
    pub source: FoxgloveError,
}

struct ObjectChannels {
    markers: Option<Arc<RawChannel>>,
    singular_points: Option<Arc<RawChannel>>,
    status: Option<Arc<RawChannel>>,
}

/// The running server and one channel per output topic.
pub struct FoxgloveOut {
    objects: Vec<ObjectChannels>,
    colliders: Option<Arc<RawChannel>>,
    tf: Option<Arc<RawChannel>>,
    server: Option<WebSocketServerHandle>,
    port: u16,
    _context: Arc<Context>,
    /// Messages that could not be encoded (never expected; counted, not fatal).
    pub encode_errors: u64,
}

fn channel<M: RosMessage>(
    ctx: &Arc<Context>,
    topic: &str,
) -> Result<Arc<RawChannel>, FoxgloveError> {
    ChannelBuilder::new(topic)
        .context(ctx)
        .message_encoding("cdr")
        .schema(Schema::new(M::TYPE, "ros2msg", M::schema().into_bytes()))
        .build_raw()
}

/// What the node publishes, so the server advertises exactly those topics.
#[derive(Clone, Copy, Debug)]
pub struct Advertised {
    pub content: FrameContent,
    pub colliders: bool,
    pub tf: bool,
}

impl FoxgloveOut {
    /// Bind and start the server, and advertise the node's topics.
    pub fn start(
        cfg: &FoxgloveConfig,
        names: &NodeNames,
        what: Advertised,
    ) -> Result<FoxgloveOut, FoxgloveStartError> {
        let err = |source| FoxgloveStartError {
            bind: cfg.bind.clone(),
            port: cfg.port,
            source,
        };
        // a context of our own: channels of this node only, whatever else the process holds
        let ctx = Context::new();
        let opt = |on: bool, topic: &str, f: fn(&Arc<Context>, &str) -> _| {
            on.then(|| f(&ctx, topic)).transpose().map_err(err)
        };
        let mut objects = Vec::new();
        for o in &names.objects {
            objects.push(ObjectChannels {
                markers: opt(what.content.markers, &o.markers, channel::<MarkerArray>)?,
                singular_points: opt(
                    what.content.singular_points,
                    &o.singular_points,
                    channel::<SingularPoints>,
                )?,
                status: opt(what.content.status, &o.status, channel::<SimStatus>)?,
            });
        }
        let colliders = opt(what.colliders, &names.colliders, channel::<MarkerArray>)?;
        let tf = opt(what.tf, &names.tf, channel::<TFMessage>)?;
        let server = WebSocketServer::new()
            .name(names.fqn())
            .bind(cfg.bind.clone(), cfg.port)
            .message_backlog_size(CLIENT_BACKLOG)
            .context(&ctx)
            .start_blocking()
            .map_err(err)?;
        Ok(FoxgloveOut {
            objects,
            colliders,
            tf,
            port: server.port(),
            server: Some(server),
            _context: ctx,
            encode_errors: 0,
        })
    }

    /// The port the server listens on.
    pub fn port(&self) -> u16 {
        self.port
    }

    fn log<M: RosMessage>(&mut self, ch: &Option<Arc<RawChannel>>, msg: &M) {
        let Some(ch) = ch else { return };
        if !ch.has_sinks() {
            return;
        }
        match super::cdr::encode(msg) {
            Ok(bytes) => ch.log(&bytes),
            Err(_) => self.encode_errors += 1,
        }
    }

    /// Send a frame's messages (markers only when `markers_due`, as on DDS) and the
    /// frame's TF message if the node publishes one.
    pub fn emit(&mut self, frame: &Frame, markers_due: bool, tf: Option<&TFMessage>) {
        let objects = std::mem::take(&mut self.objects);
        for (o, ch) in frame.objects.iter().zip(&objects) {
            if let (Some(m), true) = (&o.markers, markers_due) {
                self.log(&ch.markers, m);
            }
            if let Some(s) = &o.singular_points {
                self.log(&ch.singular_points, s);
            }
            if let Some(s) = &o.status {
                self.log(&ch.status, s);
            }
        }
        self.objects = objects;
        if let Some(m) = &frame.colliders {
            let ch = self.colliders.clone();
            self.log(&ch, m);
        }
        if let Some(t) = tf {
            let ch = self.tf.clone();
            self.log(&ch, t);
        }
    }
}

impl Drop for FoxgloveOut {
    fn drop(&mut self) {
        // close the connections; do not wait for clients that stopped reading
        if let Some(s) = self.server.take() {
            s.stop().detach_all();
        }
    }
}
