//! Step 1, elastic deformation (Schreck et al. sec. 4): one implicit-Euler step of S_P
//! with Green-strain (St Venant-Kirchhoff) stretching, discrete dihedral bending with
//! rest angles (Bridson et al. 2003, Grinspun et al. 2003), gravity, collider
//! repulsion springs, handles as hard constraints; optionally a strain-limit penalty on
//! the edges (the relaxation of step 3, [`super::isometry`]). Newton's method on the incremental
//! potential with a Gauss-Newton (positive semi-definite) Hessian, faer's sparse
//! Cholesky and a backtracking line search.

use nalgebra::{Matrix2, Matrix3, Vector2};

use super::isometry::{edge_excess, excess_hessian};
use super::params::PaperParams;
use super::physical::{signed_dihedral, PhysicalMesh};
use super::sparse::{row_major3, BlockSpd};
use crate::geometry::{Point3, Vector3};

/// A hard constraint: world coordinate `axis` of vertex `vertex` equals `value` (m).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Dirichlet {
    pub vertex: u32,
    pub axis: usize,
    pub value: f64,
}

/// A soft spring pulling `vertex` to `target` with `stiffness` N/m.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Spring {
    pub vertex: u32,
    pub target: Point3,
    pub stiffness: f64,
}

/// The strain-limit penalty (k / 2) e^2 on every S_P edge, e the part of its length
/// outside [(1 - s) L, (1 + s) L] (m, L its pattern length); counted as stretching.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StrainLimit {
    /// s, dimensionless.
    pub limit: f64,
    /// k, N/m.
    pub stiffness: f64,
}

/// Per-triangle rest data.
#[derive(Clone, Copy, Debug)]
struct TriangleRest {
    /// Shape-function gradients b_v (F = sum_v x_v b_v^T), 1/m.
    b: [Vector2<f64>; 3],
    /// Rest area, m^2.
    area: f64,
}

/// Energies after a step, J.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FemEnergies {
    pub stretching: f64,
    pub bending: f64,
    pub gravity: f64,
    pub collision: f64,
    pub springs: f64,
    pub kinetic: f64,
}

/// What one implicit step did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FemReport {
    pub iterations: u32,
    pub converged: bool,
    /// The factorization failed or the state became non-finite; positions kept.
    pub failed: bool,
    pub energies: FemEnergies,
    /// Upper bound on the work the handles (Dirichlet vertices) did over the step, J:
    /// sum over held coordinates of |reaction| |Δx|, the reaction being the gradient of
    /// the incremental potential there (the force the handle must supply) at the last
    /// Newton iterate. The anchors of springs (normal-guided handles) are not counted.
    pub handle_work: f64,
}

/// The solver state of one S_P topology (rest data, sparse pattern, buffers).
#[derive(Clone, Debug)]
pub struct FemSystem {
    rest: Vec<TriangleRest>,
    matrix: BlockSpd,
    topology: (usize, Vec<[u32; 3]>),
    /// Per vertex of the last step: the force its Dirichlet constraints exerted on the
    /// sheet, N (the incremental potential's gradient on the held coordinates at the
    /// last Newton iterate; zero on free coordinates).
    pub reactions: Vec<Vector3>,
}

impl FemSystem {
    pub fn new(mesh: &PhysicalMesh) -> FemSystem {
        let rest = mesh
            .triangles
            .iter()
            .map(|t| {
                let [m0, m1, m2] = t.map(|i| mesh.material[i as usize]);
                let dm = Matrix2::from_columns(&[m1 - m0, m2 - m0]);
                let area = 0.5 * dm.determinant().abs();
                let inv = dm.try_inverse().unwrap_or_else(Matrix2::zeros);
                let b1 = Vector2::new(inv[(0, 0)], inv[(0, 1)]);
                let b2 = Vector2::new(inv[(1, 0)], inv[(1, 1)]);
                TriangleRest {
                    b: [-b1 - b2, b1, b2],
                    area,
                }
            })
            .collect();
        let mut groups = mesh
            .triangles
            .iter()
            .map(|t| t.to_vec())
            .chain(mesh.hinges.iter().map(|h| h.v.to_vec()));
        let matrix = BlockSpd::new(mesh.material.len(), 3, &mut groups);
        FemSystem {
            rest,
            matrix,
            topology: (mesh.material.len(), mesh.triangles.clone()),
            reactions: Vec::new(),
        }
    }

