//! The camera against geometry worked out independently: planes give exact depth,
//! vertices land on the pixels K predicts, triangles cover exactly the pixel centres
//! inside their projection, the cloud is the depth back-projected through K, the
//! output does not depend on the thread count, and the D435 noise has its statistics.
//! Each checker has a negative test that shows it fails when it should.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::*;
use crate::contact::{Collider, ColliderShape};
use crate::geometry::{Point2, SurfaceMesh, VertexRegion};

fn intrinsics(w: u32, h: u32) -> Intrinsics {
    Intrinsics::new(w, h, 0.75, 0.1, 4.0).unwrap()
}

fn camera(w: u32, h: u32, noise: Noise) -> Camera {
    Camera {
        intrinsics: intrinsics(w, h),
        noise,
    }
}

fn collider(shape: ColliderShape, pose: Pose) -> Collider {
    Collider {
        shape,
        pose,
        friction: 0.5,
        attached_to: None,
    }
}

/// A mesh of `vertices` and `triangles`, material = the vertices' x, y, all flat.
fn mesh(vertices: Vec<Point3>, triangles: Vec<[u32; 3]>) -> SurfaceMesh {
    SurfaceMesh {
        material: vertices.iter().map(|p| Point2::new(p.x, p.y)).collect(),
        regions: vec![VertexRegion::Flat; vertices.len()],
        vertices,
        triangles,
        rulings: vec![],
    }
}

/// A tilted camera: at (0.3, -1.2, 0.9) looking at (0.1, 0.2, 0.0).
fn tilted() -> Pose {
    look_at(Vector3::new(0.3, -1.2, 0.9), Vector3::new(0.1, 0.2, 0.0)).unwrap()
}

/// The depth (m) where the ray of pixel (i, j) meets the plane through `point` with
/// normal `normal` (world), worked out in the world frame: the camera at o, the ray
/// direction R (x/z, y/z, 1) from K's entries, t where n . (o + t dir) = n . point;
/// the ray's z component is 1, so t is the depth. None: parallel or behind.
fn plane_depth(
    k: &[f64; 9],
    pose: &Pose,
    normal: Vector3,
    point: Vector3,
    i: u32,
    j: u32,
) -> Option<f64> {
    let local = Vector3::new((i as f64 - k[2]) / k[0], (j as f64 - k[5]) / k[4], 1.0);
    let dir = pose.rotation * local;
    let o = pose.translation.vector;
    let t = normal.dot(&(point - o)) / normal.dot(&dir);
    (t.is_finite() && t > 0.0).then_some(t)
}

/// The pixels whose depth is not `expected` to float32 rounding: the exact depth e
/// rounded to float32 is within e 2^-24 of it, and the float64 arithmetic before the
/// rounding adds a few ulps of float64 (1e-12 relative covers 4500 of them); expected
/// None (or beyond `far`) must give NaN.
fn depth_mismatches(f: &Frame, far: f64, expected: impl Fn(u32, u32) -> Option<f64>) -> usize {
    let mut bad = 0;
    for j in 0..f.height {
        for i in 0..f.width {
            let got = f.depth_at(i, j);
            let ok = match expected(i, j).filter(|e| *e <= far) {
                Some(e) => (got as f64 - e).abs() <= e * (2f64.powi(-24) + 1e-12),
                None => got.is_nan(),
            };
            bad += usize::from(!ok);
        }
    }
    bad
}

