//! The RealSense D435 depth noise model (as mujoco_ros2_control's camera uses): a
//! stereo camera's depth error grows with the square of the depth,
//! sigma(z) = z^2 * subpixel / (f * baseline), with the matching error 0.08 px, the
//! baseline 50 mm and f the focal length in px; 1 % of the returns drop out (NaN), and
//! nothing nearer than the minimum range 0.28 m is returned.
//!
//! Seeded: each image row draws from its own ChaCha8 stream keyed by the scene's seed,
//! the camera, the frame index and the row, one 32-bit word a pixel whatever the scene
//! shows, so a frame's noise depends on nothing else (not the thread count, not
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
    /// plus a normal error of sigma(z). Always draws the pixel's one 32-bit word w: the
    /// return drops out when w < 1 % of 2^32; otherwise w is uniform over the rest, and
    /// its place there is the error's quantile.
    pub(crate) fn d435(&mut self, z: f64, focal: f64) -> f64 {
        let w = self.rng.next_u32();
        if !(z >= D435_MIN_RANGE) || w < DROPOUT_BELOW {
            return f64::NAN;
        }
        let p = ((w - DROPOUT_BELOW) as f64 + 0.5) / (TWO_TO_32 - DROPOUT_BELOW as f64);
        z + Noise::D435.sigma(z, focal) * inverse_normal_cdf(p)
    }
}

const TWO_TO_32: f64 = 4_294_967_296.0;

/// A word below this drops the return: round(0.01 x 2^32), a share of 0.01 + 9e-12.
const DROPOUT_BELOW: u32 = (D435_DROPOUT * TWO_TO_32 + 0.5) as u32;

/// The standard normal quantile at p in (0, 1) (Acklam's rational approximation,
/// relative error below 1.15e-9): a uniform p gives a standard normal sample without a
/// logarithm or a cosine in the central 95 % (p from a 32-bit word reaches 6.2 sigma).
fn inverse_normal_cdf(p: f64) -> f64 {
    const A: [f64; 6] = [
        -3.969683028665376e+01,
        2.209460984245205e+02,
        -2.759285104469687e+02,
        1.38357751867269e+02,
        -3.066479806614716e+01,
        2.506628277459239e+00,
    ];
    const B: [f64; 5] = [
        -5.447609879822406e+01,
        1.615858368580409e+02,
        -1.556989798598866e+02,
        6.680131188771972e+01,
        -1.328068155288572e+01,
    ];
    const C: [f64; 6] = [
        -7.784894002430293e-03,
        -3.223964580411365e-01,
        -2.400758277161838e+00,
        -2.549732539343734e+00,
        4.374664141464968e+00,
        2.938163982698783e+00,
    ];
    const D: [f64; 4] = [
        7.784695709041462e-03,
        3.224671290700398e-01,
        2.445134137142996e+00,
        3.754408661907416e+00,
    ];
    const LOW: f64 = 0.02425;
    let tail = |q: f64| {
        let q = (-2.0 * q.ln()).sqrt();
        (((((C[0] * q + C[1]) * q + C[2]) * q + C[3]) * q + C[4]) * q + C[5])
            / ((((D[0] * q + D[1]) * q + D[2]) * q + D[3]) * q + 1.0)
    };
    if p < LOW {
        tail(p)
    } else if p > 1.0 - LOW {
        -tail(1.0 - p)
    } else {
        let q = p - 0.5;
        let r = q * q;
        (((((A[0] * r + A[1]) * r + A[2]) * r + A[3]) * r + A[4]) * r + A[5]) * q
            / (((((B[0] * r + B[1]) * r + B[2]) * r + B[3]) * r + B[4]) * r + 1.0)
    }
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
    fn the_quantiles_are_the_normal_ones() {
        // Phi^-1 at 0.975 (central branch), 0.01 and 1e-6 (tails), to the
        // approximation's 1.15e-9 relative error
        for (p, x) in [
            (0.975, 1.959963984540054),
            (0.01, -2.326347874040841),
            (1e-6, -4.753424308822899),
            (1.0 - 1e-6, 4.753424308822899),
        ] {
            let got = inverse_normal_cdf(p);
            assert!((got - x).abs() < 1.15e-9 * x.abs(), "{p}: {got} vs {x}");
        }
        assert_eq!(inverse_normal_cdf(0.5), 0.0);
    }

    #[test]
    fn the_normal_samples_have_unit_variance() {
        // 2e5 samples: the mean's standard error is 1 / sqrt(2e5) = 2.2e-3, the
        // variance's sqrt(2 / 2e5) = 3.2e-3; 4 standard errors each
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let n = 200_000;
        let (mut s, mut s2) = (0.0, 0.0);
        for _ in 0..n {
            let x = inverse_normal_cdf((rng.next_u32() as f64 + 0.5) / TWO_TO_32);
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
