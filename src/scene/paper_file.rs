//! The `paper:` section of a scene (Schreck et al.): every key with its unit and
//! default (table VI of the paper, converted to SI). Builds a [`PaperSim`].

use serde::{Deserialize, Serialize};

use super::check::{pose_from, Check};
use super::handle_file::PoseFile;
use super::SceneError;
use crate::geometry::{Point2, Pose, Vector3};
use crate::paper::{Collider, LengthRestoration, PaperParams, PaperSim, PresetCrease};
use crate::sim::HandleSpec;

/// A sheet of paper. Every key is optional; defaults in parentheses.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct PaperFile {
    /// Pattern rectangle [width, height], m ([0.1, 0.1]: L_paper = 10 cm, sec. 7.1).
    #[serde(default = "d_size")]
    pub size: [f64; 2],
    /// `world_from_pattern` at t = 0: the pattern's (u, v, 0) maps to
    /// position + R(rotation) (u, v, 0). (identity)
    #[serde(default)]
    pub placement: Option<PoseFile>,
    /// Areal density, kg/m^2 (0.07: 70 g/m^2 paper).
    #[serde(default = "d_density")]
    pub density: f64,
    /// Membrane stiffness Y t of the Green-strain stretching energy, N/m (1e3).
    #[serde(default = "d_stretch")]
    pub stretch_stiffness: f64,
    /// Poisson ratio, in (-1, 0.5) (0.3).
    #[serde(default = "d_poisson")]
    pub poisson_ratio: f64,
    /// Bending stiffness k_b of the dihedral energy, J (1e-4).
    #[serde(default = "d_bending")]
    pub bending_stiffness: f64,
    /// Velocity damping, 1/s (20).
    #[serde(default = "d_damping")]
    pub damping: f64,
    /// rho_bound: boundary samples and ruling density, samples/m (120 = 1.2 /cm).
    #[serde(default = "d_rho_bound")]
    pub boundary_density: f64,
    /// rho_int: interior samples of flat regions, samples/m^2 (see the default in
    /// `PaperParams::interior_density` and docs/paper_simulator.md).
    #[serde(default)]
    pub interior_density: Option<f64>,
    /// theta_0: coplanarity threshold, rad (0.01).
    #[serde(default = "d_theta0")]
    pub flat_angle: f64,
    /// Split flat regions at plain edges sharper than theta_0 (the literal sec. 5.1),
    /// bool (false).
    #[serde(default)]
    pub split_flat_regions_at_folds: bool,
    /// Rulings meeting a curved region's ruling at a smaller angle are compatible (no
    /// singular vertex), rad (0.26).
    #[serde(default = "d_conflict")]
    pub conflict_angle: f64,
    /// theta_low, rad (theta_0 / 10).
    #[serde(default)]
    pub junction_low_angle: Option<f64>,
    /// theta_high, rad (theta_0).
    #[serde(default)]
    pub junction_high_angle: Option<f64>,
    /// epsilon_c: compression threshold, dimensionless (0.001 = 0.1 %).
    #[serde(default = "d_eps_c")]
    pub compression_threshold: f64,
    /// sigma of chi(s) = exp(-d^2/sigma^2), m (0.001 = 0.1 cm).
    #[serde(default = "d_sigma")]
    pub singularity_sigma: f64,
    /// epsilon_Blaschke / L_paper, dimensionless (0.005).
    #[serde(default = "d_blaschke")]
    pub blaschke_tolerance: f64,
    /// theta_i = plastic_angle / N_i around singular vertices (eq. 1), rad (pi/8).
    #[serde(default = "d_plastic")]
    pub plastic_angle: f64,
    /// Newton iterations of step 1, at most (20).
    #[serde(default = "d_newton_max")]
    pub newton_max_iterations: u32,
    /// Newton stop on the largest vertex update, m (1e-6).
    #[serde(default = "d_newton_tol")]
    pub newton_tolerance: f64,
    /// Phase I iterations of the length restoration, at most (200; `paper` only).
    #[serde(default = "d_iso_max")]
    pub isometry_max_iterations: u32,
    /// How step 3 restores the edge lengths of S_P: `strain_limit` (every edge within
    /// `strain_limit` of its pattern length; ours) or `paper` (phases I and II of sec.
    /// 6.3). (strain_limit)
    #[serde(default = "d_restoration")]
    pub length_restoration: String,
    /// s: the largest |l / L - 1| step 3 leaves on an edge, dimensionless, in (0, 0.5]
    /// (0.005).
    #[serde(default = "d_strain_limit")]
    pub strain_limit: f64,
    /// k: stiffness of the strain-limit penalty in step 3's relaxation, N/m (3e4).
    #[serde(default = "d_strain_limit_k")]
    pub strain_limit_stiffness: f64,
    /// Collision repulsion stiffness, N/m (1e4).
    #[serde(default = "d_kc")]
    pub collision_stiffness: f64,
    /// Distance kept from colliders, m (5e-4).
    #[serde(default = "d_thick")]
    pub collision_thickness: f64,
    /// Seeded out-of-plane noise of the initial vertices, m (0).
    #[serde(default)]
    pub imperfection: f64,
    /// Static colliders (step 1 collisions). ([])
    #[serde(default)]
    pub colliders: Vec<PaperColliderFile>,
    /// Pre-set creases (fig. 22). ([])
    #[serde(default)]
    pub creases: Vec<CreaseFile>,
}

