//! The z-buffer rasterizer: bands of rows drawn in parallel (rayon), each pixel's
//! value computed from its own ray whatever the band, so the output is bit-identical
//! at any thread count. Pixel (i, j) is sampled at its centre, u = i, v = j; its ray
//! in the optical frame is (x/z, y/z, 1) = ((i - cx) / f, (j - cy) / f, 1), and a
//! surface's depth along the optical axis is read off that ray exactly: c / (n . ray)
//! for a plane n . p = c (triangles and half-spaces), the entry root of a quadric
//! (balls, capsules). Every buffer is kept between frames: drawing allocates nothing
//! once warm.

use rayon::prelude::*;

use crate::contact::Collider;
use crate::geometry::{Pose, Vector3};

use super::frame::{pack_rgb, CLOUD_POINT_STEP};
use super::noise::RowNoise;
use super::prepare::{ColliderModel, Plane, Polygon, Prepared, Round, View};
use super::tint;
use super::{Camera, Frame, Noise, NoiseKey, Snapshot};

/// Rows per parallel task: fixed, so the partition does not depend on the thread count
/// (and it would not matter: no pixel reads another).
const BAND: usize = 8;

/// Renders one camera's frames. Build it once per camera (the colliders' shapes are
/// copied in), then call [`Renderer::render`] per frame.
#[derive(Clone, Debug)]
pub struct Renderer {
    camera: Camera,
    colliders: Vec<ColliderModel>,
    /// (i - cx) / f per column and (j - cy) / f per row.
    ray_x: Vec<f64>,
    ray_y: Vec<f64>,
    prepared: Prepared,
    /// Depth of the nearest surface per pixel, m (infinite: none).
    zbuf: Vec<f64>,
    frame: Frame,
    /// The view of the last [`Renderer::prepare`].
    view: View,
}

impl Renderer {
    /// A renderer for `camera` and the scene's colliders (`colliders`, in the order of
    /// [`Snapshot::collider_poses`]).
    pub fn new(camera: Camera, colliders: &[Collider]) -> Renderer {
        let intr = camera.intrinsics;
        let f = intr.focal();
        let [cx, cy] = intr.principal_point();
        Renderer {
            camera,
            colliders: colliders.iter().map(ColliderModel::new).collect(),
            ray_x: (0..intr.width).map(|i| (i as f64 - cx) / f).collect(),
            ray_y: (0..intr.height).map(|j| (j as f64 - cy) / f).collect(),
            prepared: Prepared::default(),
            zbuf: vec![f64::INFINITY; intr.width as usize * intr.height as usize],
            frame: Frame::sized(intr.width, intr.height),
            view: View::new(intr, &Pose::identity()),
        }
    }

    pub fn camera(&self) -> &Camera {
        &self.camera
    }

    /// The last frame drawn.
    pub fn frame(&self) -> &Frame {
        &self.frame
    }

    /// Render `scene` seen from `world_from_optical`, with the noise of frame `key`
    /// (ignored without a noise model): [`Renderer::prepare`] then [`Renderer::draw`].
    pub fn render(
        &mut self,
        scene: &Snapshot,
        world_from_optical: &Pose,
        key: &NoiseKey,
    ) -> &Frame {
        self.prepare(scene, world_from_optical);
        self.draw(key)
    }

    /// The frame's setup (sequential; proportional to the triangle count): every mesh
    /// and collider in the optical frame. Colliders are drawn at
    /// `scene.collider_poses` (one per collider given to [`Renderer::new`]; missing
    /// poses leave their colliders out).
    pub fn prepare(&mut self, scene: &Snapshot, world_from_optical: &Pose) {
        self.view = View::new(self.camera.intrinsics, world_from_optical);
        let view = &self.view;
        self.prepared.clear();
        for m in &scene.meshes {
            self.prepared.add_mesh(view, m);
        }
        for (model, pose) in self.colliders.iter().zip(&scene.collider_poses) {
            self.prepared.add_collider(view, model, pose);
        }
    }

