//! Step 3(h): preserving lengths with respect to the pattern (Schreck et al. sec.
//! 6.3). Phase I finds unit edge directions u_ij close to the current ones under two
//! aggregated constraints, C_unit = sum (u.u - 1)^2 = 0 and C_closed = sum over
//! triangles |l_ij u_ij + l_jk u_jk + l_ki u_ki|^2 = 0, with two Lagrange multipliers
//! (eqs. 3-6: a 2x2 system per iteration, at most 200 iterations). Phase II places the
//! vertices by least squares on (p_j - p_i) - l_ij u_ij (eq. 7) with the handle
//! vertices fixed; x, y and z decouple and share one sparse Cholesky factorization.
//!
//! Ours, the default ([`super::params::LengthRestoration::StrainLimit`]): every edge
//! within a strain limit s of its pattern length by Newton's method on the excess
//! ([`limit_strains`]), a relaxation of the FEM's energy with that limit as a penalty
//! (in [`super::PaperSim`]), then the limit once more. See docs/paper_simulator.md.

use super::physical::PhysicalMesh;
use super::sparse::{row_major3, BlockSpd};
use crate::geometry::{Matrix3, Point3, Vector3};

/// What the length restoration did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct IsometryReport {
    pub iterations: u32,
    /// sqrt(C_closed / #triangles) before and after phase I, m.
    pub closure_before: f64,
    pub closure_after: f64,
    /// Mean relative edge-length error before and after, dimensionless.
    pub length_error_before: f64,
    pub length_error_after: f64,
    /// Largest |l / L - 1| over the edges before and after (strain limit only; 0 for
    /// the paper's phases), dimensionless.
    pub strain_before: f64,
    pub strain_after: f64,
}

/// Mean |l / L - 1| over the edges of `mesh`, dimensionless.
pub fn mean_length_error(mesh: &PhysicalMesh) -> f64 {
    let mut s = 0.0;
    for [a, b] in &mesh.edges {
        let rest = (mesh.material[*a as usize] - mesh.material[*b as usize]).norm();
        let len = (mesh.position[*a as usize] - mesh.position[*b as usize]).norm();
        s += (len - rest).abs() / rest;
    }
    s / mesh.edges.len().max(1) as f64
}

/// Restore edge lengths of `mesh` (positions only). `fixed[v]` marks handle
/// vertices, which do not move. At most `max_iterations` phase I iterations.
pub fn restore_lengths(
    mesh: &mut PhysicalMesh,
    fixed: &[bool],
    max_iterations: u32,
) -> IsometryReport {
    let mut report = IsometryReport {
        length_error_before: mean_length_error(mesh),
        ..Default::default()
    };
    if mesh.edges.is_empty() || mesh.triangles.is_empty() {
        return report;
    }
    let problem = EdgeDirections::new(mesh);
    let u = problem.phase_one(max_iterations, &mut report);
    place_vertices(mesh, fixed, &problem.rest, &u);
    report.length_error_after = mean_length_error(mesh);
    report
}

/// Phase I's unknowns and data: the edges' rest lengths, each triangle's three edges
/// with their traversal signs, and the current unit directions u^o.
struct EdgeDirections {
    /// Pattern length of each edge of `mesh.edges`, m.
    rest: Vec<f64>,
    /// Each triangle: three (edge, sign) with the traversal i -> j -> k -> i.
    tri_edges: Vec<[(usize, f64); 3]>,
    /// u^o: current unit directions (edge a -> b, a < b).
    u0: Vec<Vector3>,
}

impl EdgeDirections {
    fn new(mesh: &PhysicalMesh) -> EdgeDirections {
        let rest: Vec<f64> = mesh
            .edges
            .iter()
            .map(|[a, b]| (mesh.material[*a as usize] - mesh.material[*b as usize]).norm())
            .collect();
        let find = |a: u32, b: u32| -> (usize, f64) {
            let key = if a < b { [a, b] } else { [b, a] };
            let i = mesh.edges.binary_search(&key).unwrap_or(0);
            (i, if a < b { 1.0 } else { -1.0 })
        };
        let tri_edges = mesh
            .triangles
            .iter()
            .map(|t| [find(t[0], t[1]), find(t[1], t[2]), find(t[2], t[0])])
            .collect();
        let u0 = mesh
            .edges
            .iter()
            .map(|[a, b]| {
                let d = mesh.position[*b as usize] - mesh.position[*a as usize];
                let n = d.norm();
                if n > 1e-300 {
                    d / n
                } else {
                    Vector3::x()
                }
            })
            .collect();
        EdgeDirections {
            rest,
            tri_edges,
            u0,
        }
    }

