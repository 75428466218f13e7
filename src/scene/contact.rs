//! The `colliders:` and `contact:` sections of a scene file, and the contact stage
//! built from them. A scene with neither builds no stage.

use std::path::Path;

use serde::{Deserialize, Serialize};

use super::check::{pose_from, Check};
use super::mesh_file::load_mesh;
use super::SceneError;
use crate::contact::barrier::PairSource;
use crate::contact::{
    BarrierSettings, Closeness, Collider, ColliderShape, ContactSettings, ContactStage,
};
use crate::geometry::{Point3, Vector3};
use crate::sim::World;

fn d_friction() -> f64 {
    0.5
}
fn d_thickness() -> f64 {
    1e-3
}
fn d_stiffness() -> f64 {
    1e2
}
fn d_closeness() -> String {
    "stiff".into()
}
fn d_max_iterations() -> u32 {
    50
}
fn d_max_qp_iterations() -> u32 {
    10_000
}
fn d_tolerance() -> f64 {
    1e-6
}
fn d_true() -> bool {
    true
}
fn d_method() -> String {
    "barrier".into()
}
fn d_barrier_pressure() -> f64 {
    1e3
}
fn d_friction_velocity() -> f64 {
    1e-4
}

/// A rigid obstacle.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct ColliderFile {
    /// Name ([A-Za-z0-9_], unique). Default `collider_<index>`.
    #[serde(default)]
    pub name: Option<String>,
    /// `plane` (the half-space below the plane z = 0 of its frame: the ground), `box`,
    /// `sphere`, `capsule` or `mesh`.
    pub kind: String,
    /// Origin of the collider frame, m (box, sphere: the centre; capsule: the middle of
    /// its axis; plane: a point of the plane). Default [0, 0, 0].
    #[serde(default)]
    pub position: [f64; 3],
    /// Rotation vector of the collider frame, rad (plane: turns its +z normal; capsule:
    /// its axis is the frame's z). Default [0, 0, 0].
    #[serde(default)]
    pub rotation: [f64; 3],
    /// box: full edge lengths along the frame's x, y, z, m (> 0). Required for a box.
    #[serde(default)]
    pub size: Option<[f64; 3]>,
    /// sphere, capsule: radius, m (> 0). Required for them.
    #[serde(default)]
    pub radius: Option<f64>,
    /// capsule: length of its axis segment (between the centres of the end caps), m
    /// (>= 0). Required for a capsule.
    #[serde(default)]
    pub length: Option<f64>,
    /// mesh: an OBJ or STL file (ASCII or binary), path relative to the scene file. The
    /// mesh is a surface: ribbons keep `contact.thickness / 2` from either side.
    #[serde(default)]
    pub file: Option<String>,
    /// mesh: scale applied to the file's coordinates (0.001 for a file in mm). Default 1.
    #[serde(default)]
    pub scale: Option<f64>,
    /// Coulomb friction coefficient μ against ribbons (>= 0). Default 0.5.
    #[serde(default = "d_friction")]
    pub friction: f64,
    /// Handle whose target pose carries the collider (a gripper body that pushes);
    /// `position` / `rotation` are then relative to the gripper frame. Default none
    /// (static).
    #[serde(default)]
    pub handle: Option<String>,
}

