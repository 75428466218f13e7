//! Parameters of the paper simulator, SI units (m, rad, kg, s). Defaults follow
//! table VI of Schreck et al. converted from cm; the physical constants of step 1
//! (which the paper takes from Narain et al.'s FEM code without listing them) are ours
//! and documented here.

use crate::geometry::{Point2, Pose, Vector3};

/// Something the sheet collides with in step 1 (sec. 4): one-sided repulsion springs
/// (Bridson et al. 2002) keep S_P vertices `thickness` away from it. This is the hook
/// for the contact module: anything with a signed distance and a normal fits here.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Collider {
    /// The half-space above the plane through `point` with unit `normal`.
    Plane { point: Vector3, normal: Vector3 },
    /// A solid sphere.
    Sphere { center: Vector3, radius: f64 },
}

impl Collider {
    /// Signed distance (m, > 0 outside) and outward unit normal at `x`.
    pub fn distance(&self, x: &Vector3) -> (f64, Vector3) {
        match self {
            Collider::Plane { point, normal } => ((x - point).dot(normal), *normal),
            Collider::Sphere { center, radius } => {
                let d = x - center;
                let len = d.norm();
                let n = if len > 1e-12 { d / len } else { Vector3::z() };
                (len - radius, n)
            }
        }
    }
}

/// A crease set in the sheet before the simulation starts (fig. 22, third row): a
/// straight fold from boundary to boundary with a plastic rest angle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PresetCrease {
    /// Ends on ∂S̄, pattern coordinates, m.
    pub from: Point2,
    pub to: Point2,
    /// Signed rest dihedral angle of the S_P edges along it, rad (> 0 folds towards
    /// the material +z side).
    pub rest_angle: f64,
}

/// How step 3(h) restores the edge lengths of S_P.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LengthRestoration {
    /// Schreck et al. sec. 6.3: phase I (unit edge directions under two aggregated
    /// constraints) and phase II (least squares on positions, eq. 7). Its unweighted
    /// least squares spreads one absolute error over short and long edges alike and
    /// leaves the shortest edges, next to held corners, strained by 10-100 %
    /// (docs/paper_simulator.md).
    Paper,
    /// Every S_P edge within `strain_limit` of its pattern length: Newton's method on
    /// the excess, a relaxation of the FEM's energy with the limit as a penalty of
    /// stiffness `strain_limit_stiffness` (handles held), the limit once more.
    StrainLimit,
}

/// Initial shape of the sheet.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PaperInitialShape {
    /// Flat, in the plane z = 0 of the placement frame.
    Flat,
}

