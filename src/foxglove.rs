//! The live Foxglove view (`--foxglove PORT`, parameter `foxglove_port`): a Foxglove
//! WebSocket server (the Foxglove SDK, subprotocol `foxglove.sdk.v1`: protocol v1) that
//! advertises the node's output topics under their ROS names, each with its `ros2msg`
//! schema (the text the bags carry) and `cdr` message encoding, and sends the CDR bytes
//! the DDS writers and the bags send (the session's frames, encoded once).
//! Foxglove's 3D panel then shows the meshes live with no ROS installation.
//!
//! The node never waits for a WebSocket client: the SDK queues each client's data in a
//! bounded queue and, when it is full, drops the oldest message (foxglove 0.30
//! `websocket/connected_client/send_lossy.rs`: `try_send`, then `try_recv` of the oldest);
//! the sending happens on the SDK's own tokio threads. A message goes only to the
//! clients subscribed to its topic.

use std::sync::Arc;

use foxglove::{
    ChannelBuilder, Context, FoxgloveError, RawChannel, Schema, WebSocketServer,
    WebSocketServerHandle,
};

use crate::session::names::NodeNames;
use crate::session::{Frame, OutputTable};

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

/// The running server and one channel per published row of the outputs table.
pub struct FoxgloveOut {
    /// Per row of the session's outputs table (None: not published).
    channels: Vec<Option<Arc<RawChannel>>>,
    server: Option<WebSocketServerHandle>,
    port: u16,
    _context: Arc<Context>,
}

impl FoxgloveOut {
    /// Bind and start the server, and advertise the published rows of `outputs`.
    pub fn start(
        cfg: &FoxgloveConfig,
        names: &NodeNames,
        outputs: &OutputTable,
    ) -> Result<FoxgloveOut, FoxgloveStartError> {
        let err = |source| FoxgloveStartError {
            bind: cfg.bind.clone(),
            port: cfg.port,
            source,
        };
        // a context of our own: channels of this node only, whatever else the process holds
        let ctx = Context::new();
        let channels = outputs
            .rows
            .iter()
            .map(|row| {
                let p = row.kind.producer;
                row.want
                    .published
                    .then(|| {
                        ChannelBuilder::new(&row.topic)
                            .context(&ctx)
                            .message_encoding("cdr")
                            .schema(Schema::new(
                                p.type_name(),
                                "ros2msg",
                                p.schema().into_bytes(),
                            ))
                            .build_raw()
                    })
                    .transpose()
            })
            .collect::<Result<Vec<_>, _>>()
            .map_err(err)?;
        let server = WebSocketServer::new()
            .name(names.fqn())
            .bind(cfg.bind.clone(), cfg.port)
            .message_backlog_size(CLIENT_BACKLOG)
            .context(&ctx)
            .start_blocking()
            .map_err(err)?;
        Ok(FoxgloveOut {
            channels,
            port: server.port(),
            server: Some(server),
            _context: ctx,
        })
    }

    /// The port the server listens on.
    pub fn port(&self) -> u16 {
        self.port
    }

    /// Send a frame's messages to the clients subscribed to them (the throttled rows,
    /// the markers, only when `markers_due`, as on DDS).
    pub fn emit(&mut self, outputs: &OutputTable, frame: &Frame, markers_due: bool) {
        let rows = outputs.rows.iter().zip(&frame.messages).zip(&self.channels);
        for ((row, msg), ch) in rows {
            let (Some(msg), Some(ch)) = (msg, ch) else {
                continue;
            };
            if (row.kind.throttled && !markers_due) || !ch.has_sinks() {
                continue;
            }
            ch.log(msg);
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
