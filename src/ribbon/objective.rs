//! The implicit-Euler objective of one ribbon step (Pan et al. sec. 4, 5) over the
//! generalized coordinates q = <w, t | c_1..c_{n-1} | psi_1..psi_{n-1}>, with
//!
//! - its gradient in adjoint mode, O(n) (appendix C): every term contributes a wrench
//!   on the element carrying its point, and the gradient of coordinate q_a is the twist
//!   of q_a paired with the suffix sum of wrenches of the elements it moves;
//! - the chain-rule gradient of appendix A as the baseline: the full Jacobian ∇x_j,
//!   O(n^2);
//! - a Gauss-Newton Hessian of the least-squares terms, assembled in O(n^2) from 8x8
//!   per-element blocks (6 twist + 2 local crease sliding) and the same suffix sums.
//!
//! Why twists: element E_e is the rigid image of its flat trapezoid under
//! T_0 T_1 ... T_e, so a change of T_k (k <= e) moves E_e rigidly. The velocity of a
//! point of E_e under dq_a is `ξ_a(p)` for every coordinate a whose transform precedes
//! e, plus, for a rim vertex on crease k, the sliding of its material position along
//! the rim when c_k changes (eq. 2).

use nalgebra::{DMatrix, SMatrix, SVector};

use super::mass::{element_mass, lumped_centerline_mass};
use super::params::{KineticModel, LoopKind};
use super::reconstruct::{
    crease_axis, crease_axis_derivative, crease_transform, reconstruct, Coordinates, Frames, Strip,
};
use crate::geometry::{
    exp_so3, left_jacobian_so3, skew, Matrix3, Point2, Point3, Pose, Twist, Vector3,
};

type Vec8 = SVector<f64, 8>;
type Mat8 = SMatrix<f64, 8, 8>;
type Mat3x8 = SMatrix<f64, 3, 8>;

/// Where each generalized coordinate lives in q.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Layout {
    pub segments: usize,
    pub floating: bool,
}

impl Layout {
    /// Number of base coordinates (6 for a floating base: rotation vector, translation).
    #[inline]
    pub fn base_len(&self) -> usize {
        if self.floating {
            6
        } else {
            0
        }
    }
    /// Index of c_k (k = 1..n-1).
    #[inline]
    pub fn c(&self, k: usize) -> usize {
        self.base_len() + k - 1
    }
    /// Index of psi_k (k = 1..n-1).
    #[inline]
    pub fn psi(&self, k: usize) -> usize {
        self.base_len() + self.segments - 1 + k - 1
    }
    pub fn len(&self) -> usize {
        self.base_len() + 2 * (self.segments - 1)
    }
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// The first element a coordinate moves (s_a): 0 for the base, k for c_k and psi_k.
    #[inline]
    pub fn first_element(&self, a: usize) -> usize {
        let b = self.base_len();
        if a < b {
            0
        } else {
            let k = (a - b) % (self.segments - 1);
            k + 1
        }
    }

    /// Pack coordinates into q. A floating base is stored relative to `reference`:
    /// R = exp(w) R_ref, so w stays small (exact Newton curvature at w = 0, no
    /// rotation-vector singularity at |w| = pi) when the reference is the last state.
    pub fn pack(&self, coords: &Coordinates, reference: &Pose, q: &mut [f64]) {
        if self.floating {
            let w = (coords.base.rotation * reference.rotation.inverse()).scaled_axis();
            let t = coords.base.translation.vector;
            q[0..3].copy_from_slice(w.as_slice());
            q[3..6].copy_from_slice(t.as_slice());
        }
        for k in 1..self.segments {
            q[self.c(k)] = coords.crease_direction[k];
            q[self.psi(k)] = coords.bending_angle[k];
        }
    }

    /// Unpack q into coordinates (a prescribed base keeps `coords.base`; a floating
    /// one is exp(w) R_ref with `reference`'s rotation).
    pub fn unpack(&self, q: &[f64], reference: &Pose, coords: &mut Coordinates) {
        if self.floating {
            let w = Vector3::new(q[0], q[1], q[2]);
            let t = Vector3::new(q[3], q[4], q[5]);
            let r = nalgebra::Rotation3::from_matrix_unchecked(exp_so3(&w));
            let r = nalgebra::UnitQuaternion::from_rotation_matrix(&r) * reference.rotation;
            coords.base = Pose::from_parts(t.into(), r);
        }
        for k in 1..self.segments {
            coords.crease_direction[k] = q[self.c(k)];
            coords.bending_angle[k] = q[self.psi(k)];
        }
        coords.crease_direction[0] = 0.0;
        coords.crease_direction[self.segments] = 0.0;
    }
}

/// X^n and V^n of the previous step on both rims, with the material stations u (m)
/// they sit at: the data the resampling operator R (eq. 4) interpolates.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RimHistory {
    /// Material coordinate along the rim of each bottom vertex, m (increasing).
    pub u_bottom: Vec<f64>,
    pub u_top: Vec<f64>,
    /// World positions, m (as vectors from the world origin).
    pub x_bottom: Vec<Vector3>,
    pub x_top: Vec<Vector3>,
    /// Velocities, m/s.
    pub v_bottom: Vec<Vector3>,
    pub v_top: Vec<Vector3>,
}

impl RimHistory {
    /// The history of a ribbon at rest in `frames` with creases `c`.
    pub fn at_rest(strip: &Strip, c: &[f64], frames: &Frames) -> Self {
        let n = strip.segments;
        RimHistory {
            u_bottom: (0..=n).map(|j| strip.material_bottom(j, c[j]).x).collect(),
            u_top: (0..=n).map(|j| strip.material_top(j, c[j]).x).collect(),
            x_bottom: frames.rim_bottom.iter().map(|p| p.coords).collect(),
            x_top: frames.rim_top.iter().map(|p| p.coords).collect(),
            v_bottom: vec![Vector3::zeros(); n + 1],
            v_top: vec![Vector3::zeros(); n + 1],
        }
    }
}

/// Piecewise-linear interpolation on a rim: value and slope d/du at station `u`.
#[inline]
pub(crate) fn interpolate<T>(us: &[f64], values: &[T], u: f64, hint: usize) -> (T, T)
where
    T: Copy
        + std::ops::Sub<Output = T>
        + std::ops::Mul<f64, Output = T>
        + std::ops::Add<Output = T>,
{
    // segment k with us[k] <= u < us[k+1] (clamped to the ends), walking from `hint`:
    // a new rim vertex sits next to the old one of the same index (the crease bounds
    // keep it within one element), so this is O(1) and the kinetic term stays O(n).
    let last = us.len() - 2;
    let mut k = hint.min(last);
    while k > 0 && u < us[k] {
        k -= 1;
    }
    while k < last && u >= us[k + 1] {
        k += 1;
    }
    let span = us[k + 1] - us[k];
    let slope = (values[k + 1] - values[k]) * (1.0 / span);
    (values[k] + slope * (u - us[k]), slope)
}

/// K/2 |n_e - n_target|^2 on element `element` (normal guiding, sec. 5.1).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NormalGuide {
    pub material_point: Point2,
    pub target: Vector3,
    /// K, J.
    pub stiffness: f64,
}

/// A constant force (N) at a material point: potential -F.x.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointForce {
    pub material_point: Point2,
    pub force: Vector3,
}

/// An equality constraint C(X) = 0 enforced by the augmented Lagrangian.
#[derive(Clone, Debug, PartialEq)]
pub enum Equality {
    /// The grasp point at `material_point` (m) is at `target` (m) along the held axes.
    Position {
        material_point: Point2,
        target: Point3,
        axes: [bool; 3],
    },
    /// The element frame under `material_point` has rotation `target`.
    Orientation {
        material_point: Point2,
        target: Matrix3,
    },
    /// The two ends are joined (sec. 5.1).
    Loop(LoopKind),
}

impl Equality {
    /// Number of scalar constraint rows.
    pub fn rows(&self) -> usize {
        match self {
            Equality::Position { .. } => 3,
            Equality::Orientation { .. } | Equality::Loop(_) => 9,
        }
    }
    /// Whether residual row `i` is a rotation row (dimensionless) rather than a
    /// position row (m): every row of an orientation, rows 6.. of a loop (3 + 3
    /// position rows for the two rim points, then the normals).
    pub fn is_rotation_row(&self, i: usize) -> bool {
        match self {
            Equality::Position { .. } => false,
            Equality::Orientation { .. } => true,
            Equality::Loop(_) => i >= 6,
        }
    }
}

/// Everything that defines one step's objective except q.
#[derive(Clone, Debug)]
pub struct StepTerms {
    /// Time step h, s.
    pub h: f64,
    pub kinetic: KineticModel,
    pub density: f64,
    /// Bending weight of crease k (k = 1..n-1; n + 1 entries), J: the crease's energy
    /// is `crease_bending[k] (1 + c_k^2) psi_k^2` (see [`super::bending`]).
    pub crease_bending: Vec<f64>,
    pub crease_regularizer: f64,
    pub gravity: Vector3,
    pub normal_guides: Vec<NormalGuide>,
    pub forces: Vec<PointForce>,
    pub equalities: Vec<Equality>,
    /// Multipliers λ of each equality (rows() entries each), J/m for positions.
    pub multipliers: Vec<Vec<f64>>,
    /// Multipliers (<= 0) of the two end-crease inequalities Δc_max -+ c_{n-1} >= 0.
    pub end_crease_multipliers: [f64; 2],
    /// Augmented-Lagrangian penalty μ.
    pub penalty: f64,
    /// Δc_max of eq. (1).
    pub crease_bound: f64,
}