    /// Draw what [`Renderer::prepare`] set up (parallel by bands of rows): colour,
    /// depth, noise, cloud.
    pub fn draw(&mut self, key: &NoiseKey) -> &Frame {
        let w = self.camera.intrinsics.width as usize;
        let ctx = Band {
            view: &self.view,
            noise: self.camera.noise,
            key,
            prepared: &self.prepared,
            ray_x: &self.ray_x,
            ray_y: &self.ray_y,
        };
        let frame = &mut self.frame;
        self.zbuf
            .par_chunks_mut(BAND * w)
            .zip(frame.color.par_chunks_mut(3 * BAND * w))
            .zip(frame.depth.par_chunks_mut(4 * BAND * w))
            .zip(frame.cloud.par_chunks_mut(CLOUD_POINT_STEP * BAND * w))
            .enumerate()
            .for_each(|(b, (((z, c), d), p))| ctx.draw(b * BAND, z, c, d, p));
        &self.frame
    }
}

/// What every band reads.
struct Band<'a> {
    view: &'a View,
    noise: Noise,
    key: &'a NoiseKey,
    prepared: &'a Prepared,
    ray_x: &'a [f64],
    ray_y: &'a [f64],
}

impl Band<'_> {
    /// Rows `row0..` of the image into their slices of the buffers.
    fn draw(
        &self,
        row0: usize,
        z: &mut [f64],
        color: &mut [u8],
        depth: &mut [u8],
        cloud: &mut [u8],
    ) {
        let w = self.ray_x.len();
        let rows = row0..row0 + z.len() / w;
        z.fill(f64::INFINITY);
        let bg = tint::to_rgb8(tint::BACKGROUND);
        for px in color.chunks_exact_mut(3) {
            px.copy_from_slice(&bg);
        }
        for plane in &self.prepared.planes {
            self.plane(plane, rows.clone(), z, color);
        }
        for round in &self.prepared.rounds {
            self.round(round, rows.clone(), z, color);
        }
        for poly in &self.prepared.polygons {
            self.polygon(poly, rows.clone(), z, color);
        }
        for (k, j) in rows.enumerate() {
            let s = k * w..(k + 1) * w;
            self.finish_row(
                j,
                &z[s.clone()],
                &color[3 * s.start..3 * s.end],
                &mut depth[4 * s.start..4 * s.end],
                &mut cloud[CLOUD_POINT_STEP * s.start..CLOUD_POINT_STEP * s.end],
            );
        }
    }

    /// A half-space's surface, exactly per pixel: depth c / (n . ray) where positive.
    fn plane(&self, p: &Plane, rows: std::ops::Range<usize>, z: &mut [f64], color: &mut [u8]) {
        let w = self.ray_x.len();
        let near = self.view.intrinsics.near;
        for (k, j) in rows.enumerate() {
            let ry = self.ray_y[j];
            let (nr, xr, yr) = (
                p.normal.y * ry + p.normal.z,
                p.ex.y * ry + p.ex.z,
                p.ey.y * ry + p.ey.z,
            );
            for (i, &rx) in self.ray_x.iter().enumerate() {
                let t = p.offset / (p.normal.x * rx + nr);
                let at = k * w + i;
                if t >= near && t < z[at] {
                    z[at] = t;
                    // the checker in the half-space's frame
                    let qx = t * (p.ex.x * rx + xr) - p.origin_x;
                    let qy = t * (p.ey.x * rx + yr) - p.origin_y;
                    let parity = (floor(qx * INV_CHECKER) + floor(qy * INV_CHECKER)) & 1;
                    color[3 * at..3 * at + 3].copy_from_slice(&p.colors[parity as usize]);
                }
            }
        }
    }

    /// A ball or capsule, exactly per pixel in its bounds.
    fn round(&self, r: &Round, rows: std::ops::Range<usize>, z: &mut [f64], color: &mut [u8]) {
        let w = self.ray_x.len();
        let near = self.view.intrinsics.near;
        let (lo, hi) = (
            rows.start.max(r.rows[0] as usize),
            rows.end.min(r.rows[1] as usize + 1),
        );
        for j in lo..hi {
            let k = j - rows.start;
            for i in r.cols[0] as usize..=r.cols[1] as usize {
                let d = Vector3::new(self.ray_x[i], self.ray_y[j], 1.0);
                let Some((t, normal)) = round_entry(r, &d) else {
                    continue;
                };
                let at = k * w + i;
                if t >= near && t < z[at] {
                    z[at] = t;
                    // the entry point faces the camera: shade with the outward normal
                    color[3 * at..3 * at + 3].copy_from_slice(&self.view.collider_color(&normal));
                }
            }
        }
    }

    /// A convex polygon: pixel centres inside its exact edge functions, depth from its
    /// plane.
    fn polygon(&self, p: &Polygon, rows: std::ops::Range<usize>, z: &mut [f64], color: &mut [u8]) {
        let w = self.ray_x.len();
        let near = self.view.intrinsics.near;
        let (lo, hi) = (
            rows.start.max(p.rows[0] as usize),
            rows.end.min(p.rows[1] as usize + 1),
        );
        for j in lo..hi {
            let v = j as f64;
            let r = p.edges.map(|e| e[1] * v + e[2]);
            let Some((i0, i1)) = span(&p.edges, &r, p.cols) else {
                continue;
            };
            let k = j - rows.start;
            let nr = p.normal.y * self.ray_y[j] + p.normal.z;
            for i in i0..=i1 {
                let u = i as f64;
                if (0..4).all(|e| p.edges[e][0] * u + r[e] >= 0.0) {
                    let t = p.offset / (p.normal.x * self.ray_x[i] + nr);
                    let at = k * w + i;
                    if t >= near && t < z[at] {
                        z[at] = t;
                        color[3 * at..3 * at + 3].copy_from_slice(&p.color);
                    }
                }
            }
        }
    }

    /// Depth (with noise), and the cloud: depth back-projected through K.
    fn finish_row(&self, j: usize, z: &[f64], color: &[u8], depth: &mut [u8], cloud: &mut [u8]) {
        let far = self.view.intrinsics.far;
        let near = self.view.intrinsics.near;
        let mut noise = (self.noise == Noise::D435).then(|| RowNoise::new(self.key, j as u32));
        let ry = self.ray_y[j];
        let pixels = z
            .iter()
            .zip(self.ray_x)
            .zip(color.chunks_exact(3))
            .zip(depth.chunks_exact_mut(4))
            .zip(cloud.chunks_exact_mut(CLOUD_POINT_STEP));
        for ((((&t, &rx), c), d_out), p_out) in pixels {
            let mut d = if t <= far { t } else { f64::NAN };
            if let Some(n) = noise.as_mut() {
                d = n.d435(d, self.view.focal);
                if !(d >= near && d <= far) {
                    d = f64::NAN;
                }
            }
            let df = d as f32;
            d_out.copy_from_slice(&df.to_le_bytes());
            let zf = df as f64;
            let rgb = pack_rgb([c[0], c[1], c[2]]);
            let point = [(zf * rx) as f32, (zf * ry) as f32, df, rgb];
            for (o, v) in p_out.chunks_exact_mut(4).zip(point) {
                o.copy_from_slice(&v.to_le_bytes());
            }
        }
    }
}

