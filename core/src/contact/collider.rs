//! Rigid colliders: the ground plane, boxes, spheres, capsules and triangle meshes.
//!
//! A collider is static or carried: by a handle (a gripper body pushing the ribbon),
//! or by a kinematic body whose pose the caller sets before each step (a robot link
//! following TF, `sim::World::set_kinematic_colliders`). Either way its motion over a
//! step goes from its carrier's pose at the start to the one at the end, which gives it
//! a velocity (friction) and a swept volume (continuous detection). Detection against
//! it has two parts:
//!
//! - every ribbon vertex against the *solid* (half-space, box, sphere, capsule) with
//!   parry's point projection (signed distance) and, for the continuous part, a ray
//!   cast of the vertex motion expressed in the collider frame (so a thin box cannot be
//!   tunnelled through and a moving gripper sweeps its volume);
//! - the collider's own *features* (box corners and edges, the sphere centre, the
//!   capsule axis, every vertex, edge and triangle of a mesh) against the ribbon's
//!   triangles and edges, with the generic vertex-face / edge-edge tests, so a box
//!   corner or a thin rod cannot poke through the middle of a ribbon element. Spheres
//!   and capsules are a point and a segment with a radius.
//!
//! A triangle mesh is a surface (two-sided, no inside): ribbons stay `thickness / 2`
//! away from either side.

use parry3d_f64::query::Ray;
use parry3d_f64::shape::{Ball, Capsule, Cuboid, HalfSpace, Shape};

use crate::geometry::{Point3, Pose, Vector3};

/// The geometry of a collider in its own frame (m).
#[derive(Clone, Debug, PartialEq)]
pub enum ColliderShape {
    /// The half-space z <= 0 of the collider frame: the ground when the pose is the
    /// identity (its surface is the plane z = 0, its outward normal +z).
    HalfSpace,
    /// A box centred at the origin with these half extents, m.
    Cuboid { half_extents: Vector3 },
    /// A sphere centred at the origin, radius m.
    Ball { radius: f64 },
    /// A capsule: the segment from -half_height to +half_height on the z axis, m,
    /// thickened by `radius`, m.
    Capsule { half_height: f64, radius: f64 },
    /// A triangle mesh (a surface): vertices in the collider frame, m, and triangles as
    /// vertex indices.
    TriMesh {
        vertices: Vec<Point3>,
        triangles: Vec<[u32; 3]>,
    },
}

/// A rigid obstacle.
#[derive(Clone, Debug, PartialEq)]
pub struct Collider {
    pub shape: ColliderShape,
    /// `world_from_collider`, or `carrier_from_collider` when `attached_to` is set.
    pub pose: Pose,
    /// Coulomb friction coefficient μ against ribbons (dimensionless, >= 0).
    pub friction: f64,
    /// Index of the carrier pose that carries the collider: the world's carriers are its
    /// handles' targets (`world_from_gripper`), then its kinematic bodies' poses
    /// (`world_from_body`; see `sim::World::current_targets`).
    pub attached_to: Option<usize>,
}

impl Collider {
    /// Signed distance (m, negative inside) of world point `x` to this collider's solid
    /// with the carrier poses `targets`, and the outward normal; None for a mesh (a
    /// surface). Prepares the geometry on every call: for checks, not for loops.
    pub fn signed_distance(&self, targets: &[Pose], x: &Vector3) -> Option<(f64, Vector3)> {
        ColliderGeometry::new(&self.shape).signed_distance(&self.world_pose(targets), x)
    }

    /// `world_from_collider` given the world's carrier poses (handle targets, then
    /// kinematic bodies).
    pub fn world_pose(&self, targets: &[Pose]) -> Pose {
        match self.attached_to.and_then(|h| targets.get(h)) {
            Some(gripper) => gripper * self.pose,
            None => self.pose,
        }
    }
}

/// The parry shape tested point-wise against ribbon vertices.
#[derive(Clone, Debug)]
pub(crate) enum Solid {
    HalfSpace(HalfSpace),
    Cuboid(Cuboid),
    Ball(Ball),
    Capsule(Capsule),
}

impl Solid {
    fn shape(&self) -> &dyn Shape {
        match self {
            Solid::HalfSpace(s) => s,
            Solid::Cuboid(s) => s,
            Solid::Ball(s) => s,
            Solid::Capsule(s) => s,
        }
    }
}

/// A contact of a ribbon vertex with a solid: the constraint n · (x - point) >= distance.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct SolidContact {
    /// Outward unit normal, world.
    pub normal: Vector3,
    /// Point on the collider surface, world, m.
    pub point: Vector3,
    /// Signed distance of the vertex's end position along `normal`, m (negative inside).
    pub gap: f64,
    /// Found by the continuous test (the motion enters the solid).
    pub crossing: bool,
}

