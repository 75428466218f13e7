//! Ribbon parameters (Pan et al. sec. 3-5). SI units throughout.

use crate::geometry::Pose;

/// Kinetic term of the implicit-Euler objective.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum KineticModel {
    /// Consistent FEM mass of each trapezoid element with material-space resampling R
    /// (paper sec. 4, eq. 4, appendix B). The default.
    Full,
    /// All mass lumped on the centerline (paper sec. 6): cheaper, misses the rotation
    /// about the centerline (fig. 11).
    Lumped,
    /// No kinetic term: each step finds the static equilibrium (rest shapes).
    QuasiStatic,
}

/// Which optimizer solves one implicit-Euler step.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SolverKind {
    /// Ours, dense: projected Newton on the exact Hessian of the objective, assembled
    /// densely and factorized by a dense Cholesky (faer), O(n^3) per iteration; the
    /// baseline of [`SolverKind::Chain`], which takes the same iterates.
    GaussNewton,
    /// The paper's: L-BFGS-B inside the augmented Lagrangian (algorithm 2).
    Lbfgsb,
    /// Ours, the default: the same projected Newton method (line search, held
    /// variables, damping, adaptive penalty) with the Newton system solved along the
    /// chain in O(n)
    /// (`ribbon::objective::chain`, docs/ribbon_chain_solver.md); a loop closure's
    /// coupling of the two ends by a Woodbury step on top of the sweep.
    Chain,
    /// Ours: a trust-region projected Newton method (TRON / LANCELOT family) on the same
    /// O(n) chain model: the end crease |c_{n-1}| <= Δc_max held exactly (a slab, no
    /// augmented-Lagrangian term), an l-infinity region in the unknowns' own units, a
    /// generalized Cauchy point, undamped chain sweeps on the free set and directions
    /// of negative curvature where they meet it (`optim::trust_region`,
    /// docs/ribbon_chain_solver.md).
    TrustRegion,
    /// Ours (issue 47): a primal-dual interior-point method on the same O(n) chain
    /// model, the crease bounds and the end crease as barrier terms with their duals
    /// (`optim::interior_point`, docs/ribbon_chain_solver.md).
    InteriorPoint,
}

/// How a clamp weights the creases next to it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ClampRule {
    /// Every crease has d_k = l/n (Pan et al.: a clamp acts half an element away from
    /// its point, first order in n).
    Paper,
    /// The crease next to a clamp at s_c has d_k = |m - s_c|, m the midpoint of its
    /// free neighbour element (second order in n).
    DualLength,
    /// The first two creases beside a clamp share the dual lengths of
    /// [`ClampRule::DualLength`] so that their sum also integrates a linearly varying
    /// curvature exactly from the clamp on (second order in n, with a ~10x smaller
    /// constant at end clamps). The default.
    #[default]
    MomentMatched,
}

/// How the first element (E_0) is placed.
#[derive(Clone, Debug, PartialEq)]
pub enum BaseMode {
    /// T_0 is prescribed: `world_from_base` at every step. `driven_by` names a handle
    /// index whose target is T_0 (a gripper holding the first element), or `None` for
    /// a fixed end at `pose`.
    Prescribed {
        pose: Pose,
        driven_by: Option<usize>,
    },
    /// T_0 is free: rotation vector w (rad) and translation t (m) are unknowns, starting
    /// at `initial`.
    Floating { initial: Pose },
}

/// Loop closure (paper sec. 5.1).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LoopKind {
    /// x_0 = x_n, y_0 = y_n, n_0 = n_{n-1}.
    Orientable,
    /// Moebius: x_0 = y_n, y_0 = x_n, n_0 = -n_{n-1}.
    NonOrientable,
}