/// Contact settings: inside the step (`barrier`, docs/contact_barrier.md) or after it
/// (`projection`, Pan et al. sec. 5.2).
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct ContactFile {
    /// `barrier` (IPC's barrier inside the step: every frame isometric and intersection
    /// free) or `projection` (the paper's post-step impact-zone QP, the baseline).
    /// Default `barrier`.
    #[serde(default = "d_method")]
    pub method: String,
    /// barrier: the gap beyond the thickness within which the barrier acts, ŝ, m
    /// (> 0, below (pi/2 - 1) thickness). Default thickness / 10.
    #[serde(default)]
    pub activation_distance: Option<f64>,
    /// barrier: the contact pressure at a gap of ŝ/2, Pa (> 0). Default 1000.
    #[serde(default = "d_barrier_pressure")]
    pub barrier_pressure: f64,
    /// barrier: the slip speed below which friction is a viscous stick, m/s (> 0).
    /// Default 1e-4.
    #[serde(default = "d_friction_velocity")]
    pub friction_velocity: f64,
    /// barrier: Coulomb friction coefficient μ between two ribbons (>= 0; IPC's lagged
    /// friction, as against colliders). Default 0: ribbons slide freely over each other
    /// (Pan et al.'s chains are frictionless).
    #[serde(default)]
    pub ribbon_friction: f64,
    /// Ribbon thickness h, m (> 0): a mid-surface stays h/2 from colliders and h from
    /// other ribbons. Default 0.001.
    #[serde(default = "d_thickness")]
    pub thickness: f64,
    /// Artificial edge stiffness K of the closeness measure (dimensionless, >= 0; the
    /// paper: 1e2). Default 100.
    #[serde(default = "d_stiffness")]
    pub stiffness: f64,
    /// `stiff` (closeness with the edge stiffness K, the paper's) or `plain` (Harmon et
    /// al., no stiffness: the paper's fig. 6 baseline). Default `stiff`.
    #[serde(default = "d_closeness")]
    pub closeness: String,
    /// Detection/response rounds per step (>= 1). Default 50.
    #[serde(default = "d_max_iterations")]
    pub max_iterations: u32,
    /// Active-set changes per QP (>= 1). Default 10000.
    #[serde(default = "d_max_qp_iterations")]
    pub max_qp_iterations: u32,
    /// Accepted violation of a contact distance, m (> 0). Default 1e-6.
    #[serde(default = "d_tolerance")]
    pub tolerance: f64,
    /// Contact between non-neighbouring parts of one ribbon. Default true.
    #[serde(default = "d_true")]
    pub self_contact: bool,
}

impl Default for ContactFile {
    fn default() -> Self {
        ContactFile {
            method: d_method(),
            activation_distance: None,
            barrier_pressure: d_barrier_pressure(),
            friction_velocity: d_friction_velocity(),
            ribbon_friction: 0.0,
            thickness: d_thickness(),
            stiffness: d_stiffness(),
            closeness: d_closeness(),
            max_iterations: d_max_iterations(),
            max_qp_iterations: d_max_qp_iterations(),
            tolerance: d_tolerance(),
            self_contact: true,
        }
    }
}

/// `world` with its contact: the barrier inside the steps or the contact stage after
/// them (`contact.method`), or as it is when the scene declares neither colliders, nor
/// a `contact:` section, nor robot colliders (`robot`: their links become kinematic
/// colliders at run time).
pub(super) fn build_contact(
    (collider_files, contact, robot): (&[ColliderFile], Option<&ContactFile>, bool),
    ck: &Check,
    file: &Path,
    world: World,
) -> Result<World, SceneError> {
    if collider_files.is_empty() && contact.is_none() && !robot {
        return Ok(world);
    }
    let defaults = ContactFile::default();
    let c = contact.unwrap_or(&defaults);
    // the projection's keys are checked whichever method runs (a typo is an error)
    contact_settings(ck, c)?;
    if ck.choice("contact.method", &c.method, &["barrier", "projection"])? == "barrier" {
        return build_barrier(collider_files, c, ck, file, world);
    }
    if c.ribbon_friction != 0.0 {
        return Err(ck.fail(
            "contact.ribbon_friction",
            "friction between ribbons acts with contact.method: barrier only (the projection has none)",
        ));
    }
    match build_stage(collider_files, c, ck, file, &world)? {
        Some(stage) => Ok(world.with_contact(stage)),
        None => Ok(world),
    }
}

