//! Step 3(h), completed: the edge lengths of S_P projected onto the pattern's
//! (Goldenthal, Harmon, Fattal, Bercovier, Grinspun, "Efficient simulation of
//! inextensible cloth", SIGGRAPH 2007, sec. 4: fast projection).
//!
//! Schreck et al.'s two phases (sec. 6.3, [`super::isometry`]) reduce the length error
//! but do not converge (their phase I "does not guarantee theoretical convergence" and
//! stops after 200 iterations; phase II weighs every edge by its absolute residual, so
//! the short edges next to a held corner take the residual: +128 % measured on
//! paper_crumple, 2026-12-02). The paper is silent on what remains. We finish with the
//! fast projection: the constraints are the relative edge-length defects
//! C_e = (|p_j - p_i|^2 / l_e^2 - 1) / 2 (dimensionless, ~ the strain), and each step
//! solves (J M^-1 J^T) dlambda = C, dx = -M^-1 J^T dlambda with the held vertices of
//! infinite mass (they do not move, as in the paper's phase II). By the push-through
//! identity the step is dx = -(J^T J + mu M)^-1 J^T C, which we solve in the vertices
//! (3 dofs each, the sparsity of the edges): mu -> 0 is the fast projection (the
//! M-nearest configuration along the constraint manifold), mu > 0 a Levenberg-Marquardt
//! damping that keeps the step defined where J is rank deficient (a flat part of the
//! sheet has no first-order out-of-plane constraint) and that, when the held vertices
//! make the lengths unreachable, gives the least-squares strain instead of a blow-up.

use super::physical::PhysicalMesh;
use super::sparse::BlockSpd;
use crate::geometry::Vector3;

/// What the projection did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ProjectionReport {
    /// Linear solves (accepted and rejected steps).
    pub solves: u32,
    /// Largest |l / l_rest - 1| over the edges before and after, dimensionless.
    pub strain_before: f64,
    pub strain_after: f64,
}

/// Largest |l / l_rest - 1| and sum of C_e^2 of `position`.
fn measure(mesh: &PhysicalMesh, rest: &[f64], position: &[crate::geometry::Point3]) -> (f64, f64) {
    let mut worst = 0.0f64;
    let mut merit = 0.0;
    for ([a, b], l) in mesh.edges.iter().zip(rest) {
        let d2 = (position[*b as usize] - position[*a as usize]).norm_squared();
        worst = worst.max((d2.sqrt() / l - 1.0).abs());
        let c = 0.5 * (d2 / (l * l) - 1.0);
        merit += c * c;
    }
    (worst, merit)
}

/// Project the positions of `mesh` onto |p_j - p_i| = l_e (pattern lengths) until the
/// largest |strain| is below `tolerance` (dimensionless) or `max_solves` linear solves
/// are spent; `fixed[v]` marks held vertices, which do not move. Positions only.
pub fn project_lengths(
    mesh: &mut PhysicalMesh,
    fixed: &[bool],
    tolerance: f64,
    max_solves: u32,
) -> ProjectionReport {
    let n = mesh.position.len();
    let rest: Vec<f64> = mesh
        .edges
        .iter()
        .map(|[a, b]| (mesh.material[*a as usize] - mesh.material[*b as usize]).norm())
        .collect();
    let (mut worst, mut merit) = measure(mesh, &rest, &mesh.position);
    let mut report = ProjectionReport {
        strain_before: worst,
        strain_after: worst,
        ..Default::default()
    };
    if mesh.edges.is_empty() || rest.iter().any(|l| *l <= 0.0) {
        return report;
    }
    let held = |v: usize| fixed.get(v).copied().unwrap_or(false);
    let fixed_dofs: Vec<bool> = (0..3 * n).map(|d| held(d / 3)).collect();
    // M: lumped masses relative to their mean (uniform without masses); the damping is
    // mu times M times the mean stiffness 1/l^2 of J^T J, so mu is dimensionless
    let mean_mass = mesh.mass.iter().sum::<f64>() / mesh.mass.len().max(1) as f64;
    let weight: Vec<f64> = (0..n)
        .map(|v| match mesh.mass.get(v) {
            Some(m) if mean_mass > 0.0 && *m > 0.0 => m / mean_mass,
            _ => 1.0,
        })
        .collect();
    let scale = rest.iter().map(|l| 1.0 / (l * l)).sum::<f64>() / rest.len() as f64;
    let mut groups = mesh.edges.iter().map(|e| e.to_vec());
    let mut a = BlockSpd::new(n, 3, &mut groups);
    let mut mu = 1e-6;
    let mut rhs = faer::Mat::<f64>::zeros(3 * n, 1);
    let mut trial = mesh.position.clone();
    while worst > tolerance && report.solves < max_solves {
        assemble(mesh, &rest, &weight, mu * scale, &mut a, &mut rhs);
        for (d, f) in fixed_dofs.iter().enumerate() {
            if *f {
                rhs[(d, 0)] = 0.0;
            }
        }
        a.fix_all(&fixed_dofs);
        report.solves += 1;
        if a.solve_in_place(rhs.as_mut()).is_err() {
            mu *= 10.0;
            continue;
        }
        for (v, p) in trial.iter_mut().enumerate() {
            *p = mesh.position[v]
                + Vector3::new(rhs[(3 * v, 0)], rhs[(3 * v + 1, 0)], rhs[(3 * v + 2, 0)]);
        }
        let (w, m) = measure(mesh, &rest, &trial);
        if m.is_finite() && m < merit {
            mesh.position.copy_from_slice(&trial);
            (worst, merit) = (w, m);
            mu = (mu * 0.1).max(1e-9);
        } else {
            // Levenberg-Marquardt: a shorter, more gradient-like step
            mu *= 10.0;
        }
    }
    report.strain_after = worst;
    report
}