    /// C_closed of the directions `u` and each triangle's closure residual
    /// l_ij u_ij + l_jk u_jk + l_ki u_ki, m.
    fn closure(&self, u: &[Vector3]) -> (f64, Vec<Vector3>) {
        let mut c = 0.0;
        let mut r = Vec::with_capacity(self.tri_edges.len());
        for te in &self.tri_edges {
            let mut v = Vector3::zeros();
            for &(e, s) in te {
                v += s * self.rest[e] * u[e];
            }
            c += v.norm_squared();
            r.push(v);
        }
        (c, r)
    }

    /// Phase I: iterate eq. (6) from u^o; returns the best unit directions found
    /// (judged on C_closed of the normalized directions, what phase II receives).
    fn phase_one(&self, max_iterations: u32, report: &mut IsometryReport) -> Vec<Vector3> {
        let (ne, nt) = (self.rest.len(), self.tri_edges.len());
        let mut u = self.u0.clone();
        let (c2_start, _) = self.closure(&u);
        report.closure_before = (c2_start / nt as f64).sqrt();
        let (mut lambda1, mut lambda2) = (0.0, 0.0);
        let mut best = (c2_start, u.clone());
        let mut g1 = vec![Vector3::zeros(); ne];
        let mut g2 = vec![Vector3::zeros(); ne];
        let mut bx = vec![Vector3::zeros(); ne];
        let mut since_best = 0;
        let tiny_closure = 1e-24 * self.rest.iter().map(|l| l * l).sum::<f64>();
        for it in 0..max_iterations {
            let (c2, resid) = self.closure(&u);
            let c1: f64 = u.iter().map(|v| (v.norm_squared() - 1.0).powi(2)).sum();
            let unit: Vec<Vector3> = u.iter().map(|v| v / v.norm().max(1e-300)).collect();
            let (c2_unit, _) = self.closure(&unit);
            if c2_unit < best.0 {
                best = (c2_unit, unit);
                since_best = 0;
            } else {
                since_best += 1;
                // the iteration stagnates once L is near zero (sec. 6.3: "does not
                // guarantee theoretical convergence"); stop early, keep the best
                if since_best > 25 {
                    break;
                }
            }
            report.iterations = it + 1;
            if c2 <= tiny_closure {
                break;
            }
            // gradients of the constraints
            for (e, v) in u.iter().enumerate() {
                g1[e] = 4.0 * (v.norm_squared() - 1.0) * v;
                g2[e] = Vector3::zeros();
            }
            for (te, r) in self.tri_edges.iter().zip(&resid) {
                for &(e, s) in te {
                    g2[e] += 2.0 * s * self.rest[e] * r;
                }
            }
            // b_x = -grad E - lambda1 grad C1 - lambda2 grad C2, b_lambda = -C
            let (mut l11, mut l12, mut l22, mut r1, mut r2) = (0.0, 0.0, 0.0, 0.0, 0.0);
            for e in 0..ne {
                bx[e] = -(u[e] - self.u0[e]) - lambda1 * g1[e] - lambda2 * g2[e];
                l11 += g1[e].norm_squared();
                l12 += g1[e].dot(&g2[e]);
                l22 += g2[e].norm_squared();
                r1 += g1[e].dot(&bx[e]);
                r2 += g2[e].dot(&bx[e]);
            }
            // L^T L dlambda = L^T b_x - b_lambda
            r1 += c1;
            r2 += c2;
            let det = l11 * l22 - l12 * l12;
            let (d1, d2) = if det.abs() > 1e-14 * (l11 * l22).max(1e-300) {
                ((l22 * r1 - l12 * r2) / det, (l11 * r2 - l12 * r1) / det)
            } else if l22 > 1e-300 {
                // C_unit is satisfied exactly (its gradient vanishes): one multiplier
                (0.0, r2 / l22)
            } else {
                break;
            };
            let mut finite = true;
            for e in 0..ne {
                let dx = bx[e] - d1 * g1[e] - d2 * g2[e];
                u[e] += dx;
                finite &= u[e].iter().all(|c| c.is_finite());
            }
            lambda1 += d1;
            lambda2 += d2;
            if !finite || !lambda1.is_finite() || !lambda2.is_finite() {
                break;
            }
        }
        let (c2_end, mut u) = (best.0, best.1);
        report.closure_after = (c2_end / nt as f64).sqrt();
        for v in u.iter_mut() {
            let n = v.norm();
            if n > 1e-300 {
                *v /= n;
            }
        }
        u
    }
}