/// Contact inside every ribbon's step (`contact.method: barrier`), checked: the
/// settings, every ribbon solved by our Newton method, nothing touching at the start.
fn build_barrier(
    collider_files: &[ColliderFile],
    c: &ContactFile,
    ck: &Check,
    file: &Path,
    world: World,
) -> Result<World, SceneError> {
    let thickness = ck.positive("contact.thickness", c.thickness)?;
    let settings = BarrierSettings {
        thickness,
        activation_distance: match c.activation_distance {
            Some(d) => ck.positive("contact.activation_distance", d)?,
            None => 0.1 * thickness,
        },
        barrier_pressure: ck.positive("contact.barrier_pressure", c.barrier_pressure)?,
        friction_velocity: ck.positive("contact.friction_velocity", c.friction_velocity)?,
        body_friction: ck.non_negative("contact.ribbon_friction", c.ribbon_friction)?,
        self_contact: c.self_contact,
    };
    settings
        .check()
        .map_err(|m| ck.fail("contact.activation_distance", m))?;
    for (o, object) in world.objects().iter().enumerate() {
        if object.contact_body().is_none() {
            return Err(ck.fail(
                "contact",
                format!(
                    "contact acts on ribbons, not on a {} object; a paper sheet collides through `paper.colliders`",
                    object.kind()
                ),
            ));
        }
        if object.solver_name() == "lbfgsb" {
            return Err(ck.fail(
                "solver.kind",
                format!(
                    "`{}`: contact.method barrier needs a Newton solver (chain or gauss_newton): L-BFGS-B's line search cannot be clamped by the collision check; or set contact.method: projection",
                    world.object_names()[o]
                ),
            ));
        }
    }
    let colliders = colliders(ck, collider_files, file, &world)?;
    check_outside_solids(ck, &colliders, &world, thickness)?;
    let mut world = world.with_barrier(settings, colliders);
    check_barrier_start(ck, &mut world, thickness)?;
    Ok(world)
}

/// Every ribbon vertex at least thickness/2 outside every collider's solid.
fn check_outside_solids(
    ck: &Check,
    colliders: &[Collider],
    world: &World,
    thickness: f64,
) -> Result<(), SceneError> {
    let half = 0.5 * thickness;
    for (k, collider) in colliders.iter().enumerate() {
        for (o, name) in world.object_names().iter().enumerate() {
            for v in &world.mesh(o).vertices {
                if let Some((sd, _)) = collider.signed_distance(world.current_targets(), &v.coords)
                {
                    if sd <= half {
                        return Err(ck.fail(
                            &format!("colliders.{k}"),
                            format!(
                                "ribbon `{name}` starts inside or closer than thickness/2 = {half} m (a vertex at [{:.4}, {:.4}, {:.4}] is at {sd:.4} m)",
                                v.x, v.y, v.z
                            ),
                        ));
                    }
                }
            }
        }
    }
    Ok(())
}

/// A barrier scene must start with every pair apart (a gap beyond the thickness).
fn check_barrier_start(ck: &Check, world: &mut World, thickness: f64) -> Result<(), SceneError> {
    let Some((gap, o, source)) = world.barrier_start_gap() else {
        return Ok(());
    };
    if gap > 0.0 {
        return Ok(());
    }
    let names = world.object_names();
    let other = match source {
        PairSource::Collider(k) => format!("collider {k}"),
        PairSource::Body(b) => format!("ribbon `{}`", names[b]),
        PairSource::Itself => "itself".to_string(),
    };
    Err(ck.fail(
        "contact",
        format!(
            "the scene starts with overlapping surfaces: ribbon `{}` and {other} are {:.4} m closer than the thickness {thickness} m; move them apart or reduce contact.thickness",
            names[o], -gap
        ),
    ))
}

/// The contact stage of a scene (`contact.method: projection`).
fn build_stage(
    collider_files: &[ColliderFile],
    c: &ContactFile,
    ck: &Check,
    file: &Path,
    world: &World,
) -> Result<Option<ContactStage>, SceneError> {
    let settings = contact_settings(ck, c)?;
    let colliders = colliders(ck, collider_files, file, world)?;
    let topologies = world
        .objects()
        .iter()
        .map(|o| match o.contact_body() {
            Some(body) => Ok(body.contact_topology()),
            None => Err(ck.fail(
                "contact",
                format!(
                    "the contact stage acts on ribbons, not on a {} object; a paper sheet collides through `paper.colliders`",
                    o.kind()
                ),
            )),
        })
        .collect::<Result<_, _>>()?;
    let mut stage = ContactStage::new(settings, topologies, colliders)
        .map_err(|e| ck.fail("contact", e.to_string()))?;
    check_start(ck, &mut stage, &settings, world)?;
    Ok(Some(stage))
}