#[test]
fn a_ground_plane_gives_exact_depth_at_every_pixel() {
    let ground = collider(
        ColliderShape::HalfSpace,
        Pose::new(Vector3::new(0.0, 0.0, -0.05), Vector3::new(0.1, -0.2, 0.0)),
    );
    // far = 2.5 m: the top rows see the ground beyond it
    let cam = Camera {
        intrinsics: Intrinsics::new(160, 120, 0.75, 0.1, 2.5).unwrap(),
        noise: Noise::None,
    };
    let mut r = Renderer::new(cam, std::slice::from_ref(&ground));
    let pose = tilted();
    let scene = Snapshot {
        meshes: vec![],
        collider_poses: vec![ground.pose],
    };
    let frame = r.render(&scene, &pose, &NoiseKey::default()).clone();
    let normal = ground.pose.rotation * Vector3::z();
    let point = ground.pose.translation.vector;
    let k = cam.intrinsics.k();
    let expected = |i, j| plane_depth(&k, &pose, normal, point, i, j);
    assert_eq!(depth_mismatches(&frame, 2.5, expected), 0);
    // the view reaches past `far` at the top: NaN there, depth below
    let hits = (0..120)
        .filter(|&j| frame.depth_at(80, j).is_finite())
        .count();
    assert!(hits > 20 && hits < 120, "{hits} rows hit");
    // negative: the plane 1 um higher, or one pixel 2 float32 ulps off, is caught
    let shifted = |i, j| {
        plane_depth(
            &k,
            &pose,
            normal,
            point + Vector3::new(0.0, 0.0, 1e-6),
            i,
            j,
        )
    };
    assert!(depth_mismatches(&frame, 2.5, shifted) > 1000);
    let mut off = frame.clone();
    let d = off.depth_at(80, 100);
    let bumped = f32::from_bits(d.to_bits() + 2);
    let at = 4 * (100 * 160 + 80);
    off.depth[at..at + 4].copy_from_slice(&bumped.to_le_bytes());
    assert_eq!(depth_mismatches(&off, 2.5, expected), 1);
}

#[test]
fn a_mesh_plane_and_a_box_face_give_exact_depth_too() {
    let pose = tilted();
    // a 4 m square in the tilted plane z = 0.02 + 0.1 x (two triangles)
    let n = Vector3::new(-0.1, 0.0, 1.0);
    let z = |x: f64| 0.02 + 0.1 * x;
    let corners = [[-2.0, -2.0], [2.0, -2.0], [2.0, 2.0], [-2.0, 2.0]];
    let square = mesh(
        corners
            .iter()
            .map(|c| Point3::new(c[0], c[1], z(c[0])))
            .collect(),
        vec![[0, 1, 2], [0, 2, 3]],
    );
    let cam = camera(160, 120, Noise::None);
    let k = cam.intrinsics.k();
    let mut r = Renderer::new(cam, &[]);
    let scene = Snapshot {
        meshes: vec![square],
        collider_poses: vec![],
    };
    let frame = r.render(&scene, &pose, &NoiseKey::default()).clone();
    let point = Vector3::new(0.0, 0.0, 0.02);
    // every ray that meets the plane within the square and `far`
    let on_square = |i, j| {
        let t = plane_depth(&k, &pose, n, point, i, j)?;
        let local = Vector3::new((i as f64 - k[2]) / k[0], (j as f64 - k[5]) / k[4], 1.0);
        let p = pose * Point3::from(local * t);
        (p.x.abs() < 2.0 && p.y.abs() < 2.0).then_some(t)
    };
    assert_eq!(depth_mismatches(&frame, 4.0, on_square), 0);
    // a box's top face seen from above: depth camera height - top
    let top = Pose::new(Vector3::new(0.0, 0.0, 0.1), Vector3::new(0.0, 0.0, 0.3));
    let block = collider(
        ColliderShape::Cuboid {
            half_extents: Vector3::new(0.5, 0.4, 0.1),
        },
        top,
    );
    let above = look_at(Vector3::new(0.05, 0.02, 1.2), Vector3::new(0.05, 0.02, 0.0)).unwrap();
    let mut r = Renderer::new(cam, std::slice::from_ref(&block));
    let scene = Snapshot {
        meshes: vec![],
        collider_poses: vec![top],
    };
    let frame = r.render(&scene, &above, &NoiseKey::default()).clone();
    let top_face = |i, j| {
        let t = plane_depth(&k, &above, Vector3::z(), Vector3::new(0.0, 0.0, 0.2), i, j)?;
        let local = Vector3::new((i as f64 - k[2]) / k[0], (j as f64 - k[5]) / k[4], 1.0);
        let p = top.inverse() * (above * Point3::from(local * t));
        (p.x.abs() < 0.5 && p.y.abs() < 0.4).then_some(t)
    };
    // pixel centres within 1e-9 px of the face's outline could go either way; none is
    let bad = depth_mismatches(&frame, 4.0, top_face);
    assert_eq!(bad, 0);
}