/// Objective value split by kind, J.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ObjectiveParts {
    pub kinetic: f64,
    pub elastic: f64,
    pub gravity: f64,
    pub external: f64,
    pub constraint: f64,
}

impl ObjectiveParts {
    pub fn total(&self) -> f64 {
        self.kinetic + self.elastic + self.gravity + self.external + self.constraint
    }
}

/// How the gradient is evaluated.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GradientMode {
    /// Appendix C: suffix sums of element wrenches, O(n).
    Adjoint,
    /// Appendix A: the explicit Jacobian of every point, O(n^2).
    ChainRule,
}

/// A point gradient recorded for the chain-rule baseline: dF/dp = gamma for the point
/// with material coordinates `material` carried by element `element`; `direction` marks
/// a direction (normal, frame column) instead of a point (no translation part).
#[derive(Clone, Copy, Debug)]
struct PointGradient {
    element: usize,
    material: Vector3,
    gamma: Vector3,
    direction: bool,
}

/// Second-order accumulators of one element.
#[derive(Clone, Copy, Debug)]
struct SecondOrder {
    p_gamma: Matrix3,
    slide: [Vector3; 2],
}

impl Default for SecondOrder {
    fn default() -> Self {
        SecondOrder {
            p_gamma: Matrix3::zeros(),
            slide: [Vector3::zeros(); 2],
        }
    }
}

/// Buffers reused across evaluations (no allocation per evaluation once warm).
#[derive(Clone, Debug, Default)]
pub struct Workspace {
    pub coords: Coordinates,
    pub frames: Frames,
    twists: Vec<Twist>,
    /// Per-element generalized force: [wrench (moment, force); local c_e; local c_{e+1}].
    element_gradient: Vec<Vec8>,
    element_hessian: Vec<Mat8>,
    /// Off-diagonal blocks (e1, e2, B) of the Gauss-Newton Hessian (loop closure).
    cross_blocks: Vec<(usize, usize, Mat8)>,
    /// Kinetic residual D per vertex (bottom then top), m/s.
    residual_bottom: Vec<Vector3>,
    residual_top: Vec<Vector3>,
    point_gradients: Vec<PointGradient>,
    /// Per element: Σ p γ^T over points and directions (for the geometric stiffness),
    /// and Σ s × γ of vertices sliding with c_e (index 0) and c_{e+1} (index 1).
    element_second: Vec<SecondOrder>,
    /// Per crease k: (axis point A_k, R_{k-1} ḋ, dΩ_c/dc) for same-crease second
    /// derivatives.
    crease_extra: Vec<(Vector3, Vector3, Vector3)>,
    suffix: Vec<Vec8>,
    scratch_first: Vec<usize>,
    scratch_u: Vec<SVector<f64, 6>>,
    scratch_twists: Vec<[f64; 6]>,
    scratch_columns: Vec<[f64; 6]>,
    scratch_psuf: Vec<(Matrix3, Vector3, Vector3)>,
    hessian_suffix: Vec<SMatrix<f64, 6, 6>>,
    /// Kinetic-term slopes of the resampling along u (bottom, top rim).
    slope_bottom: Vec<Vector3>,
    slope_top: Vec<Vector3>,
    /// Cross-block scratch (loop closure): P_e1 columns and B P_e2 columns.
    scratch_left: Vec<Vec8>,
    scratch_right: Vec<(usize, Vec8)>,
    /// Whether the last evaluation kept what `assemble_newton_hessian` needs.
    second_order_recorded: bool,
    pub parts: ObjectiveParts,
}

impl Default for Coordinates {
    fn default() -> Self {
        Coordinates::flat(1, Pose::identity())
    }
}

/// The objective of one step. Holds references to everything fixed during the step.
pub struct Objective<'a> {
    pub strip: Strip,
    pub layout: Layout,
    pub terms: &'a StepTerms,
    pub history: &'a RimHistory,
    /// Base frame when prescribed; for a floating base, the reference rotation R_ref
    /// (R = exp(w) R_ref) and nothing else.
    pub base: Pose,
}

#[inline(always)]
fn dot6(a: &[f64; 6], b: &[f64]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3] + a[4] * b[4] + a[5] * b[5]
}

/// Projection of a symmetric 2x2 matrix onto the PSD cone (negative eigenvalues
/// clamped to zero), in closed form.
fn psd_2x2(m: &nalgebra::Matrix2<f64>) -> nalgebra::Matrix2<f64> {
    let (a, b, d) = (m[(0, 0)], m[(0, 1)], m[(1, 1)]);
    let mean = 0.5 * (a + d);
    let radius = (0.25 * (a - d) * (a - d) + b * b).sqrt();
    let (hi, lo) = (mean + radius, mean - radius);
    if lo >= 0.0 {
        return *m;
    }
    if hi <= 0.0 {
        return nalgebra::Matrix2::zeros();
    }
    // eigenvector of `hi`: the larger of the two candidate columns of (M - lo I)
    let v1 = nalgebra::Vector2::new(a - lo, b);
    let v2 = nalgebra::Vector2::new(b, d - lo);
    let v = if v1.norm_squared() >= v2.norm_squared() {
        v1
    } else {
        v2
    };
    let v = v / v.norm();
    v * v.transpose() * hi
}

/// ∂u/∂c of a rim vertex: -w/2 on the bottom rim, +w/2 on the top rim (eq. 2).
#[inline]
fn sliding_rate(width: f64, top: bool) -> f64 {
    if top {
        0.5 * width
    } else {
        -0.5 * width
    }
}

/// 3x8 Jacobian of a world point of element e w.r.t. [twist; c_e; c_{e+1}].
#[inline]
fn point_jacobian(p: &Point3) -> Mat3x8 {
    let mut j = Mat3x8::zeros();
    j.fixed_view_mut::<3, 3>(0, 0)
        .copy_from(&(-skew(&p.coords)));
    j.fixed_view_mut::<3, 3>(0, 3)
        .copy_from(&Matrix3::identity());
    j
}

/// 3x8 Jacobian of a world direction of element e (rotates only).
#[inline]
fn direction_jacobian(d: &Vector3) -> Mat3x8 {
    let mut j = Mat3x8::zeros();
    j.fixed_view_mut::<3, 3>(0, 0).copy_from(&(-skew(d)));
    j
}

impl<'a> Objective<'a> {
    pub fn new(
        strip: Strip,
        floating: bool,
        terms: &'a StepTerms,
        history: &'a RimHistory,
        base: Pose,
    ) -> Self {
        Objective {
            strip,
            layout: Layout {
                segments: strip.segments,
                floating,
            },
            terms,
            history,
            base,
        }
    }

    /// Set up coordinates and frames for q.
    pub fn prepare(&self, q: &[f64], ws: &mut Workspace) {
        let n = self.strip.segments;
        if ws.coords.segments() != n {
            ws.coords = Coordinates::flat(n, self.base);
        }
        if !self.layout.floating {
            ws.coords.base = self.base;
        }
        self.layout.unpack(q, &self.base, &mut ws.coords);
        reconstruct(&self.strip, &ws.coords, &mut ws.frames);
    }

    /// World twists ξ_a of all coordinates (needs `prepare`).
    fn compute_twists(&self, q: &[f64], ws: &mut Workspace) {
        let n = self.strip.segments;
        ws.twists.clear();
        if self.layout.floating {
            let w = Vector3::new(q[0], q[1], q[2]);
            let t = Vector3::new(q[3], q[4], q[5]);
            let jl = left_jacobian_so3(&w);
            for i in 0..3 {
                let omega = jl.column(i).into_owned();
                ws.twists.push(Twist {
                    angular: omega,
                    linear: t.cross(&omega),
                });
            }
            for i in 0..3 {
                let mut lin = Vector3::zeros();
                lin[i] = 1.0;
                ws.twists.push(Twist {
                    angular: Vector3::zeros(),
                    linear: lin,
                });
            }
        }
        let f = &ws.frames;
        ws.crease_extra.clear();
        ws.crease_extra
            .push((Vector3::zeros(), Vector3::zeros(), Vector3::zeros()));
        for k in 1..n {
            let r_prev = f.rotation[k - 1];
            let c = ws.coords.crease_direction[k];
            let psi = ws.coords.bending_angle[k];
            let a = r_prev * Vector3::new(self.strip.crease_station(k), 0.0, 0.0)
                + f.translation[k - 1];
            let d = crease_axis(c);
            let dd = crease_axis_derivative(c);
            let s = 1.0 + c * c;
            let ddd = Vector3::new(-3.0 * c, 2.0 * c * c - 1.0, 0.0) / (s * s * s.sqrt());
            let domega = ddd * psi.sin() + d.cross(&ddd) * (1.0 - psi.cos());
            ws.crease_extra.push((a, r_prev * dd, r_prev * domega));
        }
        // c_k twists, then psi_k twists (matching the layout order)
        for pass in 0..2 {
            for k in 1..n {
                let r_prev = f.rotation[k - 1];
                let t_prev = f.translation[k - 1];
                let c = ws.coords.crease_direction[k];
                let psi = ws.coords.bending_angle[k];
                let axis_point = Point3::from(
                    r_prev * Vector3::new(self.strip.crease_station(k), 0.0, 0.0) + t_prev,
                );
                let d = crease_axis(c);
                let omega_local = if pass == 0 {
                    // derivative of exp(psi d(c)) w.r.t. the axis at fixed angle
                    let dd = crease_axis_derivative(c);
                    dd * psi.sin() + d.cross(&dd) * (1.0 - psi.cos())
                } else {
                    d
                };
                ws.twists
                    .push(Twist::rotation_about(r_prev * omega_local, &axis_point));
            }
        }
    }