    /// True when built for this mesh's topology (same vertices and triangles).
    pub fn matches(&self, mesh: &PhysicalMesh) -> bool {
        self.topology.0 == mesh.material.len() && self.topology.1 == mesh.triangles
    }
}

/// Lame parameters (plane stress) from the membrane stiffness Y t (N/m) and nu.
fn lame(params: &PaperParams) -> (f64, f64) {
    let k = params.stretch_stiffness;
    let nu = params.poisson_ratio;
    (k / (2.0 * (1.0 + nu)), k * nu / (1.0 - nu * nu))
}

/// Gradient of the signed dihedral angle ([`signed_dihedral`]) of hinge (x0, x1; x2
/// left, x3 right) with respect to its four vertices (Bridson et al. 2003).
pub fn dihedral_gradient(x: &[Vector3; 4]) -> [Vector3; 4] {
    let e = x[1] - x[0];
    let el2 = e.norm_squared();
    let na = e.cross(&(x[2] - x[0]));
    let nb = (x[3] - x[0]).cross(&e);
    let (la, lb) = (na.norm_squared(), nb.norm_squared());
    if el2 < 1e-300 || la < 1e-300 || lb < 1e-300 {
        return [Vector3::zeros(); 4];
    }
    let el = el2.sqrt();
    let g2 = -el * na / la;
    let g3 = -el * nb / lb;
    // positions of the wing tips' projections along the edge (rotation invariance)
    let a2 = (x[2] - x[0]).dot(&e) / el2;
    let a3 = (x[3] - x[0]).dot(&e) / el2;
    let g0 = -((1.0 - a2) * g2 + (1.0 - a3) * g3);
    let g1 = -(a2 * g2 + a3 * g3);
    [g0, g1, g2, g3]
}

/// The incremental potential of one implicit-Euler step (J) and what it needs.
struct Potential<'a> {
    mesh: &'a PhysicalMesh,
    rest: &'a [TriangleRest],
    params: &'a PaperParams,
    x_tilde: &'a [Vector3],
    inv_h2: f64,
    springs: &'a [Spring],
    strain_limit: Option<StrainLimit>,
    mu: f64,
    lambda: f64,
    /// Keep only the positive part of the stress in the geometric stiffness (a
    /// positive semi-definite Hessian); otherwise the full term (faster near buckled
    /// states, may be indefinite).
    clamp_stress: std::cell::Cell<bool>,
}

/// Where [`Potential::evaluate`] accumulates the gradient (J/m) and the Hessian, if
/// asked for them.
type GradHess<'b> = Option<(&'b mut [Vector3], &'b mut BlockSpd)>;