/// Vertices placed on the rays of chosen pixel centres (x = z (i - cx) / fx, ...), at
/// depths varying over the mesh: each must be seen at its pixel, at its depth, and the
/// cloud must give back the vertex.
fn vertex_mismatches(frame: &Frame, k: &[f64; 9], vertices: &[(u32, u32, Point3)]) -> usize {
    let mut bad = 0;
    for &(i, j, p) in vertices {
        let q = frame.point_at(i, j);
        // z: rounded once to float32 (2^-24 relative) after float64 arithmetic; x and y
        // are computed from that rounded z and rounded again: 2^-23
        let close = |a: f32, b: f64, rel: f64| (a as f64 - b).abs() <= b.abs() * (rel + 1e-12);
        let ok = close(q[2], p.z, 2f64.powi(-24))
            && close(q[0], p.x, 2f64.powi(-23))
            && close(q[1], p.y, 2f64.powi(-23));
        // and K maps the vertex back to the pixel's centre
        let u = k[0] * p.x / p.z + k[2];
        let v = k[4] * p.y / p.z + k[5];
        let centred = (u - i as f64).abs() < 1e-9 && (v - j as f64).abs() < 1e-9;
        bad += usize::from(!(ok && centred));
    }
    bad
}

#[test]
fn each_mesh_vertex_is_seen_at_the_pixel_k_predicts() {
    let cam = camera(96, 72, Noise::None);
    let k = cam.intrinsics.k();
    // a 9 x 7 grid of vertices every 10 px, depth a smooth bump 0.8 .. 1.2 m
    let mut grid = Vec::new();
    for b in 0..7u32 {
        for a in 0..9u32 {
            let (i, j) = (8 + 10 * a, 6 + 10 * b);
            let z = 1.0 + 0.2 * ((a as f64) * 0.7).sin() * ((b as f64) * 0.9).cos();
            let p = Point3::new(
                z * (i as f64 - k[2]) / k[0],
                z * (j as f64 - k[5]) / k[4],
                z,
            );
            grid.push((i, j, p));
        }
    }
    let mut triangles = Vec::new();
    for b in 0..6u32 {
        for a in 0..8u32 {
            let v = b * 9 + a;
            triangles.push([v, v + 1, v + 10]);
            triangles.push([v, v + 10, v + 9]);
        }
    }
    // the camera anywhere: the mesh is built in its optical frame, then moved to the world
    let pose = tilted();
    let world = mesh(grid.iter().map(|g| pose * g.2).collect(), triangles);
    let mut r = Renderer::new(cam, &[]);
    let scene = Snapshot {
        meshes: vec![world],
        collider_poses: vec![],
    };
    let frame = r.render(&scene, &pose, &NoiseKey::default());
    // the inner vertices: one on the mesh's outline sits exactly on the edge of the
    // covered region, where a pixel centre may go either way
    let inner: Vec<_> = grid
        .iter()
        .enumerate()
        .filter(|(v, _)| !matches!(v % 9, 0 | 8) && !matches!(v / 9, 0 | 6))
        .map(|(_, g)| *g)
        .collect();
    assert_eq!(inner.len(), 35);
    assert_eq!(vertex_mismatches(frame, &k, &inner), 0);
    // negative: a focal length 0.1 % off, or a principal point a pixel off
    let mut wrong = k;
    wrong[0] *= 1.001;
    assert_eq!(vertex_mismatches(frame, &wrong, &inner), inner.len());
    let mut wrong = k;
    wrong[5] += 1.0;
    assert_eq!(vertex_mismatches(frame, &wrong, &inner), inner.len());
}