    /// Evaluate the objective; with `gradient`, also its gradient (by `mode`); with
    /// `hessian`, also the Gauss-Newton Hessian (N x N, N = layout.len()).
    pub fn evaluate(
        &self,
        q: &[f64],
        ws: &mut Workspace,
        gradient: Option<(&mut [f64], GradientMode)>,
        hessian: Option<&mut DMatrix<f64>>,
    ) -> f64 {
        let value = self.evaluate_recording(q, ws, gradient, hessian.is_some());
        if let Some(h) = hessian {
            self.assemble_newton_hessian(ws, h);
        }
        value
    }

    /// The objective at q and, if asked, its gradient; with `second_order`, also the
    /// per-element second-order data, so that [`Self::assemble_newton_hessian`] can
    /// build the Hessian at q afterwards without another pass (a Newton solver only
    /// needs it once it knows it has not converged).
    pub fn evaluate_recording(
        &self,
        q: &[f64],
        ws: &mut Workspace,
        gradient: Option<(&mut [f64], GradientMode)>,
        second_order: bool,
    ) -> f64 {
        let n = self.strip.segments;
        self.prepare(q, ws);
        let want_hessian = second_order;
        let record_points = matches!(gradient, Some((_, GradientMode::ChainRule)));
        ws.element_gradient.clear();
        ws.element_gradient.resize(n, Vec8::zeros());
        if want_hessian {
            ws.element_hessian.clear();
            ws.element_hessian.resize(n, Mat8::zeros());
        }
        ws.cross_blocks.clear();
        ws.point_gradients.clear();
        if want_hessian {
            ws.element_second.clear();
            ws.element_second.resize(n, SecondOrder::default());
        }
        ws.parts = ObjectiveParts::default();
        let mut grad_out = gradient;
        if let Some((g, _)) = grad_out.as_mut() {
            g.iter_mut().for_each(|x| *x = 0.0);
        }

        let mut acc = Accumulator {
            strip: &self.strip,
            ws_gradient: &mut ws.element_gradient,
            ws_hessian: if want_hessian {
                Some(&mut ws.element_hessian)
            } else {
                None
            },
            points: if record_points {
                Some(&mut ws.point_gradients)
            } else {
                None
            },
            second: if want_hessian {
                Some(&mut ws.element_second)
            } else {
                None
            },
            frames: &ws.frames,
            coords: &ws.coords,
        };

        // --- kinetic term (sec. 4) ---
        let t = self.terms;
        match t.kinetic {
            KineticModel::Full => {
                ws.parts.kinetic = self.kinetic_full(
                    &mut acc,
                    [&mut ws.residual_bottom, &mut ws.residual_top],
                    [&mut ws.slope_bottom, &mut ws.slope_top],
                );
            }
            KineticModel::Lumped => {
                ws.parts.kinetic = self.kinetic_lumped(&mut acc);
            }
            KineticModel::QuasiStatic => {}
        }

        // --- gravity: V = -rho g^T M X with the consistent M (row sums) ---
        if t.gravity.norm_squared() > 0.0 {
            ws.parts.gravity = self.gravity(&mut acc);
        }

        // --- normal guiding (sec. 5.1) ---
        for guide in &t.normal_guides {
            let e = self
                .strip
                .element_of(&acc.coords.crease_direction, &guide.material_point);
            let normal = acc.frames.normals[e];
            let diff = normal - guide.target;
            ws.parts.external += 0.5 * guide.stiffness * diff.norm_squared();
            acc.add_direction_gradient(e, &Vector3::z(), &normal, &(diff * guide.stiffness));
            if let Some(hs) = acc.ws_hessian.as_deref_mut() {
                let j = direction_jacobian(&normal);
                hs[e] += j.transpose() * j * guide.stiffness;
            }
        }

        // --- point forces: potential -F.x ---
        for force in &t.forces {
            let e = self
                .strip
                .element_of(&acc.coords.crease_direction, &force.material_point);
            let m = Point3::new(force.material_point.x, force.material_point.y, 0.0);
            let p = acc.frames.to_world(e, &m);
            ws.parts.external -= force.force.dot(&p.coords);
            acc.add_point_gradient(e, &m, &p, &(-force.force), None);
        }

        // --- equality constraints: augmented Lagrangian -λ.C + μ/2 |C|^2 ---
        for (eq, lambda) in t.equalities.iter().zip(&t.multipliers) {
            ws.parts.constraint +=
                self.equality(&mut acc, &mut ws.cross_blocks, eq, lambda, t.penalty);
        }

        // --- bending, regularizer, end-crease inequality: direct in (c, psi) ---
        let direct = |idx: usize, value: f64, g: &mut Option<(&mut [f64], GradientMode)>| {
            if let Some((gg, _)) = g.as_mut() {
                gg[idx] += value;
            }
        };
        for k in 1..n {
            let c = acc.coords.crease_direction[k];
            let psi = acc.coords.bending_angle[k];
            let s = 1.0 + c * c;
            let bend_k = t.crease_bending[k];
            ws.parts.elastic += bend_k * s * psi * psi + t.crease_regularizer * c * c;
            let (ic, ip) = (self.layout.c(k), self.layout.psi(k));
            direct(
                ic,
                2.0 * bend_k * c * psi * psi + 2.0 * t.crease_regularizer * c,
                &mut grad_out,
            );
            direct(ip, 2.0 * bend_k * s * psi, &mut grad_out);
        }
        // |c_{n-1}| <= Δc_max, the inequality left after the substitution (sec. 5.1),
        // in the paper's form mu/2 min(C + λ/μ, 0)^2 (constant terms dropped).
        let c_last = acc.coords.crease_direction[n - 1];
        if n >= 2 {
            for (sign, shifted) in self.end_crease_shifts(c_last) {
                if shifted < 0.0 {
                    ws.parts.constraint += 0.5 * t.penalty * shifted * shifted;
                    let ic = self.layout.c(n - 1);
                    direct(ic, t.penalty * shifted * sign, &mut grad_out);
                }
            }
        }

        let value = ws.parts.total();

        // --- assemble the geometric part ---
        let need_twists = grad_out.is_some() || second_order;
        if need_twists {
            self.compute_twists(q, ws);
        }
        if let Some((g, mode)) = grad_out {
            match mode {
                GradientMode::Adjoint => self.gradient_adjoint(ws, g),
                GradientMode::ChainRule => self.gradient_chain_rule(q, ws, g),
            }
        }
        ws.second_order_recorded = second_order;
        value
    }

    /// The end-crease inequalities |c_{n-1}| <= Δc_max as C = Δc_max ∓ c_{n-1} >= 0: per
    /// side, the sign of c_{n-1} in C and min(C + λ/μ, 0), negative where the augmented-
    /// Lagrangian term mu/2 min(C + λ/μ, 0)^2 is active.
    fn end_crease_shifts(&self, c_last: f64) -> [(f64, f64); 2] {
        let t = self.terms;
        [
            (-1.0, t.end_crease_multipliers[0]),
            (1.0, t.end_crease_multipliers[1]),
        ]
        .map(|(sign, lambda)| {
            let cval = t.crease_bound + sign * c_last;
            (sign, (cval + lambda / t.penalty).min(0.0))
        })
    }

    /// The Hessian (N x N, N = layout.len()) at the q of the last
    /// [`Self::evaluate_recording`] with `second_order`, whose data `ws` still holds.
    pub fn assemble_newton_hessian(&self, ws: &mut Workspace, hm: &mut DMatrix<f64>) {
        assert!(
            ws.second_order_recorded,
            "assemble_newton_hessian needs an evaluation that recorded second-order data"
        );
        let n = self.strip.segments;
        let nq = self.layout.len();
        if hm.nrows() != nq || hm.ncols() != nq {
            *hm = DMatrix::zeros(nq, nq);
        } else {
            // one memset (nalgebra's fill walks the matrix entry by entry)
            hm.as_mut_slice().fill(0.0);
        }
        let t = self.terms;
        for k in 1..n {
            let c = ws.coords.crease_direction[k];
            let psi = ws.coords.bending_angle[k];
            let s = 1.0 + c * c;
            let bend_k = t.crease_bending[k];
            let (ic, ip) = (self.layout.c(k), self.layout.psi(k));
            // Exact Hessian of k (1+c^2) psi^2, clamped to PSD (it is indefinite for
            // c^2 > 1/3), plus 2 beta on c.
            let block = nalgebra::Matrix2::new(
                2.0 * bend_k * psi * psi,
                4.0 * bend_k * c * psi,
                4.0 * bend_k * c * psi,
                2.0 * bend_k * s,
            );
            let clamped = psd_2x2(&block);
            hm[(ic, ic)] += clamped[(0, 0)] + 2.0 * t.crease_regularizer;
            // (each unordered pair once: the matrix is symmetrized at the end)
            hm[(ic, ip)] += clamped[(0, 1)];
            hm[(ip, ip)] += clamped[(1, 1)];
        }
        // the end-crease inequality term, where active (see `evaluate_recording`)
        if n >= 2 {
            let c_last = ws.coords.crease_direction[n - 1];
            for (_, shifted) in self.end_crease_shifts(c_last) {
                if shifted < 0.0 {
                    let ic = self.layout.c(n - 1);
                    hm[(ic, ic)] += t.penalty;
                }
            }
        }
        self.assemble_hessian(ws, hm);
    }

