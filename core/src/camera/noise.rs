//! The RealSense D435 depth noise model (as mujoco_ros2_control's camera uses): a
//! stereo camera's depth error grows with the square of the depth,
//! sigma(z) = z^2 * subpixel / (f * baseline), with the matching error 0.08 px, the
//! baseline 50 mm and f the focal length in px; 1 % of the returns drop out (NaN), and
//! nothing nearer than the minimum range 0.28 m is returned.
//!
//! Seeded: each image row draws from its own ChaCha8 stream keyed by the scene's seed,
//! the camera, the frame index and the row, two 64-bit words a pixel whatever the
//! scene shows, so a frame's noise depends on nothing else (not the thread count, not
//! the previous frames): a recording replays bit for bit.

use rand::{RngCore, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Stereo matching error of the D435, px.
pub const D435_SUBPIXEL: f64 = 0.08;
/// Stereo baseline of the D435, m.
pub const D435_BASELINE: f64 = 0.05;
/// Share of the returns that drop out (NaN).
pub const D435_DROPOUT: f64 = 0.01;
/// Minimum range of the D435, m: nearer surfaces give no depth.
pub const D435_MIN_RANGE: f64 = 0.28;

/// A camera's depth noise.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Noise {
    /// Exact depth.
    #[default]
    None,
    /// The RealSense D435 model (see the module).
    D435,
}

impl Noise {
    /// Standard deviation of the depth error at depth `z` (m) for focal length `focal`
    /// (px), m.
    pub fn sigma(&self, z: f64, focal: f64) -> f64 {
        match self {
            Noise::None => 0.0,
            Noise::D435 => z * z * D435_SUBPIXEL / (focal * D435_BASELINE),
        }
    }
}

/// What a frame's noise is drawn from: the scene's seed, the camera (its index in the
/// scene) and the frame index (the camera's tick count).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct NoiseKey {
    pub seed: u64,
    pub camera: u32,
    pub frame: u64,
}

/// The noise stream of one image row.
pub(crate) struct RowNoise {
    rng: ChaCha8Rng,
}

/// Tells the streams of this model apart from any other use of the same seed.
const DOMAIN: [u8; 8] = *b"D435row1";

impl RowNoise {
    pub(crate) fn new(key: &NoiseKey, row: u32) -> RowNoise {
        let mut seed = [0u8; 32];
        seed[0..8].copy_from_slice(&key.seed.to_le_bytes());
        seed[8..16].copy_from_slice(&key.frame.to_le_bytes());
        seed[16..20].copy_from_slice(&key.camera.to_le_bytes());
        seed[20..24].copy_from_slice(&row.to_le_bytes());
        seed[24..32].copy_from_slice(&DOMAIN);
        RowNoise {
            rng: ChaCha8Rng::from_seed(seed),
        }
    }

    /// The D435 measurement of true depth `z` (m; NaN: no return) with focal length
    /// `focal` (px): NaN when nearer than the minimum range or dropped out, else `z`
    /// plus a normal error of sigma(z). Always draws the pixel's two words.
    pub(crate) fn d435(&mut self, z: f64, focal: f64) -> f64 {
        let a = self.rng.next_u64();
        let b = self.rng.next_u64();
        // a uniform in [0, 1) from the top 53 bits
        let dropout = (a >> 11) as f64 * (1.0 / (1u64 << 53) as f64);
        if !(z >= D435_MIN_RANGE) || dropout < D435_DROPOUT {
            return f64::NAN;
        }
        z + Noise::D435.sigma(z, focal) * standard_normal(b)
    }
}

/// A standard normal sample from one 64-bit word (Box-Muller, the cosine branch): u1 in
/// (0, 1] from the high 32 bits, u2 in [0, 1) from the low 32, so the tails reach
/// sqrt(-2 ln 2^-32) = 6.7 sigma.
fn standard_normal(word: u64) -> f64 {
    const SCALE: f64 = 1.0 / 4_294_967_296.0;
    let u1 = ((word >> 32) as f64 + 1.0) * SCALE;
    let u2 = (word & 0xffff_ffff) as f64 * SCALE;
    (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sigma_is_the_d435_formula() {
        // f = 600 px, z = 1 m: 0.08 / (600 * 0.05) = 2.67 mm
        assert_eq!(Noise::D435.sigma(1.0, 600.0), 0.08 / 30.0);
        assert_eq!(Noise::D435.sigma(2.0, 600.0), 4.0 * 0.08 / 30.0);
        assert_eq!(Noise::None.sigma(2.0, 600.0), 0.0);
    }

    #[test]
    fn the_normal_samples_have_unit_variance() {
        // 2e5 samples: the mean's standard error is 1 / sqrt(2e5) = 2.2e-3, the
        // variance's sqrt(2 / 2e5) = 3.2e-3; 4 standard errors each
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let n = 200_000;
        let (mut s, mut s2) = (0.0, 0.0);
        for _ in 0..n {
            let x = standard_normal(rng.next_u64());
            s += x;
            s2 += x * x;
        }
        let mean = s / n as f64;
        let var = s2 / n as f64 - mean * mean;
        assert!(mean.abs() < 4.0 * 2.2e-3, "{mean}");
        assert!((var - 1.0).abs() < 4.0 * 3.2e-3, "{var}");
    }

    #[test]
    fn rows_frames_and_cameras_draw_different_streams() {
        let key = NoiseKey {
            seed: 1,
            camera: 0,
            frame: 5,
        };
        let draw = |k: &NoiseKey, row| {
            let mut r = RowNoise::new(k, row);
            (0..8)
                .map(|_| r.d435(1.0, 600.0).to_bits())
                .collect::<Vec<_>>()
        };
        assert_eq!(draw(&key, 3), draw(&key, 3));
        assert_ne!(draw(&key, 3), draw(&key, 4));
        assert_ne!(draw(&key, 3), draw(&NoiseKey { frame: 6, ..key }, 3));
        assert_ne!(draw(&key, 3), draw(&NoiseKey { camera: 1, ..key }, 3));
        assert_ne!(draw(&key, 3), draw(&NoiseKey { seed: 2, ..key }, 3));
        // below the minimum range, or no return: NaN
        let mut r = RowNoise::new(&key, 0);
        assert!(r.d435(0.27, 600.0).is_nan());
        assert!(r.d435(f64::NAN, 600.0).is_nan());
    }
}