impl Potential<'_> {
    /// Value, J; with `grad`, also the gradient (J/m) and the Gauss-Newton Hessian.
    fn evaluate(&self, x: &[Vector3], mut out: GradHess<'_>, parts: &mut FemEnergies) -> f64 {
        *parts = FemEnergies::default();
        if let Some((g, h)) = out.as_mut() {
            g.iter_mut().for_each(|v| *v = Vector3::zeros());
            h.clear();
        }
        let inertia = self.add_inertia_and_gravity(x, &mut out, parts);
        for (t, rest) in self.mesh.triangles.iter().zip(self.rest) {
            self.add_stretching(t, rest, x, &mut out, parts);
        }
        self.add_bending(x, &mut out, parts);
        self.add_strain_limit(x, &mut out, parts);
        self.add_collisions_and_springs(x, &mut out, parts);
        inertia + parts.stretching + parts.bending + parts.gravity + parts.collision + parts.springs
    }

    /// The inertia term (m / 2h^2) |x - x~|^2 (returned, J) and gravity's potential.
    fn add_inertia_and_gravity(
        &self,
        x: &[Vector3],
        out: &mut GradHess<'_>,
        parts: &mut FemEnergies,
    ) -> f64 {
        let mesh = self.mesh;
        let mut inertia = 0.0;
        for i in 0..x.len() {
            let m = mesh.mass[i];
            let d = x[i] - self.x_tilde[i];
            inertia += 0.5 * m * self.inv_h2 * d.norm_squared();
            parts.gravity -= m * self.params.gravity.dot(&x[i]);
            if let Some((g, h)) = out.as_mut() {
                g[i] += m * self.inv_h2 * d - m * self.params.gravity;
                let k = m * self.inv_h2;
                h.add_block(i, i, &[k, 0.0, 0.0, 0.0, k, 0.0, 0.0, 0.0, k]);
            }
        }
        inertia
    }

    /// Stretching of one triangle: St Venant-Kirchhoff on the Green strain.
    fn add_stretching(
        &self,
        t: &[u32; 3],
        rest: &TriangleRest,
        x: &[Vector3],
        out: &mut GradHess<'_>,
        parts: &mut FemEnergies,
    ) {
        let (mu, lambda) = (self.mu, self.lambda);
        let xs = t.map(|i| x[i as usize]);
        let b = &rest.b;
        let f0 = xs[0] * b[0].x + xs[1] * b[1].x + xs[2] * b[2].x;
        let f1 = xs[0] * b[0].y + xs[1] * b[1].y + xs[2] * b[2].y;
        let e00 = 0.5 * (f0.dot(&f0) - 1.0);
        let e11 = 0.5 * (f1.dot(&f1) - 1.0);
        let e01 = 0.5 * f0.dot(&f1);
        let tr = e00 + e11;
        let a = rest.area;
        parts.stretching +=
            a * (mu * (e00 * e00 + e11 * e11 + 2.0 * e01 * e01) + 0.5 * lambda * tr * tr);
        let Some((g, h)) = out.as_mut() else { return };
        let s00 = 2.0 * mu * e00 + lambda * tr;
        let s11 = 2.0 * mu * e11 + lambda * tr;
        let s01 = 2.0 * mu * e01;
        // Voigt rows J_k,v (k = 00, 11, 01) and the material tangent C
        let mut jac = [[Vector3::zeros(); 3]; 3];
        for v in 0..3 {
            jac[0][v] = f0 * b[v].x;
            jac[1][v] = f1 * b[v].y;
            jac[2][v] = 0.5 * (f1 * b[v].x + f0 * b[v].y);
            g[t[v] as usize] +=
                a * (s00 * b[v].x * f0 + s01 * (b[v].x * f1 + b[v].y * f0) + s11 * b[v].y * f1);
        }
        let c = [
            [a * (2.0 * mu + lambda), a * lambda, 0.0],
            [a * lambda, a * (2.0 * mu + lambda), 0.0],
            [0.0, 0.0, a * 4.0 * mu],
        ];
        let splus = self.stress_for_geometric_stiffness(Matrix2::new(s00, s01, s01, s11));
        for v in 0..3 {
            for w in 0..=v {
                let mut blk = Matrix3::zeros();
                for k in 0..3 {
                    for l in 0..3 {
                        if c[k][l] != 0.0 {
                            blk += c[k][l] * jac[k][v] * jac[l][w].transpose();
                        }
                    }
                }
                let geo = a * (b[v].transpose() * splus * b[w])[(0, 0)];
                blk += Matrix3::identity() * geo;
                add_block3(h, t[v] as usize, t[w] as usize, &blk, v == w);
            }
        }
    }

    /// The second Piola-Kirchhoff stress `s` (N/m) as the geometric stiffness uses it:
    /// rebuilt from its eigen-decomposition, with only the positive part when
    /// `clamp_stress` is set.
    fn stress_for_geometric_stiffness(&self, s: Matrix2<f64>) -> Matrix2<f64> {
        let eig = s.symmetric_eigen();
        let mut splus = Matrix2::zeros();
        let clamp = self.clamp_stress.get();
        for k in 0..2 {
            let l = if clamp {
                eig.eigenvalues[k].max(0.0)
            } else {
                eig.eigenvalues[k]
            };
            let v = eig.eigenvectors.column(k);
            splus += l * v * v.transpose();
        }
        splus
    }

    /// Bending: (k_b / 2) w (theta - theta_rest)^2 per hinge.
    fn add_bending(&self, x: &[Vector3], out: &mut GradHess<'_>, parts: &mut FemEnergies) {
        let kb = self.params.bending_stiffness;
        if kb <= 0.0 {
            return;
        }
        for hinge in &self.mesh.hinges {
            let xs = hinge.v.map(|i| x[i as usize]);
            let theta = signed_dihedral(&xs);
            let d = theta - hinge.rest_angle;
            let k = kb * hinge.weight;
            parts.bending += 0.5 * k * d * d;
            let Some((g, h)) = out.as_mut() else { continue };
            let grad = dihedral_gradient(&xs);
            for v in 0..4 {
                g[hinge.v[v] as usize] += k * d * grad[v];
            }
            for v in 0..4 {
                for w in 0..=v {
                    let blk = k * grad[v] * grad[w].transpose();
                    add_block3(h, hinge.v[v] as usize, hinge.v[w] as usize, &blk, v == w);
                }
            }
        }
    }

    /// The strain-limit penalty, if any ([`StrainLimit`]); its transverse curvature
    /// k e / l is negative on a compressed edge and follows `clamp_stress` like the
    /// membrane's geometric stiffness.
    fn add_strain_limit(&self, x: &[Vector3], out: &mut GradHess<'_>, parts: &mut FemEnergies) {
        let Some(StrainLimit { limit, stiffness }) = self.strain_limit else {
            return;
        };
        let mesh = self.mesh;
        for [a, b] in &mesh.edges {
            let (i, j) = (*a as usize, *b as usize);
            let rest = (mesh.material[i] - mesh.material[j]).norm();
            let d = x[j] - x[i];
            let len = d.norm();
            let excess = edge_excess(len, rest, limit);
            if excess == 0.0 || len < 1e-300 {
                continue;
            }
            parts.stretching += 0.5 * stiffness * excess * excess;
            let Some((g, h)) = out.as_mut() else { continue };
            let u = d / len;
            g[j] += stiffness * excess * u;
            g[i] -= stiffness * excess * u;
            let blk = stiffness * excess_hessian(&u, excess, len, self.clamp_stress.get());
            h.add_edge_block(i, j, &row_major3(&blk));
        }
    }

    /// Collisions (one-sided repulsion springs) and the handles' soft springs.
    fn add_collisions_and_springs(
        &self,
        x: &[Vector3],
        out: &mut GradHess<'_>,
        parts: &mut FemEnergies,
    ) {
        let kc = self.params.collision_stiffness;
        let thick = self.params.collision_thickness;
        for col in &self.params.colliders {
            for (i, xi) in x.iter().enumerate() {
                let (dist, n) = col.distance(xi);
                let pen = thick - dist;
                if pen <= 0.0 {
                    continue;
                }
                parts.collision += 0.5 * kc * pen * pen;
                if let Some((g, h)) = out.as_mut() {
                    g[i] -= kc * pen * n;
                    let blk = kc * n * n.transpose();
                    add_block3(h, i, i, &blk, true);
                }
            }
        }
        for s in self.springs {
            let i = s.vertex as usize;
            let d = x[i] - s.target.coords;
            parts.springs += 0.5 * s.stiffness * d.norm_squared();
            if let Some((g, h)) = out.as_mut() {
                g[i] += s.stiffness * d;
                let k = s.stiffness;
                h.add_block(i, i, &[k, 0.0, 0.0, 0.0, k, 0.0, 0.0, 0.0, k]);
            }
        }
    }
}