    /// Full kinetic term with resampling: rho/2 |(X - R(X̄, X^n))/h - R(X̄, V^n)|_M^2.
    fn kinetic_full(
        &self,
        acc: &mut Accumulator,
        [res_b, res_t]: [&mut Vec<Vector3>; 2],
        [slope_b, slope_t]: [&mut Vec<Vector3>; 2],
    ) -> f64 {
        let n = self.strip.segments;
        let t = self.terms;
        let h = t.h;
        let hist = self.history;
        let w = self.strip.width;
        let c = &acc.coords.crease_direction;
        res_b.resize(n + 1, Vector3::zeros());
        res_t.resize(n + 1, Vector3::zeros());
        // slopes of R along u for the local (sliding) derivative
        slope_b.resize(n + 1, Vector3::zeros());
        slope_t.resize(n + 1, Vector3::zeros());
        for j in 0..=n {
            for top in [false, true] {
                let m = if top {
                    self.strip.material_top(j, c[j])
                } else {
                    self.strip.material_bottom(j, c[j])
                };
                let (us, xs, vs) = if top {
                    (&hist.u_top, &hist.x_top, &hist.v_top)
                } else {
                    (&hist.u_bottom, &hist.x_bottom, &hist.v_bottom)
                };
                let (rx, drx) = interpolate(us, xs, m.x, j);
                let (rv, drv) = interpolate(us, vs, m.x, j);
                let x = if top {
                    acc.frames.rim_top[j]
                } else {
                    acc.frames.rim_bottom[j]
                };
                let d = (x.coords - rx) / h - rv;
                // dD/du at fixed world motion: -(R_X'/h + R_V')
                let s = -(drx / h + drv);
                if top {
                    res_t[j] = d;
                    slope_t[j] = s;
                } else {
                    res_b[j] = d;
                    slope_b[j] = s;
                }
            }
        }
        let mut value = 0.0;
        for e in 0..n {
            let mass = element_mass(self.strip.length, w, n, c[e + 1] - c[e]);
            let verts = [(e, false), (e, true), (e + 1, false), (e + 1, true)];
            let d: [Vector3; 4] = verts.map(|(j, top)| if top { res_t[j] } else { res_b[j] });
            let mut gamma = [Vector3::zeros(); 4];
            let mut dmass = 0.0;
            for a in 0..4 {
                for b in 0..4 {
                    gamma[a] += d[b] * (t.density * mass.k[a][b]);
                    dmass += 0.5 * t.density * mass.dk_ddelta_c[a][b] * d[a].dot(&d[b]);
                }
                value += 0.5 * d[a].dot(&gamma[a]);
            }
            // explicit mass dependence on Δc = c_{e+1} - c_e
            acc.add_local(e, -dmass, dmass);
            // per vertex: world position and the sliding column σ_a of dD_a/dc_j (zero
            // for the fixed end creases), for the Gauss-Newton block
            let mut xs = [Vector3::zeros(); 4];
            let mut sigma = [Vector3::zeros(); 4];
            let mut column = [None::<usize>; 4];
            for (a, &(j, top)) in verts.iter().enumerate() {
                let x = if top {
                    acc.frames.rim_top[j]
                } else {
                    acc.frames.rim_bottom[j]
                };
                let mat = if top {
                    self.strip.material_top(j, c[j])
                } else {
                    self.strip.material_bottom(j, c[j])
                };
                // dD/dX = I/h: the point gradient is gamma/h; the resampling slope adds a
                // local term on c_j.
                let slope = if top { slope_t[j] } else { slope_b[j] };
                let du = sliding_rate(w, top);
                acc.add_point_gradient(e, &mat, &x, &(gamma[a] / h), Some((j, du)));
                xs[a] = x.coords;
                if j != 0 && j != n {
                    let local_extra = gamma[a].dot(&slope) * du;
                    if j == e {
                        acc.add_local(e, local_extra, 0.0);
                    } else {
                        acc.add_local(e, 0.0, local_extra);
                    }
                    sigma[a] = acc.frames.rotation[e].column(0) * (du / h) + slope * du;
                    column[a] = Some(if j == e { 6 } else { 7 });
                }
            }
            if let Some(hs) = acc.ws_hessian.as_deref_mut() {
                // G = rho Σ_ab K_ab J_a^T J_b with J_a = [-[x_a]×/h, I/h | σ_a], in closed
                // form (rigid-body inertia structure): with y_a = Σ_b K_ab x_b, row sums
                // r_a and z = Σ r_a x_a, the twist block is
                // [[Σ (x_a.y_a) I - y_a x_a^T, [z]×], [-[z]×, (Σ K) I]] / h^2.
                let rho = t.density;
                let mut block = Mat8::zeros();
                let mut rot = Matrix3::zeros();
                let mut z = Vector3::zeros();
                let mut total = 0.0;
                let mut y = [Vector3::zeros(); 4];
                for a in 0..4 {
                    let mut r = 0.0;
                    for b in 0..4 {
                        y[a] += xs[b] * mass.k[a][b];
                        r += mass.k[a][b];
                    }
                    rot += Matrix3::identity() * xs[a].dot(&y[a]) - y[a] * xs[a].transpose();
                    z += xs[a] * r;
                    total += r;
                }
                let inv_h2 = rho / (h * h);
                block
                    .fixed_view_mut::<3, 3>(0, 0)
                    .copy_from(&(rot * inv_h2));
                block
                    .fixed_view_mut::<3, 3>(0, 3)
                    .copy_from(&(skew(&z) * inv_h2));
                block
                    .fixed_view_mut::<3, 3>(3, 0)
                    .copy_from(&(-skew(&z) * inv_h2));
                block
                    .fixed_view_mut::<3, 3>(3, 3)
                    .copy_from(&(Matrix3::identity() * (total * inv_h2)));
                for b in 0..4 {
                    let Some(cb) = column[b] else { continue };
                    // twist-local: (rho/h) Σ_a K_ab [x_a × σ_b; σ_b]
                    let mut ang = Vector3::zeros();
                    let mut r = 0.0;
                    for a in 0..4 {
                        ang += xs[a].cross(&sigma[b]) * mass.k[a][b];
                        r += mass.k[a][b];
                    }
                    let lin = sigma[b] * r;
                    for i in 0..3 {
                        block[(i, cb)] += ang[i] * rho / h;
                        block[(cb, i)] += ang[i] * rho / h;
                        block[(3 + i, cb)] += lin[i] * rho / h;
                        block[(cb, 3 + i)] += lin[i] * rho / h;
                    }
                    for a in 0..4 {
                        if let Some(ca) = column[a] {
                            block[(ca, cb)] += rho * mass.k[a][b] * sigma[a].dot(&sigma[b]);
                        }
                    }
                }
                hs[e] += block;
            }
        }
        value
    }

    /// Lumped kinetic term: sum_i M_i/2 |(m_i - m_i^n)/h - ṁ_i^n|^2 on the centerline
    /// points m_i = (x_i + y_i)/2 (material station (l i/n, 0), independent of c).
    fn kinetic_lumped(&self, acc: &mut Accumulator) -> f64 {
        let n = self.strip.segments;
        let t = self.terms;
        let h = t.h;
        let hist = self.history;
        let mut value = 0.0;
        for i in 0..=n {
            let e = i.min(n - 1);
            let mass = lumped_centerline_mass(t.density, self.strip.length, self.strip.width, n, i);
            let m = Point3::from(
                (acc.frames.rim_bottom[i].coords + acc.frames.rim_top[i].coords) * 0.5,
            );
            let m_prev = (hist.x_bottom[i] + hist.x_top[i]) * 0.5;
            let v_prev = (hist.v_bottom[i] + hist.v_top[i]) * 0.5;
            let d = (m.coords - m_prev) / h - v_prev;
            value += 0.5 * mass * d.norm_squared();
            let material = Point3::new(self.strip.crease_station(i), 0.0, 0.0);
            acc.add_point_gradient(e, &material, &m, &(d * (mass / h)), None);
            if let Some(hs) = acc.ws_hessian.as_deref_mut() {
                let j = point_jacobian(&m) / h;
                hs[e] += j.transpose() * j * mass;
            }
        }
        value
    }

