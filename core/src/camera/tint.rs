//! The colours of a scene, shared by the camera and the offline pictures
//! (`developable_sim render`): the surface's material +z side in its region's colour,
//! the other side pale; colliders grey, the ground a light checker. RGB in 0..=255.

use crate::geometry::{SurfaceMesh, VertexRegion};

/// A flat region (material +z side).
pub const FLAT: [f64; 3] = [80.0, 135.0, 215.0];
/// A curved (ruled) region (material +z side).
pub const CURVED: [f64; 3] = [235.0, 150.0, 55.0];
/// Colour the back side (material -z) is mixed toward, and how far: a light grey, so
/// the back reads as the same region's other side.
pub const BACK_TINT: [f64; 3] = [205.0, 207.0, 212.0];
pub const BACK_MIX: f64 = 0.7;
/// Where nothing is hit, a cool off-white.
pub const BACKGROUND: [f64; 3] = [246.0, 247.0, 250.0];
/// The ground, and the darker squares of its checker.
pub const FLOOR: [f64; 3] = [228.0, 228.0, 222.0];
pub const FLOOR_DARK: [f64; 3] = [206.0, 206.0, 200.0];
/// Side of a checker square on a ground plane, m.
pub const CHECKER: f64 = 0.1;
/// Colliders other than the ground (the markers' grey).
pub const COLLIDER: [f64; 3] = [153.0, 153.0, 158.0];

/// Lambert shading: the share of a surface's colour left when its normal makes the
/// angle acos(`cos_light`) with the light (0.42 in the dark, 1 facing the light).
pub fn shade(cos_light: f64) -> f64 {
    0.42 + 0.58 * cos_light.max(0.0)
}

/// `a` mixed toward `b` by `t` (0: a, 1: b).
pub fn mix(a: [f64; 3], b: [f64; 3], t: f64) -> [f64; 3] {
    [0, 1, 2].map(|k| a[k] + (b[k] - a[k]) * t)
}

/// A colour rounded to 8 bits.
pub fn to_rgb8(c: [f64; 3]) -> [u8; 3] {
    c.map(|x| x.round().clamp(0.0, 255.0) as u8)
}

/// The colour of triangle `t` of `m` seen from its `front` (material +z) side or its
/// back: curved when at least two of its vertices are curved or singular (a vertex on
/// the border of a flat region belongs to the curved region beside it too).
pub fn surface(m: &SurfaceMesh, t: &[u32; 3], front: bool) -> [f64; 3] {
    let bent = t
        .iter()
        .filter(|&&i| {
            !matches!(
                m.regions
                    .get(i as usize)
                    .copied()
                    .unwrap_or(VertexRegion::Flat),
                VertexRegion::Flat
            )
        })
        .count();
    let base = if bent >= 2 { CURVED } else { FLAT };
    if front {
        base
    } else {
        mix(base, BACK_TINT, BACK_MIX)
    }
}
