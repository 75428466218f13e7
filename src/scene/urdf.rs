//! A robot description (URDF text) as collision shapes per link, for the contact
//! stage's kinematic colliders (`robot_colliders:`). Parsing is the `urdf-rs` crate's
//! (URDF 1.0 to 1.2); mesh files are read by [`super::mesh_file::load_mesh`] (STL, OBJ).
//!
//! Shapes, in the link frame (each `<collision>`'s `<origin>`), grown by the scene's
//! `thickness` t (m):
//! - `box` -> a box with half extents size/2 + t (it contains the box rounded by t);
//! - `sphere` -> a sphere of radius r + t;
//! - `cylinder` (axis z) -> a closed prism of [`CYLINDER_SIDES`] sides circumscribed
//!   about the cylinder of radius r + t and length + 2t (a triangle mesh: the contact
//!   stage's solids have no cylinder); it contains the cylinder and exceeds it by at
//!   most (r + t)(1/cos(pi/24) - 1) = 0.86 % of the radius, at its edges;
//! - `capsule` (URDF 1.2, axis z, `length` between the caps' centres) -> a capsule of
//!   radius r + t;
//! - `mesh` (STL or OBJ; `scale` per axis) -> a triangle mesh whose vertices move out by
//!   t along their normals (see [`grow`]).
//!
//! A shape that cannot be made (a missing or unreadable mesh file, a format other than
//! STL or OBJ, a dimension that is not a positive finite number) is skipped and named in
//! [`RobotDescription::skipped`]; the rest of the robot still collides.

use std::path::{Path, PathBuf};

use super::mesh_file::load_mesh;
use super::robot_file::RobotColliders;
use crate::contact::ColliderShape;
use crate::geometry::{Point3, Pose, Vector3};

/// Sides of the prism that stands for a URDF cylinder.
pub const CYLINDER_SIDES: usize = 24;

/// A collision shape of a link and where it sits in the link frame.
#[derive(Clone, Debug, PartialEq)]
pub struct LinkShape {
    pub shape: ColliderShape,
    /// `link_from_shape`: the `<collision>`'s `<origin>`.
    pub pose: Pose,
}

/// A link that collides: its name, its TF frame and its shapes (at least one).
#[derive(Clone, Debug, PartialEq)]
pub struct RobotLink {
    pub name: String,
    /// The TF frame it follows: `frame_prefix` + name.
    pub frame: String,
    pub shapes: Vec<LinkShape>,
}

/// A robot description as colliders: the links taken (description order) and what was
/// skipped, each a sentence naming the link.
#[derive(Clone, Debug, PartialEq)]
pub struct RobotDescription {
    /// The `<robot name>`.
    pub robot: String,
    pub links: Vec<RobotLink>,
    pub skipped: Vec<String>,
}

impl RobotDescription {
    /// The links of the URDF `urdf` that `cfg` takes, with their collision shapes. An
    /// error only for a text that is not a URDF; a shape or link that cannot be used is
    /// listed in `skipped`.
    pub fn load(urdf: &str, cfg: &RobotColliders) -> Result<RobotDescription, String> {
        let robot = urdf_rs::read_from_string(urdf).map_err(|e| format!("not a URDF: {e}"))?;
        if robot.links.is_empty() {
            // urdf-rs takes any root element; a robot has at least one link
            return Err("not a URDF: no <link>".into());
        }
        let mut skipped = Vec::new();
        let wanted: Vec<&urdf_rs::Link> = match &cfg.links {
            None => robot
                .links
                .iter()
                .filter(|l| !l.collision.is_empty())
                .collect(),
            Some(names) => names
                .iter()
                .filter_map(|n| {
                    let found = robot.links.iter().find(|l| &l.name == n);
                    match found {
                        None => skipped.push(format!("link `{n}` is not in the description")),
                        Some(l) if l.collision.is_empty() => {
                            skipped.push(format!("link `{n}` has no <collision>"))
                        }
                        Some(_) => {}
                    }
                    found.filter(|l| !l.collision.is_empty())
                })
                .collect(),
        };
        let mut links = Vec::new();
        for link in wanted {
            let mut shapes = Vec::new();
            for (i, c) in link.collision.iter().enumerate() {
                match link_shape(&c.geometry, cfg) {
                    Ok(shape) => shapes.push(LinkShape {
                        shape,
                        pose: urdf_pose(&c.origin),
                    }),
                    Err(why) => skipped.push(format!(
                        "link `{}`: collision {i} ({}): {why}",
                        link.name,
                        geometry_name(&c.geometry)
                    )),
                }
            }
            if shapes.is_empty() {
                continue;
            }
            links.push(RobotLink {
                name: link.name.clone(),
                frame: format!("{}{}", cfg.frame_prefix, link.name),
                shapes,
            });
        }
        Ok(RobotDescription {
            robot: robot.name,
            links,
            skipped,
        })
    }
}