    /// Gravity with the consistent mass: -sum_v m_v(c) g.x_v.
    fn gravity(&self, acc: &mut Accumulator) -> f64 {
        let n = self.strip.segments;
        let t = self.terms;
        let w = self.strip.width;
        let c = &acc.coords.crease_direction;
        let mut value = 0.0;
        for e in 0..n {
            let mass = element_mass(self.strip.length, w, n, c[e + 1] - c[e]);
            let verts = [(e, false), (e, true), (e + 1, false), (e + 1, true)];
            let mut dvalue = 0.0;
            for (a, &(j, top)) in verts.iter().enumerate() {
                let m_a: f64 = t.density * mass.k[a].iter().sum::<f64>();
                let dm_a: f64 = t.density * mass.dk_ddelta_c[a].iter().sum::<f64>();
                let x = if top {
                    acc.frames.rim_top[j]
                } else {
                    acc.frames.rim_bottom[j]
                };
                let mat = if top {
                    self.strip.material_top(j, c[j])
                } else {
                    self.strip.material_bottom(j, c[j])
                };
                value -= m_a * t.gravity.dot(&x.coords);
                dvalue -= dm_a * t.gravity.dot(&x.coords);
                acc.add_point_gradient(
                    e,
                    &mat,
                    &x,
                    &(-t.gravity * m_a),
                    Some((j, sliding_rate(w, top))),
                );
            }
            acc.add_local(e, -dvalue, dvalue);
        }
        value
    }

    /// One augmented-Lagrangian equality term; returns its value.
    fn equality(
        &self,
        acc: &mut Accumulator,
        cross: &mut Vec<(usize, usize, Mat8)>,
        eq: &Equality,
        lambda: &[f64],
        mu: f64,
    ) -> f64 {
        let n = self.strip.segments;
        let mut value = 0.0;
        match eq {
            Equality::Position {
                material_point,
                target,
                axes,
            } => {
                let e = self
                    .strip
                    .element_of(&acc.coords.crease_direction, material_point);
                let m = Point3::new(material_point.x, material_point.y, 0.0);
                let p = acc.frames.to_world(e, &m);
                let mut gamma = Vector3::zeros();
                let mut jac = point_jacobian(&p);
                for i in 0..3 {
                    if axes[i] {
                        let ci = p[i] - target[i];
                        value += -lambda[i] * ci + 0.5 * mu * ci * ci;
                        gamma[i] = mu * ci - lambda[i];
                    } else {
                        jac.row_mut(i).fill(0.0);
                    }
                }
                acc.add_point_gradient(e, &m, &p, &gamma, None);
                if let Some(hs) = acc.ws_hessian.as_deref_mut() {
                    hs[e] += jac.transpose() * jac * mu;
                }
            }
            Equality::Orientation {
                material_point,
                target,
            } => {
                let e = self
                    .strip
                    .element_of(&acc.coords.crease_direction, material_point);
                let r = acc.frames.rotation[e];
                for i in 0..3 {
                    let col = r.column(i).into_owned();
                    let ci = col - target.column(i);
                    let lam = Vector3::new(lambda[3 * i], lambda[3 * i + 1], lambda[3 * i + 2]);
                    value += -lam.dot(&ci) + 0.5 * mu * ci.norm_squared();
                    let mut unit = Vector3::zeros();
                    unit[i] = 1.0;
                    acc.add_direction_gradient(e, &unit, &col, &(ci * mu - lam));
                    if let Some(hs) = acc.ws_hessian.as_deref_mut() {
                        let j = direction_jacobian(&col);
                        hs[e] += j.transpose() * j * mu;
                    }
                }
            }
            Equality::Loop(kind) => {
                let f = acc.frames;
                let c = &acc.coords.crease_direction;
                let last = n - 1;
                // (point of element n-1, point of element 0, sign) triples: C = a - s b
                let pairs: [(Point3, Point3, Point3, Point3, f64, bool); 3] = match kind {
                    LoopKind::Orientable => [
                        (
                            f.rim_bottom[n],
                            self.strip.material_bottom(n, 0.0),
                            f.rim_bottom[0],
                            self.strip.material_bottom(0, c[0]),
                            1.0,
                            false,
                        ),
                        (
                            f.rim_top[n],
                            self.strip.material_top(n, 0.0),
                            f.rim_top[0],
                            self.strip.material_top(0, c[0]),
                            1.0,
                            false,
                        ),
                        (
                            Point3::from(f.normals[last]),
                            Point3::new(0.0, 0.0, 1.0),
                            Point3::from(f.normals[0]),
                            Point3::new(0.0, 0.0, 1.0),
                            1.0,
                            true,
                        ),
                    ],
                    LoopKind::NonOrientable => [
                        (
                            f.rim_bottom[n],
                            self.strip.material_bottom(n, 0.0),
                            f.rim_top[0],
                            self.strip.material_top(0, c[0]),
                            1.0,
                            false,
                        ),
                        (
                            f.rim_top[n],
                            self.strip.material_top(n, 0.0),
                            f.rim_bottom[0],
                            self.strip.material_bottom(0, c[0]),
                            1.0,
                            false,
                        ),
                        (
                            Point3::from(f.normals[last]),
                            Point3::new(0.0, 0.0, 1.0),
                            Point3::from(f.normals[0]),
                            Point3::new(0.0, 0.0, 1.0),
                            -1.0,
                            true,
                        ),
                    ],
                };
                let mut block_a = Mat8::zeros();
                let mut block_b = Mat8::zeros();
                let mut block_ab = Mat8::zeros();
                for (row, (pa, ma, pb, mb, sign, is_dir)) in pairs.iter().enumerate() {
                    let ci = pa.coords - pb.coords * *sign;
                    let lam =
                        Vector3::new(lambda[3 * row], lambda[3 * row + 1], lambda[3 * row + 2]);
                    value += -lam.dot(&ci) + 0.5 * mu * ci.norm_squared();
                    let gamma = ci * mu - lam;
                    let (ja, jb) = if *is_dir {
                        acc.add_direction_gradient(last, &ma.coords, &pa.coords, &gamma);
                        acc.add_direction_gradient(0, &mb.coords, &pb.coords, &(-gamma * *sign));
                        (
                            direction_jacobian(&pa.coords),
                            direction_jacobian(&pb.coords) * *sign,
                        )
                    } else {
                        acc.add_point_gradient(last, ma, pa, &gamma, None);
                        acc.add_point_gradient(0, mb, pb, &(-gamma * *sign), None);
                        (point_jacobian(pa), point_jacobian(pb) * *sign)
                    };
                    if acc.ws_hessian.is_some() {
                        block_a += ja.transpose() * ja * mu;
                        block_b += jb.transpose() * jb * mu;
                        block_ab -= ja.transpose() * jb * mu;
                    }
                }
                if let Some(hs) = acc.ws_hessian.as_deref_mut() {
                    hs[last] += block_a;
                    hs[0] += block_b;
                    cross.push((last, 0, block_ab));
                }
            }
        }
        value
    }

    /// Appendix C: gradient by suffix sums of element wrenches, O(n).
    fn gradient_adjoint(&self, ws: &mut Workspace, g: &mut [f64]) {
        let n = self.strip.segments;
        ws.suffix.clear();
        ws.suffix.resize(n + 1, Vec8::zeros());
        for e in (0..n).rev() {
            ws.suffix[e] = ws.suffix[e + 1] + ws.element_gradient[e];
        }
        for (a, xi) in ws.twists.iter().enumerate() {
            let s = ws.suffix[self.layout.first_element(a)];
            g[a] += xi.angular.dot(&s.fixed_rows::<3>(0)) + xi.linear.dot(&s.fixed_rows::<3>(3));
        }
        for k in 1..n {
            g[self.layout.c(k)] += ws.element_gradient[k - 1][7] + ws.element_gradient[k][6];
        }
    }

    /// Appendix A: explicit Jacobian of every recorded point, O(n^2). The local
    /// (sliding) terms are shared with the adjoint path.
    fn gradient_chain_rule(&self, q: &[f64], ws: &mut Workspace, g: &mut [f64]) {
        let n = self.strip.segments;
        let f = &ws.frames;
        let coords = &ws.coords;
        // prefix products Π_{i<=k} T_i are the element frames; derivative of T_k w.r.t.
        // psi_k / c_k as explicit 3x4 matrices, then ∂p/∂q = F_{k-1} ∂T_k (T_{k+1..e} p̄).
        for pg in &ws.point_gradients {
            let e = pg.element;
            for k in 1..=e {
                let station = self.strip.crease_station(k);
                let (c, psi) = (coords.crease_direction[k], coords.bending_angle[k]);
                // local point in frame k: T_{k+1..e} p̄ = F_k^{-1} F_e p̄
                let p_e = f.rotation[e] * pg.material
                    + if pg.direction {
                        Vector3::zeros()
                    } else {
                        f.translation[e]
                    };
                let p_k = f.rotation[k].transpose()
                    * (p_e
                        - if pg.direction {
                            Vector3::zeros()
                        } else {
                            f.translation[k]
                        });
                for (which, idx) in [(0, self.layout.c(k)), (1, self.layout.psi(k))] {
                    let (dr, dt) = crease_transform_derivative(station, c, psi, which);
                    let local = dr * p_k + if pg.direction { Vector3::zeros() } else { dt };
                    let dp = f.rotation[k - 1] * local;
                    g[idx] += pg.gamma.dot(&dp);
                }
            }
            if self.layout.floating {
                let w = Vector3::new(q[0], q[1], q[2]);
                let p_e = f.rotation[e] * pg.material
                    + if pg.direction {
                        Vector3::zeros()
                    } else {
                        f.translation[e]
                    };
                let base_r = exp_so3(&w);
                let p_0 = base_r.transpose()
                    * (p_e
                        - if pg.direction {
                            Vector3::zeros()
                        } else {
                            Vector3::new(q[3], q[4], q[5])
                        });
                for i in 0..3 {
                    // ∂exp(w)/∂w_i by central differences of Rodrigues' formula would be
                    // approximate; use the closed form skew(J_l e_i) exp(w).
                    let omega = left_jacobian_so3(&w).column(i).into_owned();
                    let dp = skew(&omega) * base_r * p_0;
                    g[i] += pg.gamma.dot(&dp);
                    if !pg.direction {
                        g[3 + i] += pg.gamma[i];
                    }
                }
            }
        }
        for k in 1..n {
            g[self.layout.c(k)] += ws.element_gradient[k - 1][7] + ws.element_gradient[k][6];
        }
    }