/// Phase II: least squares on positions, (p_j - p_i) - l_ij u_ij (eq. 7), handle
/// vertices fixed, plus a tiny pull (1e-8) to the current positions so that parts
/// without a handle stay determined. Keeps the positions if the solve fails or is not
/// finite.
fn place_vertices(mesh: &mut PhysicalMesh, fixed: &[bool], rest: &[f64], u: &[Vector3]) {
    let n = mesh.material.len();
    let mut groups = mesh.edges.iter().map(|e| e.to_vec());
    let mut a = BlockSpd::new(n, 1, &mut groups);
    let eps = 1e-8;
    let mut rhs = faer::Mat::<f64>::zeros(n, 3);
    for v in 0..n {
        a.add(v, v, eps);
        for c in 0..3 {
            rhs[(v, c)] = eps * mesh.position[v][c];
        }
    }
    for (e, [i, j]) in mesh.edges.iter().enumerate() {
        let (i, j) = (*i as usize, *j as usize);
        let d = rest[e] * u[e];
        a.add(i, i, 1.0);
        a.add(j, j, 1.0);
        a.add(i, j, -1.0);
        for c in 0..3 {
            rhs[(j, c)] += d[c];
            rhs[(i, c)] -= d[c];
        }
    }
    // fixed vertices: move their columns to the right-hand side
    let fixed_dofs: Vec<bool> = (0..n)
        .map(|v| fixed.get(v).copied().unwrap_or(false))
        .collect();
    for [i, j] in &mesh.edges {
        let (i, j) = (*i as usize, *j as usize);
        for (free, fix) in [(i, j), (j, i)] {
            if !fixed_dofs[free] && fixed_dofs[fix] {
                for c in 0..3 {
                    rhs[(free, c)] += mesh.position[fix][c];
                }
            }
        }
    }
    for v in 0..n {
        if fixed_dofs[v] {
            for c in 0..3 {
                rhs[(v, c)] = mesh.position[v][c];
            }
        }
    }
    a.fix_all(&fixed_dofs);
    if a.solve_in_place(rhs.as_mut()).is_ok() {
        let ok = (0..n).all(|v| (0..3).all(|c| rhs[(v, c)].is_finite()));
        if ok {
            for v in 0..n {
                if !fixed_dofs[v] {
                    mesh.position[v] = Point3::new(rhs[(v, 0)], rhs[(v, 1)], rhs[(v, 2)]);
                }
            }
        }
    }
}

/// The part of an edge's length `len` outside [(1 - limit) rest, (1 + limit) rest],
/// m: positive when stretched beyond the limit, negative when compressed beyond it.
pub fn edge_excess(len: f64, rest: f64, limit: f64) -> f64 {
    len - len.clamp((1.0 - limit) * rest, (1.0 + limit) * rest)
}

/// The Hessian of e^2 / 2 with respect to the edge's end point (the other end fixed),
/// e = [`edge_excess`] of an edge of length `len` and direction `u`: u u^T + (e / len)
/// (I - u u^T). The transverse part is negative on a compressed edge (a buckling
/// direction); with `clamp` it is dropped there, which keeps the block positive
/// semi-definite.
pub fn excess_hessian(u: &Vector3, excess: f64, len: f64, clamp: bool) -> Matrix3 {
    let uu = u * u.transpose();
    let transverse = if clamp {
        (excess / len).max(0.0)
    } else {
        excess / len
    };
    uu + transverse * (Matrix3::identity() - uu)
}