fn add_block3(h: &mut BlockSpd, i: usize, j: usize, m: &Matrix3<f64>, diagonal: bool) {
    let a = row_major3(m);
    if i == j && !diagonal {
        // an off-diagonal pair of local vertices that is the same node (cannot happen
        // in a valid mesh): symmetrize
        let mut s = [0.0; 9];
        for r in 0..3 {
            for c in 0..3 {
                s[3 * r + c] = a[3 * r + c] + a[3 * c + r];
            }
        }
        h.add_block(i, i, &s);
    } else {
        h.add_block(i, j, &a);
    }
}

/// Line-search step length (fraction of the Newton step) below which a step shorter
/// than the Newton tolerance is a stall, not convergence: four halvings.
const STALLED_STEP: f64 = 1.0 / 16.0;

/// A Newton direction (in `rhs`) at `x` and what the line search needs.
struct NewtonDirection {
    /// The incremental potential at `x`, J.
    phi: f64,
    /// Its directional derivative along the direction, J.
    slope: f64,
    /// The direction's largest coordinate, m.
    step_max: f64,
}

/// Solve H d = -g at `x` into `rhs` with the full geometric stiffness; if that Hessian
/// is not positive definite (or gives no descent), with the positive-stress one. None
/// when neither gives a descent direction. Leaves `grad` and `parts` at `x`.
fn newton_direction(
    potential: &Potential,
    matrix: &mut BlockSpd,
    x: &[Vector3],
    fixed: &[bool],
    grad: &mut [Vector3],
    parts: &mut FemEnergies,
    rhs: &mut faer::Mat<f64>,
) -> Option<NewtonDirection> {
    let n = x.len();
    for clamp in [false, true] {
        potential.clamp_stress.set(clamp);
        let phi = potential.evaluate(x, Some((&mut *grad, &mut *matrix)), parts);
        matrix.fix_all(fixed);
        for i in 0..n {
            for a in 0..3 {
                rhs[(3 * i + a, 0)] = if fixed[3 * i + a] { 0.0 } else { -grad[i][a] };
            }
        }
        if matrix.solve_in_place(rhs.as_mut()).is_err() {
            continue;
        }
        let mut slope = 0.0;
        let mut step_max: f64 = 0.0;
        for i in 0..n {
            for a in 0..3 {
                slope += grad[i][a] * rhs[(3 * i + a, 0)];
                step_max = step_max.max(rhs[(3 * i + a, 0)].abs());
            }
        }
        if slope < 0.0 || step_max == 0.0 {
            return Some(NewtonDirection {
                phi,
                slope,
                step_max,
            });
        }
    }
    None
}

