//! The scene file's ribbon sections (`ribbon:` or `ribbons:`): the schema and its
//! validation into the ribbon's parameters and initial shape (Pan et al.).

use serde::{Deserialize, Serialize};

use super::check::{pose_from, Check};
use super::SceneError;
use crate::geometry::{Pose, Vector3};
use crate::ribbon::{
    BaseMode, ClampRule, KineticModel, LoopKind, RibbonInitialShape, RibbonParams, SolverSettings,
};
use crate::sim::HandleSpec;

/// One ribbon (Pan et al.).
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct RibbonFile {
    /// Object name, required in a `ribbons:` list ([A-Za-z0-9_], unique); not used by
    /// the single `ribbon:` section (its object is called `ribbon`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// Length l, m. 1.0.
    #[serde(default = "d_length")]
    pub length: f64,
    /// Width w, m (< length). 0.05.
    #[serde(default = "d_width")]
    pub width: f64,
    /// Elements n (>= 2). 50.
    #[serde(default = "d_segments")]
    pub segments: usize,
    /// Areal density rho, kg/m^2. 0.1.
    #[serde(default = "d_density")]
    pub density: f64,
    /// Bending stiffness alpha, J. 0.1.
    #[serde(default = "d_alpha")]
    pub bending_stiffness: f64,
    /// Crease regularizer beta, J (paper 0.1).
    #[serde(default = "d_beta")]
    pub crease_regularizer: f64,
    /// `full` (default), `lumped` or `quasi_static`.
    #[serde(default = "d_kinetic")]
    pub kinetic: String,
    /// How a clamp (fixed or driven base, a handle with `orientation: full`) weights the
    /// creases next to it: `moment_matched` (default, second order in n),
    /// `dual_length` (the crease next to a clamp at s_c stands for the centerline from
    /// s_c to the midpoint of its free neighbour element: second order, a ~10x larger
    /// constant at end clamps) or `paper` (every crease l/n as in Pan et al.: the clamp
    /// acts half an element away from its point, first order). See docs/accuracy.md.
    #[serde(default = "d_clamp")]
    pub clamp: String,
    /// How the first element is held.
    #[serde(default)]
    pub base: BaseFile,
    /// `none` (default), `orientable` or `non_orientable`.
    #[serde(default = "d_loop", rename = "loop")]
    pub loop_closure: String,
    /// Initial shape (in the base frame).
    #[serde(default)]
    pub initial_shape: InitialShapeFile,
    /// Settle to a static equilibrium before t = 0 (closes loops from a ring guess).
    /// Default false.
    #[serde(default)]
    pub settle: bool,
    /// Initial rigid velocity.
    #[serde(default)]
    pub initial_velocity: Option<VelocityFile>,
    /// Safety factor of the crease bound (paper 0.95), in (0, 1].
    #[serde(default = "d_bound")]
    pub crease_bound_factor: f64,
}
fn d_length() -> f64 {
    1.0
}
fn d_width() -> f64 {
    0.05
}
fn d_segments() -> usize {
    50
}
fn d_density() -> f64 {
    0.1
}
fn d_alpha() -> f64 {
    0.1
}
fn d_beta() -> f64 {
    0.1
}
fn d_kinetic() -> String {
    "full".into()
}
fn d_clamp() -> String {
    "dual_length".into()
}
fn d_loop() -> String {
    "none".into()
}
fn d_bound() -> f64 {
    0.95
}

#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct BaseFile {
    /// `fixed` (default: E_0 held at `position`/`rotation`), `floating`, or `driven`
    /// (E_0 follows `handle`).
    #[serde(default = "d_base_mode")]
    pub mode: String,
    /// Position of the ribbon's material origin (start of the centerline), m.
    #[serde(default)]
    pub position: [f64; 3],
    /// Rotation vector (axis * angle), rad.
    #[serde(default)]
    pub rotation: [f64; 3],
    /// The handle driving E_0 when `mode: driven`.
    #[serde(default)]
    pub handle: Option<String>,
}
fn d_base_mode() -> String {
    "fixed".into()
}
impl Default for BaseFile {
    fn default() -> Self {
        BaseFile {
            mode: d_base_mode(),
            position: [0.0; 3],
            rotation: [0.0; 3],
            handle: None,
        }
    }
}