/// Solver settings of one ribbon.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SolverSettings {
    pub kind: SolverKind,
    /// Inner convergence: projected-gradient infinity norm relative to its value at the
    /// start of the step (dimensionless). Default 1e-6.
    pub tolerance: f64,
    /// Inner iteration limit per augmented-Lagrangian round.
    pub max_iterations: u32,
    /// Augmented-Lagrangian penalty mu (paper: 1e3), in J/m^2 for position constraints:
    /// the L-BFGS-B baseline keeps it fixed; our solver starts from it and raises it up
    /// to 100x where an outer round stalls (see `ribbon::step`).
    pub penalty: f64,
    /// Outer stop: ||q_k - q_{k-1}||_inf below this (paper: 1e-4).
    pub outer_tolerance: f64,
    /// Outer round limit.
    pub max_outer_iterations: u32,
    /// Outer stop when every constraint holds to this: position rows in m, rotation
    /// rows dimensionless. Default 1e-6.
    pub constraint_tolerance: f64,
    /// Start each step from q + (q - q_previous) (linear extrapolation) instead of q.
    pub extrapolate: bool,
    /// Issue 47 variants of [`SolverKind::Chain`] (each off by default; the other
    /// kinds ignore them; docs/ribbon_chain_solver.md, 2026-12-07).
    pub chain_variant: ChainVariant,
}

/// Variants of the damped projected Newton method on the chain model (issue 47),
/// selectable for measurement; all off is the default solver.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ChainVariant {
    /// Hold the end crease |c_{n-1}| = |Σ z_k| <= Δc_max exactly (the trust region's
    /// slab: projection onto box and slab, its face held in the Newton step) instead
    /// of by the augmented-Lagrangian term (no mu in the Newton matrix there).
    pub end_crease_exact: bool,
    /// Saddle-free pivots: where the chain's sweep meets a 2x2 pivot that is not
    /// positive definite (or nearly singular), its eigenvalues are replaced by their
    /// absolute values (floored) instead of raising the global shift.
    pub saddle_free: bool,
    /// A line-search cut (alpha < 1) leaves the Levenberg-Marquardt shift as it is
    /// instead of multiplying it by 10.
    pub cut_keeps_shift: bool,
}

impl Default for SolverSettings {
    fn default() -> Self {
        SolverSettings {
            kind: SolverKind::Chain,
            tolerance: 1e-6,
            max_iterations: 200,
            penalty: 1e3,
            outer_tolerance: 1e-4,
            max_outer_iterations: 20,
            constraint_tolerance: 1e-6,
            extrapolate: false,
            chain_variant: ChainVariant::default(),
        }
    }
}

/// Physical and numerical parameters of one ribbon.
#[derive(Clone, Debug, PartialEq)]
pub struct RibbonParams {
    /// Length l along the centerline, m.
    pub length: f64,
    /// Width w, m (must be < length).
    pub width: f64,
    /// Number of elements n (>= 2).
    pub segments: usize,
    /// Areal density rho, kg/m^2.
    pub density: f64,
    /// Bending stiffness alpha, J (energy alpha * n w (1+c^2) psi^2 / l per crease).
    pub bending_stiffness: f64,
    /// Crease-direction regularizer beta, J (energy beta * c^2 per crease; paper 0.1).
    pub crease_regularizer: f64,
    /// How a clamp (fixed or driven base, a handle holding orientation) weights the
    /// creases next to it; default [`ClampRule::DualLength`] (second order in n).
    pub clamp: ClampRule,
    /// Gravity, m/s^2.
    pub gravity: [f64; 3],
    pub kinetic: KineticModel,
    pub base: BaseMode,
    pub loop_closure: Option<LoopKind>,
    /// Safety factor on the crease non-intersection bound: Delta c_max = factor * 2l/(wn)
    /// (paper: 0.95).
    pub crease_bound_factor: f64,
    pub solver: SolverSettings,
}

impl RibbonParams {
    /// Delta c_max of eq. (1): the largest difference of neighbouring crease directions.
    pub fn crease_bound(&self) -> f64 {
        self.crease_bound_factor * 2.0 * self.length / (self.width * self.segments as f64)
    }
    /// Element length l/n, m.
    pub fn element_length(&self) -> f64 {
        self.length / self.segments as f64
    }
}
