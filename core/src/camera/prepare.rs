//! A frame's setup, before any pixel: every surface in the optical frame (x right, y
//! down, z forward, m) as the per-pixel tests need it. Triangles (object meshes, boxes,
//! collider meshes) become convex screen polygons, cut by the near plane, with exact
//! edge functions and the plane their depth is read from; half-spaces become planes;
//! balls and capsules become round segments. Sequential and allocation-free once warm.

use crate::contact::{Collider, ColliderShape};
use crate::geometry::{Matrix3, Point3, Pose, SurfaceMesh, Vector3};

use super::tint;
use super::Intrinsics;

/// A collider's geometry in its own frame, as the camera draws it.
#[derive(Clone, Debug)]
pub(crate) enum ColliderModel {
    /// The half-space z <= 0: its surface is drawn per pixel by ray-plane intersection.
    HalfSpace,
    /// The points within `radius` (m) of the segment a-b (a ball when a = b).
    Round { a: Point3, b: Point3, radius: f64 },
    /// Boxes and meshes: triangles (two-sided).
    Triangles {
        vertices: Vec<Point3>,
        triangles: Vec<[u32; 3]>,
    },
}

impl ColliderModel {
    pub(crate) fn new(c: &Collider) -> ColliderModel {
        match &c.shape {
            ColliderShape::HalfSpace => ColliderModel::HalfSpace,
            ColliderShape::Ball { radius } => ColliderModel::Round {
                a: Point3::origin(),
                b: Point3::origin(),
                radius: *radius,
            },
            ColliderShape::Capsule {
                half_height,
                radius,
            } => ColliderModel::Round {
                a: Point3::new(0.0, 0.0, -half_height),
                b: Point3::new(0.0, 0.0, *half_height),
                radius: *radius,
            },
            ColliderShape::Cuboid { half_extents: h } => {
                // corner k has x = +h.x when bit 0 is set, y bit 1, z bit 2
                let vertices = (0..8)
                    .map(|k| {
                        let s = |bit: u32, e: f64| if k & bit == 0 { -e } else { e };
                        Point3::new(s(1, h.x), s(2, h.y), s(4, h.z))
                    })
                    .collect();
                let triangles = vec![
                    [0, 2, 3],
                    [0, 3, 1], // z-
                    [4, 5, 7],
                    [4, 7, 6], // z+
                    [0, 1, 5],
                    [0, 5, 4], // y-
                    [2, 6, 7],
                    [2, 7, 3], // y+
                    [0, 4, 6],
                    [0, 6, 2], // x-
                    [1, 3, 7],
                    [1, 7, 5], // x+
                ];
                ColliderModel::Triangles {
                    vertices,
                    triangles,
                }
            }
            ColliderShape::TriMesh {
                vertices,
                triangles,
            } => ColliderModel::Triangles {
                vertices: vertices.clone(),
                triangles: triangles.clone(),
            },
        }
    }
}

/// A convex screen polygon: a triangle, or a triangle cut by the near plane.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Polygon {
    /// Edge functions (a, b, c): pixel (u, v) is inside when a u + (b v + c) >= 0 for
    /// all four (a triangle's fourth is 0 u + 0 v + 1). A shared edge has the same a,
    /// b, c in both polygons up to sign, so no pixel centre falls between them.
    pub edges: [[f64; 3]; 4],
    /// The supporting plane n . p = c (optical frame): the depth along the ray
    /// (x/z, y/z, 1) is c / (n . ray).
    pub normal: Vector3,
    pub offset: f64,
    /// Inclusive pixel bounds: columns and rows.
    pub cols: [u32; 2],
    pub rows: [u32; 2],
    pub color: [u8; 3],
}

/// The surface of a half-space, n . p = c with n its outward unit normal; the checker
/// is laid out on its frame's x, y axes.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Plane {
    pub normal: Vector3,
    pub offset: f64,
    /// The half-space frame's x and y axes and their offsets (ex . origin, ey . origin).
    pub ex: Vector3,
    pub ey: Vector3,
    pub origin_x: f64,
    pub origin_y: f64,
    /// The light and dark checker squares, shaded.
    pub colors: [[u8; 3]; 2],
}

/// A ball or capsule: the points within `radius` of the segment a-b (optical frame, m).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Round {
    pub a: Vector3,
    pub b: Vector3,
    pub radius: f64,
    pub cols: [u32; 2],
    pub rows: [u32; 2],
}