/// Relative overshoot of the limit [`limit_strains`] stops at (0.5 % becomes at most
/// 0.5005 %).
pub const LIMIT_TOLERANCE: f64 = 1e-3;

/// What [`limit_strains`] did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StrainLimitReport {
    /// Newton iterations.
    pub iterations: u32,
    /// Largest |l / L - 1| over the edges before and after, dimensionless.
    pub strain_before: f64,
    pub strain_after: f64,
}

/// f = 1/2 sum over edges of (e / L)^2 (dimensionless, zero when every edge strain is
/// within `limit`) and the largest |l / L - 1|.
fn strain_excess(mesh: &PhysicalMesh, rest: &[f64], limit: f64) -> (f64, f64) {
    let (mut f, mut worst) = (0.0, 0.0f64);
    for (e, [i, j]) in mesh.edges.iter().enumerate() {
        let len = (mesh.position[*j as usize] - mesh.position[*i as usize]).norm();
        f += 0.5 * (edge_excess(len, rest[e], limit) / rest[e]).powi(2);
        worst = worst.max((len / rest[e] - 1.0).abs());
    }
    (f, worst)
}

/// Move the vertices of `mesh` (those with `fixed[v]` stay) until no edge is strained
/// by more than `limit`: Newton's method on [`strain_excess`] (Provot 1995's strain
/// limit, solved as one system instead of edge by edge). Edges within the limit feel
/// nothing. Each Newton matrix is the sum of the edges' [`excess_hessian`] blocks
/// (clamped: positive semi-definite) plus a Levenberg-Marquardt shift mu * mean
/// diagonal, which keeps the steps small where the excess allows many solutions; a
/// backtracking search keeps f decreasing. At most `max_iterations`.
pub fn limit_strains(
    mesh: &mut PhysicalMesh,
    fixed: &[bool],
    limit: f64,
    max_iterations: u32,
) -> StrainLimitReport {
    let rest: Vec<f64> = mesh
        .edges
        .iter()
        .map(|[a, b]| (mesh.material[*a as usize] - mesh.material[*b as usize]).norm())
        .collect();
    let (mut f, worst) = strain_excess(mesh, &rest, limit);
    let mut report = StrainLimitReport {
        strain_before: worst,
        strain_after: worst,
        ..Default::default()
    };
    let n = mesh.material.len();
    if worst <= limit * (1.0 + LIMIT_TOLERANCE) || n == 0 {
        return report;
    }
    let mut groups = mesh.edges.iter().map(|e| e.to_vec());
    let mut h = BlockSpd::new(n, 3, &mut groups);
    let fixed_dofs: Vec<bool> = (0..3 * n)
        .map(|d| fixed.get(d / 3).copied().unwrap_or(false))
        .collect();
    let mut mu = 1e-6;
    let mut rhs = faer::Mat::<f64>::zeros(3 * n, 1);
    let mut trial = mesh.position.clone();
    for it in 0..max_iterations {
        report.iterations = it + 1;
        let diag_mean = newton_system(mesh, &rest, limit, &mut h, &mut rhs);
        for v in 0..3 * n {
            h.add(v, v, mu * diag_mean);
            if fixed_dofs[v] {
                rhs[(v, 0)] = 0.0;
            }
        }
        h.fix_all(&fixed_dofs);
        if h.solve_in_place(rhs.as_mut()).is_err() {
            mu *= 100.0;
            continue;
        }
        let Some(ft) = backtrack(mesh, &rest, limit, &rhs, &mut trial, f) else {
            break;
        };
        f = ft;
        report.strain_after = strain_excess(mesh, &rest, limit).1;
        // the excess vanishes on the limit: Newton approaches it from outside, and
        // the last digits are not worth iterations
        if report.strain_after <= limit * (1.0 + LIMIT_TOLERANCE) {
            break;
        }
        mu = (mu * 0.3).max(1e-9);
    }
    report
}