/// J^T J + damping * M (3x3 blocks) and the right-hand side -J^T C at the current
/// positions of `mesh`.
fn assemble(
    mesh: &PhysicalMesh,
    rest: &[f64],
    weight: &[f64],
    damping: f64,
    a: &mut BlockSpd,
    rhs: &mut faer::Mat<f64>,
) {
    a.clear();
    rhs.fill(0.0);
    for (v, w) in weight.iter().enumerate() {
        let m = damping * w;
        a.add_block(v, v, &[m, 0.0, 0.0, 0.0, m, 0.0, 0.0, 0.0, m]);
    }
    for ([i, j], l) in mesh.edges.iter().zip(rest) {
        let (i, j) = (*i as usize, *j as usize);
        let d = mesh.position[j] - mesh.position[i];
        let l2 = l * l;
        // dC/dp_j = d / l^2 = -dC/dp_i
        let g = d / l2;
        let c = 0.5 * (d.norm_squared() / l2 - 1.0);
        let mut block = [0.0; 9];
        for r in 0..3 {
            for s in 0..3 {
                block[3 * r + s] = g[r] * g[s];
            }
        }
        a.add_edge_block(i, j, &block);
        for r in 0..3 {
            rhs[(3 * j + r, 0)] -= g[r] * c;
            rhs[(3 * i + r, 0)] += g[r] * c;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{Point2, Point3};

    /// A flat n x n grid of squares split into triangles, spacing h, unit masses.
    fn grid(n: usize, h: f64) -> PhysicalMesh {
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
    fn a_squeezed_cylinder_is_projected_back_to_its_lengths() {
        let mut mesh = grid(6, 0.01);
        // a cylinder of radius 3 cm squeezed by 5 % along the axis with a wobble:
        // an isometric shape exists (the unsqueezed cylinder), the start is 5 % off
        for (p, m) in mesh.position.iter_mut().zip(&mesh.material) {
            let r = 0.03;
            let phi = m.x / r;
            *p = Point3::new(r * phi.sin(), 0.95 * m.y, r * (1.0 - phi.cos()));
            p.z += 2e-4 * (37.0 * m.x + 11.0 * m.y).sin();
        }
        let mut fixed = vec![false; mesh.material.len()];
        fixed[0] = true;
        let held = mesh.position[0];
        let report = project_lengths(&mut mesh, &fixed, 1e-6, 20);
        assert!(report.strain_before > 0.04, "{report:?}");
        assert!(report.strain_after < 1e-6, "{report:?}");
        assert!(report.solves <= 10, "a few Newton steps: {report:?}");
        assert_eq!(mesh.position[0], held, "the held vertex stays");
    }

    #[test]
    fn unreachable_held_vertices_give_the_least_strain_not_a_blow_up() {
        let mut mesh = grid(4, 0.01);
        // two opposite corners held 10 % farther apart than the pattern allows
        let (first, last) = (0, mesh.position.len() - 1);
        for p in mesh.position.iter_mut() {
            *p = Point3::from(p.coords * 1.1);
        }
        let mut fixed = vec![false; mesh.material.len()];
        fixed[first] = true;
        fixed[last] = true;
        let report = project_lengths(&mut mesh, &fixed, 1e-6, 30);
        // the diagonal edges form a path between the held corners 10 % shorter than
        // their distance: one of them must stay stretched by 10 % or more; the others
        // need not make it worse
        assert!(report.strain_after >= 0.1 - 1e-9, "{report:?}");
        assert!(report.strain_after < 0.12, "no blow-up: {report:?}");
        assert!(mesh
            .position
            .iter()
            .all(|p| p.coords.iter().all(|c| c.is_finite())));
    }
}
