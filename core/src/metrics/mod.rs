//! Error measures shared by tests, stats and the report: isometry, distance between two
//! surfaces at matched material points (the ribbon remeshes in material space, so
//! vertex indices do not correspond across runs).

pub mod elastica;

use crate::geometry::{Point2, Point3, SurfaceMesh};

/// World position of the material point `m` on `mesh` (barycentric interpolation in
/// the triangle of the flat pattern containing it), or None if outside the pattern.
pub fn world_at_material(mesh: &SurfaceMesh, m: &Point2) -> Option<Point3> {
    let mut best: Option<(f64, Point3)> = None;
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|i| i as usize);
        let (pa, pb, pc) = (mesh.material[a], mesh.material[b], mesh.material[c]);
        let v0 = pb - pa;
        let v1 = pc - pa;
        let v2 = m - pa;
        let det = v0.x * v1.y - v0.y * v1.x;
        if det.abs() < 1e-18 {
            continue;
        }
        let l1 = (v2.x * v1.y - v2.y * v1.x) / det;
        let l2 = (v0.x * v2.y - v0.y * v2.x) / det;
        let l0 = 1.0 - l1 - l2;
        // how far outside the triangle (0 inside): pick the best triangle so points on
        // the boundary, within round-off, still resolve
        let outside = (-l0).max(-l1).max(-l2).max(0.0);
        let p = Point3::from(
            mesh.vertices[a].coords * l0
                + mesh.vertices[b].coords * l1
                + mesh.vertices[c].coords * l2,
        );
        if best.as_ref().is_none_or(|(o, _)| outside < *o) {
            best = Some((outside, p));
        }
        if outside == 0.0 {
            break;
        }
    }
    best.filter(|(o, _)| *o < 1e-9).map(|(_, p)| p)
}

/// Material sample points on a length x width strip: `along` x `across` grid, m.
pub fn strip_samples(length: f64, width: f64, along: usize, across: usize) -> Vec<Point2> {
    let mut out = Vec::with_capacity(along * across);
    for i in 0..along {
        for j in 0..across {
            let u = length * i as f64 / (along - 1).max(1) as f64;
            let v = width * (j as f64 / (across - 1).max(1) as f64 - 0.5);
            out.push(Point2::new(u, v));
        }
    }
    out
}

/// RMS distance (m) between two meshes of the same flat pattern at matched material
/// points; None if a sample is outside either pattern.
pub fn rms_distance(a: &SurfaceMesh, b: &SurfaceMesh, samples: &[Point2]) -> Option<f64> {
    let mut sum = 0.0;
    for s in samples {
        let pa = world_at_material(a, s)?;
        let pb = world_at_material(b, s)?;
        sum += (pa - pb).norm_squared();
    }
    Some((sum / samples.len().max(1) as f64).sqrt())
}

/// Like [`rms_distance`] but skipping the samples outside either pattern (a remeshed
/// paper pattern need not cover every grid point): the RMS distance (m) over the
/// samples both meshes cover and how many those are; None if none is covered.
pub fn rms_distance_where_defined(
    a: &SurfaceMesh,
    b: &SurfaceMesh,
    samples: &[Point2],
) -> Option<(f64, usize)> {
    let mut sum = 0.0;
    let mut used = 0;
    for s in samples {
        if let (Some(pa), Some(pb)) = (world_at_material(a, s), world_at_material(b, s)) {
            sum += (pa - pb).norm_squared();
            used += 1;
        }
    }
    (used > 0).then(|| ((sum / used as f64).sqrt(), used))
}

/// Material sample points on an `along` x `across` grid inside the rectangle
/// [lo, hi] (m), inset by `inset` (m) so boundary points resolve after remeshing.
pub fn grid_samples(
    lo: Point2,
    hi: Point2,
    along: usize,
    across: usize,
    inset: f64,
) -> Vec<Point2> {
    let mut out = Vec::with_capacity(along * across);
    let span = |a: f64, b: f64, i: usize, n: usize| {
        a + inset + (b - a - 2.0 * inset) * i as f64 / (n - 1).max(1) as f64
    };
    for i in 0..along {
        for j in 0..across {
            out.push(Point2::new(
                span(lo.x, hi.x, i, along),
                span(lo.y, hi.y, j, across),
            ));
        }
    }
    out
}