/// Pixels covered differently from the pixel centres inside the triangle K projects
/// (centres within 1e-9 px of an edge are not counted: either answer is right).
fn coverage_mismatches(frame: &Frame, k: &[f64; 9], tri: &[Point3; 3]) -> usize {
    let s = tri.map(|p| [k[0] * p.x / p.z + k[2], k[4] * p.y / p.z + k[5]]);
    let cross = |a: [f64; 2], b: [f64; 2], p: [f64; 2]| {
        let len = ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2)).sqrt();
        ((b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0])) / len
    };
    let mut bad = 0;
    for j in 0..frame.height {
        for i in 0..frame.width {
            let p = [i as f64, j as f64];
            let d = [
                cross(s[0], s[1], p),
                cross(s[1], s[2], p),
                cross(s[2], s[0], p),
            ];
            if d.iter().any(|x| x.abs() < 1e-9) {
                continue;
            }
            let inside = d.iter().all(|&x| x > 0.0) || d.iter().all(|&x| x < 0.0);
            bad += usize::from(inside != frame.depth_at(i, j).is_finite());
        }
    }
    bad
}

#[test]
fn triangles_cover_exactly_the_pixel_centres_inside_their_projection() {
    let cam = camera(64, 48, Noise::None);
    let k = cam.intrinsics.k();
    let mut rng = ChaCha8Rng::seed_from_u64(48);
    let mut r = Renderer::new(cam, &[]);
    let mut scene = Snapshot::default();
    let (mut covered, mut wrong_k) = (0, 0);
    for _ in 0..50 {
        // three points in front of the camera, the optical frame = the world
        let tri: [Point3; 3] = std::array::from_fn(|_| {
            let z = rng.random_range(0.5..3.0);
            Point3::new(
                z * rng.random_range(-0.5..0.5),
                z * rng.random_range(-0.4..0.4),
                z,
            )
        });
        scene.meshes = vec![mesh(tri.to_vec(), vec![[0, 1, 2]])];
        let frame = r.render(&scene, &Pose::identity(), &NoiseKey::default());
        assert_eq!(coverage_mismatches(frame, &k, &tri), 0);
        covered += (0..48)
            .flat_map(|j| (0..64).map(move |i| (i, j)))
            .filter(|&(i, j)| frame.depth_at(i, j).is_finite())
            .count();
        let mut shifted = k;
        shifted[2] += 1.0;
        wrong_k += coverage_mismatches(frame, &shifted, &tri);
    }
    assert!(covered > 5000, "{covered} pixels covered in all");
    // negative: a principal point one pixel off misplaces the edges
    assert!(wrong_k > 200, "{wrong_k}");
}

#[test]
fn two_triangles_sharing_an_edge_leave_no_gap() {
    // a fan of thin triangles around a centre: every pixel centre inside the fan's
    // outline is covered (no crack along the shared edges)
    let cam = camera(64, 48, Noise::None);
    let c = Point3::new(0.01, -0.02, 1.0);
    let n = 37;
    let mut vertices = vec![c];
    for k in 0..n {
        let a = std::f64::consts::TAU * k as f64 / n as f64;
        vertices.push(Point3::new(
            0.3 * a.cos(),
            0.3 * a.sin(),
            1.0 + 0.1 * a.sin(),
        ));
    }
    let triangles = (0..n).map(|k| [0, 1 + k, 1 + (k + 1) % n]).collect();
    let mut r = Renderer::new(cam, &[]);
    let scene = Snapshot {
        meshes: vec![mesh(vertices, triangles)],
        collider_poses: vec![],
    };
    let frame = r.render(&scene, &Pose::identity(), &NoiseKey::default());
    let k = cam.intrinsics.k();
    // the inscribed circle of the outline (radius 0.3 cos(pi / n) at depth <= 1.1)
    let mut holes = 0;
    for j in 0..48 {
        for i in 0..64 {
            let (x, y) = ((i as f64 - k[2]) / k[0], (j as f64 - k[5]) / k[4]);
            if (x * x + y * y).sqrt() < 0.25 / 1.1 {
                holes += usize::from(frame.depth_at(i, j).is_nan());
            }
        }
    }
    assert_eq!(holes, 0);
}