/// `link_from_shape` of a URDF `<origin xyz rpy>`: rpy are fixed-axis rotations about
/// x, then y, then z (R = Rz(yaw) Ry(pitch) Rx(roll)), rad.
pub fn urdf_pose(origin: &urdf_rs::Pose) -> Pose {
    let [x, y, z] = origin.xyz.0;
    let [roll, pitch, yaw] = origin.rpy.0;
    Pose::from_parts(
        nalgebra::Translation3::new(x, y, z),
        nalgebra::UnitQuaternion::from_euler_angles(roll, pitch, yaw),
    )
}

fn geometry_name(g: &urdf_rs::Geometry) -> String {
    match g {
        urdf_rs::Geometry::Box { .. } => "box".into(),
        urdf_rs::Geometry::Cylinder { .. } => "cylinder".into(),
        urdf_rs::Geometry::Capsule { .. } => "capsule".into(),
        urdf_rs::Geometry::Sphere { .. } => "sphere".into(),
        urdf_rs::Geometry::Mesh { filename, .. } => format!("mesh `{filename}`"),
    }
}

/// A positive finite dimension `name`, m.
fn dimension(name: &str, v: f64) -> Result<f64, String> {
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        Err(format!("{name} must be a positive finite number, got {v}"))
    }
}

/// The collider shape of one URDF geometry, grown by `cfg.thickness`.
fn link_shape(g: &urdf_rs::Geometry, cfg: &RobotColliders) -> Result<ColliderShape, String> {
    let t = cfg.thickness;
    Ok(match g {
        urdf_rs::Geometry::Box { size } => {
            let mut half = Vector3::zeros();
            for (i, axis) in ["x", "y", "z"].iter().enumerate() {
                half[i] = 0.5 * dimension(&format!("size {axis}"), size.0[i])? + t;
            }
            ColliderShape::Cuboid { half_extents: half }
        }
        urdf_rs::Geometry::Sphere { radius } => ColliderShape::Ball {
            radius: dimension("radius", *radius)? + t,
        },
        urdf_rs::Geometry::Cylinder { radius, length } => prism(
            dimension("radius", *radius)? + t,
            0.5 * dimension("length", *length)? + t,
        ),
        urdf_rs::Geometry::Capsule { radius, length } => ColliderShape::Capsule {
            half_height: 0.5 * dimension("length", *length)?,
            radius: dimension("radius", *radius)? + t,
        },
        urdf_rs::Geometry::Mesh { filename, scale } => {
            let path = mesh_path(filename, cfg)?;
            let (mut vertices, triangles) = load_mesh(&path)?;
            if triangles.is_empty() {
                return Err(format!("{} has no triangles", path.display()));
            }
            let s = scale.map_or([1.0; 3], |s| s.0);
            if let Some(bad) = s.iter().find(|x| !(x.is_finite() && **x != 0.0)) {
                return Err(format!("scale {bad} must be finite and non-zero"));
            }
            for v in &mut vertices {
                *v = Point3::new(v.x * s[0], v.y * s[1], v.z * s[2]);
            }
            grow(&mut vertices, &triangles, t);
            ColliderShape::TriMesh {
                vertices,
                triangles,
            }
        }
    })
}

