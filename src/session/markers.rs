//! The marker producers: each object's surface (TRIANGLE_LIST with per-vertex region
//! colors), rulings (LINE_LIST) and singular points (SPHERE_LIST), and the colliders at
//! their current pose. Finite values only: RViz drops a whole marker for one NaN.

use crate::contact::ColliderShape;
use crate::geometry::{SurfaceMesh, VertexRegion};
use crate::sim::SingularPoint;
use crate::wire::convert::{point, pose};
use crate::wire::msgs::{ColorRGBA, Header, Marker, MarkerArray, Point, Vector3};

use super::produce::{Produce, Scope};
use super::style::MarkerStyle;

/// Markers of one object's mesh, in its namespaces `<object>/surface`, `<object>/rulings`,
/// `<object>/singular_points` (None for a mesh that is not finite: RViz would drop it).
pub fn object_markers(p: &Produce, scope: Scope) -> Option<MarkerArray> {
    let Scope::Object(object) = scope else {
        return None;
    };
    let world = &p.scene.world;
    let mesh = world.mesh(object);
    if !mesh.is_finite() {
        return None;
    }
    Some(markers(
        p.style,
        &world.object_names()[object],
        &p.header(),
        mesh,
        world.singular_points(object),
    ))
}

fn markers(
    style: &MarkerStyle,
    name: &str,
    header: &Header,
    mesh: &SurfaceMesh,
    singular: &[SingularPoint],
) -> MarkerArray {
    let base = |ns: &str, type_: i32, scale: f64, color: ColorRGBA| Marker {
        header: header.clone(),
        ns: format!("{name}/{ns}"),
        id: 0,
        type_,
        action: Marker::ADD,
        scale: Vector3 {
            x: scale,
            y: scale,
            z: scale,
        },
        color,
        ..Marker::default()
    };
    let region_color = |r: VertexRegion| match r {
        VertexRegion::Flat => style.flat,
        VertexRegion::Curved => style.curved,
        VertexRegion::Singular => style.singular,
    };
    let mut surface = base("surface", Marker::TRIANGLE_LIST, 1.0, style.flat);
    surface.points.reserve(mesh.triangles.len() * 3);
    surface.colors.reserve(mesh.triangles.len() * 3);
    for t in &mesh.triangles {
        for &v in t {
            let v = v as usize;
            surface.points.push(point(&mesh.vertices[v]));
            surface.colors.push(
                mesh.regions
                    .get(v)
                    .map(|r| region_color(*r))
                    .unwrap_or(style.flat),
            );
        }
    }
    let mut rulings = base("rulings", Marker::LINE_LIST, style.line_width, style.ruling);
    for r in &mesh.rulings {
        rulings.points.push(point(&mesh.vertices[r[0] as usize]));
        rulings.points.push(point(&mesh.vertices[r[1] as usize]));
    }
    let mut spheres = base(
        "singular_points",
        Marker::SPHERE_LIST,
        style.sphere_diameter,
        style.singular,
    );
    spheres.points = singular
        .iter()
        .filter(|s| s.position.coords.iter().all(|v| v.is_finite()))
        .map(|s| point(&s.position))
        .collect();
    MarkerArray {
        markers: vec![surface, rulings, spheres],
    }
}

/// One marker per collider, at its current pose (attached colliders follow their
/// handle's target, a robot's links their TF frames): the ground as a thin square of
/// `style.ground_size`, boxes, spheres, capsules (a cylinder and its two end spheres)
/// and triangle meshes. With `robot_colliders:` the set changes at run time: a
/// DELETEALL of the namespace comes first, so links that left are not drawn on.
pub fn colliders(p: &Produce, _: Scope) -> Option<MarkerArray> {
    let (scene, header) = (p.scene, p.header());
    let world = &scene.world;
    let colliders = world.contact_stage()?.colliders();
    let robot = scene.robot.is_some();
    if colliders.is_empty() && !robot {
        return None;
    }
    let style = p.style;
    let targets = world.current_targets();
    let mut markers = Vec::with_capacity(colliders.len() + 2);
    if robot {
        markers.push(Marker {
            header: header.clone(),
            ns: "colliders".into(),
            action: Marker::DELETEALL,
            ..Marker::default()
        });
    }
    for (i, c) in colliders.iter().enumerate() {
        let world_from_collider = c.world_pose(targets);
        let mut m = Marker {
            header: header.clone(),
            ns: "colliders".into(),
            id: i as i32,
            action: Marker::ADD,
            pose: pose(&world_from_collider),
            color: style.collider,
            ..Marker::default()
        };
        let uniform = |d: f64| Vector3 { x: d, y: d, z: d };
        match &c.shape {
            ColliderShape::HalfSpace => {
                // the surface is z = 0 of the collider frame; a 1 mm slab below it
                m.type_ = Marker::CUBE;
                let below = world_from_collider * nalgebra::Translation3::new(0.0, 0.0, -0.0005);
                m.pose = pose(&below);
                m.scale = Vector3 {
                    x: style.ground_size,
                    y: style.ground_size,
                    z: 0.001,
                };
            }
            ColliderShape::Cuboid { half_extents } => {
                m.type_ = Marker::CUBE;
                m.scale = Vector3 {
                    x: 2.0 * half_extents.x,
                    y: 2.0 * half_extents.y,
                    z: 2.0 * half_extents.z,
                };
            }
            ColliderShape::Ball { radius } => {
                m.type_ = Marker::SPHERE;
                m.scale = uniform(2.0 * radius);
            }
            ColliderShape::Capsule {
                half_height,
                radius,
            } => {
                m.type_ = Marker::CYLINDER;
                m.scale = Vector3 {
                    x: 2.0 * radius,
                    y: 2.0 * radius,
                    z: 2.0 * half_height,
                };
                // the end caps, in the same frame (ids after the colliders')
                let mut caps = m.clone();
                caps.id = (colliders.len() + i) as i32;
                caps.type_ = Marker::SPHERE_LIST;
                caps.scale = uniform(2.0 * radius);
                caps.points = [-half_height, *half_height]
                    .iter()
                    .map(|z| Point {
                        x: 0.0,
                        y: 0.0,
                        z: *z,
                    })
                    .collect();
                markers.push(caps);
            }
            ColliderShape::TriMesh {
                vertices,
                triangles,
            } => {
                m.type_ = Marker::TRIANGLE_LIST;
                m.scale = uniform(1.0);
                m.points = triangles
                    .iter()
                    .flat_map(|t| t.iter().map(|&v| point(&vertices[v as usize])))
                    .collect();
            }
        }
        markers.push(m);
    }
    Some(MarkerArray { markers })
}