/// A static collider.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct PaperColliderFile {
    /// `plane` (the half-space above `point` along `normal`) or `sphere`.
    pub kind: String,
    /// Plane: a point on it, m. ([0, 0, 0])
    #[serde(default)]
    pub point: [f64; 3],
    /// Plane: its normal (normalized here). ([0, 0, 1])
    #[serde(default = "d_up")]
    pub normal: [f64; 3],
    /// Sphere: center, m. ([0, 0, 0])
    #[serde(default)]
    pub center: [f64; 3],
    /// Sphere: radius, m (> 0). (0.01)
    #[serde(default = "d_radius")]
    pub radius: f64,
}

/// A pre-set crease from boundary to boundary.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct CreaseFile {
    /// Ends on the pattern's boundary, [u, v] m.
    pub from: [f64; 2],
    pub to: [f64; 2],
    /// Signed rest dihedral angle, rad.
    pub rest_angle: f64,
}

fn d_size() -> [f64; 2] {
    [0.1, 0.1]
}
fn d_density() -> f64 {
    PaperParams::default().density
}
fn d_stretch() -> f64 {
    PaperParams::default().stretch_stiffness
}
fn d_poisson() -> f64 {
    PaperParams::default().poisson_ratio
}
fn d_bending() -> f64 {
    PaperParams::default().bending_stiffness
}
fn d_damping() -> f64 {
    PaperParams::default().damping
}
fn d_rho_bound() -> f64 {
    PaperParams::default().boundary_density
}
fn d_theta0() -> f64 {
    PaperParams::default().flat_angle
}
fn d_conflict() -> f64 {
    PaperParams::default().conflict_angle
}
fn d_eps_c() -> f64 {
    PaperParams::default().compression_threshold
}
fn d_sigma() -> f64 {
    PaperParams::default().singularity_sigma
}
fn d_blaschke() -> f64 {
    PaperParams::default().blaschke_tolerance
}
fn d_plastic() -> f64 {
    PaperParams::default().plastic_angle
}
fn d_newton_max() -> u32 {
    PaperParams::default().newton_max_iterations
}
fn d_newton_tol() -> f64 {
    PaperParams::default().newton_tolerance
}
fn d_iso_max() -> u32 {
    PaperParams::default().isometry_max_iterations
}
fn d_restoration() -> String {
    "strain_limit".into()
}
fn d_strain_limit() -> f64 {
    PaperParams::default().strain_limit
}
fn d_strain_limit_k() -> f64 {
    PaperParams::default().strain_limit_stiffness
}
fn d_kc() -> f64 {
    PaperParams::default().collision_stiffness
}
fn d_thick() -> f64 {
    PaperParams::default().collision_thickness
}
fn d_up() -> [f64; 3] {
    [0.0, 0.0, 1.0]
}
fn d_radius() -> f64 {
    0.01
}

/// What a paper object reads besides its `paper:` section.
pub(super) struct PaperScene<'a> {
    pub(super) paper: &'a PaperFile,
    /// Top-level `colliders:`, `contact:` and `forces:` are given (none applies to paper).
    pub(super) has_colliders: bool,
    pub(super) has_contact: bool,
    pub(super) has_forces: bool,
    pub(super) seed: u64,
}

/// A validated sheet, waiting for the scene's handle list to be built.
pub(super) struct PreparedPaper {
    params: PaperParams,
}

impl PreparedPaper {
    /// The sheet as object `index` of a world whose handles are `handles`.
    pub(super) fn build(
        self,
        ck: &Check,
        index: usize,
        handles: &[HandleSpec],
    ) -> Result<PaperSim, SceneError> {
        PaperSim::new(self.params, handles, index).map_err(|e| ck.fail(PK, e.to_string()))
    }
}

