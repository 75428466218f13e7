//! Reconstruction of the ribbon from ruling-bending coordinates (Pan et al. eqs. 2, 3).
//!
//! Element E_e (e = 0..n-1) is the rigid image of its flat material trapezoid under the
//! frame `world_from_element[e] = T_0 T_1 ... T_e`, where T_k (k >= 1) rotates by the
//! bending angle psi_k about crease k: the line through (l k / n, 0, 0) with direction
//! (c_k, 1, 0). Every element is a rigid copy of the flat strip, so the mesh is exactly
//! isometric by construction.

use crate::geometry::{skew, Matrix3, Point3, Pose, Vector3};

/// Ruling-bending coordinates of one ribbon.
#[derive(Clone, Debug, PartialEq)]
pub struct Coordinates {
    /// c_k = tan(theta_k) for k = 0..=n; c_0 = c_n = 0 always (the ends are square).
    pub crease_direction: Vec<f64>,
    /// psi_k, rad, for k = 0..=n; psi_0 = psi_n = 0 (unused).
    pub bending_angle: Vec<f64>,
    /// T_0 = `world_from_base`: the frame of element E_0.
    pub base: Pose,
}

impl Coordinates {
    /// A flat ribbon with square creases at `base`.
    pub fn flat(segments: usize, base: Pose) -> Self {
        Coordinates {
            crease_direction: vec![0.0; segments + 1],
            bending_angle: vec![0.0; segments + 1],
            base,
        }
    }
    pub fn segments(&self) -> usize {
        self.crease_direction.len() - 1
    }
}

/// Ribbon dimensions: length l (m), width w (m), n elements.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Strip {
    pub length: f64,
    pub width: f64,
    pub segments: usize,
}

impl Strip {
    /// Material coordinate of the centerline at crease k: l k / n, m.
    #[inline]
    pub fn crease_station(&self, k: usize) -> f64 {
        self.length * k as f64 / self.segments as f64
    }
    /// Material position of bottom rim vertex x̄_j (eq. 2), m.
    #[inline]
    pub fn material_bottom(&self, j: usize, c_j: f64) -> Point3 {
        Point3::new(
            self.crease_station(j) - 0.5 * self.width * c_j,
            -0.5 * self.width,
            0.0,
        )
    }
    /// Element containing material point `p` (m) given creases `c` (element borders
    /// at height v are u = l k / n + c_k v). O(1) from the nearest station, then walks.
    pub fn element_of(&self, c: &[f64], p: &crate::geometry::Point2) -> usize {
        let n = self.segments;
        let mut e = ((p.x / self.length) * n as f64)
            .floor()
            .clamp(0.0, (n - 1) as f64) as usize;
        for _ in 0..n {
            let lo = self.crease_station(e) + c[e] * p.y;
            let hi = self.crease_station(e + 1) + c[e + 1] * p.y;
            if p.x < lo && e > 0 {
                e -= 1;
            } else if p.x > hi && e + 1 < n {
                e += 1;
            } else {
                break;
            }
        }
        e
    }
    /// Material position of top rim vertex ȳ_j (eq. 2), m.
    #[inline]
    pub fn material_top(&self, j: usize, c_j: f64) -> Point3 {
        Point3::new(
            self.crease_station(j) + 0.5 * self.width * c_j,
            0.5 * self.width,
            0.0,
        )
    }
}

/// Unit direction of crease k in material space: (c, 1, 0) / sqrt(1 + c^2).
#[inline]
pub fn crease_axis(c: f64) -> Vector3 {
    Vector3::new(c, 1.0, 0.0) / (1.0 + c * c).sqrt()
}

/// d(crease_axis)/dc = (1, -c, 0) / (1 + c^2)^(3/2).
#[inline]
pub fn crease_axis_derivative(c: f64) -> Vector3 {
    let s = 1.0 + c * c;
    Vector3::new(1.0, -c, 0.0) / (s * s.sqrt())
}