#[derive(Clone, Debug, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct InitialShapeFile {
    /// `flat` (default), `helix` (every crease with the values below), `ring`
    /// (square creases bent by 2 pi / n: a closed polygon, the start guess of loops) or
    /// `explicit` (every crease given: `crease_directions`, `bending_angles`).
    #[serde(default)]
    pub kind: Option<String>,
    /// Crease direction c = tan(theta) of every crease (helix). 0.
    #[serde(default)]
    pub crease_direction: f64,
    /// Bending angle psi of every crease, rad (helix). 0.
    #[serde(default)]
    pub bending_angle: f64,
    /// `explicit`: c_1 .. c_{n-1}, one per interior crease (dimensionless). Required
    /// for `explicit`, not used otherwise.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub crease_directions: Option<Vec<f64>>,
    /// `explicit`: psi_1 .. psi_{n-1}, rad. Required for `explicit`, not used otherwise.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub bending_angles: Option<Vec<f64>>,
    /// Amplitude of a seeded random perturbation of every c and psi (rad), drawn from
    /// the scene `seed`. A flat strip twisted or spun about its axis sits on a
    /// bifurcation; this breaks the symmetry as a real ribbon's imperfections do. 0.
    #[serde(default)]
    pub imperfection: f64,
}

#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct VelocityFile {
    /// Angular velocity, rad/s.
    #[serde(default)]
    pub angular: [f64; 3],
    /// Linear velocity, m/s.
    #[serde(default)]
    pub linear: [f64; 3],
    /// Centre of the rotation, m.
    #[serde(default)]
    pub center: [f64; 3],
}

fn initial_kind_is_not_explicit(ribbon: &RibbonFile) -> bool {
    ribbon.initial_shape.kind.as_deref() != Some("explicit")
}

/// The ribbons declared (`ribbon:` or `ribbons:`) with their key prefixes, and the
/// object names.
#[allow(clippy::type_complexity)]
pub(super) fn ribbon_entries<'a>(
    ck: &Check,
    ribbon: &'a Option<RibbonFile>,
    ribbons: &'a [RibbonFile],
) -> Result<(Vec<(String, &'a RibbonFile)>, Vec<String>), SceneError> {
    match (ribbon, ribbons.is_empty()) {
        (Some(_), false) => Err(ck.fail(
            "ribbons",
            "declare either one `ribbon:` section or a `ribbons:` list, not both",
        )),
        (None, true) => Err(ck.fail(
            "ribbon",
            "the scene declares no object (add a `ribbon:` section or a `ribbons:` list)",
        )),
        (Some(r), true) => {
            if r.name.is_some() {
                return Err(ck.fail(
                    "ribbon.name",
                    "the single `ribbon:` object is called `ribbon`; use a `ribbons:` list to name objects",
                ));
            }
            Ok((vec![("ribbon".to_string(), r)], vec!["ribbon".to_string()]))
        }
        (None, false) => {
            let mut entries = Vec::new();
            let mut names: Vec<String> = Vec::new();
            for (i, r) in ribbons.iter().enumerate() {
                let key = format!("ribbons.{i}");
                let Some(name) = &r.name else {
                    return Err(ck.fail(&format!("{key}.name"), "every listed ribbon needs a name"));
                };
                if name.is_empty() || !name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') {
                    return Err(ck.fail(
                        &format!("{key}.name"),
                        format!("`{name}` must be non-empty [A-Za-z0-9_]"),
                    ));
                }
                if names.contains(name) {
                    return Err(ck.fail(
                        &format!("{key}.name"),
                        format!("duplicate object name `{name}`"),
                    ));
                }
                names.push(name.clone());
                entries.push((key, r));
            }
            Ok((entries, names))
        }
    }
}