/// The Gauss-Newton system of [`strain_excess`] at `mesh`'s positions: its matrix in
/// `h`, minus its gradient in `rhs`; returns the mean diagonal of the matrix (1/m^2).
fn newton_system(
    mesh: &PhysicalMesh,
    rest: &[f64],
    limit: f64,
    h: &mut BlockSpd,
    rhs: &mut faer::Mat<f64>,
) -> f64 {
    h.clear();
    for v in 0..rhs.nrows() {
        rhs[(v, 0)] = 0.0;
    }
    let mut diag_sum = 0.0;
    for (e, [i, j]) in mesh.edges.iter().enumerate() {
        let (i, j) = (*i as usize, *j as usize);
        let d = mesh.position[j] - mesh.position[i];
        let len = d.norm();
        let excess = edge_excess(len, rest[e], limit);
        if excess == 0.0 || len < 1e-300 {
            continue;
        }
        let w = 1.0 / (rest[e] * rest[e]);
        let u = d / len;
        let g = w * excess * u;
        for c in 0..3 {
            rhs[(3 * j + c, 0)] -= g[c];
            rhs[(3 * i + c, 0)] += g[c];
        }
        h.add_edge_block(
            i,
            j,
            &row_major3(&(w * excess_hessian(&u, excess, len, true))),
        );
        diag_sum += 2.0 * w;
    }
    diag_sum / mesh.material.len().max(1) as f64
}

