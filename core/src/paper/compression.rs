//! Step 2(a) (Schreck et al. sec. 5.1): flat regions as maximal sets of pairwise
//! coplanar S_G triangles, and the compression of each triangle from its principal
//! strains (the stretch tensor, Rohmer et al. 2010).

use nalgebra::{Matrix2, Matrix3x2, Vector2};

use super::geometric::{EdgeKind, FaceKind, GeometricMesh};

/// Principal stretches of one flat triangle of S_G.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TriangleStrain {
    pub face: usize,
    /// 1 - lambda_min: how much the triangle is compressed along `v` (dimensionless,
    /// <= 0 when not compressed).
    pub compression: f64,
    /// v: direction of maximal compression in the pattern (unit).
    pub direction: Vector2<f64>,
    /// v_perp: direction of minimal compression (the new rulings' direction).
    pub ruling_direction: Vector2<f64>,
}

/// Principal strains of triangle `face` (three vertices) of S_G.
pub fn triangle_strain(gmesh: &GeometricMesh, face: usize) -> Option<TriangleStrain> {
    let f = &gmesh.faces[face];
    if f.vertices.len() != 3 {
        return None;
    }
    let [a, b, c] = [0, 1, 2].map(|k| &gmesh.vertices[f.vertices[k] as usize]);
    let dm = Matrix2::from_columns(&[b.material - a.material, c.material - a.material]);
    let inv = dm.try_inverse()?;
    let ds = Matrix3x2::from_columns(&[b.position - a.position, c.position - a.position]);
    let deformation = ds * inv;
    // right Cauchy-Green tensor C = F^T F: principal stretches lambda_i = sqrt(eig C)
    let cauchy_green = deformation.transpose() * deformation;
    let eig = cauchy_green.symmetric_eigen();
    let (kmin, kmax) = if eig.eigenvalues[0] <= eig.eigenvalues[1] {
        (0, 1)
    } else {
        (1, 0)
    };
    let lambda_min = eig.eigenvalues[kmin].max(0.0).sqrt();
    let v = eig.eigenvectors.column(kmin).into_owned();
    let v_perp = eig.eigenvectors.column(kmax).into_owned();
    Some(TriangleStrain {
        face,
        compression: 1.0 - lambda_min,
        direction: v.normalize(),
        ruling_direction: v_perp.normalize(),
    })
}

/// The flat region of each face (`usize::MAX` for curved faces): flat triangles joined
/// across plain edges (rulings and creases always separate), and, when `fold_angle` is
/// given (theta_0, rad), only across plain edges whose dihedral angle is at most that.
/// Labels are numbered in face order.
pub fn flat_regions(gmesh: &GeometricMesh, fold_angle: Option<f64>) -> Vec<usize> {
    let n = gmesh.faces.len();
    let mut parent: Vec<usize> = (0..n).collect();
    fn find(p: &mut [usize], mut x: usize) -> usize {
        while p[x] != x {
            p[x] = p[p[x]];
            x = p[x];
        }
        x
    }
    for (&(a, b), e) in &gmesh.edges {
        let [Some(f0), Some(f1)] = e.faces else {
            continue;
        };
        if gmesh.faces[f0].kind != FaceKind::Flat || gmesh.faces[f1].kind != FaceKind::Flat {
            continue;
        }
        if e.kind != EdgeKind::Plain {
            continue;
        }
        if fold_angle.is_none_or(|t| gmesh.dihedral(a, b).is_some_and(|d| d <= t)) {
            let (r0, r1) = (find(&mut parent, f0), find(&mut parent, f1));
            if r0 != r1 {
                parent[r0.max(r1)] = r0.min(r1);
            }
        }
    }
    let mut label = vec![usize::MAX; n];
    let mut next = 0;
    let mut root_label = vec![usize::MAX; n];
    for f in 0..n {
        if gmesh.faces[f].kind != FaceKind::Flat {
            continue;
        }
        let r = find(&mut parent, f);
        if root_label[r] == usize::MAX {
            root_label[r] = next;
            next += 1;
        }
        label[f] = root_label[r];
    }
    label
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{Point2, Point3};
    use crate::paper::geometric::{GVertexKind, GeometricLayer};
    use crate::paper::pattern::Pattern;

    #[test]
    fn a_uniformly_shortened_sheet_is_compressed_along_the_shortening() {
        let pattern = Pattern::rectangle(0.1, 0.1);
        let layer = GeometricLayer::default();
        // compress u by 1 %, keep v
        let squeeze = |_: &GVertexKind, m: &Point2| Point3::new(0.99 * m.x, m.y, 0.0);
        let gmesh = GeometricMesh::build(&layer, &pattern, &squeeze).unwrap();
        let labels = flat_regions(&gmesh, Some(0.01));
        assert!(
            labels.iter().all(|&l| l == 0),
            "one flat region: {labels:?}"
        );
        for f in 0..gmesh.faces.len() {
            let s = triangle_strain(&gmesh, f).unwrap();
            assert!((s.compression - 0.01).abs() < 1e-12);
            assert!(
                s.direction.x.abs() > 1.0 - 1e-12,
                "v along u: {:?}",
                s.direction
            );
            assert!(s.ruling_direction.y.abs() > 1.0 - 1e-12);
        }
    }
}