    /// Hessian of the objective: the Gauss-Newton part P^T (blockdiag G_e + cross
    /// blocks) P plus the geometric stiffness Σ_p γ_p · ∂²p/∂q_a∂q_b.
    ///
    /// Twist-twist entries: with S_m = Σ_{e>=m} G_e[tw,tw], the Gauss-Newton part is
    /// H_ab = ξ_a^T S_max(s_a,s_b) ξ_b. Geometric stiffness: for a before b in the chain
    /// (s_a < s_b, or the base translation before the base rotation)
    /// ∂²p/∂q_a∂q_b = Ω_a × ξ_b(p) (Jacobi identity), so with suffix sums P = Σ p γ^T and
    /// F = Σ γ over the elements b moves, Σ γ·(Ω_a × ξ_b(p)) =
    /// Ω_a · (P Ω_b - tr(P) Ω_b + v_b × F). The pair (c_k, psi_k) of one crease adds
    /// the terms of the c-dependence of the axis; a vertex sliding with c_j adds
    /// Ω_a · (s × γ). Both parts share one pass: O(n^2) 6-vector dot products written
    /// down contiguous columns, each unordered pair once, then one symmetrizing pass.
    fn assemble_hessian(&self, ws: &mut Workspace, h: &mut DMatrix<f64>) {
        let n = self.strip.segments;
        let lay = self.layout;
        let nq = lay.len();
        let base = lay.base_len();
        let psi0 = base + n - 1;
        let Workspace {
            twists,
            element_hessian,
            element_gradient,
            element_second,
            crease_extra,
            cross_blocks,
            hessian_suffix,
            scratch_first,
            scratch_u,
            scratch_psuf,
            scratch_twists,
            scratch_columns,
            scratch_left,
            scratch_right,
            ..
        } = ws;
        // first element moved by each coordinate, and the twists as 6-vectors
        scratch_first.clear();
        scratch_first.extend((0..nq).map(|a| lay.first_element(a)));
        let first = &*scratch_first;
        let xi = |a: usize| SVector::<f64, 6>::from(twists[a].to_array());
        let omega = |a: usize| twists[a].angular;

        // suffix sums: S (6x6 Gauss-Newton), P, F, M (geometric)
        hessian_suffix.clear();
        hessian_suffix.resize(n + 1, SMatrix::<f64, 6, 6>::zeros());
        scratch_psuf.clear();
        scratch_psuf.resize(
            n + 1,
            (Matrix3::zeros(), Vector3::zeros(), Vector3::zeros()),
        );
        for e in (0..n).rev() {
            hessian_suffix[e] = hessian_suffix[e + 1] + element_hessian[e].fixed_view::<6, 6>(0, 0);
            let (p, f, m) = scratch_psuf[e + 1];
            scratch_psuf[e] = (
                p + element_second[e].p_gamma,
                f + element_gradient[e].fixed_rows::<3>(3),
                m + element_gradient[e].fixed_rows::<3>(0),
            );
        }
        // U_b = S ξ_b + [P Ω_b - tr(P) Ω_b + v_b × F; 0] at s_b: H_ab = ξ_a · U_b for
        // s_a < s_b (the geometric part pairs with Ω_a only: zero-padded)
        scratch_u.clear();
        scratch_u.extend((0..nq).map(|b| {
            let sb = first[b];
            let (p, f, _) = &scratch_psuf[sb];
            let ob = omega(b);
            let w = p * ob - ob * p.trace() + twists[b].linear.cross(f);
            let mut u = hessian_suffix[sb] * xi(b);
            u[0] += w.x;
            u[1] += w.y;
            u[2] += w.z;
            u
        }));
        let u = &*scratch_u;
        // twist-local columns: c_m slides vertices of element m-1 (local column 7) and m
        // (6): the Gauss-Newton column of G plus the geometric Σ s × γ on the angular
        // part. For rows a with s_a <= m-1 both elements count; they share the row range
        // of the twist-twist pass of column c_m, so they join its vector.
        let local = |e: usize, col: usize| -> SVector<f64, 6> {
            let mut v: SVector<f64, 6> = element_hessian[e]
                .fixed_view::<6, 1>(0, 6 + col)
                .into_owned();
            let s = element_second[e].slide[col];
            v[0] += s.x;
            v[1] += s.y;
            v[2] += s.z;
            v
        };
        scratch_twists.clear();
        scratch_twists.extend(twists.iter().map(|t| t.to_array()));
        scratch_columns.clear();
        scratch_columns.extend((0..nq).map(|b| {
            let mut v = u[b];
            if b >= base && b < psi0 {
                let m = b - base + 1;
                v += local(m - 1, 1) + local(m, 0);
            }
            let mut out = [0.0; 6];
            out.copy_from_slice(v.as_slice());
            out
        }));
        let xs = &*scratch_twists;
        let hs = h.as_mut_slice();
        let dot = |a: usize, v: &SVector<f64, 6>| -> f64 { dot6(&xs[a], v.as_slice()) };
        for b in 0..nq {
            let sb = first[b];
            // rows strictly before b in the chain: base, c_1..c_{sb-1}, psi_1..psi_{sb-1}
            if sb > 0 {
                let m = sb - 1;
                let ub = &scratch_columns[b];
                let col = &mut hs[b * nq..(b + 1) * nq];
                for range in [0..base, base..base + m, psi0..psi0 + m] {
                    for (h_ab, x_a) in col[range.clone()].iter_mut().zip(&xs[range]) {
                        *h_ab += dot6(x_a, ub);
                    }
                }
            }
        }
        // same-element pairs: Gauss-Newton ξ_a^T S ξ_b (each unordered pair once, a <= b)
        // plus the geometric terms of the base rotation and of each crease
        for b in 0..nq {
            let sb = first[b];
            let gn_b = hessian_suffix[sb] * xi(b);
            let same = if sb == 0 { 0..base } else { 0..0 };
            for a in same.chain(if sb > 0 {
                [lay.c(sb), lay.psi(sb)].into_iter().take(2)
            } else {
                [0, 0].into_iter().take(0)
            }) {
                if a <= b {
                    hs[a + b * nq] += xi(a).dot(&gn_b);
                }
            }
        }
        if base == 6 {
            // rotation-vector coordinates of the base: exact at w = 0, symmetrized
            // elsewhere (the translation comes before the rotation: no t-w terms)
            for j in 0..3 {
                for i in 0..=j {
                    let wi =
                        u[i].fixed_rows::<3>(0) - (hessian_suffix[0] * xi(i)).fixed_rows::<3>(0);
                    let wj =
                        u[j].fixed_rows::<3>(0) - (hessian_suffix[0] * xi(j)).fixed_rows::<3>(0);
                    hs[i + j * nq] += 0.5 * (omega(i).dot(&wj) + omega(j).dot(&wi));
                }
            }
        }
        for k in 1..n {
            let (ic, ip) = (lay.c(k), lay.psi(k));
            let (a_k, dd_world, domega_world) = crease_extra[k];
            let (_, f, m) = &scratch_psuf[k];
            let arm = m - a_k.cross(f);
            let gn = |b: usize| hessian_suffix[k] * xi(b);
            let geo = |b: usize| u[b].fixed_rows::<3>(0) - gn(b).fixed_rows::<3>(0);
            hs[ip + ip * nq] += omega(ip).dot(&geo(ip));
            hs[ic + ip * nq] += omega(ip).dot(&geo(ic)) + dd_world.dot(&arm);
            hs[ic + ic * nq] += omega(ic).dot(&geo(ic)) + domega_world.dot(&arm);
        }
        // twist-local entries of rows with s_a == m (c_m itself and psi_m)
        for m in 1..n {
            let cm = lay.c(m);
            let only_m = local(m, 0);
            // c_m with itself: twice Ω·(s×γ) and twice ξ·G[tw, c_m], plus G's local
            // diagonal from both elements
            let s_self = element_second[m].slide[0];
            let g_self: SVector<f64, 6> = element_hessian[m].fixed_view::<6, 1>(0, 6).into_owned();
            hs[cm + cm * nq] += element_hessian[m - 1][(7, 7)]
                + element_hessian[m][(6, 6)]
                + 2.0 * omega(cm).dot(&s_self)
                + 2.0 * dot(cm, &g_self);
            let ip = lay.psi(m);
            hs[cm + ip * nq] += dot(ip, &only_m);
            if m + 1 < n {
                let cn = lay.c(m + 1);
                hs[cm + cn * nq] += element_hessian[m][(6, 7)];
            }
        }
        // cross blocks B between elements e1, e2 (loop closure): H += M + M^T with
        // M_ab = P_e1(a)^T B P_e2(b). Column b of P_e2 is zero unless b moves element e2
        // (for e2 = 0 only the base and c_1), so only those columns are visited: O(N)
        // per block instead of O(N^2). M_ab goes to (a, b) and the symmetrizing pass
        // below adds M_ba from (b, a); the diagonal, which that pass keeps as is, takes
        // both halves here.
        for (e1, e2, block) in cross_blocks.iter() {
            let p = |e: usize, a: usize| -> Vec8 {
                let mut v = Vec8::zeros();
                if first[a] <= e {
                    v.fixed_rows_mut::<6>(0).copy_from(&xi(a));
                }
                if a >= base && a < psi0 {
                    let k = a - base + 1;
                    if k == e {
                        v[6] = 1.0;
                    } else if k == e + 1 {
                        v[7] = 1.0;
                    }
                }
                v
            };
            scratch_right.clear();
            scratch_right.extend(
                (0..nq)
                    .map(|b| (b, p(*e2, b)))
                    .filter(|(_, v)| v.iter().any(|x| *x != 0.0))
                    .map(|(b, v)| (b, block * v)),
            );
            scratch_left.clear();
            scratch_left.extend((0..nq).map(|a| p(*e1, a)));
            for (b, right_b) in scratch_right.iter() {
                let col = &mut hs[b * nq..(b + 1) * nq];
                for (h_ab, left_a) in col.iter_mut().zip(scratch_left.iter()) {
                    *h_ab += left_a.dot(right_b);
                }
                col[*b] += scratch_left[*b].dot(right_b);
            }
        }
        // every unordered pair was written once at (a, b) or (b, a): H = A + A^T - diag,
        // in 8 x 8 tiles so that the transposed reads stay in a few cache lines
        const TILE: usize = 8;
        for jb in (0..nq).step_by(TILE) {
            for ib in (jb..nq).step_by(TILE) {
                for j in jb..(jb + TILE).min(nq) {
                    for i in ib.max(j + 1)..(ib + TILE).min(nq) {
                        let v = hs[i + j * nq] + hs[j + i * nq];
                        hs[i + j * nq] = v;
                        hs[j + i * nq] = v;
                    }
                }
            }
        }
    }
}