/// The `contact:` section `c` checked into the stage's settings.
fn contact_settings(ck: &Check, c: &ContactFile) -> Result<ContactSettings, SceneError> {
    Ok(ContactSettings {
        thickness: ck.positive("contact.thickness", c.thickness)?,
        stiffness: ck.non_negative("contact.stiffness", c.stiffness)?,
        closeness: match ck.choice("contact.closeness", &c.closeness, &["stiff", "plain"])? {
            "plain" => Closeness::Plain,
            _ => Closeness::Stiff,
        },
        max_iterations: at_least_one(ck, "contact.max_iterations", c.max_iterations)?,
        max_qp_iterations: at_least_one(ck, "contact.max_qp_iterations", c.max_qp_iterations)?,
        tolerance: ck.positive("contact.tolerance", c.tolerance)?,
        self_contact: c.self_contact,
    })
}

/// The `colliders:` list, each with a valid unique name (`collider_<index>` by
/// default); mesh files are relative to `file`.
fn colliders(
    ck: &Check,
    collider_files: &[ColliderFile],
    file: &Path,
    world: &World,
) -> Result<Vec<Collider>, SceneError> {
    let mut colliders = Vec::new();
    let mut names: Vec<String> = Vec::new();
    for (i, cf) in collider_files.iter().enumerate() {
        let key = format!("colliders.{i}");
        let name = cf.name.clone().unwrap_or_else(|| format!("collider_{i}"));
        if name.is_empty() || !name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') {
            return Err(ck.fail(
                &format!("{key}.name"),
                format!("`{name}` must be non-empty [A-Za-z0-9_]"),
            ));
        }
        if names.contains(&name) {
            return Err(ck.fail(
                &format!("{key}.name"),
                format!("duplicate collider name `{name}`"),
            ));
        }
        names.push(name);
        colliders.push(collider(ck, &key, cf, file, world)?);
    }
    Ok(colliders)
}

/// Whether the scene can start: every ribbon vertex at least thickness/2 outside every
/// collider, and no two surfaces closer than the contact distance.
fn check_start(
    ck: &Check,
    stage: &mut ContactStage,
    settings: &ContactSettings,
    world: &World,
) -> Result<(), SceneError> {
    // A ribbon must start outside every solid (the continuous detection keeps it
    // there; it cannot tell which side a vertex that starts inside belongs to).
    let half = 0.5 * settings.thickness;
    for k in 0..stage.colliders().len() {
        for (o, name) in world.object_names().iter().enumerate() {
            for v in &world.mesh(o).vertices {
                if let Some((sd, _)) =
                    stage.collider_signed_distance(k, world.current_targets(), &v.coords)
                {
                    if sd < half - settings.tolerance {
                        return Err(ck.fail(
                            &format!("colliders.{k}"),
                            format!(
                                "ribbon `{name}` starts inside or closer than thickness/2 = {half} m (a vertex at [{:.4}, {:.4}, {:.4}] is at {sd:.4} m)",
                                v.x, v.y, v.z
                            ),
                        ));
                    }
                }
            }
        }
    }
    // ... and the ribbons must not start intersecting each other or themselves.
    let meshes: Vec<&[Point3]> = (0..world.objects().len())
        .map(|o| world.mesh(o).vertices.as_slice())
        .collect();
    let (overlap, pair) = stage.overlap(&meshes, world.current_targets());
    if overlap > settings.tolerance {
        let names = world.object_names();
        let pair = names.iter().enumerate().fold(pair, |p, (i, n)| {
            p.replace(&format!("body {i}"), &format!("ribbon `{n}`"))
        });
        return Err(ck.fail(
            "contact",
            format!(
                "the scene starts with overlapping surfaces ({pair}: {overlap:.4} m closer than the contact distance); move the ribbons apart or reduce contact.thickness"
            ),
        ));
    }
    Ok(())
}

fn at_least_one(ck: &Check, key: &str, v: u32) -> Result<u32, SceneError> {
    if v == 0 {
        Err(ck.fail(key, "must be at least 1"))
    } else {
        Ok(v)
    }
}

