//! The crease-dependent consistent mass matrix of a trapezoid element (Pan et al.
//! appendix B) and the lumped centerline masses (sec. 6).
//!
//! Element E_i is the material trapezoid x̄_i, ȳ_i, x̄_{i+1}, ȳ_{i+1}. With bilinear
//! shape functions its consistent mass is `rho * K ⊗ I_3` in vertex order
//! (x_i, y_i, x_{i+1}, y_{i+1}), with Δc = c_{i+1} - c_i,
//! a = w (4l - Δc n w) / (72 n), b = w (4l + Δc n w) / (72 n), e = l w / (36 n):
//!
//! ```text
//! K = [[2a, 2e,  a,  e],
//!      [2e, 2b,  e,  b],
//!      [ a,  e, 2a, 2e],
//!      [ e,  b, 2e, 2b]]
//! ```
//! Its entries sum to l w / n, the element's area (m^2): the bottom edge shortens by
//! w Δc / 2 and the top edge lengthens by as much, so the area is independent of Δc.

/// The 4x4 matrix K (m^2) of one element and its derivative dK/dΔc (m^2 per unit Δc).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ElementMass {
    pub k: [[f64; 4]; 4],
    pub dk_ddelta_c: [[f64; 4]; 4],
}

/// K for an element of a ribbon of length `l`, width `w`, `n` elements, with crease
/// difference `delta_c` = c_{i+1} - c_i.
pub fn element_mass(l: f64, w: f64, n: usize, delta_c: f64) -> ElementMass {
    let nf = n as f64;
    let a = w * (4.0 * l - delta_c * nf * w) / (72.0 * nf);
    let b = w * (4.0 * l + delta_c * nf * w) / (72.0 * nf);
    let e = l * w / (36.0 * nf);
    let da = -w * w / 72.0;
    let db = w * w / 72.0;
    let k = [
        [2.0 * a, 2.0 * e, a, e],
        [2.0 * e, 2.0 * b, e, b],
        [a, e, 2.0 * a, 2.0 * e],
        [e, b, 2.0 * e, 2.0 * b],
    ];
    let dk_ddelta_c = [
        [2.0 * da, 0.0, da, 0.0],
        [0.0, 2.0 * db, 0.0, db],
        [da, 0.0, 2.0 * da, 0.0],
        [0.0, db, 0.0, 2.0 * db],
    ];
    ElementMass { k, dk_ddelta_c }
}