/// The closed prism of [`CYLINDER_SIDES`] sides about the z axis circumscribed about the
/// cylinder of `radius` from z = -`half_length` to +`half_length` (m); triangles wound
/// counter-clockwise seen from outside.
pub fn prism(radius: f64, half_length: f64) -> ColliderShape {
    let n = CYLINDER_SIDES;
    let corner = radius / (std::f64::consts::PI / n as f64).cos();
    let mut vertices = Vec::with_capacity(2 * n + 2);
    for z in [-half_length, half_length] {
        for i in 0..n {
            let a = 2.0 * std::f64::consts::PI * i as f64 / n as f64;
            vertices.push(Point3::new(corner * a.cos(), corner * a.sin(), z));
        }
    }
    vertices.push(Point3::new(0.0, 0.0, -half_length));
    vertices.push(Point3::new(0.0, 0.0, half_length));
    let (bottom, top) = ((2 * n) as u32, (2 * n + 1) as u32);
    let mut triangles = Vec::with_capacity(4 * n);
    for i in 0..n as u32 {
        let j = (i + 1) % n as u32;
        let (b0, b1, t0, t1) = (i, j, i + n as u32, j + n as u32);
        triangles.extend([[b0, b1, t1], [b0, t1, t0], [bottom, b1, b0], [top, t0, t1]]);
    }
    ColliderShape::TriMesh {
        vertices,
        triangles,
    }
}

/// The file a URDF mesh `uri` names: `package://NAME/PATH` (NAME from
/// `robot_colliders.packages`, else `share/NAME` under an `AMENT_PREFIX_PATH` entry),
/// `file:///PATH`, an absolute path, or a path relative to the scene file.
pub fn mesh_path(uri: &str, cfg: &RobotColliders) -> Result<PathBuf, String> {
    if let Some(rest) = uri.strip_prefix("package://") {
        let (package, path) = rest
            .split_once('/')
            .ok_or_else(|| format!("`{uri}` names no file inside the package"))?;
        if let Some(dir) = cfg.packages.get(package) {
            return Ok(dir.join(path));
        }
        let prefixes = std::env::var("AMENT_PREFIX_PATH").unwrap_or_default();
        return prefixes
            .split(':')
            .filter(|p| !p.is_empty())
            .map(|p| Path::new(p).join("share").join(package))
            .find(|d| d.is_dir())
            .map(|d| d.join(path))
            .ok_or_else(|| {
                format!(
                    "package `{package}` is neither in robot_colliders.packages nor under AMENT_PREFIX_PATH"
                )
            });
    }
    if let Some(path) = uri.strip_prefix("file://") {
        return Ok(PathBuf::from(path));
    }
    if let Some((scheme, _)) = uri.split_once("://") {
        return Err(format!(
            "`{scheme}://` URIs are not supported (package://, file:// or a path)"
        ));
    }
    Ok(cfg.base_dir.join(uri))
}