/// Validate one ribbon's keys (under `rk`) into its parameters and initial shape.
pub(super) fn ribbon_params(
    ck: &Check,
    rk: &str,
    ribbon: &RibbonFile,
    gravity: Vector3,
    solver: SolverSettings,
    specs: &[(HandleSpec, Option<Pose>)],
) -> Result<(RibbonParams, RibbonInitialShape), SceneError> {
    let strip = strip_params(ck, rk, ribbon)?;
    let (kinetic, clamp, loop_closure) = models(ck, rk, ribbon)?;
    let base = base_mode(ck, rk, &ribbon.base, specs)?;
    let initial = initial_shape(ck, rk, ribbon)?;
    let params = RibbonParams {
        length: strip.length,
        width: strip.width,
        segments: ribbon.segments,
        density: strip.density,
        bending_stiffness: strip.bending_stiffness,
        crease_regularizer: strip.crease_regularizer,
        clamp,
        gravity: gravity.into(),
        kinetic,
        base,
        loop_closure,
        crease_bound_factor: strip.crease_bound_factor,
        solver,
    };
    if let RibbonInitialShape::Helix {
        crease_direction, ..
    } = initial
    {
        if crease_direction.abs() > params.crease_bound() {
            return Err(ck.fail(
                &format!("{rk}.initial_shape.crease_direction"),
                format!(
                    "|c| = {} exceeds the crease bound 0.95*2l/(wn) = {}",
                    crease_direction.abs(),
                    params.crease_bound()
                ),
            ));
        }
    }
    Ok((params, initial))
}

/// The strip and its material, validated (`segments` too, kept in the file).
struct StripParams {
    /// l, m.
    length: f64,
    /// w, m (< l).
    width: f64,
    /// rho, kg/m^2.
    density: f64,
    /// alpha, J.
    bending_stiffness: f64,
    /// beta, J.
    crease_regularizer: f64,
    /// Safety factor of the crease bound, in (0, 1].
    crease_bound_factor: f64,
}

/// Validate the strip's size, element count, density, stiffnesses and crease bound
/// factor.
fn strip_params(ck: &Check, rk: &str, ribbon: &RibbonFile) -> Result<StripParams, SceneError> {
    let length = ck.positive(&format!("{rk}.length"), ribbon.length)?;
    let width = ck.positive(&format!("{rk}.width"), ribbon.width)?;
    if width >= length {
        return Err(ck.fail(&format!("{rk}.width"), format!("must be smaller than ribbon.length ({width} >= {length}): a ribbon is long and narrow")));
    }
    if ribbon.segments < 2 {
        return Err(ck.fail(
            &format!("{rk}.segments"),
            format!("must be at least 2, got {}", ribbon.segments),
        ));
    }
    if ribbon.segments > 20_000 {
        return Err(ck.fail(
            &format!("{rk}.segments"),
            format!("{} is more than the supported 20000", ribbon.segments),
        ));
    }
    let density = ck.positive(&format!("{rk}.density"), ribbon.density)?;
    let alpha = ck.non_negative(&format!("{rk}.bending_stiffness"), ribbon.bending_stiffness)?;
    let beta = ck.non_negative(
        &format!("{rk}.crease_regularizer"),
        ribbon.crease_regularizer,
    )?;
    let factor = ck.positive(
        &format!("{rk}.crease_bound_factor"),
        ribbon.crease_bound_factor,
    )?;
    if factor > 1.0 {
        return Err(ck.fail(
            &format!("{rk}.crease_bound_factor"),
            format!("must be in (0, 1], got {factor}"),
        ));
    }
    Ok(StripParams {
        length,
        width,
        density,
        bending_stiffness: alpha,
        crease_regularizer: beta,
        crease_bound_factor: factor,
    })
}

/// The kinetic model, the clamp rule and the loop closure, from their names.
fn models(
    ck: &Check,
    rk: &str,
    ribbon: &RibbonFile,
) -> Result<(KineticModel, ClampRule, Option<LoopKind>), SceneError> {
    let kinetic = match ck.choice(
        &format!("{rk}.kinetic"),
        &ribbon.kinetic,
        &["full", "lumped", "quasi_static"],
    )? {
        "full" => KineticModel::Full,
        "lumped" => KineticModel::Lumped,
        _ => KineticModel::QuasiStatic,
    };
    let clamp = match ck.choice(
        &format!("{rk}.clamp"),
        &ribbon.clamp,
        &["moment_matched", "dual_length", "paper"],
    )? {
        "paper" => ClampRule::Paper,
        "dual_length" => ClampRule::DualLength,
        _ => ClampRule::MomentMatched,
    };
    let loop_closure = match ck.choice(
        &format!("{rk}.loop"),
        &ribbon.loop_closure,
        &["none", "orientable", "non_orientable"],
    )? {
        "orientable" => Some(LoopKind::Orientable),
        "non_orientable" => Some(LoopKind::NonOrientable),
        _ => None,
    };
    Ok((kinetic, clamp, loop_closure))
}