/// Lumped centerline masses M_i (kg) of the simplified kinetic term: rho l w / n at
/// interior stations, half of it at the two ends.
pub fn lumped_centerline_mass(density: f64, l: f64, w: f64, n: usize, station: usize) -> f64 {
    let m = density * l * w / n as f64;
    if station == 0 || station == n {
        0.5 * m
    } else {
        m
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Consistent mass by 4x4 Gauss quadrature of bilinear shape functions over the
    /// material trapezoid: the independent derivation the closed form must match.
    fn quadrature_mass(l: f64, w: f64, n: usize, c0: f64, c1: f64) -> [[f64; 4]; 4] {
        let h = l / n as f64;
        // material corners (x_i, y_i, x_{i+1}, y_{i+1}) of element 0 (station 0)
        let corners = [
            [-0.5 * w * c0, -0.5 * w],
            [0.5 * w * c0, 0.5 * w],
            [h - 0.5 * w * c1, -0.5 * w],
            [h + 0.5 * w * c1, 0.5 * w],
        ];
        let gauss = [
            (-0.861_136_311_594_052_6, 0.347_854_845_137_453_9),
            (-0.339_981_043_584_856_3, 0.652_145_154_862_546_1),
            (0.339_981_043_584_856_3, 0.652_145_154_862_546_1),
            (0.861_136_311_594_052_6, 0.347_854_845_137_453_9),
        ];
        let mut m = [[0.0; 4]; 4];
        for &(gs, ws) in &gauss {
            for &(gt, wt) in &gauss {
                let (s, t) = (0.5 * (gs + 1.0), 0.5 * (gt + 1.0));
                // shape functions in vertex order (x_i, y_i, x_{i+1}, y_{i+1})
                let nfun = [(1.0 - s) * (1.0 - t), (1.0 - s) * t, s * (1.0 - t), s * t];
                let ds = [-(1.0 - t), -t, 1.0 - t, t];
                let dt = [-(1.0 - s), 1.0 - s, -s, s];
                let mut jac = [[0.0; 2]; 2];
                for a in 0..4 {
                    for d in 0..2 {
                        jac[0][d] += ds[a] * corners[a][d];
                        jac[1][d] += dt[a] * corners[a][d];
                    }
                }
                let det = (jac[0][0] * jac[1][1] - jac[0][1] * jac[1][0]).abs();
                let weight = ws * wt * 0.25 * det;
                for a in 0..4 {
                    for b in 0..4 {
                        m[a][b] += weight * nfun[a] * nfun[b];
                    }
                }
            }
        }
        m
    }

    #[test]
    fn closed_form_matches_quadrature_of_bilinear_shape_functions() {
        // every |Δc| within the non-intersection bound 0.95 * 2l/(wn) = 0.76 (beyond it the
        // trapezoid folds over itself)
        for (c0, c1) in [
            (0.0, 0.0),
            (0.3, -0.2),
            (-0.4, 0.3),
            (1.2, 1.9),
            (0.5, -0.25),
        ] {
            let (l, w, n) = (1.0, 0.05, 50);
            let k = element_mass(l, w, n, c1 - c0).k;
            let q = quadrature_mass(l, w, n, c0, c1);
            for a in 0..4 {
                for b in 0..4 {
                    assert!(
                        (k[a][b] - q[a][b]).abs() < 1e-15,
                        "{a},{b}: {} vs {}",
                        k[a][b],
                        q[a][b]
                    );
                }
            }
        }
    }

    #[test]
    fn entries_sum_to_the_element_area_and_are_symmetric() {
        let (l, w, n) = (1.3, 0.1, 17);
        for dc in [-0.9, 0.0, 0.4] {
            let m = element_mass(l, w, n, dc);
            let sum: f64 = m.k.iter().flatten().sum();
            assert!((sum - l * w / n as f64).abs() < 1e-15);
            let dsum: f64 = m.dk_ddelta_c.iter().flatten().sum();
            assert!(dsum.abs() < 1e-18);
            for a in 0..4 {
                for b in 0..4 {
                    assert_eq!(m.k[a][b], m.k[b][a]);
                }
            }
        }
    }

    #[test]
    fn matches_the_papers_printed_entries() {
        // Appendix B prints the entries as lw/36n, lw/18n and (±Δc n w^2 + 4lw)/(72n),
        // (±...)/36n: check each against our a, b, e.
        let (l, w, n, dc) = (1.0, 0.05, 50_usize, 0.37);
        let nf = n as f64;
        let m = element_mass(l, w, n, dc).k;
        assert!((m[0][3] - l * w / (36.0 * nf)).abs() < 1e-16);
        assert!((m[0][1] - l * w / (18.0 * nf)).abs() < 1e-16);
        assert!((m[0][2] - (-dc * nf * w * w + 4.0 * l * w) / (72.0 * nf)).abs() < 1e-16);
        assert!((m[0][0] - (-dc * nf * w * w + 4.0 * l * w) / (36.0 * nf)).abs() < 1e-16);
        assert!((m[1][1] - (dc * nf * w * w + 4.0 * l * w) / (36.0 * nf)).abs() < 1e-16);
    }

    #[test]
    fn lumped_masses_sum_to_total() {
        let total: f64 = (0..=10)
            .map(|i| lumped_centerline_mass(0.08, 1.0, 0.05, 10, i))
            .sum();
        assert!((total - 0.08 * 0.05).abs() < 1e-15);
    }
}
