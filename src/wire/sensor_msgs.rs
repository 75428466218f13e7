//! `sensor_msgs` of the simulated RGB-D camera (issue 48): images, camera info and point
//! clouds, field for field as in ROS 2 Jazzy (`interfaces/sensor_msgs/`). Re-exported by
//! [`super::msgs`].
//!
//! The byte buffers (`data`) serialize as one block (CDR `uint8[]`: a length, then the
//! bytes), not byte by byte: a 640 x 480 cloud is 4.9 MB.

use serde::{Deserialize, Serialize};

use super::{Header, RosMessage};

/// A `uint8[]` field written and read as one block of bytes.
mod byte_block {
    use serde::de::{Deserializer, SeqAccess, Visitor};
    use serde::Serializer;

    pub fn serialize<S: Serializer>(bytes: &[u8], s: S) -> Result<S::Ok, S::Error> {
        s.serialize_bytes(bytes)
    }

    struct Bytes;

    impl<'de> Visitor<'de> for Bytes {
        type Value = Vec<u8>;
        fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
            f.write_str("a byte sequence")
        }
        fn visit_bytes<E>(self, v: &[u8]) -> Result<Vec<u8>, E> {
            Ok(v.to_vec())
        }
        fn visit_byte_buf<E>(self, v: Vec<u8>) -> Result<Vec<u8>, E> {
            Ok(v)
        }
        fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Vec<u8>, A::Error> {
            let mut out = Vec::with_capacity(seq.size_hint().unwrap_or(0));
            while let Some(b) = seq.next_element()? {
                out.push(b);
            }
            Ok(out)
        }
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<u8>, D::Error> {
        d.deserialize_byte_buf(Bytes)
    }
}

/// `sensor_msgs/msg/Image`: `rgb8` colour or `32FC1` depth (m), rows from the top.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Image {
    pub header: Header,
    /// px
    pub height: u32,
    /// px
    pub width: u32,
    pub encoding: String,
    pub is_bigendian: u8,
    /// Bytes a row.
    pub step: u32,
    #[serde(with = "byte_block")]
    pub data: Vec<u8>,
}
ros_message!(
    Image,
    "sensor_msgs/msg/Image",
    "RIHS01_d31d41a9a4c4bc8eae9be757b0beed306564f7526c88ea6a4588fb9582527d47"
);

/// `sensor_msgs/msg/RegionOfInterest` (the whole image here: all zero).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct RegionOfInterest {
    pub x_offset: u32,
    pub y_offset: u32,
    pub height: u32,
    pub width: u32,
    pub do_rectify: bool,
}

/// `sensor_msgs/msg/CameraInfo`: the pinhole model, K, R, P row-major (px).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct CameraInfo {
    pub header: Header,
    pub height: u32,
    pub width: u32,
    pub distortion_model: String,
    pub d: Vec<f64>,
    pub k: [f64; 9],
    pub r: [f64; 9],
    pub p: [f64; 12],
    pub binning_x: u32,
    pub binning_y: u32,
    pub roi: RegionOfInterest,
}
ros_message!(
    CameraInfo,
    "sensor_msgs/msg/CameraInfo",
    "RIHS01_b3dfd68ff46c9d56c80fd3bd4ed22c7a4ddce8c8348f2f59c299e73118e7e275"
);

/// `sensor_msgs/msg/PointField`: one field of a cloud's points.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct PointField {
    pub name: String,
    /// Byte offset in the point.
    pub offset: u32,
    pub datatype: u8,
    pub count: u32,
}

impl PointField {
    /// `datatype` of a float32.
    pub const FLOAT32: u8 = 7;
}

/// `sensor_msgs/msg/PointCloud2`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct PointCloud2 {
    pub header: Header,
    pub height: u32,
    pub width: u32,
    pub fields: Vec<PointField>,
    pub is_bigendian: bool,
    /// Bytes a point.
    pub point_step: u32,
    /// Bytes a row.
    pub row_step: u32,
    #[serde(with = "byte_block")]
    pub data: Vec<u8>,
    /// No invalid (NaN) points.
    pub is_dense: bool,
}
ros_message!(
    PointCloud2,
    "sensor_msgs/msg/PointCloud2",
    "RIHS01_9198cabf7da3796ae6fe19c4cb3bdd3525492988c70522628af5daa124bae2b5"
);

