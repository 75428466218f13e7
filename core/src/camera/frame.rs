//! One camera frame in the byte layouts ROS messages carry (little-endian), so the
//! edges copy it into `sensor_msgs/Image` and `sensor_msgs/PointCloud2` as it is.

/// Bytes per point of the organized cloud: x, y, z, rgb, each a float32.
pub const CLOUD_POINT_STEP: usize = 16;

/// The cloud's `PointField`s: name and byte offset, each a FLOAT32 (datatype 7),
/// count 1.
pub const CLOUD_FIELDS: [(&str, u32); 4] = [("x", 0), ("y", 4), ("z", 8), ("rgb", 12)];

/// A rendered frame: rows from the top of the image, pixels from the left.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Frame {
    /// px
    pub width: u32,
    /// px
    pub height: u32,
    /// `rgb8`: 3 bytes a pixel, row step 3 * width.
    pub color: Vec<u8>,
    /// `32FC1`: depth along the optical axis, m, as a little-endian float32 per pixel
    /// (row step 4 * width); NaN where nothing is hit or outside [near, far].
    pub depth: Vec<u8>,
    /// The organized cloud (width x height points, row step 16 * width): x, y, z in the
    /// optical frame (m) and rgb as ROS packs it (the float32 whose bits are
    /// 0x00RRGGBB), each a little-endian float32. x, y, z are NaN where the depth is;
    /// where it is not, they are the depth back-projected through K:
    /// (z (i - cx) / f, z (j - cy) / f, z), computed in f64 from the float32 depth and
    /// rounded once.
    pub cloud: Vec<u8>,
}

impl Frame {
    /// Buffers for a `width` x `height` frame (zeroed).
    pub(crate) fn sized(width: u32, height: u32) -> Frame {
        let n = width as usize * height as usize;
        Frame {
            width,
            height,
            color: vec![0; 3 * n],
            depth: vec![0; 4 * n],
            cloud: vec![0; CLOUD_POINT_STEP * n],
        }
    }

    fn index(&self, i: u32, j: u32) -> usize {
        assert!(
            i < self.width && j < self.height,
            "pixel ({i}, {j}) outside the frame"
        );
        j as usize * self.width as usize + i as usize
    }

    /// The colour of pixel (i, j) (column, row).
    pub fn rgb_at(&self, i: u32, j: u32) -> [u8; 3] {
        let k = 3 * self.index(i, j);
        [self.color[k], self.color[k + 1], self.color[k + 2]]
    }

    /// The depth of pixel (i, j), m (NaN: none).
    pub fn depth_at(&self, i: u32, j: u32) -> f32 {
        f32_at(&self.depth, 4 * self.index(i, j))
    }

    /// The cloud's point at pixel (i, j): x, y, z (m, optical frame) and the packed rgb.
    pub fn point_at(&self, i: u32, j: u32) -> [f32; 4] {
        let k = CLOUD_POINT_STEP * self.index(i, j);
        [0, 4, 8, 12].map(|o| f32_at(&self.cloud, k + o))
    }
}

fn f32_at(bytes: &[u8], k: usize) -> f32 {
    f32::from_le_bytes([bytes[k], bytes[k + 1], bytes[k + 2], bytes[k + 3]])
}

/// rgb packed as ROS does (`pcl::PointXYZRGB`, `sensor_msgs_py`): the float32 whose
/// bits are 0x00RRGGBB.
pub(crate) fn pack_rgb(c: [u8; 3]) -> f32 {
    f32::from_bits(((c[0] as u32) << 16) | ((c[1] as u32) << 8) | c[2] as u32)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rgb_is_packed_as_ros_does() {
        let p = pack_rgb([0x12, 0x34, 0x56]);
        assert_eq!(p.to_bits(), 0x0012_3456);
        assert_eq!(pack_rgb([255, 255, 255]).to_bits(), 0x00ff_ffff);
    }

    #[test]
    fn accessors_read_the_layout() {
        let mut f = Frame::sized(3, 2);
        // pixel (2, 1) is the last: index 5
        f.color[15..18].copy_from_slice(&[1, 2, 3]);
        f.depth[20..24].copy_from_slice(&1.5f32.to_le_bytes());
        f.cloud[80 + 8..80 + 12].copy_from_slice(&2.5f32.to_le_bytes());
        assert_eq!(f.rgb_at(2, 1), [1, 2, 3]);
        assert_eq!(f.depth_at(2, 1), 1.5);
        assert_eq!(f.point_at(2, 1)[2], 2.5);
        assert_eq!(f.depth_at(0, 0), 0.0);
    }
}