/// Validate the `paper:` section and the handles on it: `specs[h]` (already parsed, as
/// object 0) must hold a boundary point; one without an initial pose gets its point on
/// the placed sheet.
pub(super) fn prepare_paper(
    scene: PaperScene,
    ck: &Check,
    gravity: Vector3,
    specs: &mut [(HandleSpec, Option<Pose>)],
) -> Result<PreparedPaper, SceneError> {
    let paper = scene.paper;
    // The contact stage (Pan et al. sec. 5) acts on ribbons; a sheet collides
    // through its own FEM collision energy (Schreck et al. step 1).
    if scene.has_colliders {
        return Err(ck.fail(
                "colliders",
                "top-level colliders feed the ribbon contact stage; a paper sheet takes `paper.colliders` (plane, sphere)",
            ));
    }
    if scene.has_contact {
        return Err(ck.fail(
            "contact",
            "the contact stage acts on ribbons; a paper sheet collides through `paper.colliders`",
        ));
    }
    let sheet = sheet(ck, paper)?;
    let thresholds = thresholds(ck, paper)?;
    let colliders = paper_colliders(ck, &paper.colliders)?;
    let preset_creases = preset_creases(ck, &sheet, &paper.creases)?;
    paper_handles(ck, &sheet, specs)?;
    if scene.has_forces {
        return Err(ck.fail("forces", "point forces are not supported on paper objects"));
    }
    let m = material(ck, paper)?;
    let restoration = restoration(ck, paper)?;
    let params = PaperParams {
        width: sheet.width,
        height: sheet.height,
        placement: sheet.placement,
        density: m.density,
        stretch_stiffness: m.stretch_stiffness,
        poisson_ratio: thresholds.poisson_ratio,
        bending_stiffness: m.bending_stiffness,
        damping: m.damping,
        gravity,
        boundary_density: m.boundary_density,
        interior_density: m.interior_density,
        flat_angle: thresholds.flat_angle,
        split_flat_regions_at_folds: paper.split_flat_regions_at_folds,
        conflict_angle: m.conflict_angle,
        junction_low_angle: thresholds.junction_low_angle,
        junction_high_angle: thresholds.junction_high_angle,
        compression_threshold: thresholds.compression_threshold,
        singularity_sigma: m.singularity_sigma,
        blaschke_tolerance: m.blaschke_tolerance,
        plastic_angle: m.plastic_angle,
        newton_max_iterations: paper.newton_max_iterations,
        newton_tolerance: m.newton_tolerance,
        isometry_max_iterations: paper.isometry_max_iterations,
        length_restoration: restoration.0,
        strain_limit: restoration.1,
        strain_limit_stiffness: restoration.2,
        collision_stiffness: m.collision_stiffness,
        collision_thickness: m.collision_thickness,
        colliders,
        preset_creases,
        imperfection: m.imperfection,
        seed: scene.seed,
        initial_shape: crate::paper::PaperInitialShape::Flat,
    };
    Ok(PreparedPaper { params })
}

/// The key prefix of the section.
const PK: &str = "paper";

/// `paper.<k>`.
fn key(k: &str) -> String {
    format!("{PK}.{k}")
}

/// The pattern rectangle [0, width] x [0, height] (m) and where it sits at t = 0.
struct Sheet {
    width: f64,
    height: f64,
    /// `world_from_pattern` at t = 0.
    placement: Pose,
}

impl Sheet {
    /// Whether the pattern point `p` (m) lies on the rectangle's boundary (within 1e-9 m
    /// of an edge, 1e-12 m outside at most).
    fn on_boundary(&self, p: &Point2) -> bool {
        let (width, height) = (self.width, self.height);
        let inside =
            p.x >= -1e-12 && p.x <= width + 1e-12 && p.y >= -1e-12 && p.y <= height + 1e-12;
        let edge = p.x.abs() < 1e-9
            || (p.x - width).abs() < 1e-9
            || p.y.abs() < 1e-9
            || (p.y - height).abs() < 1e-9;
        inside && edge
    }
}

/// Validate the size and the placement.
fn sheet(ck: &Check, paper: &PaperFile) -> Result<Sheet, SceneError> {
    let width = ck.positive(&key("size.0"), paper.size[0])?;
    let height = ck.positive(&key("size.1"), paper.size[1])?;
    let placement = match &paper.placement {
        Some(p) => pose_from(
            ck.vec3(&key("placement.position"), p.position)?,
            ck.vec3(&key("placement.rotation"), p.rotation)?,
        ),
        None => Pose::identity(),
    };
    Ok(Sheet {
        width,
        height,
        placement,
    })
}