/// Everything a frame draws, in the optical frame.
#[derive(Clone, Debug, Default)]
pub(crate) struct Prepared {
    pub polygons: Vec<Polygon>,
    pub planes: Vec<Plane>,
    pub rounds: Vec<Round>,
    /// Scratch: the vertices of the mesh being prepared, optical frame.
    optical: Vec<Point3>,
}

/// The camera of one frame: intrinsics, `optical_from_world` as a matrix, the light.
#[derive(Clone, Debug)]
pub(crate) struct View {
    pub intrinsics: Intrinsics,
    pub focal: f64,
    pub center: [f64; 2],
    rotation: Matrix3,
    translation: Vector3,
    /// Unit vector towards the light: from the upper left, behind the camera.
    light: Vector3,
}

impl View {
    pub(crate) fn new(intrinsics: Intrinsics, world_from_optical: &Pose) -> View {
        let optical_from_world = world_from_optical.inverse();
        View {
            intrinsics,
            focal: intrinsics.focal(),
            center: intrinsics.principal_point(),
            rotation: optical_from_world
                .rotation
                .to_rotation_matrix()
                .into_inner(),
            translation: optical_from_world.translation.vector,
            // right is +x, up is -y, forward +z (the offline pictures' light)
            light: Vector3::new(-0.5, -0.9, -1.0).normalize(),
        }
    }

    fn to_optical(&self, p: &Point3) -> Point3 {
        Point3::from(self.rotation * p.coords + self.translation)
    }

    fn shaded(&self, base: [f64; 3], facing: &Vector3) -> [u8; 3] {
        let s = tint::shade(facing.dot(&self.light));
        tint::to_rgb8(base.map(|c| c * s))
    }

    /// The shaded collider colour for a unit normal facing the camera.
    pub(crate) fn collider_color(&self, facing: &Vector3) -> [u8; 3] {
        self.shaded(tint::COLLIDER, facing)
    }
}

impl Prepared {
    pub(crate) fn clear(&mut self) {
        self.polygons.clear();
        self.planes.clear();
        self.rounds.clear();
    }

    /// An object's surface: both sides, in the front and back tints, flat-shaded.
    pub(crate) fn add_mesh(&mut self, view: &View, m: &SurfaceMesh) {
        self.optical.clear();
        self.optical
            .extend(m.vertices.iter().map(|p| view.to_optical(p)));
        let optical = std::mem::take(&mut self.optical);
        for t in &m.triangles {
            let Some(p) = t.iter().map(|&i| optical.get(i as usize)).collect_tri() else {
                continue;
            };
            self.add_triangle(view, p, |front| tint::surface(m, t, front));
        }
        self.optical = optical;
    }

    /// A collider at `world_from_collider`.
    pub(crate) fn add_collider(&mut self, view: &View, model: &ColliderModel, pose: &Pose) {
        let to_optical = |p: &Point3| view.to_optical(&(pose * p));
        match model {
            ColliderModel::HalfSpace => self.add_plane(view, pose),
            ColliderModel::Round { a, b, radius } => {
                let (a, b) = (to_optical(a).coords, to_optical(b).coords);
                if let Some((cols, rows)) = round_bounds(view, &a, &b, *radius) {
                    self.rounds.push(Round {
                        a,
                        b,
                        radius: *radius,
                        cols,
                        rows,
                    });
                }
            }
            ColliderModel::Triangles {
                vertices,
                triangles,
            } => {
                self.optical.clear();
                self.optical.extend(vertices.iter().map(to_optical));
                let optical = std::mem::take(&mut self.optical);
                for t in triangles {
                    let Some(p) = t.iter().map(|&i| optical.get(i as usize)).collect_tri() else {
                        continue;
                    };
                    self.add_triangle(view, p, |_| tint::COLLIDER);
                }
                self.optical = optical;
            }
        }
    }

    fn add_plane(&mut self, view: &View, pose: &Pose) {
        let r = view.rotation * pose.rotation.to_rotation_matrix().into_inner();
        let origin = view
            .to_optical(&Point3::from(pose.translation.vector))
            .coords;
        let (ex, ey, normal) = (
            r.column(0).into_owned(),
            r.column(1).into_owned(),
            r.column(2).into_owned(),
        );
        if !(origin.iter().chain(normal.iter()).all(|x| x.is_finite())) {
            return;
        }
        let offset = normal.dot(&origin);
        // the camera (the origin) is outside when -offset > 0: it sees the +n side
        let facing = if offset < 0.0 { normal } else { -normal };
        self.planes.push(Plane {
            normal,
            offset,
            ex,
            ey,
            origin_x: ex.dot(&origin),
            origin_y: ey.dot(&origin),
            colors: [
                view.shaded(tint::FLOOR, &facing),
                view.shaded(tint::FLOOR_DARK, &facing),
            ],
        });
    }