/// All parameters of one sheet.
#[derive(Clone, Debug, PartialEq)]
pub struct PaperParams {
    /// Pattern rectangle [0, width] x [0, height], m. Default 0.1 x 0.1 (L_paper = 10 cm,
    /// the paper's validation sheet, sec. 7.1).
    pub width: f64,
    pub height: f64,
    /// `world_from_pattern`: where the flat pattern sits at t = 0.
    pub placement: Pose,
    /// Areal density, kg/m^2. Default 0.07 (70 g/m^2 paper, sec. 4).
    pub density: f64,
    /// Membrane stiffness Y t of the Green-strain (St Venant-Kirchhoff) stretching
    /// energy, N/m. Default 1e3: "medium range" (sec. 3.3: only a medium stiffness is
    /// needed since step 3 restores the lengths; real 70 g/m^2 paper is ~4e5 N/m).
    pub stretch_stiffness: f64,
    /// Poisson ratio nu of the membrane (plane stress). Default 0.3.
    pub poisson_ratio: f64,
    /// Bending stiffness k_b of the discrete dihedral energy (Grinspun et al. 2003),
    /// J. Default 1e-4 (real 70 g/m^2 paper: ~3e-4 J).
    pub bending_stiffness: f64,
    /// Velocity damping, 1/s: velocities are scaled by 1/(1 + damping dt) each step.
    /// Default 20 (the sheet relaxes to a smooth rest state, sec. 4).
    pub damping: f64,
    /// Gravity, m/s^2.
    pub gravity: Vector3,
    /// rho_bound: boundary sample density of S_P and of the rulings, samples/m.
    /// Default 120 (1.2 /cm, table VI).
    pub boundary_density: f64,
    /// rho_int: interior sample density of the flat regions of S_P, samples/m^2.
    /// Default 1/6 cm^-2 = 1666.7 /m^2 (table VI prints "6 vertices/cm^2", but that
    /// gives ~1300 triangles on the paper's 10 cm sheet where tables II and V report
    /// 87-156: we read the 6 as cm^2 per sample; see docs/paper_simulator.md).
    pub interior_density: f64,
    /// theta_0: two adjacent triangles are coplanar when their dihedral angle is below
    /// this, rad. Default 0.01 (table VI).
    pub flat_angle: f64,
    /// Whether a plain edge of the flat triangulation of S_G whose dihedral angle
    /// exceeds theta_0 separates two flat regions (the literal reading of sec. 5.1).
    /// Default false: the coarse S_G triangles of a smoothly bent flat region are chords
    /// of S_P that fold along arbitrary triangulation edges (the paper: they "can only
    /// become compressed"), and splitting there puts singular vertices on every bend
    /// that is not aligned with the triangulation. Flat regions are then separated by
    /// rulings and creases only. See docs/paper_simulator.md.
    pub split_flat_regions_at_folds: bool,
    /// Imaginary rulings that meet a ruling of a curved region at less than this angle
    /// are compatible with it (no conflict, no singular vertex: the region can grow
    /// instead, sec. 6.1), rad. Default 0.26 (15 deg). Not a parameter of the paper,
    /// which leaves "in conflict" undefined; see docs/paper_simulator.md.
    pub conflict_angle: f64,
    /// theta_low: a curved region shrinks at a border ruling flatter than this, rad.
    /// Default theta_0 / 10 (sec. 6.1).
    pub junction_low_angle: f64,
    /// theta_high: a curved region grows at a border ruling sharper than this, rad.
    /// Default theta_0 (sec. 6.1).
    pub junction_high_angle: f64,
    /// epsilon_c: a flat region is compressed when a triangle's principal stretch is
    /// below 1 - epsilon_c (dimensionless). Default 0.001 (0.1 %, table VI).
    pub compression_threshold: f64,
    /// sigma: spread of the position of a new singular vertex around e_sing,
    /// chi(s) = exp(-d^2 / sigma^2), m. Default 0.001 (0.1 cm, table VI).
    pub singularity_sigma: f64,
    /// epsilon_Blaschke as a fraction of L_paper (dimensionless). Default 0.005
    /// (0.5 %, sec. 6.2).
    pub blaschke_tolerance: f64,
    /// The plastic rest angle around a singular vertex is
    /// theta_i = plastic_angle / N_i, rad (eq. 1). Default pi/8.
    pub plastic_angle: f64,
    /// Newton iterations of the implicit step, at most. Default 100: the paper
    /// "usually obtain[s] convergence after 10 to 100 iterations" (sec. 4); a hard
    /// frame (dt 0.1 s compression, the sheet buckling) needs 20-30.
    pub newton_max_iterations: u32,
    /// Newton stops when the largest vertex update is below this, m. Default 1e-6
    /// (1e-5 of the sheet; step 3 restores lengths to ~1e-3 anyway).
    pub newton_tolerance: f64,
    /// Phase I iterations of the length restoration, at most (sec. 6.3: 200).
    pub isometry_max_iterations: u32,
    /// How step 3 restores lengths. Default [`LengthRestoration::StrainLimit`].
    pub length_restoration: LengthRestoration,
    /// s: the largest |l / L - 1| step 3 leaves on an S_P edge (dimensionless).
    /// Default 0.005 (0.5 %; table IV's n_comp counts edges over 1 %).
    pub strain_limit: f64,
    /// k: stiffness of the strain-limit penalty (k / 2) e^2 on an edge's length beyond
    /// the limit (e, m) in step 3's relaxation, N/m. Default 3e4 (30 x the membrane's
    /// Y t: the excess the relaxation lets through, which the last limit removes, stays
    /// small).
    pub strain_limit_stiffness: f64,
    /// Stiffness of the collision repulsion springs, N/m. Default 1e4.
    pub collision_stiffness: f64,
    /// Distance kept from colliders (half the paper thickness plus margin), m.
    /// Default 5e-4.
    pub collision_thickness: f64,
    pub colliders: Vec<Collider>,
    pub preset_creases: Vec<PresetCrease>,
    /// Amplitude of a seeded out-of-plane perturbation of the initial vertices, m: a
    /// perfectly flat sheet pushed in its plane sits on a bifurcation. Default 0.
    pub imperfection: f64,
    /// Seed of every random choice (singular vertex placement, imperfection).
    pub seed: u64,
    pub initial_shape: PaperInitialShape,
}