/// The thresholds validated before the colliders: coplanarity and junction angles,
/// the Poisson ratio and the compression threshold.
struct Thresholds {
    /// theta_0, rad.
    flat_angle: f64,
    /// theta_low, rad (<= theta_high).
    junction_low_angle: f64,
    /// theta_high, rad.
    junction_high_angle: f64,
    /// In (-1, 0.5).
    poisson_ratio: f64,
    /// epsilon_c, in (0, 1).
    compression_threshold: f64,
}

/// Validate theta_0, theta_low <= theta_high (defaults theta_0 / 10 and theta_0), the
/// Poisson ratio, epsilon_c and the Newton iteration limit.
fn thresholds(ck: &Check, paper: &PaperFile) -> Result<Thresholds, SceneError> {
    let theta0 = ck.positive(&key("flat_angle"), paper.flat_angle)?;
    let low = match paper.junction_low_angle {
        Some(v) => ck.non_negative(&key("junction_low_angle"), v)?,
        None => theta0 / 10.0,
    };
    let high = match paper.junction_high_angle {
        Some(v) => ck.non_negative(&key("junction_high_angle"), v)?,
        None => theta0,
    };
    if low > high {
        return Err(ck.fail(
            &key("junction_low_angle"),
            format!("theta_low = {low} must not exceed theta_high = {high} (hysteresis)"),
        ));
    }
    let poisson = ck.finite(&key("poisson_ratio"), paper.poisson_ratio)?;
    if !(poisson > -1.0 && poisson < 0.5) {
        return Err(ck.fail(
            &key("poisson_ratio"),
            format!("must be in (-1, 0.5), got {poisson}"),
        ));
    }
    let eps_c = ck.positive(&key("compression_threshold"), paper.compression_threshold)?;
    if eps_c >= 1.0 {
        return Err(ck.fail(
            &key("compression_threshold"),
            format!("is a fraction (0.001 = 0.1 %), got {eps_c}"),
        ));
    }
    if paper.newton_max_iterations == 0 {
        return Err(ck.fail(&key("newton_max_iterations"), "must be at least 1"));
    }
    Ok(Thresholds {
        flat_angle: theta0,
        junction_low_angle: low,
        junction_high_angle: high,
        poisson_ratio: poisson,
        compression_threshold: eps_c,
    })
}

/// Validate step 3's length restoration: the method, s in (0, 0.5] and k > 0.
fn restoration(ck: &Check, paper: &PaperFile) -> Result<(LengthRestoration, f64, f64), SceneError> {
    let kind = match ck.choice(
        &key("length_restoration"),
        &paper.length_restoration,
        &["strain_limit", "paper"],
    )? {
        "paper" => LengthRestoration::Paper,
        _ => LengthRestoration::StrainLimit,
    };
    let limit = ck.positive(&key("strain_limit"), paper.strain_limit)?;
    if limit > 0.5 {
        return Err(ck.fail(
            &key("strain_limit"),
            format!("is a fraction (0.005 = 0.5 %) of at most 0.5, got {limit}"),
        ));
    }
    let stiffness = ck.positive(&key("strain_limit_stiffness"), paper.strain_limit_stiffness)?;
    Ok((kind, limit, stiffness))
}

/// The static colliders (plane with a normalized normal, or sphere).
fn paper_colliders(ck: &Check, files: &[PaperColliderFile]) -> Result<Vec<Collider>, SceneError> {
    let mut colliders = Vec::new();
    for (i, c) in files.iter().enumerate() {
        let ckey = format!("{PK}.colliders.{i}");
        colliders.push(
            match ck.choice(&format!("{ckey}.kind"), &c.kind, &["plane", "sphere"])? {
                "plane" => {
                    let n = ck.vec3(&format!("{ckey}.normal"), c.normal)?;
                    if n.norm() < 1e-12 {
                        return Err(ck.fail(&format!("{ckey}.normal"), "must be non-zero"));
                    }
                    Collider::Plane {
                        point: ck.vec3(&format!("{ckey}.point"), c.point)?,
                        normal: n.normalize(),
                    }
                }
                _ => Collider::Sphere {
                    center: ck.vec3(&format!("{ckey}.center"), c.center)?,
                    radius: ck.positive(&format!("{ckey}.radius"), c.radius)?,
                },
            },
        );
    }
    Ok(colliders)
}