    /// Triangle `p` (optical frame) in the colour `base(front)`, cut by the near plane.
    fn add_triangle(&mut self, view: &View, p: [Point3; 3], base: impl Fn(bool) -> [f64; 3]) {
        let n = (p[1] - p[0]).cross(&(p[2] - p[0]));
        let offset = n.dot(&p[0].coords);
        // the plane through the camera is seen edge-on: nothing to draw
        if !(n.iter().all(|x| x.is_finite()) && offset.is_finite() && offset != 0.0) {
            return;
        }
        // the front (material +z, counter-clockwise) side faces the camera when the
        // camera, at the origin, is on the +n side: n . (0 - p0) > 0
        let front = offset < 0.0;
        let facing = if front { n } else { -n }.normalize();
        let color = view.shaded(base(front), &facing);
        let mut clipped = [Point3::origin(); 4];
        let count = clip_near(&p, view.intrinsics.near, &mut clipped);
        if count < 3 {
            return;
        }
        let mut screen = [[0.0; 2]; 4];
        for k in 0..count {
            let q = &clipped[k];
            screen[k] = [
                view.focal * (q.x / q.z) + view.center[0],
                view.focal * (q.y / q.z) + view.center[1],
            ];
        }
        let Some((edges, (cols, rows))) = polygon_edges(&screen[..count], &view.intrinsics) else {
            return;
        };
        self.polygons.push(Polygon {
            edges,
            normal: n,
            offset,
            cols,
            rows,
            color,
        });
    }
}

/// Three vertices from an iterator of lookups, None when one is missing or not finite.
trait CollectTri<'a> {
    fn collect_tri(self) -> Option<[Point3; 3]>;
}

impl<'a, I: Iterator<Item = Option<&'a Point3>>> CollectTri<'a> for I {
    fn collect_tri(mut self) -> Option<[Point3; 3]> {
        let mut out = [Point3::origin(); 3];
        for o in &mut out {
            let p = self.next()??;
            if !p.coords.iter().all(|x| x.is_finite()) {
                return None;
            }
            *o = *p;
        }
        Some(out)
    }
}

/// Triangle `p` cut to z >= `near` (Sutherland-Hodgman against one plane) into `out`;
/// returns the vertex count (0, 3 or 4). A cut point is computed from its edge's
/// endpoints in a fixed order, so two triangles sharing the edge cut it identically.
fn clip_near(p: &[Point3; 3], near: f64, out: &mut [Point3; 4]) -> usize {
    let mut n = 0;
    for k in 0..3 {
        let (a, b) = (&p[k], &p[(k + 1) % 3]);
        let (a_in, b_in) = (a.z >= near, b.z >= near);
        if a_in {
            out[n] = *a;
            n += 1;
        }
        if a_in != b_in {
            let (s, e) = if lex_less(a, b) { (a, b) } else { (b, a) };
            let t = (near - s.z) / (e.z - s.z);
            let mut q = s + (e - s) * t;
            q.z = near;
            out[n] = q;
            n += 1;
        }
    }
    n
}

fn lex_less(a: &Point3, b: &Point3) -> bool {
    (a.x, a.y, a.z) < (b.x, b.y, b.z)
}

/// Inclusive pixel bounds: columns, rows.
type Bounds = ([u32; 2], [u32; 2]);

/// The edge functions of a convex screen polygon (u, v px) with inside >= 0, and its
/// pixel bounds (columns, rows); None when it is degenerate or off the image.
fn polygon_edges(s: &[[f64; 2]], intr: &Intrinsics) -> Option<([[f64; 3]; 4], Bounds)> {
    let n = s.len();
    let mut area = 0.0;
    for k in 0..n {
        let (p, q) = (s[k], s[(k + 1) % n]);
        area += p[0] * q[1] - q[0] * p[1];
    }
    if !(area.is_finite() && area != 0.0) {
        return None;
    }
    let mut edges = [[0.0, 0.0, 1.0]; 4];
    for k in 0..n {
        let (p, q) = (s[k], s[(k + 1) % n]);
        // the canonical direction: from the lexicographically smaller end
        let swapped = (q[0], q[1]) < (p[0], p[1]);
        let (a, b) = if swapped { (q, p) } else { (p, q) };
        // cross(b - a, x - a) = -(b.v - a.v) u + (b.u - a.u) v + ((b.v - a.v) a.u - (b.u - a.u) a.v)
        let e = [
            -(b[1] - a[1]),
            b[0] - a[0],
            (b[1] - a[1]) * a[0] - (b[0] - a[0]) * a[1],
        ];
        // inside is left of p -> q for a positive area
        let sign = if (area > 0.0) != swapped { 1.0 } else { -1.0 };
        edges[k] = e.map(|x| sign * x);
    }
    let lo = |k: usize| s.iter().map(|p| p[k]).fold(f64::INFINITY, f64::min);
    let hi = |k: usize| s.iter().map(|p| p[k]).fold(f64::NEG_INFINITY, f64::max);
    Some((edges, pixel_bounds([lo(0), hi(0)], [lo(1), hi(1)], intr)?))
}