/// Move every vertex of the triangle mesh out by `t` (m) along its normal (the mean of
/// its faces' unit normals weighted by their angles at the vertex, so it does not depend
/// on how a face is split into triangles; pointing out of the mesh: the winding is
/// flipped when the signed volume is negative), scaled by 1/min(n_v . n_f) over its
/// faces (at most 3) so that every face next to it moves out by at least t there: a
/// convex mesh grows to contain its offset by t (a cube grows by t on every face).
/// A vertex whose faces' normals cancel (an open sheet seen from both sides) stays.
pub fn grow(vertices: &mut [Point3], triangles: &[[u32; 3]], t: f64) {
    if t == 0.0 {
        return;
    }
    let face = |tri: &[u32; 3]| {
        let [a, b, c] = tri.map(|i| vertices[i as usize].coords);
        (b - a).cross(&(c - a))
    };
    let volume: f64 = triangles
        .iter()
        .map(|tri| vertices[tri[0] as usize].coords.dot(&face(tri)))
        .sum();
    let outward = if volume < 0.0 { -1.0 } else { 1.0 };
    let mut sum = vec![Vector3::zeros(); vertices.len()];
    let mut weight = vec![0.0; vertices.len()];
    for tri in triangles {
        let Some(n) = (face(tri) * outward).try_normalize(1e-300) else {
            continue;
        };
        for k in 0..3 {
            let [a, b, c] = [0, 1, 2].map(|j| vertices[tri[(k + j) % 3] as usize].coords);
            let angle = (b - a).angle(&(c - a));
            sum[tri[k] as usize] += n * angle;
            weight[tri[k] as usize] += angle;
        }
    }
    let mut min_dot = vec![1.0f64; vertices.len()];
    for tri in triangles {
        let Some(nf) = (face(tri) * outward).try_normalize(1e-300) else {
            continue;
        };
        for &i in tri {
            if let Some(nv) = sum[i as usize].try_normalize(1e-300) {
                min_dot[i as usize] = min_dot[i as usize].min(nv.dot(&nf));
            }
        }
    }
    for (i, v) in vertices.iter_mut().enumerate() {
        if let Some(nv) = sum[i].try_normalize(1e-9 * weight[i]) {
            let factor = 1.0 / min_dot[i].max(1.0 / 3.0);
            *v += nv * (t * factor);
        }
    }
}