/// An [`Image`] whose pixels are borrowed: encodes to the same bytes without copying
/// them first (a frame's buffers are encoded as they are).
#[derive(Serialize)]
pub struct ImageRef<'a> {
    pub header: &'a Header,
    pub height: u32,
    pub width: u32,
    pub encoding: &'a str,
    pub is_bigendian: u8,
    pub step: u32,
    #[serde(with = "byte_block")]
    pub data: &'a [u8],
}

/// A [`PointCloud2`] whose points are borrowed (see [`ImageRef`]).
#[derive(Serialize)]
pub struct PointCloud2Ref<'a> {
    pub header: &'a Header,
    pub height: u32,
    pub width: u32,
    pub fields: &'a [PointField],
    pub is_bigendian: bool,
    pub point_step: u32,
    pub row_step: u32,
    #[serde(with = "byte_block")]
    pub data: &'a [u8],
    pub is_dense: bool,
}

/// The `PointField`s of float32 fields `(name, offset)`, count 1 each.
pub fn float32_fields(fields: &[(&str, u32)]) -> Vec<PointField> {
    fields
        .iter()
        .map(|(name, offset)| PointField {
            name: (*name).to_string(),
            offset: *offset,
            datatype: PointField::FLOAT32,
            count: 1,
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::wire::cdr;

    #[test]
    fn a_byte_block_is_a_cdr_uint8_sequence() {
        let m = Image {
            encoding: "rgb8".into(),
            height: 1,
            width: 2,
            step: 6,
            data: vec![1, 2, 3, 4, 5, 6],
            ..Default::default()
        };
        let b = cdr::encode(&m).unwrap();
        // the same bytes as a plain Vec<u8> field encoded element by element
        #[derive(Serialize)]
        struct Plain<'a> {
            header: &'a Header,
            height: u32,
            width: u32,
            encoding: &'a str,
            is_bigendian: u8,
            step: u32,
            data: Vec<u8>,
        }
        let plain = Plain {
            header: &m.header,
            height: 1,
            width: 2,
            encoding: "rgb8",
            is_bigendian: 0,
            step: 6,
            data: m.data.clone(),
        };
        assert_eq!(b, cdr::encode(&plain).unwrap());
        let borrowed = ImageRef {
            header: &m.header,
            height: 1,
            width: 2,
            encoding: "rgb8",
            is_bigendian: 0,
            step: 6,
            data: &m.data,
        };
        assert_eq!(b, cdr::encode(&borrowed).unwrap());
        assert_eq!(cdr::decode::<Image>(&b).unwrap(), m);
        assert!(cdr::decode::<Image>(&b[..b.len() - 1]).is_err());
    }

    #[test]
    fn a_borrowed_cloud_encodes_as_the_owned_one() {
        let m = PointCloud2 {
            height: 1,
            width: 1,
            fields: float32_fields(&[("x", 0), ("rgb", 4)]),
            point_step: 8,
            row_step: 8,
            data: vec![1, 2, 3, 4, 5, 6, 7, 8],
            is_dense: true,
            ..Default::default()
        };
        let borrowed = PointCloud2Ref {
            header: &m.header,
            height: 1,
            width: 1,
            fields: &m.fields,
            is_bigendian: false,
            point_step: 8,
            row_step: 8,
            data: &m.data,
            is_dense: true,
        };
        let b = cdr::encode(&borrowed).unwrap();
        assert_eq!(b, cdr::encode(&m).unwrap());
        assert_eq!(cdr::decode::<PointCloud2>(&b).unwrap(), m);
        // a field changed in the owned one shows
        let mut other = m.clone();
        other.is_dense = false;
        assert_ne!(b, cdr::encode(&other).unwrap());
    }
}