/// The pre-set creases, each from boundary to boundary of the sheet.
fn preset_creases(
    ck: &Check,
    sheet: &Sheet,
    files: &[CreaseFile],
) -> Result<Vec<PresetCrease>, SceneError> {
    let (width, height) = (sheet.width, sheet.height);
    let mut preset_creases = Vec::new();
    for (i, c) in files.iter().enumerate() {
        let ckey = format!("{PK}.creases.{i}");
        let from = Point2::new(
            ck.finite(&format!("{ckey}.from.0"), c.from[0])?,
            ck.finite(&format!("{ckey}.from.1"), c.from[1])?,
        );
        let to = Point2::new(
            ck.finite(&format!("{ckey}.to.0"), c.to[0])?,
            ck.finite(&format!("{ckey}.to.1"), c.to[1])?,
        );
        for (k, p) in [("from", from), ("to", to)] {
            if !sheet.on_boundary(&p) {
                return Err(ck.fail(
                    &format!("{ckey}.{k}"),
                    format!(
                        "[{}, {}] is not on the sheet's boundary [0, {width}] x [0, {height}] (m)",
                        p.x, p.y
                    ),
                ));
            }
        }
        preset_creases.push(PresetCrease {
            from,
            to,
            rest_angle: ck.finite(&format!("{ckey}.rest_angle"), c.rest_angle)?,
        });
    }
    Ok(preset_creases)
}

/// Check the handles on the sheet (each holds a boundary point, sec. 3.3) and place a
/// handle without an initial pose at its point on the placed sheet.
fn paper_handles(
    ck: &Check,
    sheet: &Sheet,
    specs: &mut [(HandleSpec, Option<Pose>)],
) -> Result<(), SceneError> {
    let (width, height) = (sheet.width, sheet.height);
    for (i, (spec, initial)) in specs.iter_mut().enumerate() {
        let hkey = format!("handles.{i}");
        let p = spec.material_point;
        if !sheet.on_boundary(&p) {
            return Err(ck.fail(
                    &format!("{hkey}.point"),
                    format!(
                        "[{}, {}] is not on the sheet's boundary [0, {width}] x [0, {height}] (m): the paper's handles hold the boundary (sec. 3.3)",
                        p.x, p.y
                    ),
                ));
        }
        let at = sheet.placement * Pose::translation(p.x, p.y, 0.0);
        spec.trajectory.initial = initial.unwrap_or(at);
    }
    Ok(())
}

/// The keys validated after the handles: density, stiffnesses, damping, sampling,
/// fitting and collision settings.
struct Material {
    /// kg/m^2.
    density: f64,
    /// Y t, N/m.
    stretch_stiffness: f64,
    /// k_b, J.
    bending_stiffness: f64,
    /// 1/s.
    damping: f64,
    /// rho_bound, samples/m.
    boundary_density: f64,
    /// rho_int, samples/m^2.
    interior_density: f64,
    /// rad.
    conflict_angle: f64,
    /// sigma, m.
    singularity_sigma: f64,
    /// epsilon_Blaschke / L_paper.
    blaschke_tolerance: f64,
    /// rad.
    plastic_angle: f64,
    /// m.
    newton_tolerance: f64,
    /// N/m.
    collision_stiffness: f64,
    /// m.
    collision_thickness: f64,
    /// m.
    imperfection: f64,
}

/// Validate the material keys, in the order of [`PaperParams`]' fields.
fn material(ck: &Check, paper: &PaperFile) -> Result<Material, SceneError> {
    let defaults = PaperParams::default();
    Ok(Material {
        density: ck.positive(&key("density"), paper.density)?,
        stretch_stiffness: ck.positive(&key("stretch_stiffness"), paper.stretch_stiffness)?,
        bending_stiffness: ck.non_negative(&key("bending_stiffness"), paper.bending_stiffness)?,
        damping: ck.non_negative(&key("damping"), paper.damping)?,
        boundary_density: ck.positive(&key("boundary_density"), paper.boundary_density)?,
        interior_density: match paper.interior_density {
            Some(v) => ck.positive(&key("interior_density"), v)?,
            None => defaults.interior_density,
        },
        conflict_angle: ck.non_negative(&key("conflict_angle"), paper.conflict_angle)?,
        singularity_sigma: ck.positive(&key("singularity_sigma"), paper.singularity_sigma)?,
        blaschke_tolerance: ck.positive(&key("blaschke_tolerance"), paper.blaschke_tolerance)?,
        plastic_angle: ck.non_negative(&key("plastic_angle"), paper.plastic_angle)?,
        newton_tolerance: ck.positive(&key("newton_tolerance"), paper.newton_tolerance)?,
        collision_stiffness: ck
            .non_negative(&key("collision_stiffness"), paper.collision_stiffness)?,
        collision_thickness: ck.positive(&key("collision_thickness"), paper.collision_thickness)?,
        imperfection: ck.non_negative(&key("imperfection"), paper.imperfection)?,
    })
}