/// The pixels whose centres lie in [u0, u1] x [v0, v1], clipped to the image.
fn pixel_bounds(u: [f64; 2], v: [f64; 2], intr: &Intrinsics) -> Option<Bounds> {
    let range = |lo: f64, hi: f64, size: u32| -> Option<[u32; 2]> {
        let (a, b) = (lo.ceil().max(0.0), hi.floor().min(size as f64 - 1.0));
        (a <= b).then_some([a as u32, b as u32])
    };
    Some((
        range(u[0], u[1], intr.width)?,
        range(v[0], v[1], intr.height)?,
    ))
}

/// The pixel bounds of a round segment: the projection of its bounding sphere's box, or
/// the whole image when that sphere reaches the near plane.
fn round_bounds(view: &View, a: &Vector3, b: &Vector3, radius: f64) -> Option<Bounds> {
    let m = (a + b) / 2.0;
    let r = (b - a).norm() / 2.0 + radius;
    if !(m.iter().all(|x| x.is_finite()) && r.is_finite()) {
        return None;
    }
    let intr = &view.intrinsics;
    if m.z - r <= intr.near {
        return pixel_bounds([0.0, f64::INFINITY], [0.0, f64::INFINITY], intr);
    }
    // x/z over a box in front of the camera is extreme at its corners
    let extent = |c: f64, k: usize| {
        let vals = [
            (c - r) / (m.z - r),
            (c - r) / (m.z + r),
            (c + r) / (m.z - r),
            (c + r) / (m.z + r),
        ];
        let lo = vals.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = vals.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        [
            view.focal * lo + view.center[k],
            view.focal * hi + view.center[k],
        ]
    };
    pixel_bounds(extent(m.x, 0), extent(m.y, 1), intr)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_near_plane_cuts_a_triangle_into_a_quad() {
        let p = [
            Point3::new(0.0, 0.0, 0.05),
            Point3::new(1.0, 0.0, 1.0),
            Point3::new(0.0, 1.0, 1.0),
        ];
        let mut out = [Point3::origin(); 4];
        assert_eq!(clip_near(&p, 0.1, &mut out), 4);
        assert!(out.iter().all(|q| q.z >= 0.1));
        // all behind: nothing; all in front: the triangle
        let behind = p.map(|q| Point3::new(q.x, q.y, 0.01));
        assert_eq!(clip_near(&behind, 0.1, &mut out), 0);
        let front = p.map(|q| Point3::new(q.x, q.y, 2.0));
        assert_eq!(clip_near(&front, 0.1, &mut out), 3);
        assert_eq!(out[..3], front);
    }

    #[test]
    fn a_shared_edge_has_opposite_edge_functions_in_its_two_triangles() {
        let intr = Intrinsics::new(64, 64, 0.75, 0.1, 4.0).unwrap();
        let (a, b) = ([10.3, 12.7], [40.1, 50.9]);
        let t1 = [a, b, [5.0, 60.0]];
        let t2 = [b, a, [60.0, 5.0]];
        let (e1, ..) = polygon_edges(&t1, &intr).unwrap();
        let (e2, ..) = polygon_edges(&t2, &intr).unwrap();
        assert_eq!(e1[0], e2[0].map(|x| -x));
        // the third vertex is inside both (each on its own side)
        let at = |e: &[f64; 3], p: [f64; 2]| e[0] * p[0] + (e[1] * p[1] + e[2]);
        assert!(at(&e1[0], [5.0, 60.0]) > 0.0 && at(&e2[0], [60.0, 5.0]) > 0.0);
        // degenerate and off-image polygons are dropped
        assert!(polygon_edges(&[a, b, a], &intr).is_none());
        assert!(polygon_edges(&[[-9.0, -9.0], [-5.0, -9.0], [-9.0, -5.0]], &intr).is_none());
    }
}