/// Backtracking (Armijo) line search from `x` along the direction in `rhs`: the step
/// length accepted, with the point in `trial`; None after 30 halvings.
fn armijo_step(
    potential: &Potential,
    x: &[Vector3],
    rhs: &faer::Mat<f64>,
    dir: &NewtonDirection,
    trial: &mut [Vector3],
) -> Option<f64> {
    let mut alpha = 1.0;
    let mut scratch = FemEnergies::default();
    for _ in 0..30 {
        for i in 0..x.len() {
            for a in 0..3 {
                trial[i][a] = x[i][a] + alpha * rhs[(3 * i + a, 0)];
            }
        }
        let phi_t = potential.evaluate(trial, None, &mut scratch);
        if phi_t.is_finite() && phi_t <= dir.phi + 1e-4 * alpha * dir.slope {
            return Some(alpha);
        }
        alpha *= 0.5;
    }
    None
}

/// Newton's start: the inertial prediction x~ with the Dirichlet coordinates at their
/// values, and which of the 3n coordinates those are.
fn start_point(x_tilde: &[Vector3], dirichlet: &[Dirichlet]) -> (Vec<Vector3>, Vec<bool>) {
    let n = x_tilde.len();
    let mut fixed = vec![false; 3 * n];
    let mut x = x_tilde.to_vec();
    for d in dirichlet {
        let i = d.vertex as usize;
        if i < n && d.axis < 3 {
            fixed[3 * i + d.axis] = true;
            x[i][d.axis] = d.value;
        }
    }
    (x, fixed)
}