/// The columns of a row worth testing: the polygon's bounds narrowed to where each
/// edge function can be >= 0 (a pixel of margin for rounding: the exact test decides).
/// `r` is each edge's b v + c for the row.
fn span(edges: &[[f64; 3]; 4], r: &[f64; 4], cols: [u32; 2]) -> Option<(usize, usize)> {
    let (mut lo, mut hi) = (cols[0] as f64, cols[1] as f64);
    for k in 0..4 {
        let a = edges[k][0];
        if a == 0.0 {
            if r[k] < 0.0 {
                return None;
            }
            continue;
        }
        let u = -r[k] / a;
        if a > 0.0 {
            lo = lo.max(u.floor() - 1.0);
        } else {
            hi = hi.min(u.ceil() + 1.0);
        }
    }
    (lo <= hi).then_some((lo as usize, hi as usize))
}

/// Checker squares per metre.
const INV_CHECKER: f64 = 1.0 / tint::CHECKER;

/// floor(x) as an integer without a libm call (x86-64's baseline has no rounding
/// instruction): truncate, then step down for negative non-integers. Saturates far out.
fn floor(x: f64) -> i64 {
    let t = x as i64;
    t - i64::from((t as f64) > x)
}

/// Where the ray t (x/z, y/z, 1) first enters the points within `radius` of the
/// segment a-b: the least entry of its cylinder (within the segment) and of its two
/// end spheres; t is the depth, m. With the outward unit normal there.
fn round_entry(r: &Round, d: &Vector3) -> Option<(f64, Vector3)> {
    let mut best: Option<(f64, Vector3)> = None;
    let mut offer = |t: f64, normal: Vector3| {
        if t.is_finite() && best.is_none_or(|b| t < b.0) {
            best = Some((t, normal));
        }
    };
    for c in [&r.a, &r.b] {
        if let Some(t) = sphere_entry(c, r.radius, d) {
            offer(t, (d * t - c) / r.radius);
        }
    }
    let axis = r.b - r.a;
    let len = axis.norm();
    if len > 0.0 {
        let e = axis / len;
        // components across the axis of the ray and of the camera (origin) - a
        let dp = d - e * d.dot(&e);
        let op = -(r.a - e * r.a.dot(&e));
        let (qa, qb, qc) = (dp.dot(&dp), dp.dot(&op), op.dot(&op) - r.radius * r.radius);
        let h = qb * qb - qa * qc;
        if qa > 0.0 && h >= 0.0 {
            let t = (-qb - h.sqrt()) / qa;
            let w = d * t - r.a;
            let s = w.dot(&e);
            if (0.0..=len).contains(&s) {
                offer(t, (w - e * s) / r.radius);
            }
        }
    }
    best
}

