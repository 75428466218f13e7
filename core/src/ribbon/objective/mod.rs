//! The implicit-Euler objective of one ribbon step (Pan et al. sec. 4, 5) over the
//! generalized coordinates q = <w, t | c_1..c_{n-1} | psi_1..psi_{n-1}>, with
//!
//! - its gradient in adjoint mode, O(n) (appendix C): every term contributes a wrench
//!   on the element carrying its point, and the gradient of coordinate q_a is the twist
//!   of q_a paired with the suffix sum of wrenches of the elements it moves;
//! - the chain-rule gradient of appendix A as the baseline: the full Jacobian ∇x_j,
//!   O(n^2);
//! - its Hessian, assembled in O(n^2) from 8x8 per-element blocks (6 twist + 2 local
//!   crease sliding) and the same suffix sums: the Gauss-Newton part of the
//!   least-squares terms, the geometric stiffness of the rotation chain and the
//!   coupling of the crease-dependent consistent mass (appendix B) with the motion.
//!   Exact (checked against finite differences in every block, inertia and gravity on)
//!   with two documented departures: the bending block of a crease with c^2 > 1/3 is
//!   projected onto the PSD cone, and the base-rotation block is symmetrized away from
//!   w = 0 (a floating base restarts every step at w = 0, where it is exact).
//!
//! Why twists: element E_e is the rigid image of its flat trapezoid under
//! T_0 T_1 ... T_e, so a change of T_k (k <= e) moves E_e rigidly. The velocity of a
//! point of E_e under dq_a is `ξ_a(p)` for every coordinate a whose transform precedes
//! e, plus, for a rim vertex on crease k, the sliding of its material position along
//! the rim when c_k changes (eq. 2).
//!
//! Files: [`layout`] (where each coordinate lives in q), [`kinetic`] (the rim history,
//! the resampling operator R and the kinetic term), [`terms`] (the other terms and the
//! step's data), `accumulate` (per-element generalized forces), `gradient` (twists,
//! adjoint and chain rule), `hessian` (the dense Newton matrix).

mod accumulate;
pub mod chain;
mod contact_candidates;
mod contact_ccd;
mod contact_self;
pub mod contact_terms;
#[cfg(test)]
mod contact_tests;
mod gradient;
mod hessian;
pub mod kinetic;
pub mod layout;
pub mod terms;
#[cfg(test)]
mod tests;

use nalgebra::{DMatrix, SMatrix, SVector};

use super::params::KineticModel;
use super::reconstruct::{reconstruct, Coordinates, Frames, Strip};
use crate::geometry::{Matrix3, Pose, Twist, Vector3};
use accumulate::{Accumulator, PointGradient, SecondOrder};

use contact_terms::{CellGeometry, Found, PairFinder};
pub use contact_terms::{ContactTerms, ContactWorkspace, FrictionLag, PairTerm};
pub use gradient::GradientMode;
pub(crate) use kinetic::interpolate;
pub use kinetic::RimHistory;
pub use layout::Layout;
pub use terms::{Equality, NormalGuide, ObjectiveParts, PointForce, StepTerms};

type Vec8 = SVector<f64, 8>;
type Mat8 = SMatrix<f64, 8, 8>;
type Mat3x8 = SMatrix<f64, 3, 8>;
type Mat9x8 = SMatrix<f64, 9, 8>;

/// A loop closure's term mu/2 |J_last y_{n-1} - J_first y_0|^2 in the Newton matrix
/// (y_e = (twist, c_e, c_{e+1}) of element e; nine rows: two rim points and the normal,
/// 3 each): its Gauss-Newton part is mu J_last^T J_last on element n-1's block,
/// mu J_first^T J_first on element 0's and the cross block B = -mu J_last^T J_first. The
/// chain solver factorizes the chain without the two diagonal blocks and adds the
/// closure back as a positive rank-9 update (see `chain::ChainModel::factor`).
#[derive(Clone, Copy, Debug)]
pub struct ClosureRows {
    pub last: Mat9x8,
    pub first: Mat9x8,
    /// mu, J/m^2 (the position rows; the normal's rows are dimensionless).
    pub penalty: f64,
}