/// Backtracking along the step in `rhs` from `mesh`'s positions (f at them: `f`):
/// moves `mesh` to the first of 20 halvings that lowers f and returns the new f;
/// None (positions kept) when none does.
fn backtrack(
    mesh: &mut PhysicalMesh,
    rest: &[f64],
    limit: f64,
    rhs: &faer::Mat<f64>,
    trial: &mut Vec<Point3>,
    f: f64,
) -> Option<f64> {
    let mut alpha = 1.0;
    for _ in 0..20 {
        for (v, t) in trial.iter_mut().enumerate() {
            let dx = Vector3::new(rhs[(3 * v, 0)], rhs[(3 * v + 1, 0)], rhs[(3 * v + 2, 0)]);
            *t = mesh.position[v] + alpha * dx;
        }
        std::mem::swap(trial, &mut mesh.position);
        let (ft, _) = strain_excess(mesh, rest, limit);
        if ft.is_finite() && ft < f {
            return Some(ft);
        }
        std::mem::swap(trial, &mut mesh.position);
        alpha *= 0.5;
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Point2;

    /// A flat 5 x 5 grid of squares split into triangles, 1 cm spacing.
    fn grid() -> PhysicalMesh {
        let n = 6;
        let h = 0.01;
        let mut mesh = PhysicalMesh::default();
        for j in 0..n {
            for i in 0..n {
                mesh.material.push(Point2::new(i as f64 * h, j as f64 * h));
                mesh.position
                    .push(Point3::new(i as f64 * h, j as f64 * h, 0.0));
            }
        }
        for j in 0..n - 1 {
            for i in 0..n - 1 {
                let v = (j * n + i) as u32;
                let n = n as u32;
                mesh.triangles.push([v, v + 1, v + n + 1]);
                mesh.triangles.push([v, v + n + 1, v + n]);
            }
        }
        let mut edges: Vec<[u32; 2]> = mesh
            .triangles
            .iter()
            .flat_map(|t| [[t[0], t[1]], [t[1], t[2]], [t[2], t[0]]])
            .map(|[a, b]| if a < b { [a, b] } else { [b, a] })
            .collect();
        edges.sort_unstable();
        edges.dedup();
        mesh.edges = edges;
        mesh
    }

    #[test]
    fn restores_edge_lengths_of_a_perturbed_mesh() {
        let mut mesh = grid();
        // bend into a cylinder of radius 3 cm (isometric), then perturb with a smooth
        // 2 % in-plane compression plus a deterministic wobble
        for (p, m) in mesh.position.iter_mut().zip(&mesh.material) {
            let r = 0.03;
            let phi = m.x / r;
            let squeeze = 0.98;
            *p = Point3::new(
                r * (phi * squeeze).sin(),
                m.y * squeeze,
                r * (1.0 - (phi * squeeze).cos()),
            );
            p.z += 2e-4 * (37.0 * m.x + 11.0 * m.y).sin();
        }
        let before = mean_length_error(&mesh);
        let mut fixed = vec![false; mesh.material.len()];
        fixed[0] = true;
        let report = restore_lengths(&mut mesh, &fixed, 200);
        assert!(
            report.length_error_before > 0.01,
            "perturbed: {}",
            report.length_error_before
        );
        // phase I reduces the closure defect, phase II the length error (the paper's
        // table III: 0.15 % -> 0.13 % on fig. 1 with 200 iterations; we ask for a
        // reduction by at least 3x from a 2 % error)
        assert!(report.closure_after < report.closure_before);
        assert!(
            report.length_error_after < before / 3.0,
            "{} -> {}",
            before,
            report.length_error_after
        );
        assert!(
            mesh.position[0] == Point3::new(0.0, 0.0, 0.0),
            "handle fixed"
        );
    }
    #[test]
    fn the_excess_hessian_is_the_derivative_of_the_excess_gradient() {
        // an edge from the origin to x, rest length 1, limit 0.1: gradient e x / |x|
        let g = |x: &Vector3| {
            let l = x.norm();
            edge_excess(l, 1.0, 0.1) * x / l
        };
        let stretched = Vector3::new(1.3, 0.2, -0.1);
        let compressed = Vector3::new(0.5, 0.3, 0.2);
        for x in [stretched, compressed] {
            let l = x.norm();
            let h = excess_hessian(&(x / l), edge_excess(l, 1.0, 0.1), l, false);
            let eps = 1e-6;
            for k in 0..3 {
                let mut d = Vector3::zeros();
                d[k] = eps;
                let fd = (g(&(x + d)) - g(&(x - d))) / (2.0 * eps);
                // central differences: error O(eps^2) against second derivatives ~ 1
                assert!((fd - h.column(k)).norm() < 1e-8, "{x:?} column {k}");
            }
        }
        // within the limit: nothing
        assert_eq!(edge_excess(1.05, 1.0, 0.1), 0.0);
        // clamped, a compressed edge keeps only its own direction: positive
        // semi-definite
        let l = compressed.norm();
        let h = excess_hessian(&(compressed / l), edge_excess(l, 1.0, 0.1), l, true);
        assert!(h.symmetric_eigenvalues().min() > -1e-12);
        let h = excess_hessian(&(compressed / l), edge_excess(l, 1.0, 0.1), l, false);
        assert!(h.symmetric_eigenvalues().min() < -0.1);
    }

    #[test]
    fn limit_strains_moves_only_edges_beyond_the_limit() {
        let mut mesh = grid();
        // bent into a cylinder of radius 3 cm: isometric, nothing to do, not one bit
        for (p, m) in mesh.position.iter_mut().zip(&mesh.material) {
            let phi = m.x / 0.03;
            *p = Point3::new(0.03 * phi.sin(), m.y, 0.03 * (1.0 - phi.cos()));
        }
        let bent = mesh.position.clone();
        let fixed = vec![false; mesh.material.len()];
        let r = limit_strains(&mut mesh, &fixed, 0.005, 50);
        assert_eq!(r.iterations, 0);
        assert_eq!(mesh.position, bent);
        // the corner at (0, 0) held and pulled 3 mm away, a middle vertex lifted 2 mm
        let mut fixed = fixed;
        fixed[0] = true;
        mesh.position[0] += Vector3::new(-0.003, -0.001, 0.0);
        mesh.position[14] += Vector3::new(0.0, 0.0, 0.002);
        let held = mesh.position[0];
        let r = limit_strains(&mut mesh, &fixed, 0.005, 50);
        assert!(r.strain_before > 0.1, "{r:?}");
        let within = 0.005 * (1.0 + LIMIT_TOLERANCE);
        assert!(r.strain_after <= within && r.iterations < 50, "{r:?}");
        let rest =
            |[a, b]: [u32; 2]| (mesh.material[a as usize] - mesh.material[b as usize]).norm();
        for e in &mesh.edges {
            let len = (mesh.position[e[1] as usize] - mesh.position[e[0] as usize]).norm();
            assert!((len / rest(*e) - 1.0).abs() <= within, "edge {e:?}");
        }
        assert_eq!(mesh.position[0], held, "a fixed vertex does not move");
    }
}