/// Points of the cloud that are not the depth back-projected through K: x = z (i - cx)
/// / f, y = z (j - cy) / f in float64 from the float32 depth, rounded once; NaN where
/// the depth is NaN; rgb the pixel's colour packed as 0x00RRGGBB.
fn cloud_mismatches(frame: &Frame, k: &[f64; 9]) -> usize {
    let mut bad = 0;
    for j in 0..frame.height {
        for i in 0..frame.width {
            let z = frame.depth_at(i, j);
            let p = frame.point_at(i, j);
            let x = (z as f64 * ((i as f64 - k[2]) / k[0])) as f32;
            let y = (z as f64 * ((j as f64 - k[5]) / k[4])) as f32;
            let c = frame.rgb_at(i, j);
            let rgb = (c[0] as u32) << 16 | (c[1] as u32) << 8 | c[2] as u32;
            let same = |a: f32, b: f32| a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan());
            let ok = same(p[0], x) && same(p[1], y) && same(p[2], z) && p[3].to_bits() == rgb;
            bad += usize::from(!ok);
        }
    }
    bad
}

/// A scene with every kind of surface: a ribbon-like strip (both sides visible), the
/// ground, a box, a ball, a capsule and a mesh collider.
fn everything() -> (Vec<Collider>, Snapshot) {
    let mut vertices = Vec::new();
    let mut triangles = Vec::new();
    for k in 0..=20u32 {
        let s = k as f64 / 20.0;
        // a strip curling over itself, so the camera sees both sides
        let (x, z) = (0.3 * (s * 4.0).sin(), 0.35 + 0.15 * (1.0 - (s * 4.0).cos()));
        vertices.push(Point3::new(x, -0.05, z));
        vertices.push(Point3::new(x, 0.05, z));
        if k > 0 {
            let v = 2 * k;
            triangles.push([v - 2, v, v + 1]);
            triangles.push([v - 2, v + 1, v - 1]);
        }
    }
    let strip = mesh(vertices, triangles);
    let tetra = ColliderShape::TriMesh {
        vertices: vec![
            Point3::new(0.0, 0.0, 0.0),
            Point3::new(0.1, 0.0, 0.0),
            Point3::new(0.0, 0.1, 0.0),
            Point3::new(0.0, 0.0, 0.1),
        ],
        triangles: vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
    };
    let colliders = vec![
        collider(ColliderShape::HalfSpace, Pose::identity()),
        collider(
            ColliderShape::Cuboid {
                half_extents: Vector3::new(0.1, 0.1, 0.05),
            },
            Pose::new(Vector3::new(-0.4, 0.3, 0.05), Vector3::new(0.0, 0.0, 0.4)),
        ),
        collider(
            ColliderShape::Ball { radius: 0.08 },
            Pose::translation(0.3, 0.35, 0.08),
        ),
        collider(
            ColliderShape::Capsule {
                half_height: 0.15,
                radius: 0.03,
            },
            Pose::new(Vector3::new(0.0, 0.4, 0.2), Vector3::new(1.2, 0.0, 0.0)),
        ),
        collider(tetra, Pose::translation(-0.2, -0.3, 0.0)),
    ];
    let poses = colliders.iter().map(|c| c.pose).collect();
    (
        colliders,
        Snapshot {
            meshes: vec![strip],
            collider_poses: poses,
        },
    )
}

fn view_of_everything() -> Pose {
    look_at(Vector3::new(0.2, -1.1, 0.8), Vector3::new(0.0, 0.1, 0.15)).unwrap()
}