/// ∂T_k/∂c_k (which = 0) or ∂T_k/∂psi_k (which = 1) as (dR, dt).
fn crease_transform_derivative(station: f64, c: f64, psi: f64, which: usize) -> (Matrix3, Vector3) {
    let (r, _) = crease_transform(station, c, psi);
    let d = crease_axis(c);
    let omega = if which == 1 {
        d
    } else {
        let dd = crease_axis_derivative(c);
        dd * psi.sin() + d.cross(&dd) * (1.0 - psi.cos())
    };
    let dr = skew(&omega) * r;
    let p = Vector3::new(station, 0.0, 0.0);
    (dr, -dr * p)
}

/// Collects per-element generalized forces (and GN blocks, and recorded points).
struct Accumulator<'b> {
    strip: &'b Strip,
    ws_gradient: &'b mut Vec<Vec8>,
    ws_hessian: Option<&'b mut Vec<Mat8>>,
    points: Option<&'b mut Vec<PointGradient>>,
    second: Option<&'b mut Vec<SecondOrder>>,
    frames: &'b Frames,
    coords: &'b Coordinates,
}

impl Accumulator<'_> {
    /// dF/dp = gamma at world point p of element e (material point `material`); when
    /// `vertex` = Some((j, du/dc)) the point is the rim vertex on crease j and slides
    /// along the rim with c_j.
    fn add_point_gradient(
        &mut self,
        e: usize,
        material: &Point3,
        p: &Point3,
        gamma: &Vector3,
        vertex: Option<(usize, f64)>,
    ) {
        let g = &mut self.ws_gradient[e];
        let moment = p.coords.cross(gamma);
        g[0] += moment.x;
        g[1] += moment.y;
        g[2] += moment.z;
        g[3] += gamma.x;
        g[4] += gamma.y;
        g[5] += gamma.z;
        if let Some(second) = self.second.as_deref_mut() {
            second[e].p_gamma += p.coords * gamma.transpose();
        }
        if let Some((j, du)) = vertex {
            let n = self.strip.segments;
            if j != 0 && j != n {
                let s = self.frames.rotation[e].column(0) * du;
                let col = if j == e { 0 } else { 1 };
                g[6 + col] += s.dot(gamma);
                if let Some(second) = self.second.as_deref_mut() {
                    second[e].slide[col] += s.cross(gamma);
                }
            }
        }
        if let Some(points) = self.points.as_deref_mut() {
            points.push(PointGradient {
                element: e,
                material: material.coords,
                gamma: *gamma,
                direction: false,
            });
        }
        let _ = self.coords;
    }

    /// dF/dd = gamma for the world direction d = R_e * `material_dir` of element e.
    fn add_direction_gradient(
        &mut self,
        e: usize,
        material_dir: &Vector3,
        d: &Vector3,
        gamma: &Vector3,
    ) {
        let g = &mut self.ws_gradient[e];
        let moment = d.cross(gamma);
        g[0] += moment.x;
        g[1] += moment.y;
        g[2] += moment.z;
        if let Some(second) = self.second.as_deref_mut() {
            second[e].p_gamma += d * gamma.transpose();
        }
        if let Some(points) = self.points.as_deref_mut() {
            points.push(PointGradient {
                element: e,
                material: *material_dir,
                gamma: *gamma,
                direction: true,
            });
        }
    }

    /// Explicit derivative w.r.t. c_e (col 6) and c_{e+1} (col 7) of element e.
    fn add_local(&mut self, e: usize, d_ce: f64, d_ce1: f64) {
        let n = self.strip.segments;
        if e != 0 {
            self.ws_gradient[e][6] += d_ce;
        }
        if e + 1 != n {
            self.ws_gradient[e][7] += d_ce1;
        }
    }
}

