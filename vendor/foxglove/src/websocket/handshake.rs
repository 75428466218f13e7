use tokio::io::{AsyncRead, AsyncWrite};
use tokio_tungstenite::tungstenite::handshake::server;
use tokio_tungstenite::tungstenite::http::HeaderValue;
use tokio_tungstenite::{WebSocketStream, tungstenite};

pub(crate) const SUBPROTOCOL_V1: &str = "foxglove.sdk.v1";
pub(crate) const SUBPROTOCOL_V1_1: &str = "foxglove.sdk.v1.1";
/// The name of protocol v1 in the ws-protocol specification (foxglove/ws-protocol,
/// `docs/spec.md`): the same protocol as `foxglove.sdk.v1`, still requested by Lichtblick,
/// Foxglove Studio before the rename and the ws-protocol client libraries.
pub(crate) const SUBPROTOCOL_WEBSOCKET_V1: &str = "foxglove.websocket.v1";

/// The WebSocket subprotocol negotiated with a client.
///
/// The subprotocol is fixed for the lifetime of a connection, and determines the shape of the
/// server `advertise` message.
///
/// `foxglove.sdk.v2` is reserved for the remote-access v2 protocol and is not a WebSocket
/// subprotocol this server negotiates.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Subprotocol {
    /// `foxglove.sdk.v1`: channel advertisements carry inline schemas.
    V1,
    /// `foxglove.sdk.v1.1`: channel advertisements reference a connection-scoped schema table.
    V1_1,
}

impl Subprotocol {
    /// Returns the subprotocol identifier, as used in the `sec-websocket-protocol` header.
    pub(crate) const fn as_str(self) -> &'static str {
        match self {
            Subprotocol::V1 => SUBPROTOCOL_V1,
            Subprotocol::V1_1 => SUBPROTOCOL_V1_1,
        }
    }

    /// Returns the subprotocol identified by `name`, if it is one the server supports.
    ///
    /// The comparison is exact. A prefix match would treat `foxglove.sdk.v1.1` as `foxglove.sdk.v1`.
    /// `foxglove.websocket.v1` (the ws-protocol name of v1) selects [`Subprotocol::V1`].
    pub(crate) fn from_name(name: &str) -> Option<Self> {
        match name {
            SUBPROTOCOL_V1 | SUBPROTOCOL_WEBSOCKET_V1 => Some(Subprotocol::V1),
            SUBPROTOCOL_V1_1 => Some(Subprotocol::V1_1),
            _ => None,
        }
    }
}

/// A negotiated subprotocol and the name to answer with in `sec-websocket-protocol`.
///
/// A client may only accept a name it offered (RFC 6455, 4.1), so a client asking for
/// `foxglove.websocket.v1` is answered with that name, not with `foxglove.sdk.v1`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Selected {
    subprotocol: Subprotocol,
    /// The client asked for v1 by its ws-protocol name `foxglove.websocket.v1` only.
    ws_protocol_name: bool,
}

impl Selected {
    fn name(self) -> &'static str {
        if self.ws_protocol_name {
            SUBPROTOCOL_WEBSOCKET_V1
        } else {
            self.subprotocol.as_str()
        }
    }
}

/// Selects the subprotocol to use for a connection, given the subprotocols offered by the client,
/// and the name to answer with: for v1, `foxglove.sdk.v1` if the client offered it, else
/// `foxglove.websocket.v1`.
///
/// The server prefers the newest subprotocol it supports, regardless of the order in which the
/// client listed them. Returns `None` if the client did not offer a supported subprotocol.
fn select<'a>(offered: impl IntoIterator<Item = &'a str>) -> Option<Selected> {
    offered
        .into_iter()
        .filter_map(|name| {
            let name = name.trim();
            Subprotocol::from_name(name).map(|subprotocol| Selected {
                subprotocol,
                ws_protocol_name: name == SUBPROTOCOL_WEBSOCKET_V1,
            })
        })
        .max_by_key(|selected| {
            let version = match selected.subprotocol {
                Subprotocol::V1 => 1,
                Subprotocol::V1_1 => 2,
            };
            (version, !selected.ws_protocol_name)
        })
}