#[test]
fn the_cloud_is_the_depth_back_projected_through_k() {
    let (colliders, scene) = everything();
    let cam = camera(160, 120, Noise::D435);
    let mut r = Renderer::new(cam, &colliders);
    let frame = r
        .render(
            &scene,
            &view_of_everything(),
            &NoiseKey {
                seed: 1,
                camera: 0,
                frame: 3,
            },
        )
        .clone();
    let k = cam.intrinsics.k();
    assert_eq!(cloud_mismatches(&frame, &k), 0);
    let hits = (0..120)
        .flat_map(|j| (0..160).map(move |i| (i, j)))
        .filter(|&(i, j)| frame.depth_at(i, j).is_finite())
        .count();
    assert!(hits > 10_000, "{hits}");
    // negative: one point moved by one ulp, or a colour changed, is caught
    let mut off = frame.clone();
    let at = CLOUD_POINT_STEP * (60 * 160 + 80);
    let x = f32::from_le_bytes(off.cloud[at..at + 4].try_into().unwrap());
    off.cloud[at..at + 4].copy_from_slice(&f32::from_bits(x.to_bits() + 1).to_le_bytes());
    off.color[3 * (10 * 160 + 10)] ^= 1;
    assert_eq!(cloud_mismatches(&off, &k), 2);
}

#[test]
fn every_kind_of_surface_is_drawn_in_its_colour() {
    let (colliders, scene) = everything();
    let cam = camera(320, 240, Noise::None);
    let mut r = Renderer::new(cam, &colliders);
    let pose = view_of_everything();
    let frame = r.render(&scene, &pose, &NoiseKey::default()).clone();
    let pixel_of = |p: Vector3| {
        let q = pose.inverse() * Point3::from(p);
        let [u, v] = cam.intrinsics.project(&q).unwrap();
        (u.round() as u32, v.round() as u32)
    };
    let grey = |c: [u8; 3]| c.iter().max().unwrap() - c.iter().min().unwrap() < 12;
    // the ball's nearest point along the ray of its centre's pixel: the ray o + t R
    // (x/z, y/z, 1) enters the ball at depth t = (b - sqrt(b^2 - |r|^2 (|c - o|^2 -
    // radius^2))) / |r|^2 with b = r . (c - o)
    let centre = Vector3::new(0.3, 0.35, 0.08);
    let (i, j) = pixel_of(centre);
    let ray = pose.rotation * cam.intrinsics.ray(i as f64, j as f64);
    let oc = centre - pose.translation.vector;
    let b = ray.dot(&oc);
    let h = b * b - ray.norm_squared() * (oc.norm_squared() - 0.08 * 0.08);
    let depth = (b - h.sqrt()) / ray.norm_squared();
    let got = frame.depth_at(i, j) as f64;
    assert!(
        (got - depth).abs() <= depth * (2f64.powi(-24) + 1e-12),
        "{got} vs {depth}"
    );
    assert!(grey(frame.rgb_at(i, j)), "{:?}", frame.rgb_at(i, j));
    // the strip's two sides: its front (material +z) in the flat blue, the back pale
    let (mut blue, mut pale) = (0, 0);
    for j in 0..240 {
        for i in 0..320 {
            let c = frame.rgb_at(i, j).map(i32::from);
            // front: blue - red = 135 x shade (shade 0.42 ..= 1); back: 45.4 x shade
            let d = c[2] - c[0];
            blue += usize::from(d >= 56);
            pale += usize::from((12..=46).contains(&d));
        }
    }
    assert!(blue > 500 && pale > 200, "blue {blue} pale {pale}");
    // the top corner sees the ground 7 m away: its colour, but no depth beyond `far`
    let c = frame.rgb_at(0, 0);
    assert!(c[0] == c[1] && c[2] < c[0] && c[0] > 150, "{c:?}");
    assert!(frame.depth_at(0, 0).is_nan());
}