/// The entry depth of the ray t (x/z, y/z, 1) into the ball of `radius` at `c`.
fn sphere_entry(c: &Vector3, radius: f64, d: &Vector3) -> Option<f64> {
    let (dd, dc) = (d.dot(d), d.dot(c));
    let h = dc * dc - dd * (c.dot(c) - radius * radius);
    (h >= 0.0).then(|| (dc - h.sqrt()) / dd)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn round(a: [f64; 3], b: [f64; 3], radius: f64) -> Round {
        Round {
            a: Vector3::from(a),
            b: Vector3::from(b),
            radius,
            cols: [0, 0],
            rows: [0, 0],
        }
    }

    #[test]
    fn rays_enter_balls_and_capsules_where_the_geometry_says() {
        let ahead = Vector3::new(0.0, 0.0, 1.0);
        // a ball of radius 0.5 at depth 2: entered at 1.5, normal towards the camera
        let (t, n) = round_entry(&round([0.0, 0.0, 2.0], [0.0, 0.0, 2.0], 0.5), &ahead).unwrap();
        assert_eq!(t, 1.5);
        assert_eq!(n, Vector3::new(0.0, 0.0, -1.0));
        // a capsule across the view (along x) at depth 2, radius 0.1: its side at 1.9
        let cap = round([-1.0, 0.0, 2.0], [1.0, 0.0, 2.0], 0.1);
        let (t, n) = round_entry(&cap, &Vector3::new(0.25, 0.0, 1.0)).unwrap();
        // the discriminant h = 0.01 is 4 - 3.99: cancellation costs ~2e-14 relative in
        // h, 1e-14 in sqrt(h) = 0.1, so ~1e-15 m in t and 1e-14 in the normal (/ 0.1)
        assert!(
            (t - 1.9).abs() < 4e-15 && (n + Vector3::z()).norm() < 4e-14,
            "{t} {n}"
        );
        // past its end (the side at depth 1.9 ends at x/z = 1 / 1.9 = 0.526): the end cap, then nothing
        let (t, _) = round_entry(&cap, &Vector3::new(0.53, 0.0, 1.0)).unwrap();
        let exact = sphere_entry(
            &Vector3::new(1.0, 0.0, 2.0),
            0.1,
            &Vector3::new(0.53, 0.0, 1.0),
        );
        assert_eq!(Some(t), exact);
        assert!(round_entry(&cap, &Vector3::new(0.6, 0.0, 1.0)).is_none());
        assert!(round_entry(&cap, &Vector3::new(0.0, 0.2, 1.0)).is_none());
    }

    #[test]
    fn spans_narrow_to_the_edges_and_drop_rows_outside() {
        // the half-plane u >= 10.5: a = 1, c = -10.5
        let edges = [
            [1.0, 0.0, -10.5],
            [0.0, 0.0, 1.0],
            [0.0, 0.0, 1.0],
            [0.0, 0.0, 1.0],
        ];
        let r = edges.map(|e| e[2]);
        assert_eq!(span(&edges, &r, [0, 63]), Some((9, 63)));
        let mut below = r;
        below[1] = -1.0;
        assert_eq!(span(&edges, &below, [0, 63]), None);
    }
}