fn collider(
    ck: &Check,
    key: &str,
    cf: &ColliderFile,
    scene_file: &Path,
    world: &World,
) -> Result<Collider, SceneError> {
    let kind = ck.choice(
        &format!("{key}.kind"),
        &cf.kind,
        &["plane", "box", "sphere", "capsule", "mesh"],
    )?;
    check_keys_used(ck, key, kind, cf)?;
    let shape = collider_shape(ck, key, kind, cf, scene_file)?;
    let friction = ck.non_negative(&format!("{key}.friction"), cf.friction)?;
    let attached_to = match &cf.handle {
        None => None,
        Some(h) => Some(
            world
                .handles()
                .iter()
                .position(|s| &s.name == h)
                .ok_or_else(|| {
                    ck.fail(&format!("{key}.handle"), format!("no handle named `{h}`"))
                })?,
        ),
    };
    Ok(Collider {
        shape,
        pose: pose_from(
            ck.vec3(&format!("{key}.position"), cf.position)?,
            ck.vec3(&format!("{key}.rotation"), cf.rotation)?,
        ),
        friction,
        attached_to,
    })
}

/// Collider `key` of `kind` sets only the keys its kind uses; any other is an error
/// naming it.
fn check_keys_used(ck: &Check, key: &str, kind: &str, cf: &ColliderFile) -> Result<(), SceneError> {
    let used: &[&str] = match kind {
        "plane" => &[],
        "box" => &["size"],
        "sphere" => &["radius"],
        "capsule" => &["radius", "length"],
        _ => &["file", "scale"],
    };
    for (k, present) in [
        ("size", cf.size.is_some()),
        ("radius", cf.radius.is_some()),
        ("length", cf.length.is_some()),
        ("file", cf.file.is_some()),
        ("scale", cf.scale.is_some()),
    ] {
        if present && !used.contains(&k) {
            return Err(ck.fail(
                &format!("{key}.{k}"),
                format!("not used by a collider of kind `{kind}`"),
            ));
        }
    }
    Ok(())
}

/// The shape of collider `key` of `kind` from its keys (lengths in m; a mesh file is
/// relative to `scene_file`, its coordinates times its `scale`).
fn collider_shape(
    ck: &Check,
    key: &str,
    kind: &str,
    cf: &ColliderFile,
    scene_file: &Path,
) -> Result<ColliderShape, SceneError> {
    let required = |k: &str, v: Option<f64>| {
        v.ok_or_else(|| ck.fail(&format!("{key}.{k}"), format!("required for kind `{kind}`")))
    };
    let shape = match kind {
        "plane" => ColliderShape::HalfSpace,
        "box" => {
            let size = cf
                .size
                .ok_or_else(|| ck.fail(&format!("{key}.size"), "required for kind `box`"))?;
            let mut half = Vector3::zeros();
            for i in 0..3 {
                half[i] = 0.5 * ck.positive(&format!("{key}.size.{i}"), size[i])?;
            }
            ColliderShape::Cuboid { half_extents: half }
        }
        "sphere" => ColliderShape::Ball {
            radius: ck.positive(&format!("{key}.radius"), required("radius", cf.radius)?)?,
        },
        "capsule" => ColliderShape::Capsule {
            half_height: 0.5
                * ck.non_negative(&format!("{key}.length"), required("length", cf.length)?)?,
            radius: ck.positive(&format!("{key}.radius"), required("radius", cf.radius)?)?,
        },
        _ => {
            let rel = cf
                .file
                .as_ref()
                .ok_or_else(|| ck.fail(&format!("{key}.file"), "required for kind `mesh`"))?;
            let scale = ck.positive(&format!("{key}.scale"), cf.scale.unwrap_or(1.0))?;
            let path = scene_file.parent().unwrap_or(Path::new(".")).join(rel);
            let (vertices, triangles) =
                load_mesh(&path).map_err(|m| ck.fail(&format!("{key}.file"), m))?;
            if triangles.is_empty() {
                return Err(ck.fail(
                    &format!("{key}.file"),
                    format!("{} has no triangles", path.display()),
                ));
            }
            ColliderShape::TriMesh {
                vertices: vertices
                    .into_iter()
                    .map(|p| Point3::from(p.coords * scale))
                    .collect(),
                triangles,
            }
        }
    };
    Ok(shape)
}