#[test]
fn a_missing_triangle_leaves_a_hole_the_gap_check_sees() {
    // the negative of the fan test: the same count over a fan with one triangle out
    let cam = camera(64, 48, Noise::None);
    let n = 37;
    let mut vertices = vec![Point3::new(0.01, -0.02, 1.0)];
    for k in 0..n {
        let a = std::f64::consts::TAU * k as f64 / n as f64;
        vertices.push(Point3::new(
            0.3 * a.cos(),
            0.3 * a.sin(),
            1.0 + 0.1 * a.sin(),
        ));
    }
    let triangles = (1..n).map(|k| [0, 1 + k, 1 + (k + 1) % n]).collect();
    let mut r = Renderer::new(cam, &[]);
    let scene = Snapshot {
        meshes: vec![mesh(vertices, triangles)],
        collider_poses: vec![],
    };
    let frame = r.render(&scene, &Pose::identity(), &NoiseKey::default());
    let k = cam.intrinsics.k();
    let holes = (0..48u32)
        .flat_map(|j| (0..64u32).map(move |i| (i, j)))
        .filter(|&(i, j)| {
            let (x, y) = ((i as f64 - k[2]) / k[0], (j as f64 - k[5]) / k[4]);
            (x * x + y * y).sqrt() < 0.25 / 1.1 && frame.depth_at(i, j).is_nan()
        })
        .count();
    assert!(holes > 3, "{holes}");
}

/// Whether two frames are the same bytes.
fn identical(a: &Frame, b: &Frame) -> bool {
    a.color == b.color && a.depth == b.depth && a.cloud == b.cloud
}

fn render_in_pool(threads: usize, key: &NoiseKey) -> Frame {
    let (colliders, scene) = everything();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    let mut r = Renderer::new(camera(200, 150, Noise::D435), &colliders);
    pool.install(|| r.render(&scene, &view_of_everything(), key).clone())
}

#[test]
fn frames_are_bit_identical_at_any_thread_count() {
    let key = NoiseKey {
        seed: 7,
        camera: 1,
        frame: 12,
    };
    let one = render_in_pool(1, &key);
    assert!(identical(&one, &render_in_pool(2, &key)));
    assert!(identical(&one, &render_in_pool(3, &key)));
    // and from frame to frame of one renderer (buffers reused): the same again
    let (colliders, scene) = everything();
    let mut r = Renderer::new(camera(200, 150, Noise::D435), &colliders);
    r.render(&scene, &tilted(), &key);
    assert!(identical(
        &one,
        r.render(&scene, &view_of_everything(), &key)
    ));
    // negative: the next frame's noise differs
    let next = NoiseKey { frame: 13, ..key };
    assert!(!identical(&one, &render_in_pool(2, &next)));
}

/// A wall facing the camera at depth `z0` (m) across the whole view of a 640 x 480
/// D435 camera (identity pose: optical = world); the frame for `key`.
fn wall(z0: f64, key: &NoiseKey) -> (Frame, f64) {
    // the half-space's outward normal +z turned to -z (towards the camera)
    let pose = Pose::new(
        Vector3::new(0.0, 0.0, z0),
        Vector3::new(std::f64::consts::PI, 0.0, 0.0),
    );
    let wall = collider(ColliderShape::HalfSpace, pose);
    let cam = camera(640, 480, Noise::D435);
    let mut r = Renderer::new(cam, std::slice::from_ref(&wall));
    let scene = Snapshot {
        meshes: vec![],
        collider_poses: vec![pose],
    };
    let frame = r.render(&scene, &Pose::identity(), key).clone();
    (frame, cam.intrinsics.focal())
}