/// A collider prepared for detection: its solid (if any) and its features in the
/// collider frame.
#[derive(Clone, Debug)]
pub(crate) struct ColliderGeometry {
    pub solid: Option<Solid>,
    pub vertices: Vec<Point3>,
    pub edges: Vec<[u32; 2]>,
    pub triangles: Vec<[u32; 3]>,
    /// Rounding of the features (sphere, capsule), m.
    pub radius: f64,
    /// Ribbon vertices are tested against `triangles` (meshes: there is no solid).
    pub vertex_faces: bool,
}

impl ColliderGeometry {
    pub(crate) fn new(shape: &ColliderShape) -> Self {
        let empty = ColliderGeometry {
            solid: None,
            vertices: Vec::new(),
            edges: Vec::new(),
            triangles: Vec::new(),
            radius: 0.0,
            vertex_faces: false,
        };
        match shape {
            ColliderShape::HalfSpace => ColliderGeometry {
                solid: Some(Solid::HalfSpace(HalfSpace::new(Vector3::z_axis()))),
                ..empty
            },
            ColliderShape::Cuboid { half_extents: h } => {
                let vertices: Vec<Point3> = (0..8)
                    .map(|i| {
                        Point3::new(
                            if i & 1 == 0 { -h.x } else { h.x },
                            if i & 2 == 0 { -h.y } else { h.y },
                            if i & 4 == 0 { -h.z } else { h.z },
                        )
                    })
                    .collect();
                let mut edges = Vec::new();
                for a in 0..8u32 {
                    for bit in [1u32, 2, 4] {
                        if a & bit == 0 {
                            edges.push([a, a | bit]);
                        }
                    }
                }
                ColliderGeometry {
                    solid: Some(Solid::Cuboid(Cuboid::new(*h))),
                    vertices,
                    edges,
                    ..empty
                }
            }
            ColliderShape::Ball { radius } => ColliderGeometry {
                solid: Some(Solid::Ball(Ball::new(*radius))),
                vertices: vec![Point3::origin()],
                radius: *radius,
                ..empty
            },
            ColliderShape::Capsule {
                half_height,
                radius,
            } => ColliderGeometry {
                solid: Some(Solid::Capsule(Capsule::new_z(*half_height, *radius))),
                vertices: vec![
                    Point3::new(0.0, 0.0, -half_height),
                    Point3::new(0.0, 0.0, *half_height),
                ],
                edges: vec![[0, 1]],
                radius: *radius,
                ..empty
            },
            ColliderShape::TriMesh {
                vertices,
                triangles,
            } => {
                let mut edges: Vec<[u32; 2]> = triangles
                    .iter()
                    .flat_map(|t| [[t[0], t[1]], [t[1], t[2]], [t[2], t[0]]])
                    .map(|[a, b]| if a < b { [a, b] } else { [b, a] })
                    .collect();
                edges.sort_unstable();
                edges.dedup();
                ColliderGeometry {
                    solid: None,
                    vertices: vertices.clone(),
                    edges,
                    triangles: triangles.clone(),
                    radius: 0.0,
                    vertex_faces: true,
                }
            }
        }
    }

    /// Signed distance of world point `x` to the solid at `pose` (m, negative inside)
    /// and the outward normal at the closest surface point; `None` without a solid.
    pub(crate) fn signed_distance(&self, pose: &Pose, x: &Vector3) -> Option<(f64, Vector3)> {
        let solid = self.solid.as_ref()?;
        let p = pose.inverse_transform_point(&Point3::from(*x));
        let (sd, n) = local_signed_distance(solid, &p);
        Some((sd, pose.rotation * n))
    }

    /// A half-space's boundary plane in the world at `pose`: its outward unit normal n
    /// and offset d (m), the signed distance of x being n . x - d; None for other
    /// solids. One rotation per pose instead of one per point queried.
    pub(crate) fn world_plane(&self, pose: &Pose) -> Option<(Vector3, f64)> {
        let Some(Solid::HalfSpace(h)) = &self.solid else {
            return None;
        };
        let n = pose.rotation * h.normal.into_inner();
        Some((n, n.dot(&pose.translation.vector)))
    }