/// How the first element E_0 is held: at the base pose (m, rad), free from it, or
/// driven by the handle it names in `specs`.
fn base_mode(
    ck: &Check,
    rk: &str,
    base: &BaseFile,
    specs: &[(HandleSpec, Option<Pose>)],
) -> Result<BaseMode, SceneError> {
    let base_pose = pose_from(
        ck.vec3(&format!("{rk}.base.position"), base.position)?,
        ck.vec3(&format!("{rk}.base.rotation"), base.rotation)?,
    );
    let mode = match ck.choice(
        &format!("{rk}.base.mode"),
        &base.mode,
        &["fixed", "floating", "driven"],
    )? {
        "fixed" => BaseMode::Prescribed {
            pose: base_pose,
            driven_by: None,
        },
        "floating" => BaseMode::Floating { initial: base_pose },
        _ => {
            let Some(name) = &base.handle else {
                return Err(ck.fail(
                    &format!("{rk}.base.handle"),
                    "a driven base names the handle that drives it",
                ));
            };
            let h = specs
                .iter()
                .position(|(s, _)| &s.name == name)
                .ok_or_else(|| {
                    ck.fail(
                        &format!("{rk}.base.handle"),
                        format!("no handle named `{name}`"),
                    )
                })?;
            BaseMode::Prescribed {
                pose: base_pose,
                driven_by: Some(h),
            }
        }
    };
    if let Some(v) = &base.handle {
        if base.mode != "driven" {
            return Err(ck.fail(
                &format!("{rk}.base.handle"),
                format!("`{v}` is only used with mode: driven"),
            ));
        }
    }
    Ok(mode)
}

/// The initial shape (flat, ring, helix with one c and psi, or explicit lists), and no
/// explicit list where the kind is not `explicit`.
fn initial_shape(
    ck: &Check,
    rk: &str,
    ribbon: &RibbonFile,
) -> Result<RibbonInitialShape, SceneError> {
    let shape = &ribbon.initial_shape;
    let initial = match shape.kind.as_deref().unwrap_or("flat") {
        "flat" => RibbonInitialShape::Flat,
        "ring" => RibbonInitialShape::Ring,
        "helix" => RibbonInitialShape::Helix {
            crease_direction: ck.finite(
                &format!("{rk}.initial_shape.crease_direction"),
                shape.crease_direction,
            )?,
            bending_angle: ck.finite(
                &format!("{rk}.initial_shape.bending_angle"),
                shape.bending_angle,
            )?,
        },
        "explicit" => RibbonInitialShape::Explicit {
            crease_direction: explicit_list(
                ck,
                rk,
                ribbon.segments,
                "crease_directions",
                &shape.crease_directions,
            )?,
            bending_angle: explicit_list(
                ck,
                rk,
                ribbon.segments,
                "bending_angles",
                &shape.bending_angles,
            )?,
        },
        other => {
            return Err(ck.fail(
                &format!("{rk}.initial_shape.kind"),
                format!("unknown value `{other}`, expected one of: flat, helix, ring, explicit"),
            ))
        }
    };
    if initial_kind_is_not_explicit(ribbon) {
        for (name, present) in [
            ("crease_directions", shape.crease_directions.is_some()),
            ("bending_angles", shape.bending_angles.is_some()),
        ] {
            if present {
                return Err(ck.fail(
                    &format!("{rk}.initial_shape.{name}"),
                    "only used with kind: explicit",
                ));
            }
        }
    }
    Ok(initial)
}

/// An explicit per-crease list `initial_shape.<name>`: required, n - 1 finite values
/// for `n` segments (c dimensionless, psi rad).
fn explicit_list(
    ck: &Check,
    rk: &str,
    n: usize,
    name: &str,
    v: &Option<Vec<f64>>,
) -> Result<Vec<f64>, SceneError> {
    let key = format!("{rk}.initial_shape.{name}");
    let v = v
        .as_ref()
        .ok_or_else(|| ck.fail(&key, "required for kind `explicit` (n - 1 values)"))?;
    if v.len() + 1 != n {
        return Err(ck.fail(
            &key,
            format!(
                "{} values for {n} segments: expected n - 1 = {}",
                v.len(),
                n.saturating_sub(1)
            ),
        ));
    }
    for (i, x) in v.iter().enumerate() {
        ck.finite(&format!("{key}.{i}"), *x)?;
    }
    Ok(v.clone())
}