impl Default for PaperParams {
    fn default() -> Self {
        let theta0 = 0.01;
        PaperParams {
            width: 0.1,
            height: 0.1,
            placement: Pose::identity(),
            density: 0.07,
            stretch_stiffness: 1e3,
            poisson_ratio: 0.3,
            bending_stiffness: 1e-4,
            damping: 20.0,
            gravity: Vector3::zeros(),
            boundary_density: 120.0,
            interior_density: 1.0 / 6.0e-4,
            flat_angle: theta0,
            split_flat_regions_at_folds: false,
            conflict_angle: 0.26,
            junction_low_angle: theta0 / 10.0,
            junction_high_angle: theta0,
            compression_threshold: 0.001,
            singularity_sigma: 0.001,
            blaschke_tolerance: 0.005,
            plastic_angle: std::f64::consts::FRAC_PI_8,
            newton_max_iterations: 100,
            newton_tolerance: 1e-6,
            isometry_max_iterations: 200,
            length_restoration: LengthRestoration::StrainLimit,
            strain_limit: 0.005,
            strain_limit_stiffness: 3e4,
            collision_stiffness: 1e4,
            collision_thickness: 5e-4,
            colliders: Vec::new(),
            preset_creases: Vec::new(),
            imperfection: 0.0,
            seed: 0,
            initial_shape: PaperInitialShape::Flat,
        }
    }
}

impl PaperParams {
    /// Boundary sample spacing 1/rho_bound, m.
    pub fn boundary_spacing(&self) -> f64 {
        1.0 / self.boundary_density
    }
    /// Smallest distance kept between S_G vertices and between rulings, m: a quarter
    /// of the boundary spacing (~2 mm by default).
    pub fn min_gap(&self) -> f64 {
        0.25 * self.boundary_spacing()
    }
    /// Smallest distance between two boundary vertices of S_G, m: a tenth of the
    /// boundary spacing (~0.8 mm by default). Closer ends snap together; this keeps the
    /// edges of S_P from degenerating.
    pub fn min_boundary_spacing(&self) -> f64 {
        0.1 * self.boundary_spacing()
    }
}

/// Why a sheet cannot be built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PaperError {
    #[error("`{0}` must be a finite number > 0")]
    NotPositive(&'static str),
    #[error("`{0}` must be a finite number >= 0")]
    Negative(&'static str),
    #[error("`{key}`: {message}")]
    Invalid { key: &'static str, message: String },
    #[error("the pattern triangulation failed: {0}")]
    Triangulation(String),
}

impl PaperParams {
    /// Check every value (the scene layer reports scene keys; this guards the core).
    pub fn validate(&self) -> Result<(), PaperError> {
        let positive: [(&'static str, f64); 14] = [
            ("width", self.width),
            ("height", self.height),
            ("density", self.density),
            ("stretch_stiffness", self.stretch_stiffness),
            ("boundary_density", self.boundary_density),
            ("interior_density", self.interior_density),
            ("flat_angle", self.flat_angle),
            ("compression_threshold", self.compression_threshold),
            ("singularity_sigma", self.singularity_sigma),
            ("blaschke_tolerance", self.blaschke_tolerance),
            ("newton_tolerance", self.newton_tolerance),
            ("collision_thickness", self.collision_thickness),
            ("strain_limit", self.strain_limit),
            ("strain_limit_stiffness", self.strain_limit_stiffness),
        ];
        for (k, v) in positive {
            if !(v.is_finite() && v > 0.0) {
                return Err(PaperError::NotPositive(k));
            }
        }
        let non_negative: [(&'static str, f64); 8] = [
            ("bending_stiffness", self.bending_stiffness),
            ("damping", self.damping),
            ("junction_low_angle", self.junction_low_angle),
            ("junction_high_angle", self.junction_high_angle),
            ("plastic_angle", self.plastic_angle),
            ("conflict_angle", self.conflict_angle),
            ("collision_stiffness", self.collision_stiffness),
            ("imperfection", self.imperfection),
        ];
        for (k, v) in non_negative {
            if !(v.is_finite() && v >= 0.0) {
                return Err(PaperError::Negative(k));
            }
        }
        if !(self.poisson_ratio > -1.0 && self.poisson_ratio < 0.5) {
            return Err(PaperError::Invalid {
                key: "poisson_ratio",
                message: format!("must be in (-1, 0.5), got {}", self.poisson_ratio),
            });
        }
        if self.strain_limit > 0.5 {
            return Err(PaperError::Invalid {
                key: "strain_limit",
                message: format!("must be at most 0.5 (50 %), got {}", self.strain_limit),
            });
        }
        if self.junction_low_angle > self.junction_high_angle {
            return Err(PaperError::Invalid {
                key: "junction_low_angle",
                message: "must not exceed junction_high_angle (hysteresis)".into(),
            });
        }
        if self.newton_max_iterations == 0 {
            return Err(PaperError::Invalid {
                key: "newton_max_iterations",
                message: "must be at least 1".into(),
            });
        }
        Ok(())
    }
}