impl Objective<'_> {
    /// Residual C of an equality at the state in `ws` (after `prepare`/`evaluate`),
    /// written to `out[..eq.rows()]`. Position rows in m, rotation rows dimensionless.
    pub fn equality_residual(&self, ws: &Workspace, eq: &Equality, out: &mut [f64]) {
        let n = self.strip.segments;
        let f = &ws.frames;
        let c = &ws.coords.crease_direction;
        match eq {
            Equality::Position {
                material_point,
                target,
                axes,
            } => {
                let e = self.strip.element_of(c, material_point);
                let p = f.to_world(e, &Point3::new(material_point.x, material_point.y, 0.0));
                for i in 0..3 {
                    out[i] = if axes[i] { p[i] - target[i] } else { 0.0 };
                }
            }
            Equality::Orientation {
                material_point,
                target,
            } => {
                let e = self.strip.element_of(c, material_point);
                for i in 0..3 {
                    for r in 0..3 {
                        out[3 * i + r] = f.rotation[e][(r, i)] - target[(r, i)];
                    }
                }
            }
            Equality::Loop(kind) => {
                let (a, b, sign) = match kind {
                    LoopKind::Orientable => (
                        (f.rim_bottom[n], f.rim_top[n]),
                        (f.rim_bottom[0], f.rim_top[0]),
                        1.0,
                    ),
                    LoopKind::NonOrientable => (
                        (f.rim_bottom[n], f.rim_top[n]),
                        (f.rim_top[0], f.rim_bottom[0]),
                        -1.0,
                    ),
                };
                let rows = [a.0 - b.0, a.1 - b.1, f.normals[n - 1] - f.normals[0] * sign];
                for (i, r) in rows.iter().enumerate() {
                    out[3 * i..3 * i + 3].copy_from_slice(r.as_slice());
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ribbon::params::LoopKind;
    use rand::{Rng, SeedableRng};

    /// A random but smooth-enough test problem: every term active, history perturbed so
    /// no vertex sits exactly on a resampling kink.
    pub(super) fn problem(
        n: usize,
        floating: bool,
        kinetic: KineticModel,
        seed: u64,
    ) -> (Strip, StepTerms, RimHistory, Vec<f64>, Pose) {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let strip = Strip {
            length: 1.0,
            width: 0.08,
            segments: n,
        };
        let base = Pose::new(Vector3::new(0.1, 0.2, -0.1), Vector3::new(0.3, -0.2, 0.5));
        // previous state: random coordinates, random velocities
        let mut prev = Coordinates::flat(n, base);
        for k in 1..n {
            prev.crease_direction[k] = rng.random_range(-0.3..0.3);
            prev.bending_angle[k] = rng.random_range(-0.4..0.4);
        }
        let mut frames = Frames::default();
        reconstruct(&strip, &prev, &mut frames);
        let mut history = RimHistory::at_rest(&strip, &prev.crease_direction, &frames);
        for v in history.v_bottom.iter_mut().chain(history.v_top.iter_mut()) {
            *v = Vector3::new(
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
            );
        }
        let equalities = vec![
            Equality::Position {
                material_point: Point2::new(0.63, 0.01),
                target: Point3::new(0.2, 0.3, 0.1),
                axes: [true, false, true],
            },
            Equality::Orientation {
                material_point: Point2::new(0.97, 0.0),
                target: *nalgebra::Rotation3::new(Vector3::new(0.2, 0.1, 0.3)).matrix(),
            },
            Equality::Loop(LoopKind::NonOrientable),
        ];
        let multipliers = equalities
            .iter()
            .map(|e| (0..e.rows()).map(|_| rng.random_range(-1.0..1.0)).collect())
            .collect();
        let terms = StepTerms {
            h: 0.01,
            kinetic,
            density: 0.3,
            // 0.02 J with a clamp-like weight on crease 1 (any positive weights work)
            crease_bending: (0..=n)
                .map(|k| match k {
                    0 => 0.0,
                    1 => 0.02 * n as f64 * 0.08 / 1.5,
                    k if k == n => 0.0,
                    _ => 0.02 * n as f64 * 0.08,
                })
                .collect(),
            crease_regularizer: 0.1,
            gravity: Vector3::new(0.0, 0.0, -9.81),
            normal_guides: vec![NormalGuide {
                material_point: Point2::new(0.41, -0.02),
                target: Vector3::new(0.0, 0.6, 0.8),
                stiffness: 3.0,
            }],
            forces: vec![PointForce {
                material_point: Point2::new(0.27, 0.03),
                force: Vector3::new(0.5, -1.0, 2.0),
            }],
            equalities,
            multipliers,
            end_crease_multipliers: [-0.3, 0.0],
            penalty: 50.0,
            crease_bound: 0.95 * 2.0 / (0.08 * n as f64),
        };
        // current q: near prev, perturbed
        let layout = Layout {
            segments: n,
            floating,
        };
        let mut q = vec![0.0; layout.len()];
        let mut cur = prev.clone();
        for k in 1..n {
            cur.crease_direction[k] += rng.random_range(-0.05..0.05);
            cur.bending_angle[k] += rng.random_range(-0.1..0.1);
        }
        // make the end-crease inequality active
        cur.crease_direction[n - 1] = 0.95 * 2.0 / (0.08 * n as f64) + 0.01;
        cur.base = Pose::new(
            Vector3::new(0.12, 0.18, -0.09),
            Vector3::new(0.31, -0.22, 0.48),
        );
        layout.pack(&cur, &base, &mut q);
        (strip, terms, history, q, base)
    }

    fn check_gradient(n: usize, floating: bool, kinetic: KineticModel, mode: GradientMode) {
        let (strip, terms, history, q, base) = problem(n, floating, kinetic, 11 + n as u64);
        let obj = Objective::new(strip, floating, &terms, &history, base);
        let mut ws = Workspace::default();
        let mut g = vec![0.0; q.len()];
        let f0 = obj.evaluate(&q, &mut ws, Some((&mut g, mode)), None);
        assert!(f0.is_finite());
        let h = 1e-6;
        let mut worst: f64 = 0.0;
        let scale = g.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
        for a in 0..q.len() {
            let mut qp = q.clone();
            qp[a] += h;
            let fp = obj.evaluate(&qp, &mut ws, None, None);
            qp[a] -= 2.0 * h;
            let fm = obj.evaluate(&qp, &mut ws, None, None);
            let fd = (fp - fm) / (2.0 * h);
            let err = (fd - g[a]).abs() / scale;
            worst = worst.max(err);
            // central differences: O(h^2) truncation ~ 1e-12 relative, round-off
            // ~ eps |f| / h ~ 1e-10 relative to the gradient scale.
            assert!(
                err < 1e-6,
                "coordinate {a} ({mode:?}, {kinetic:?}): analytic {} vs fd {fd}",
                g[a]
            );
        }
        assert!(worst < 1e-6);
    }

    #[test]
    fn adjoint_gradient_matches_finite_differences_fixed_base() {
        check_gradient(9, false, KineticModel::Full, GradientMode::Adjoint);
    }
    #[test]
    fn adjoint_gradient_matches_finite_differences_floating_base() {
        check_gradient(8, true, KineticModel::Full, GradientMode::Adjoint);
    }
    #[test]
    fn chain_rule_gradient_matches_finite_differences() {
        check_gradient(8, true, KineticModel::Full, GradientMode::ChainRule);
        check_gradient(7, false, KineticModel::Lumped, GradientMode::ChainRule);
    }
    #[test]
    fn lumped_and_quasi_static_gradients_match_finite_differences() {
        check_gradient(10, true, KineticModel::Lumped, GradientMode::Adjoint);
        check_gradient(6, false, KineticModel::QuasiStatic, GradientMode::Adjoint);
    }

    #[test]
    fn adjoint_and_chain_rule_agree() {
        let (strip, terms, history, q, base) = problem(30, true, KineticModel::Full, 5);
        let obj = Objective::new(strip, true, &terms, &history, base);
        let mut ws = Workspace::default();
        let mut ga = vec![0.0; q.len()];
        let mut gc = vec![0.0; q.len()];
        obj.evaluate(&q, &mut ws, Some((&mut ga, GradientMode::Adjoint)), None);
        obj.evaluate(&q, &mut ws, Some((&mut gc, GradientMode::ChainRule)), None);
        let scale = ga.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
        for (a, c) in ga.iter().zip(&gc) {
            assert!((a - c).abs() < 1e-10 * scale, "{a} vs {c}");
        }
    }

    /// Hessian against central differences of the analytic gradient.
    fn check_hessian(
        terms: &StepTerms,
        history: &RimHistory,
        strip: Strip,
        base: Pose,
        q: &[f64],
        floating: bool,
        coords: &[usize],
    ) {
        let obj = Objective::new(strip, floating, terms, history, base);
        let mut ws = Workspace::default();
        let mut hm = DMatrix::zeros(q.len(), q.len());
        let mut g = vec![0.0; q.len()];
        obj.evaluate(
            q,
            &mut ws,
            Some((&mut g, GradientMode::Adjoint)),
            Some(&mut hm),
        );
        assert!(
            (&hm - hm.transpose()).amax() <= 1e-12 * hm.amax(),
            "symmetric"
        );
        // columns of the finite-difference Hessian, symmetrized (the standard remedy
        // for the O(h) asymmetry of differenced gradients)
        let step = 1e-6;
        let nq = q.len();
        let mut fd = DMatrix::zeros(nq, nq);
        for &b in coords {
            let mut qp = q.to_vec();
            qp[b] += step;
            let mut gp = vec![0.0; nq];
            obj.evaluate(&qp, &mut ws, Some((&mut gp, GradientMode::Adjoint)), None);
            qp[b] -= 2.0 * step;
            let mut gm = vec![0.0; nq];
            obj.evaluate(&qp, &mut ws, Some((&mut gm, GradientMode::Adjoint)), None);
            for &a in coords {
                fd[(a, b)] = (gp[a] - gm[a]) / (2.0 * step);
            }
        }
        let fd = (&fd + fd.transpose()) * 0.5;
        for &b in coords {
            for &a in coords {
                // truncation ~ h^2 times the third derivative, round-off ~ eps |g| / h
                // ~ 1e-10 |g|; 1e-6 of the largest entry is far above both and far below
                // any missing term.
                assert!(
                    (fd[(a, b)] - hm[(a, b)]).abs() < 1e-6 * hm.amax(),
                    "H[{a},{b}] = {} vs fd {}",
                    hm[(a, b)],
                    fd[(a, b)]
                );
            }
        }
    }

    #[test]
    fn newton_hessian_matches_finite_differences_quasi_static() {
        // no kinetic term, no gravity: every term's Hessian is exact (bending unclamped
        // for c^2 < 1/3), in every coordinate including crease directions
        let (strip, mut terms, history, mut q, base) =
            problem(7, true, KineticModel::QuasiStatic, 3);
        terms.gravity = Vector3::zeros();
        let lay = Layout {
            segments: 7,
            floating: true,
        };
        q[lay.c(6)] = 0.05;
        q[0..3].copy_from_slice(&[0.0; 3]); // base rotation at its reference: exact curvature
        terms.end_crease_multipliers = [0.0, 0.0];
        let all: Vec<usize> = (0..lay.len()).collect();
        check_hessian(&terms, &history, strip, base, &q, true, &all);
    }

    #[test]
    fn newton_hessian_matches_finite_differences_with_inertia_and_gravity() {
        // with the full kinetic term and gravity the mass matrix depends on c, a term
        // the Hessian leaves out: compare in the bending-angle and base coordinates
        let (strip, terms, history, mut q, base) = problem(7, true, KineticModel::Full, 4);
        let lay = Layout {
            segments: 7,
            floating: true,
        };
        q[0..3].copy_from_slice(&[0.0; 3]);
        let coords: Vec<usize> = (0..6).chain(lay.psi(1)..lay.len()).collect();
        check_hessian(&terms, &history, strip, base, &q, true, &coords);
        let (strip, terms, history, q, base) = problem(9, false, KineticModel::Lumped, 8);
        let lay = Layout {
            segments: 9,
            floating: false,
        };
        let coords: Vec<usize> = (lay.psi(1)..lay.len()).collect();
        check_hessian(&terms, &history, strip, base, &q, false, &coords);
    }
}