/// T_k as (R, t) with T_k(x) = R x + t: rotation by psi about the crease line through
/// (station, 0, 0) with direction (c, 1, 0).
#[inline]
pub fn crease_transform(station: f64, c: f64, psi: f64) -> (Matrix3, Vector3) {
    let (sin, cos) = psi.sin_cos();
    crease_transform_sin_cos(station, c, sin, cos)
}

/// [`crease_transform`] from sin psi and cos psi, so that one sin_cos per crease serves
/// the frames and the twists of an evaluation. Rodrigues' formula on the unit crease
/// axis d, with [d]x^2 = d d^T - I: R = cos psi I + sin psi [d]x + (1 - cos psi) d d^T.
/// The axis passes through p = (station, 0, 0), so t = p - R p = p - station R e_x.
#[inline]
pub fn crease_transform_sin_cos(station: f64, c: f64, sin: f64, cos: f64) -> (Matrix3, Vector3) {
    let d = crease_axis(c);
    let r = Matrix3::identity() * cos + skew(&d) * sin + d * d.transpose() * (1.0 - cos);
    let t = Vector3::new(station, 0.0, 0.0) - r.column(0) * station;
    (r, t)
}

/// World geometry of a ribbon, rebuilt by [`reconstruct`]; buffers are reused.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Frames {
    /// Rotation part of `world_from_element[e]`, e = 0..n-1.
    pub rotation: Vec<Matrix3>,
    /// Translation part of `world_from_element[e]`, m.
    pub translation: Vec<Vector3>,
    /// x_j, j = 0..=n, world, m.
    pub rim_bottom: Vec<Point3>,
    /// y_j, j = 0..=n, world, m.
    pub rim_top: Vec<Point3>,
    /// n_e = R_e (0, 0, 1), e = 0..n-1 (eq. 3).
    pub normals: Vec<Vector3>,
    /// (sin psi_k, cos psi_k) of every bending angle, k = 0..n-1 (entry 0 unused: (0, 1)).
    pub bending_sin_cos: Vec<(f64, f64)>,
}

impl Frames {
    /// World position of a material point (m) carried by element `e`.
    #[inline]
    pub fn to_world(&self, e: usize, material: &Point3) -> Point3 {
        Point3::from(self.rotation[e] * material.coords + self.translation[e])
    }
}

