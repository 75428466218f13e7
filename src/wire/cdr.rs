//! CDR encoding of messages exactly as they travel over DDS and sit in bags: a 4-byte
//! encapsulation header (`00 01 00 00`: CDR little endian) then the plain CDR body.

use byteorder::{BigEndian, LittleEndian};
use serde::de::DeserializeOwned;
use serde::Serialize;

/// A message that cannot be encoded or decoded.
#[derive(Debug, thiserror::Error)]
pub enum CdrError {
    #[error("CDR payload shorter than its 4-byte encapsulation header")]
    Truncated,
    #[error(
        "unsupported CDR encapsulation {0:02x} {1:02x} (expected CDR_LE 00 01 or CDR_BE 00 00)"
    )]
    Encapsulation(u8, u8),
    #[error("CDR: {0}")]
    Codec(#[from] cdr_encoding::Error),
}

/// Encapsulation header of little-endian plain CDR.
const CDR_LE_HEADER: [u8; 4] = [0x00, 0x01, 0x00, 0x00];

/// Encode `msg` with the CDR_LE encapsulation header.
pub fn encode<M: Serialize>(msg: &M) -> Result<Vec<u8>, CdrError> {
    encode_sized(msg, 256)
}

/// [`encode`] into a buffer of `capacity` bytes to start with (the size of a large
/// message, so its bytes are written once, with no regrowth).
pub fn encode_sized<M: Serialize>(msg: &M, capacity: usize) -> Result<Vec<u8>, CdrError> {
    let mut out = Vec::with_capacity(capacity);
    out.extend_from_slice(&CDR_LE_HEADER);
    cdr_encoding::to_writer::<M, LittleEndian, _>(&mut out, msg)?;
    Ok(out)
}

/// Decode a payload (with its encapsulation header, little or big endian).
pub fn decode<M: DeserializeOwned>(bytes: &[u8]) -> Result<M, CdrError> {
    if bytes.len() < 4 {
        return Err(CdrError::Truncated);
    }
    let body = &bytes[4..];
    let (msg, _) = match (bytes[0], bytes[1]) {
        (0x00, 0x01) => cdr_encoding::from_bytes::<M, LittleEndian>(body)?,
        (0x00, 0x00) => cdr_encoding::from_bytes::<M, BigEndian>(body)?,
        (a, b) => return Err(CdrError::Encapsulation(a, b)),
    };
    Ok(msg)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::wire::msgs::{Header, Point, PoseStamped, Time};

    #[test]
    fn pose_stamped_layout_is_ros_cdr() {
        let mut m = PoseStamped {
            header: Header {
                stamp: Time { sec: 7, nanosec: 9 },
                frame_id: "world".into(),
            },
            ..Default::default()
        };
        m.pose.position = Point {
            x: 1.5,
            y: 0.0,
            z: 0.0,
        };
        let b = encode(&m).unwrap();
        // header, sec, nanosec, string length 6 incl. NUL, "world\0", pad to 8, 7 doubles
        assert_eq!(&b[..4], &CDR_LE_HEADER);
        assert_eq!(&b[4..8], &7i32.to_le_bytes());
        assert_eq!(&b[8..12], &9u32.to_le_bytes());
        assert_eq!(&b[12..16], &6u32.to_le_bytes());
        assert_eq!(&b[16..22], b"world\0");
        // body offset 18 -> doubles aligned to 8 within the body (body starts at byte 4)
        assert_eq!(&b[28..36], &1.5f64.to_le_bytes());
        assert_eq!(b.len(), 4 + 24 + 7 * 8);
        assert_eq!(decode::<PoseStamped>(&b).unwrap(), m);
        assert!(decode::<PoseStamped>(&b[..3]).is_err());
    }
}