/// The noise of a wall frame: (share of NaN pixels, mean and standard deviation of
/// (depth - z0) / sigma over the others, their count).
fn noise_stats(frame: &Frame, z0: f64, sigma: f64) -> (f64, f64, f64, usize) {
    let (mut n, mut nan, mut s, mut s2) = (0usize, 0usize, 0.0, 0.0);
    for j in 0..frame.height {
        for i in 0..frame.width {
            let d = frame.depth_at(i, j) as f64;
            if d.is_nan() {
                nan += 1;
            } else {
                let r = (d - z0) / sigma;
                n += 1;
                s += r;
                s2 += r * r;
            }
        }
    }
    let mean = s / n as f64;
    let total = (frame.width * frame.height) as f64;
    (
        nan as f64 / total,
        mean,
        (s2 / n as f64 - mean * mean).sqrt(),
        n,
    )
}

/// Whether the measured statistics match the model within 4 standard errors of the
/// estimates over N samples: the dropout share p = 1 % (SE sqrt(p (1 - p) / N_all)),
/// the mean 0 (SE 1 / sqrt(N)) and the standard deviation 1 (SE 1 / sqrt(2 N)) in
/// units of sigma.
fn matches_d435((dropout, mean, std, n): (f64, f64, f64, usize), total: usize) -> bool {
    let p = D435_DROPOUT;
    (dropout - p).abs() < 4.0 * (p * (1.0 - p) / total as f64).sqrt()
        && mean.abs() < 4.0 / (n as f64).sqrt()
        && (std - 1.0).abs() < 4.0 / (2.0 * n as f64).sqrt()
}

#[test]
fn d435_noise_has_its_sigma_dropout_and_range_cut() {
    let key = NoiseKey {
        seed: 3,
        camera: 0,
        frame: 0,
    };
    let total = 640 * 480;
    for z0 in [1.0, 2.5] {
        let (frame, f) = wall(z0, &key);
        let sigma = Noise::D435.sigma(z0, f);
        let stats = noise_stats(&frame, z0, sigma);
        assert!(matches_d435(stats, total), "z = {z0}: {stats:?}");
        // negative: the sigma of a 2 % longer focal length (smaller by 2 %) is seen
        let wrong = noise_stats(&frame, z0, Noise::D435.sigma(z0, 1.02 * f));
        assert!(!matches_d435(wrong, total), "{wrong:?}");
    }
    // negative: a frame without dropout fails the dropout check
    let (frame, f) = wall(1.0, &key);
    let mut filled = frame.clone();
    let fill = 1.0f32.to_le_bytes();
    for px in filled.depth.chunks_exact_mut(4) {
        if f32::from_le_bytes(px.try_into().unwrap()).is_nan() {
            px.copy_from_slice(&fill);
        }
    }
    assert!(!matches_d435(
        noise_stats(&filled, 1.0, Noise::D435.sigma(1.0, f)),
        total
    ));
    // the minimum range 0.28 m: nothing at 0.27 m, the usual 1 % dropout at 0.29 m
    let (near, _) = wall(0.27, &key);
    assert_eq!(noise_stats(&near, 0.27, 1.0).0, 1.0);
    let (past, f) = wall(0.29, &key);
    assert!(matches_d435(
        noise_stats(&past, 0.29, Noise::D435.sigma(0.29, f)),
        total
    ));
}

#[test]
fn the_same_seed_and_frame_give_the_same_noise() {
    let key = NoiseKey {
        seed: 11,
        camera: 0,
        frame: 4,
    };
    let (a, _) = wall(1.5, &key);
    let (b, _) = wall(1.5, &key);
    assert!(identical(&a, &b));
    for other in [
        NoiseKey { frame: 5, ..key },
        NoiseKey { seed: 12, ..key },
        NoiseKey { camera: 1, ..key },
    ] {
        assert!(!identical(&a, &wall(1.5, &other).0), "{other:?}");
    }
    // without a noise model the key changes nothing
    let (colliders, scene) = everything();
    let mut r = Renderer::new(camera(64, 48, Noise::None), &colliders);
    let a = r.render(&scene, &view_of_everything(), &key).clone();
    assert!(identical(
        &a,
        r.render(&scene, &view_of_everything(), &NoiseKey { frame: 5, ..key })
    ));
}