/// Rebuild element frames, rims and normals from coordinates (eqs. 2, 3). O(n).
pub fn reconstruct(strip: &Strip, q: &Coordinates, out: &mut Frames) {
    let n = strip.segments;
    out.rotation.resize(n, Matrix3::identity());
    out.translation.resize(n, Vector3::zeros());
    out.rim_bottom.resize(n + 1, Point3::origin());
    out.rim_top.resize(n + 1, Point3::origin());
    out.normals.resize(n, Vector3::z());
    out.bending_sin_cos.resize(n, (0.0, 1.0));

    let mut r = *q.base.rotation.to_rotation_matrix().matrix();
    let mut t = q.base.translation.vector;
    for e in 0..n {
        if e > 0 {
            let (sin, cos) = q.bending_angle[e].sin_cos();
            out.bending_sin_cos[e] = (sin, cos);
            let (rk, tk) =
                crease_transform_sin_cos(strip.crease_station(e), q.crease_direction[e], sin, cos);
            // world_from_element[e] = world_from_element[e-1] * T_e
            t += r * tk;
            r *= rk;
        }
        out.rotation[e] = r;
        out.translation[e] = t;
        out.normals[e] = Vector3::new(r[(0, 2)], r[(1, 2)], r[(2, 2)]);
        // Vertices on crease e lie on the rotation axis of T_e, so element e-1 and
        // element e place them identically; take them from element e.
        out.rim_bottom[e] = out.to_world(e, &strip.material_bottom(e, q.crease_direction[e]));
        out.rim_top[e] = out.to_world(e, &strip.material_top(e, q.crease_direction[e]));
    }
    out.rim_bottom[n] = out.to_world(n - 1, &strip.material_bottom(n, 0.0));
    out.rim_top[n] = out.to_world(n - 1, &strip.material_top(n, 0.0));
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    fn random_coords(n: usize, seed: u64) -> Coordinates {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let mut q = Coordinates::flat(n, Pose::identity());
        for k in 1..n {
            q.crease_direction[k] = rng.random_range(-0.5..0.5);
            q.bending_angle[k] = rng.random_range(-1.0..1.0);
        }
        q.base = Pose::new(Vector3::new(0.1, -0.3, 0.2), Vector3::new(0.4, 0.1, -0.7));
        q
    }

    #[test]
    fn reconstruction_is_isometric_to_the_flat_strip() {
        let strip = Strip {
            length: 1.0,
            width: 0.05,
            segments: 20,
        };
        let q = random_coords(20, 7);
        let mut f = Frames::default();
        reconstruct(&strip, &q, &mut f);
        for j in 0..20 {
            let c0 = q.crease_direction[j];
            let c1 = q.crease_direction[j + 1];
            let pairs = [
                (
                    f.rim_bottom[j],
                    f.rim_bottom[j + 1],
                    strip.material_bottom(j, c0),
                    strip.material_bottom(j + 1, c1),
                ),
                (
                    f.rim_top[j],
                    f.rim_top[j + 1],
                    strip.material_top(j, c0),
                    strip.material_top(j + 1, c1),
                ),
                (
                    f.rim_bottom[j],
                    f.rim_top[j],
                    strip.material_bottom(j, c0),
                    strip.material_top(j, c0),
                ),
                (
                    f.rim_bottom[j],
                    f.rim_top[j + 1],
                    strip.material_bottom(j, c0),
                    strip.material_top(j + 1, c1),
                ),
            ];
            for (a, b, ma, mb) in pairs {
                let err = ((a - b).norm() - (ma - mb).norm()).abs();
                assert!(err < 1e-14, "edge at {j}: {err}");
            }
        }
    }

    #[test]
    fn crease_vertices_agree_between_neighbouring_elements() {
        let strip = Strip {
            length: 1.0,
            width: 0.1,
            segments: 12,
        };
        let q = random_coords(12, 3);
        let mut f = Frames::default();
        reconstruct(&strip, &q, &mut f);
        for j in 1..12 {
            let c = q.crease_direction[j];
            let from_prev = f.to_world(j - 1, &strip.material_bottom(j, c));
            assert!((from_prev - f.rim_bottom[j]).norm() < 1e-14);
            let from_prev = f.to_world(j - 1, &strip.material_top(j, c));
            assert!((from_prev - f.rim_top[j]).norm() < 1e-14);
        }
    }

    #[test]
    fn crease_transform_matches_the_papers_closed_form() {
        // Pan et al. appendix A writes T_k entrywise; its first column and the
        // translation's x are sign-independent checks of our Rodrigues construction.
        let (c, psi, station) = (0.3_f64, 0.8_f64, 0.25_f64);
        let (r, t) = crease_transform(station, c, psi);
        let s = c * c + 1.0;
        assert!((r[(0, 0)] - (psi.cos() + c * c) / s).abs() < 1e-14);
        assert!((r[(1, 0)] - (c - c * psi.cos()) / s).abs() < 1e-14);
        assert!((r[(1, 1)] - (1.0 + c * c * psi.cos()) / s).abs() < 1e-14);
        assert!((r[(2, 2)] - psi.cos()).abs() < 1e-14);
        // translation x of appendix A: (c^2 k l cos(psi) - c^2 k l)/(n (c^2+1)) ... with
        // k l / n = station the x offset is station * (1 - R_00).
        assert!((t.x - station * (1.0 - r[(0, 0)])).abs() < 1e-14);
    }
}