/// Negotiates a subprotocol with the client and completes the WebSocket handshake.
///
/// If the client requests subprotocols which don't include one of ours, or does not include the
/// expected header, respond with a 400.
pub(crate) async fn do_handshake<S: AsyncRead + AsyncWrite + Unpin>(
    stream: S,
) -> Result<(WebSocketStream<S>, Subprotocol), tungstenite::Error> {
    let mut negotiated = None;
    let stream = tokio_tungstenite::accept_hdr_async(
        stream,
        #[allow(clippy::result_large_err)]
        |req: &server::Request, mut res: server::Response| {
            let offered = req
                .headers()
                .get_all("sec-websocket-protocol")
                .iter()
                .flat_map(|header| header.to_str().unwrap_or_default().split(','));
            let Some(selected) = select(offered) else {
                return Err(server::Response::builder()
                    .status(400)
                    .body(Some(
                        "Missing expected sec-websocket-protocol header".into(),
                    ))
                    .unwrap());
            };
            res.headers_mut().insert(
                "sec-websocket-protocol",
                HeaderValue::from_static(selected.name()),
            );
            negotiated = Some(selected.subprotocol);
            Ok(res)
        },
    )
    .await?;
    let subprotocol = negotiated.expect("handshake callback sets the subprotocol on success");
    Ok((stream, subprotocol))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn select_subprotocol<'a>(offered: impl IntoIterator<Item = &'a str>) -> Option<Subprotocol> {
        select(offered).map(|selected| selected.subprotocol)
    }

    #[test]
    fn test_select_subprotocol_prefers_v1_1() {
        assert_eq!(
            select_subprotocol(["foxglove.sdk.v1.1", "foxglove.sdk.v1"]),
            Some(Subprotocol::V1_1)
        );
        assert_eq!(
            select_subprotocol(["foxglove.sdk.v1", " foxglove.sdk.v1.1"]),
            Some(Subprotocol::V1_1)
        );
    }

    #[test]
    fn test_select_subprotocol_matches_tokens_exactly() {
        // `foxglove.sdk.v1` is a prefix of `foxglove.sdk.v1.1`, but only the full token selects
        // the schema-table subprotocol.
        assert_eq!(
            select_subprotocol(["foxglove.sdk.v1.1"]),
            Some(Subprotocol::V1_1)
        );
        assert_eq!(
            select_subprotocol(["foxglove.sdk.v1"]),
            Some(Subprotocol::V1)
        );
        assert_eq!(select_subprotocol(["foxglove.sdk.v1.10"]), None);
        assert_eq!(select_subprotocol(["foxglove.sdk.v11"]), None);
        // Reserved for the remote-access v2 protocol; not negotiated on this WebSocket server.
        assert_eq!(select_subprotocol(["foxglove.sdk.v2"]), None);
        assert_eq!(
            select_subprotocol(["foxglove.sdk.v2", "foxglove.sdk.v1"]),
            Some(Subprotocol::V1)
        );
    }

    #[test]
    fn test_select_accepts_the_ws_protocol_name_of_v1_and_answers_with_it() {
        let answer = |offered: &[&'static str]| select(offered.iter().copied()).map(Selected::name);
        assert_eq!(
            select(["foxglove.websocket.v1"]).map(|s| s.subprotocol),
            Some(Subprotocol::V1)
        );
        assert_eq!(
            answer(&["foxglove.websocket.v1"]),
            Some(SUBPROTOCOL_WEBSOCKET_V1)
        );
        assert_eq!(
            answer(&[" foxglove.websocket.v1 "]),
            Some(SUBPROTOCOL_WEBSOCKET_V1)
        );
        // the new name wins over the old one for the same protocol, v1.1 over both
        assert_eq!(
            answer(&["foxglove.websocket.v1", "foxglove.sdk.v1"]),
            Some(SUBPROTOCOL_V1)
        );
        assert_eq!(
            answer(&["foxglove.sdk.v1", "foxglove.websocket.v1"]),
            Some(SUBPROTOCOL_V1)
        );
        assert_eq!(
            answer(&["foxglove.websocket.v1", "foxglove.sdk.v1.1"]),
            Some(SUBPROTOCOL_V1_1)
        );
        // exact tokens only: no other version or spelling of the old name
        assert_eq!(select(["foxglove.websocket.v2"]), None);
        assert_eq!(select(["foxglove.websocket.v1.1"]), None);
        assert_eq!(select(["foxglove.websocket"]), None);
        assert_eq!(select(["Foxglove.WebSocket.v1"]), None);
    }
}