/// A cross block (e1, e2, B) of the Newton matrix between two elements and, for a loop
/// closure, its rows.
pub(crate) type CrossBlock = (usize, usize, Mat8, Option<ClosureRows>);

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
    cross_blocks: Vec<CrossBlock>,
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
    /// The contact terms' buffers and what the last evaluation found.
    pub contact: ContactWorkspace,
    /// The line search's collision checks' buffers (`contact_ccd`).
    ccd: contact_ccd::CcdScratch,
    /// The pairs the last checked line-search path admits, and whether the next
    /// evaluation may read them instead of the broad phase (it lies on that path).
    candidates: contact_candidates::Candidates,
    use_candidates: bool,
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
    /// Contact inside the step (docs/contact_barrier.md), when the scene has it.
    pub contact: Option<&'a ContactTerms>,
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
            contact: None,
        }
    }

    /// The same objective with the contact terms `contact`.
    pub fn with_contact(mut self, contact: Option<&'a ContactTerms>) -> Self {
        self.contact = contact;
        self
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
        self.prepare(q, ws);
        let record_points = matches!(gradient, Some((_, GradientMode::ChainRule)));
        let mut grad_out = gradient;
        if let Some((g, _)) = grad_out.as_mut() {
            g.iter_mut().for_each(|x| *x = 0.0);
        }
        let forces = grad_out.is_some() || second_order;
        ws.parts = self.point_terms(ws, forces, second_order, record_points);
        // terms written directly in (c, psi): bending, regularizer, end-crease bound
        let (coords, parts) = (&ws.coords, &mut ws.parts);
        self.crease_terms(coords, parts, grad_out.as_mut().map(|(g, _)| &mut **g));
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

    /// Every term that acts through points and directions of the elements (kinetic,
    /// gravity, normal guiding, point forces, equalities): their values, and, with
    /// `forces`, their per-element generalized forces (and second-order data when
    /// `second_order`) collected in `ws`.
    fn point_terms(
        &self,
        ws: &mut Workspace,
        forces: bool,
        second_order: bool,
        record_points: bool,
    ) -> ObjectiveParts {
        let n = self.strip.segments;
        ws.element_gradient.clear();
        ws.element_gradient.resize(n, Vec8::zeros());
        if second_order {
            ws.element_hessian.clear();
            ws.element_hessian.resize(n, Mat8::zeros());
            ws.element_second.clear();
            ws.element_second.resize(n, SecondOrder::default());
        }
        ws.cross_blocks.clear();
        ws.point_gradients.clear();
        let mut parts = ObjectiveParts::default();
        let mut acc = Accumulator {
            strip: &self.strip,
            ws_gradient: &mut ws.element_gradient,
            ws_hessian: second_order.then_some(&mut ws.element_hessian),
            points: record_points.then_some(&mut ws.point_gradients),
            second: second_order.then_some(&mut ws.element_second),
            frames: &ws.frames,
            coords: &ws.coords,
            forces,
        };

        // --- kinetic term (sec. 4) ---
        let t = self.terms;
        match t.kinetic {
            KineticModel::Full => {
                parts.kinetic = self.kinetic_full(
                    &mut acc,
                    [&mut ws.residual_bottom, &mut ws.residual_top],
                    [&mut ws.slope_bottom, &mut ws.slope_top],
                );
            }
            KineticModel::Lumped => {
                parts.kinetic = self.kinetic_lumped(&mut acc);
            }
            KineticModel::QuasiStatic => {}
        }

        // --- gravity: V = -rho g^T M X with the consistent M (row sums) ---
        if t.gravity.norm_squared() > 0.0 {
            parts.gravity = self.gravity(&mut acc);
        }
        parts.external = self.normal_guides_and_forces(&mut acc);

        // --- equality constraints: augmented Lagrangian -λ.C + μ/2 |C|^2 ---
        for (eq, lambda) in t.equalities.iter().zip(&t.multipliers) {
            parts.constraint +=
                self.equality(&mut acc, &mut ws.cross_blocks, eq, lambda, t.penalty);
        }
        let candidates = &ws.candidates;
        let find = |acc: &mut Accumulator, geo: &CellGeometry, found: &mut Found| {
            if let Some(ct) = self.contact {
                self.candidate_pairs(acc, ct, geo, candidates, found);
            }
        };
        let cached: Option<PairFinder> = ws.use_candidates.then_some(&find);
        parts.contact = self.contact_terms(&mut acc, &mut ws.contact, cached);
        parts
    }
}
