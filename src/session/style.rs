//! How markers look: sizes (m) and colors, set by the node's parameters.

use crate::wire::msgs::ColorRGBA;

/// How markers look. Sizes in m.
#[derive(Clone, Debug, PartialEq)]
pub struct MarkerStyle {
    /// Width of the ruling lines, m (default 0.002).
    pub line_width: f64,
    /// Diameter of the singular-point spheres, m (default 0.012).
    pub sphere_diameter: f64,
    /// Vertex colors of flat, curved and singular regions.
    pub flat: ColorRGBA,
    pub curved: ColorRGBA,
    pub singular: ColorRGBA,
    pub ruling: ColorRGBA,
    /// Color of the colliders' markers.
    pub collider: ColorRGBA,
    /// Side of the square drawn for a ground plane, m (default 4).
    pub ground_size: f64,
}

impl Default for MarkerStyle {
    fn default() -> Self {
        MarkerStyle {
            line_width: 0.002,
            sphere_diameter: 0.012,
            flat: ColorRGBA::rgb(0.55, 0.72, 0.92),
            curved: ColorRGBA::rgb(0.96, 0.62, 0.22),
            singular: ColorRGBA::rgb(0.85, 0.1, 0.1),
            ruling: ColorRGBA::rgb(0.2, 0.2, 0.25),
            collider: ColorRGBA {
                r: 0.6,
                g: 0.6,
                b: 0.62,
                a: 0.6,
            },
            ground_size: 4.0,
        }
    }
}