/// One implicit-Euler step of `dt` s: new positions and velocities of `mesh`; with
/// `strain_limit`, its penalty is part of the potential.
pub fn implicit_step(
    system: &mut FemSystem,
    mesh: &mut PhysicalMesh,
    params: &PaperParams,
    dt: f64,
    dirichlet: &[Dirichlet],
    springs: &[Spring],
    strain_limit: Option<StrainLimit>,
) -> FemReport {
    let n = mesh.material.len();
    system.reactions.clear();
    let x_prev: Vec<Vector3> = mesh.position.iter().map(|p| p.coords).collect();
    let x_tilde: Vec<Vector3> = x_prev
        .iter()
        .zip(&mesh.velocity)
        .map(|(x, v)| x + dt * v)
        .collect();
    let (mut x, fixed) = start_point(&x_tilde, dirichlet);
    let (mu, lambda) = lame(params);
    let potential = Potential {
        mesh,
        rest: &system.rest,
        params,
        x_tilde: &x_tilde,
        inv_h2: 1.0 / (dt * dt),
        springs,
        strain_limit,
        mu,
        lambda,
        clamp_stress: std::cell::Cell::new(false),
    };
    let mut grad = vec![Vector3::zeros(); n];
    let mut parts = FemEnergies::default();
    let mut report = FemReport::default();
    let mut rhs = faer::Mat::<f64>::zeros(3 * n, 1);
    let mut trial = x.clone();
    for it in 0..params.newton_max_iterations {
        report.iterations = it + 1;
        let Some(dir) = newton_direction(
            &potential,
            &mut system.matrix,
            &x,
            &fixed,
            &mut grad,
            &mut parts,
            &mut rhs,
        ) else {
            report.failed = true;
            break;
        };
        let step_max = dir.step_max;
        if !step_max.is_finite() {
            report.failed = true;
            break;
        }
        if step_max < params.newton_tolerance {
            report.converged = true;
            break;
        }
        let Some(alpha) = armijo_step(&potential, &x, &rhs, &dir, &mut trial) else {
            // no descent left at round-off level: the current point is the minimizer
            report.converged = step_max < 1e3 * params.newton_tolerance;
            break;
        };
        std::mem::swap(&mut x, &mut trial);
        if alpha * step_max < params.newton_tolerance {
            // a short step is convergence only when the line search took (nearly) the
            // Newton step; one cut down by more than STALLED_STEP stopped at a kink of
            // the energy (a hinge folded through, a degenerate triangle) with descent
            // left, and is reported as such
            report.converged = alpha > STALLED_STEP;
            break;
        }
    }
    let finite = x.iter().all(|v| v.iter().all(|c| c.is_finite()));
    if report.failed || !finite {
        report.failed = true;
        report.converged = false;
        for v in mesh.velocity.iter_mut() {
            *v = Vector3::zeros();
        }
        return report;
    }
    potential.evaluate(&x, None, &mut parts);
    let damp = 1.0 / (1.0 + params.damping * dt);
    let mut kinetic = 0.0;
    for i in 0..n {
        let v = (x[i] - x_prev[i]) / dt * damp;
        kinetic += 0.5 * mesh.mass[i] * v.norm_squared();
        mesh.velocity[i] = v;
        mesh.position[i] = Point3::from(x[i]);
    }
    parts.kinetic = kinetic;
    report.energies = parts;
    system.reactions.clear();
    system.reactions.extend(
        (0..n).map(|i| Vector3::from_fn(|a, _| if fixed[3 * i + a] { grad[i][a] } else { 0.0 })),
    );
    report.handle_work = (0..n)
        .flat_map(|i| (0..3).map(move |a| (i, a)))
        .filter(|&(i, a)| fixed[3 * i + a])
        .map(|(i, a)| grad[i][a].abs() * (x[i][a] - x_prev[i][a]).abs())
        .sum();
    report
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dihedral_gradient_matches_finite_differences() {
        let x = [
            Vector3::new(0.0, 0.0, 0.0),
            Vector3::new(1.0, 0.1, 0.05),
            Vector3::new(0.4, 0.9, 0.3),
            Vector3::new(0.6, -0.8, 0.2),
        ];
        let g = dihedral_gradient(&x);
        let h = 1e-6;
        for v in 0..4 {
            for a in 0..3 {
                let mut xp = x;
                let mut xm = x;
                xp[v][a] += h;
                xm[v][a] -= h;
                let fd = (signed_dihedral(&xp) - signed_dihedral(&xm)) / (2.0 * h);
                // central differences: error O(h^2) ~ 1e-12 times third derivatives ~ 1
                assert!(
                    (fd - g[v][a]).abs() < 1e-7,
                    "vertex {v} axis {a}: {fd} vs {}",
                    g[v][a]
                );
            }
        }
    }

    /// One triangle of S_P (1 cm by 1.2 cm in the pattern) with its three edges.
    fn triangle() -> PhysicalMesh {
        use crate::geometry::Point2;
        PhysicalMesh {
            material: vec![
                Point2::new(0.0, 0.0),
                Point2::new(0.01, 0.0),
                Point2::new(0.002, 0.012),
            ],
            triangles: vec![[0, 1, 2]],
            edges: vec![[0, 1], [0, 2], [1, 2]],
            mass: vec![0.0; 3],
            ..Default::default()
        }
    }

    /// `triangle`'s deformed positions: edge 0-1 compressed by 2.4 %, 0-2 stretched by
    /// 3.4 %.
    fn deformed() -> Vec<Vector3> {
        vec![
            Vector3::new(0.0, 0.0, 0.0),
            Vector3::new(0.0095, 0.001, 0.002),
            Vector3::new(0.001, 0.0125, -0.001),
        ]
    }

    /// The potential of `mesh` (no inertia) with `params` and `strain_limit` handed to
    /// `check`, which gets it with `mesh`'s FEM system.
    fn with_potential(
        mesh: &PhysicalMesh,
        params: &PaperParams,
        strain_limit: Option<StrainLimit>,
        check: impl FnOnce(&Potential, &FemSystem),
    ) {
        let system = FemSystem::new(mesh);
        let (mu, lambda) = lame(params);
        let x_tilde = vec![Vector3::zeros(); mesh.material.len()];
        let pot = Potential {
            mesh,
            rest: &system.rest,
            params,
            x_tilde: &x_tilde,
            inv_h2: 0.0,
            springs: &[],
            strain_limit,
            mu,
            lambda,
            clamp_stress: std::cell::Cell::new(true),
        };
        check(&pot, &system);
    }

    /// The potential's gradient at `x` against central differences (h = 1e-9 m);
    /// returns the potential at `x` and its parts.
    fn assert_gradient_matches(
        pot: &Potential,
        system: &FemSystem,
        x: &[Vector3],
    ) -> (f64, FemEnergies) {
        let mut g = vec![Vector3::zeros(); x.len()];
        let mut hm = system.matrix.clone();
        let mut parts = FemEnergies::default();
        let e = pot.evaluate(x, Some((&mut g, &mut hm)), &mut parts);
        let at_x = parts;
        let h = 1e-9;
        let scale = g.iter().map(|v| v.norm()).fold(0.0, f64::max);
        for v in 0..x.len() {
            for a in 0..3 {
                let (mut xp, mut xm) = (x.to_vec(), x.to_vec());
                xp[v][a] += h;
                xm[v][a] -= h;
                let fd = (pot.evaluate(&xp, None, &mut parts)
                    - pot.evaluate(&xm, None, &mut parts))
                    / (2.0 * h);
                assert!(
                    (fd - g[v][a]).abs() < 1e-5 * scale,
                    "{v} {a}: {fd} vs {}",
                    g[v][a]
                );
            }
        }
        (e, at_x)
    }

    #[test]
    fn stretching_gradient_matches_finite_differences() {
        with_potential(&triangle(), &PaperParams::default(), None, |pot, system| {
            assert_gradient_matches(pot, system, &deformed());
        });
    }

    #[test]
    fn the_strain_limit_penalty_gradient_matches_finite_differences() {
        // a membrane too soft to matter: the gradient is the penalty's (both strained
        // edges beyond 0.5 %)
        let params = PaperParams {
            stretch_stiffness: 1e-9,
            ..PaperParams::default()
        };
        let limit = Some(StrainLimit {
            limit: 0.005,
            stiffness: 3e4,
        });
        with_potential(&triangle(), &params, limit, |pot, system| {
            let (e, parts) = assert_gradient_matches(pot, system, &deformed());
            assert!(
                parts.stretching > 0.9 * e && e > 0.0,
                "the penalty is the energy"
            );
        });
    }
}