/// The description `urdf` as the robot colliders of `scene` take it (what the node and
/// `replay` put in a `Command::RobotDescription`); an error for a scene without
/// `robot_colliders:` or a text that is not a URDF.
pub fn load_for(
    scene: &super::Scene,
    urdf: &str,
) -> Result<std::sync::Arc<RobotDescription>, String> {
    let cfg = scene
        .robot
        .as_ref()
        .ok_or("the scene has no robot_colliders section")?;
    RobotDescription::load(urdf, cfg).map(std::sync::Arc::new)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::BTreeMap;

    fn cfg(dir: &Path, thickness: f64) -> RobotColliders {
        RobotColliders {
            topic: "/robot_description".into(),
            links: None,
            thickness,
            friction: 0.5,
            frame_prefix: "arm/".into(),
            packages: BTreeMap::new(),
            base_dir: dir.to_path_buf(),
        }
    }

    /// A fresh folder under the system's temporary directory.
    fn temp_dir(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("urdf_test_{}_{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    fn robot(version: &str, links: &str) -> String {
        format!(r#"<robot name="arm" {version}>{links}</robot>"#)
    }

    const TWO_LINKS: &str = r#"
        <link name="base"/>
        <link name="upper_arm">
          <visual><geometry><box size="1 1 1"/></geometry></visual>
          <collision>
            <origin xyz="0.15 0 0.01" rpy="0.1 -0.2 0.3"/>
            <geometry><box size="0.3 0.04 0.05"/></geometry>
          </collision>
        </link>
        <link name="forearm">
          <collision><geometry><cylinder radius="0.02" length="0.3"/></geometry></collision>
          <collision><origin xyz="0.3 0 0"/><geometry><sphere radius="0.03"/></geometry></collision>
        </link>"#;

    #[test]
    fn each_link_with_a_collision_gets_its_shapes_grown_by_the_thickness() {
        let t = 0.005;
        let d = RobotDescription::load(&robot("", TWO_LINKS), &cfg(Path::new("."), t)).unwrap();
        assert_eq!(d.robot, "arm");
        assert!(d.skipped.is_empty(), "{:?}", d.skipped);
        let names: Vec<&str> = d.links.iter().map(|l| l.name.as_str()).collect();
        assert_eq!(names, ["upper_arm", "forearm"]); // base has no <collision>
        assert_eq!(d.links[0].frame, "arm/upper_arm");
        let upper = &d.links[0].shapes[0];
        assert_eq!(
            upper.shape,
            ColliderShape::Cuboid {
                half_extents: Vector3::new(0.15 + t, 0.02 + t, 0.025 + t)
            }
        );
        // rpy: fixed axes x, then y, then z: R = Rz(yaw) Ry(pitch) Rx(roll)
        let (r, p, y) = (0.1f64, -0.2f64, 0.3f64);
        let rx = nalgebra::Rotation3::from_axis_angle(&Vector3::x_axis(), r);
        let ry = nalgebra::Rotation3::from_axis_angle(&Vector3::y_axis(), p);
        let rz = nalgebra::Rotation3::from_axis_angle(&Vector3::z_axis(), y);
        let want = rz * ry * rx;
        let got = upper.pose.rotation.to_rotation_matrix();
        assert!((got.matrix() - want.matrix()).norm() < 1e-15);
        assert_eq!(upper.pose.translation.vector, Vector3::new(0.15, 0.0, 0.01));
        let forearm = &d.links[1].shapes;
        assert_eq!(forearm.len(), 2);
        assert_eq!(forearm[1].shape, ColliderShape::Ball { radius: 0.03 + t });
        assert_eq!(forearm[1].pose.translation.vector.x, 0.3);
        let ColliderShape::TriMesh {
            vertices,
            triangles,
        } = &forearm[0].shape
        else {
            panic!("a cylinder is a prism mesh: {:?}", forearm[0].shape);
        };
        assert_eq!(vertices.len(), 2 * CYLINDER_SIDES + 2);
        assert_eq!(triangles.len(), 4 * CYLINDER_SIDES);
        let z_max = vertices.iter().map(|v| v.z).fold(f64::MIN, f64::max);
        assert!((z_max - (0.15 + t)).abs() < 1e-15);
    }

    /// The prism stands for a cylinder: its faces touch the cylinder of the grown radius
    /// (their distance from the axis is exactly that radius), so it contains it.
    #[test]
    fn the_prism_of_a_cylinder_is_circumscribed_and_closed() {
        let ColliderShape::TriMesh {
            vertices,
            triangles,
        } = prism(0.02, 0.1)
        else {
            unreachable!()
        };
        let mut edges = BTreeMap::new();
        for tri in &triangles {
            let [a, b, c] = tri.map(|i| vertices[i as usize].coords);
            let n = (b - a).cross(&(c - a)).normalize();
            let centre = (a + b + c) / 3.0;
            // outward: away from the prism's centre (the origin)
            assert!(n.dot(&centre) > 0.0, "an inward face");
            if n.z.abs() < 1e-12 {
                assert!((n.dot(&a) - 0.02).abs() < 1e-15, "side at {}", n.dot(&a));
            }
            for k in 0..3 {
                let (u, v) = (tri[k], tri[(k + 1) % 3]);
                *edges.entry((u.min(v), u.max(v))).or_insert(0) += 1;
            }
        }
        // closed: every edge between exactly two faces
        assert!(edges.values().all(|&n| n == 2));
    }

    /// URDF 1.2's capsule: `length` between the caps' centres, axis z; its radius grows.
    #[test]
    fn a_capsule_keeps_its_length_and_grows_its_radius() {
        let link = r#"<link name="c"><collision><geometry><capsule radius="0.02" length="0.3"/></geometry></collision></link>"#;
        let d =
            RobotDescription::load(&robot(r#"version="1.2""#, link), &cfg(Path::new("."), 0.01));
        let shape = &d.unwrap().links[0].shapes[0].shape;
        assert_eq!(
            *shape,
            ColliderShape::Capsule {
                half_height: 0.15,
                radius: 0.03
            }
        );
        // URDF 1.2 checks dimensions itself: the whole description is refused
        let bad = r#"<link name="c"><collision><geometry><capsule radius="-1" length="0.3"/></geometry></collision></link>"#;
        assert!(
            RobotDescription::load(&robot(r#"version="1.2""#, bad), &cfg(Path::new("."), 0.0))
                .is_err()
        );
    }

    #[test]
    fn a_links_list_takes_only_those_and_names_what_it_cannot_take() {
        let mut c = cfg(Path::new("."), 0.0);
        c.links = Some(vec!["forearm".into(), "elbow".into(), "base".into()]);
        let d = RobotDescription::load(&robot("", TWO_LINKS), &c).unwrap();
        assert_eq!(d.links.len(), 1);
        assert_eq!(d.links[0].name, "forearm");
        assert_eq!(
            d.skipped,
            [
                "link `elbow` is not in the description",
                "link `base` has no <collision>"
            ]
        );
    }

    #[test]
    fn text_that_is_not_a_urdf_is_an_error() {
        let c = cfg(Path::new("."), 0.0);
        for bad in ["", "not xml", "<robot name='a'><link></robot>", "<robt/>"] {
            assert!(
                RobotDescription::load(bad, &c).is_err(),
                "{bad:?} was taken"
            );
        }
    }

    /// Shapes that cannot be made are named with their link and skipped; the rest of
    /// the robot loads.
    #[test]
    fn bad_shapes_are_skipped_and_named() {
        let dir = temp_dir("bad_shapes");
        std::fs::write(dir.join("empty.stl"), "solid e\nendsolid e\n").unwrap();
        std::fs::write(dir.join("part.dae"), "<COLLADA/>").unwrap();
        let links = r#"
            <link name="ok"><collision><geometry><sphere radius="0.1"/></geometry></collision></link>
            <link name="missing"><collision><geometry><mesh filename="meshes/missing.stl"/></geometry></collision></link>
            <link name="empty"><collision><geometry><mesh filename="empty.stl"/></geometry></collision></link>
            <link name="collada"><collision><geometry><mesh filename="part.dae"/></geometry></collision></link>
            <link name="remote"><collision><geometry><mesh filename="http://x/a.stl"/></geometry></collision></link>
            <link name="nopkg"><collision><geometry><mesh filename="package://nopkg_here_xyz/a.stl"/></geometry></collision></link>
            <link name="flat"><collision><geometry><box size="0.1 0 0.1"/></geometry></collision></link>
            <link name="nan"><collision><geometry><sphere radius="NaN"/></geometry></collision></link>"#;
        let d = RobotDescription::load(&robot("", links), &cfg(&dir, 0.0));
        let d = d.unwrap();
        assert_eq!(d.links.len(), 1, "{:?}", d.links);
        assert_eq!(d.links[0].name, "ok");
        let skipped = d.skipped.join("\n");
        for (link, why) in [
            ("missing", "missing.stl"),
            ("empty", "no triangles"),
            ("collada", "unknown mesh format"),
            ("remote", "`http://` URIs are not supported"),
            ("nopkg", "package `nopkg_here_xyz` is neither"),
            ("flat", "size y must be a positive finite number, got 0"),
            ("nan", "radius must be a positive finite number, got NaN"),
        ] {
            assert!(
                skipped.contains(&format!("link `{link}`: collision 0")) && skipped.contains(why),
                "{link}: {why} not in\n{skipped}"
            );
        }
    }

    fn cube_stl_ascii() -> String {
        // the 12 triangles of the unit cube [0, 1]^3, outward
        let v = |i: usize| [(i & 1) as f64, ((i >> 1) & 1) as f64, ((i >> 2) & 1) as f64];
        let faces = [
            [0, 2, 3, 1],
            [4, 5, 7, 6],
            [0, 1, 5, 4],
            [2, 6, 7, 3],
            [0, 4, 6, 2],
            [1, 3, 7, 5],
        ];
        let mut s = String::from("solid cube\n");
        for f in faces {
            for tri in [[f[0], f[1], f[2]], [f[0], f[2], f[3]]] {
                s += "facet normal 0 0 0\nouter loop\n";
                for i in tri {
                    let p = v(i);
                    s += &format!("vertex {} {} {}\n", p[0], p[1], p[2]);
                }
                s += "endloop\nendfacet\n";
            }
        }
        s + "endsolid cube\n"
    }

    #[test]
    fn meshes_load_from_stl_and_obj_by_path_package_and_file_uri_with_scale() {
        let dir = temp_dir("meshes");
        std::fs::create_dir_all(dir.join("pkg/meshes")).unwrap();
        std::fs::write(dir.join("pkg/meshes/cube.stl"), cube_stl_ascii()).unwrap();
        std::fs::write(dir.join("tri.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
        let abs = dir.join("tri.obj");
        let links = format!(
            r#"<link name="a"><collision><geometry><mesh filename="package://my_arm/meshes/cube.stl" scale="2 1 0.5"/></geometry></collision></link>
               <link name="b"><collision><geometry><mesh filename="tri.obj"/></geometry></collision></link>
               <link name="c"><collision><geometry><mesh filename="file://{}"/></geometry></collision></link>"#,
            abs.display()
        );
        let mut c = cfg(&dir, 0.0);
        c.packages.insert("my_arm".into(), dir.join("pkg"));
        let d = RobotDescription::load(&robot("", &links), &c).unwrap();
        assert!(d.skipped.is_empty(), "{:?}", d.skipped);
        let ColliderShape::TriMesh {
            vertices,
            triangles,
        } = &d.links[0].shapes[0].shape
        else {
            panic!()
        };
        // the STL's 36 corners merge into the cube's 8
        assert_eq!((vertices.len(), triangles.len()), (8, 12));
        let max = vertices
            .iter()
            .fold(Vector3::zeros(), |m, v| m.sup(&v.coords));
        assert_eq!(max, Vector3::new(2.0, 1.0, 0.5));
        for link in &d.links[1..] {
            let ColliderShape::TriMesh { triangles, .. } = &link.shapes[0].shape else {
                panic!()
            };
            assert_eq!(triangles.len(), 1);
        }
    }

    /// A cube grows by t on every face, whichever way its triangles are wound; t = 0
    /// leaves it as it is.
    #[test]
    fn grow_moves_every_face_of_a_cube_out_by_the_thickness() {
        let dir = temp_dir("grow");
        std::fs::write(dir.join("cube.stl"), cube_stl_ascii()).unwrap();
        let (cube, triangles) = load_mesh(&dir.join("cube.stl")).unwrap();
        let inward: Vec<[u32; 3]> = triangles.iter().map(|t| [t[0], t[2], t[1]]).collect();
        for tris in [&triangles, &inward] {
            let mut v = cube.clone();
            grow(&mut v, tris, 0.01);
            for (a, b) in cube.iter().zip(&v) {
                for k in 0..3 {
                    let want = if a[k] > 0.5 { 1.01 } else { -0.01 };
                    assert!((b[k] - want).abs() < 1e-12, "{a} -> {b}");
                }
            }
            let mut same = cube.clone();
            grow(&mut same, tris, 0.0);
            assert_eq!(same, cube);
        }
        // an open sheet (one triangle) moves along its normal
        let mut tri = vec![
            Point3::new(0.0, 0.0, 0.0),
            Point3::new(1.0, 0.0, 0.0),
            Point3::new(0.0, 1.0, 0.0),
        ];
        grow(&mut tri, &[[0, 1, 2]], 0.01);
        assert!(tri.iter().all(|p| (p.z.abs() - 0.01).abs() < 1e-15));
    }
}