    /// Ribbon vertex moving from `x0` (collider at `pose0`) to `x1` (collider at
    /// `pose1`) against the solid: the entry point when the motion enters it, else the
    /// closest surface point when the end is closer than `distance` (m).
    pub(crate) fn vertex_contact(
        &self,
        pose0: &Pose,
        pose1: &Pose,
        x0: &Vector3,
        x1: &Vector3,
        distance: f64,
    ) -> Option<SolidContact> {
        let solid = self.solid.as_ref()?;
        let p0 = pose0.inverse_transform_point(&Point3::from(*x0));
        let p1 = pose1.inverse_transform_point(&Point3::from(*x1));
        let (sd1, n1) = local_signed_distance(solid, &p1);
        // Continuous part: the motion (in the collider frame) enters the solid. A
        // half-space cannot be crossed without ending inside it.
        let dir = p1 - p0;
        let bounded = !matches!(solid, Solid::HalfSpace(_));
        if bounded && dir.norm_squared() > 0.0 {
            let (sd0, _) = local_signed_distance(solid, &p0);
            if sd0 > 0.0 {
                let ray = Ray::new(p0, dir);
                if let Some(hit) = solid.shape().cast_local_ray_and_get_normal(&ray, 1.0, true) {
                    let len = hit.normal.norm();
                    if hit.time_of_impact > 0.0 && len > 0.0 {
                        let n = hit.normal / len;
                        let s = ray.point_at(hit.time_of_impact);
                        let normal = pose1.rotation * n;
                        let point = (pose1 * s).coords;
                        return Some(SolidContact {
                            normal,
                            point,
                            gap: normal.dot(&(x1 - point)),
                            crossing: true,
                        });
                    }
                }
            }
        }
        if sd1 >= distance {
            return None;
        }
        let normal = pose1.rotation * n1;
        let point = x1 - normal * sd1;
        Some(SolidContact {
            normal,
            point,
            gap: sd1,
            crossing: false,
        })
    }

    /// World-space bounding box of the solid at `pose` (None: unbounded or no solid).
    pub(crate) fn solid_aabb(&self, pose: &Pose) -> Option<(Vector3, Vector3)> {
        match self.solid.as_ref()? {
            Solid::HalfSpace(_) => None,
            s => {
                let aabb = s.shape().compute_aabb(pose);
                Some((aabb.mins.coords, aabb.maxs.coords))
            }
        }
    }
}

/// Signed distance (m) and outward unit normal of a point in the solid's frame.
fn local_signed_distance(solid: &Solid, p: &Point3) -> (f64, Vector3) {
    if let Solid::HalfSpace(h) = solid {
        return (p.coords.dot(&h.normal), h.normal.into_inner());
    }
    let proj = solid.shape().project_local_point(p, false);
    let d = p - proj.point;
    let dist = d.norm();
    let sign = if proj.is_inside { -1.0 } else { 1.0 };
    if dist > 1e-12 {
        return (sign * dist, d * (sign / dist));
    }
    // on the surface: the feature normal
    let (_, feature) = solid.shape().project_local_point_and_get_feature(p);
    let n = solid
        .shape()
        .feature_normal_at_point(feature, &proj.point)
        .map(|n| n.into_inner())
        .unwrap_or_else(|| {
            let c = p.coords;
            if c.norm() > 0.0 {
                c.normalize()
            } else {
                Vector3::z()
            }
        });
    (0.0, n)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn signed_distances_of_the_solids() {
        let id = Pose::identity();
        let ground = ColliderGeometry::new(&ColliderShape::HalfSpace);
        let (d, n) = ground
            .signed_distance(&id, &Vector3::new(1.0, 2.0, -0.3))
            .unwrap();
        assert!((d + 0.3).abs() < 1e-15 && (n - Vector3::z()).norm() < 1e-15);
        let cube = ColliderGeometry::new(&ColliderShape::Cuboid {
            half_extents: Vector3::new(0.1, 0.2, 0.3),
        });
        let (d, n) = cube
            .signed_distance(&id, &Vector3::new(0.05, 0.0, 0.0))
            .unwrap();
        assert!((d + 0.05).abs() < 1e-15, "{d}");
        assert!((n - Vector3::x()).norm() < 1e-15);
        let ball = ColliderGeometry::new(&ColliderShape::Ball { radius: 0.5 });
        let moved = Pose::translation(1.0, 0.0, 0.0);
        let (d, n) = ball
            .signed_distance(&moved, &Vector3::new(1.0, 0.0, 1.0))
            .unwrap();
        assert!((d - 0.5).abs() < 1e-15 && (n - Vector3::z()).norm() < 1e-15);
        let cap = ColliderGeometry::new(&ColliderShape::Capsule {
            half_height: 1.0,
            radius: 0.1,
        });
        let (d, _) = cap
            .signed_distance(&id, &Vector3::new(0.3, 0.0, 0.5))
            .unwrap();
        assert!((d - 0.2).abs() < 1e-15);
        assert_eq!(cube.edges.len(), 12);
    }

    #[test]
    fn a_vertex_tunnelling_through_a_thin_box_is_caught_at_entry() {
        let plate = ColliderGeometry::new(&ColliderShape::Cuboid {
            half_extents: Vector3::new(1.0, 1.0, 0.001),
        });
        let id = Pose::identity();
        let c = plate
            .vertex_contact(
                &id,
                &id,
                &Vector3::new(0.0, 0.0, 0.1),
                &Vector3::new(0.0, 0.0, -0.1),
                0.0005,
            )
            .expect("crossing");
        assert!(c.crossing);
        assert!((c.normal - Vector3::z()).norm() < 1e-12);
        assert!((c.point.z - 0.001).abs() < 1e-12);
        assert!((c.gap + 0.101).abs() < 1e-12);
    }
}
