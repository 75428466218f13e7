//! Step 3 (Schreck et al. sec. 6.1, 6.2): junction points between flat and curved
//! regions moved with hysteresis, and curved regions segmented into generalized cones
//! by the Blaschke-cylinder apex fit (eq. 2) with their rulings realigned through the
//! apices (boundary resampling, fig. 15).

use nalgebra::{Matrix3, Vector2};

use super::crumpling::{segment_is_free, snap_to_vertex, CrumpleContext};
use super::geometric::{Endpoint, FaceKind, GVertexKind, GeometricLayer, GeometricMesh, Ruling};
use super::pattern::Pattern;
use crate::geometry::{Point2, Point3, Vector3};

/// What the junction update did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct JunctionReport {
    /// Border rulings removed (flat regions expanded).
    pub shrunk: usize,
    /// Rulings added (curved regions expanded).
    pub expanded: usize,
    /// Curved regions that became flat.
    pub flattened: usize,
}

/// The boundary endpoint one spacing beyond `s` away from `s_inner` (arc lengths, m).
fn step_out(pattern: &Pattern, s: f64, s_inner: f64, spacing: f64) -> f64 {
    let fwd = pattern.arc_ccw(s_inner, s);
    let per = pattern.perimeter();
    if fwd < 0.5 * per {
        pattern.wrap(s + spacing)
    } else {
        pattern.wrap(s - spacing)
    }
}

/// Sec. 6.1: for each curved region C and each of its two border rulings next to a
/// flat region F, with dihedral angle theta_CF: below theta_low the border ruling is
/// removed (F grows, repeatedly); above theta_high a new ruling is added one boundary
/// spacing into F (C grows), only if theta_CF exceeds the angle theta_opp of the other
/// borders at the same junction point (fig. 13). A region whose rulings are all flatter
/// than theta_low becomes flat.
/// Returns the report and, when the structure changed, its new mesh.
pub fn update_junctions(
    ctx: &CrumpleContext,
    layer: &mut GeometricLayer,
    gmesh: &GeometricMesh,
) -> (JunctionReport, Option<GeometricMesh>) {
    let params = ctx.params;
    let mut report = JunctionReport::default();
    let dihedral = |a: u32, b: u32| gmesh.dihedral(a, b).unwrap_or(0.0);
    let region_ids: Vec<u64> = layer.regions.iter().map(|r| r.id).collect();
    let mut proposals = Vec::new();
    for (ri, id) in region_ids.iter().enumerate() {
        let Some(rv) = gmesh.ruling_vertices.get(ri) else {
            continue;
        };
        let Some(cur) = layer.regions.iter().position(|r| r.id == *id) else {
            continue;
        };
        let junctions = RegionJunctions {
            ctx,
            gmesh,
            rv,
            angles: rv.iter().map(|&[a, b]| dihedral(a, b)).collect(),
        };
        if junctions
            .angles
            .iter()
            .all(|&t| t < params.junction_low_angle)
        {
            layer.regions.remove(cur);
            report.flattened += 1;
            continue;
        }
        let mut rulings = layer.regions[cur].rulings.clone();
        let (lo, hi) = junctions.shrink(rulings.len(), &mut report);
        rulings = rulings[lo..hi].to_vec();
        // expand at an end sharper than theta_high
        for front in [true, false] {
            let Some(new) = junctions.expansion(layer, &rulings, lo, hi, front) else {
                continue;
            };
            if front {
                rulings.insert(0, new);
            } else {
                rulings.push(new);
            }
            report.expanded += 1;
        }
        if rulings != layer.regions[cur].rulings {
            proposals.push((*id, rulings));
        }
    }
    let mesh = apply_validated(ctx, layer, proposals);
    let changed = report.flattened > 0 || report.shrunk > 0 || report.expanded > 0;
    let mesh = match mesh {
        Some(m) => Some(m),
        None if changed => GeometricMesh::build(layer, ctx.pattern, ctx.position).ok(),
        None => None,
    };
    (report, mesh)
}

/// A curved region's border rulings in S_G while sec. 6.1 moves its junctions.
struct RegionJunctions<'r, 'a> {
    ctx: &'r CrumpleContext<'a>,
    gmesh: &'r GeometricMesh,
    /// The S_G vertices [a, b] of each ruling.
    rv: &'r [[u32; 2]],
    /// The dihedral angle theta along each ruling (rad; 0 where it has no two faces).
    angles: Vec<f64>,
}

impl RegionJunctions<'_, '_> {
    /// Shrink the region's `n` rulings from both ends while the border ruling is
    /// flatter than theta_low next to a flat region, keeping at least 2 (each removal
    /// counted in `report.shrunk`). Returns the kept range lo..hi.
    fn shrink(&self, n: usize, report: &mut JunctionReport) -> (usize, usize) {
        let (gmesh, rv, angles) = (self.gmesh, self.rv, &self.angles);
        let low = self.ctx.params.junction_low_angle;
        let mut lo = 0usize;
        let mut hi = n;
        while hi - lo > 2 && angles[lo] < low && border_is_flat(gmesh, rv[lo]) {
            lo += 1;
            report.shrunk += 1;
        }
        while hi - lo > 2 && angles[hi - 1] < low && border_is_flat(gmesh, rv[hi - 1]) {
            hi -= 1;
            report.shrunk += 1;
        }
        (lo, hi)
    }

    /// The ruling one boundary spacing into F beyond the `front` (else back) border
    /// ruling of the kept `rulings` (range lo..hi of the original ones), when that
    /// border is next to a flat region, sharper than theta_high and than theta_opp of
    /// the other borders at its junction (fig. 13), and the new ruling is free.
    fn expansion(
        &self,
        layer: &GeometricLayer,
        rulings: &[Ruling],
        lo: usize,
        hi: usize,
        front: bool,
    ) -> Option<Ruling> {
        let (ctx, gmesh, rv) = (self.ctx, self.gmesh, self.rv);
        let params = ctx.params;
        let (k, k_in) = if front {
            (lo, lo + 1)
        } else {
            (hi - 1, hi - 2)
        };
        if k_in >= rv.len() || !border_is_flat(gmesh, rv[k]) {
            return None;
        }
        let theta = self.angles[k];
        if theta <= params.junction_high_angle {
            return None;
        }
        if theta <= opposite_angle(gmesh, rv[k]) {
            return None;
        }
        let (r, r_in) = if front {
            (rulings[0], rulings[1])
        } else {
            (rulings[rulings.len() - 1], rulings[rulings.len() - 2])
        };
        let spacing = params.boundary_spacing();
        let out = |e: Endpoint, inner: Endpoint| match (e, inner) {
            (Endpoint::Boundary(s), Endpoint::Boundary(si)) => {
                Some(Endpoint::Boundary(snap_to_vertex(
                    ctx,
                    gmesh,
                    step_out(ctx.pattern, s, si, spacing),
                    params.min_boundary_spacing(),
                    &[],
                )))
            }
            (Endpoint::Singular(id), _) => Some(Endpoint::Singular(id)),
            _ => None,
        };
        let (Some(a), Some(b)) = (out(r.a, r_in.a), out(r.b, r_in.b)) else {
            return None;
        };
        if a == r.a && b == r.b {
            return None;
        }
        let p = layer.endpoint_material(ctx.pattern, &a);
        let q = layer.endpoint_material(ctx.pattern, &b);
        if !segment_is_free(ctx, layer, gmesh, &p, &q, &[]) {
            return None;
        }
        Some(Ruling { a, b })
    }
}

/// Replace the rulings of regions (by id) and keep the result if S_G still meshes;
/// otherwise apply the proposals one at a time, keeping those that mesh. Returns the
/// mesh of the resulting structure when it was built here.
fn apply_validated(
    ctx: &CrumpleContext,
    layer: &mut GeometricLayer,
    proposals: Vec<(u64, Vec<Ruling>)>,
) -> Option<GeometricMesh> {
    if proposals.is_empty() {
        return None;
    }
    let saved = layer.clone();
    for (id, rulings) in &proposals {
        if let Some(r) = layer.regions.iter_mut().find(|r| r.id == *id) {
            r.rulings = rulings.clone();
        }
    }
    if let Ok(mesh) = GeometricMesh::build(layer, ctx.pattern, ctx.position) {
        return Some(mesh);
    }
    *layer = saved;
    let mut last = None;
    for (id, rulings) in proposals {
        let Some(k) = layer.regions.iter().position(|r| r.id == id) else {
            continue;
        };
        let old = std::mem::replace(&mut layer.regions[k].rulings, rulings);
        match GeometricMesh::build(layer, ctx.pattern, ctx.position) {
            Ok(mesh) => last = Some(mesh),
            Err(_) => layer.regions[k].rulings = old,
        }
    }
    last
}

/// True when ruling edge `r` has a flat face on one side.
fn border_is_flat(gmesh: &GeometricMesh, r: [u32; 2]) -> bool {
    gmesh
        .edge_faces(r[0], r[1])
        .iter()
        .flatten()
        .any(|&f| gmesh.faces[f].kind == FaceKind::Flat)
}

/// theta_opp (fig. 13): the largest dihedral angle of the other interior edges at the
/// boundary ends of ruling `r`.
fn opposite_angle(gmesh: &GeometricMesh, r: [u32; 2]) -> f64 {
    let mut best: f64 = 0.0;
    for &j in &r {
        if !matches!(
            gmesh.vertices[j as usize].kind,
            GVertexKind::Boundary { .. }
        ) {
            continue;
        }
        for (&(a, b), e) in &gmesh.edges {
            if (a != j && b != j) || (a.min(b), a.max(b)) == (r[0].min(r[1]), r[0].max(r[1])) {
                continue;
            }
            if e.faces[1].is_none() {
                continue;
            }
            best = best.max(gmesh.dihedral(a, b).unwrap_or(0.0));
        }
    }
    best
}

/// The tangent plane along a ruling: unit normal n_i and signed distance w_i (m) to
/// the origin, n_i . x + w_i = 0 (sec. 6.2).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TangentPlane {
    pub normal: Vector3,
    pub offset: f64,
}

/// The best common apex of a family of tangent planes (eq. 2).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ConeFit {
    /// The apex a minimizing e = sum (n_i . a + w_i)^2, m; for a cylinder (apex at
    /// infinity) the point of the axis closest to the planes' centroid.
    pub apex: Point3,
    /// Some(direction) when the apex is at infinity (a generalized cylinder).
    pub direction: Option<Vector3>,
    /// sqrt(e), m.
    pub error: f64,
}

/// Eq. (2): least-squares apex of the planes (Blaschke cylinder: the planes are the
/// points (n_i, w_i) of B, the apex a the hyperplane n . a + w = 0 closest to them).
/// `reference` (a point near the planes) and `scale` (m) decide when the apex is at
/// infinity: farther than 1e3 * scale.
pub fn fit_apex(planes: &[TangentPlane], reference: &Point3, scale: f64) -> ConeFit {
    let mut m = Matrix3::zeros();
    let mut rhs = Vector3::zeros();
    for p in planes {
        // centred at the reference point: w' = w + n . c
        let w = p.offset + p.normal.dot(&reference.coords);
        m += p.normal * p.normal.transpose();
        rhs -= w * p.normal;
    }
    let eig = m.symmetric_eigen();
    let top = eig.eigenvalues.iter().copied().fold(0.0, f64::max);
    let mut local = Vector3::zeros();
    let mut smallest = (f64::INFINITY, Vector3::z());
    for k in 0..3 {
        let l = eig.eigenvalues[k];
        let v = eig.eigenvectors.column(k).into_owned();
        if l < smallest.0 {
            smallest = (l, v);
        }
        if l > 1e-12 * top.max(1e-300) {
            local += v * (v.dot(&rhs) / l);
        }
    }
    let direction = if local.norm() > 1e3 * scale || smallest.0 < 1e-10 * top.max(1e-300) {
        // apex at infinity: keep the well-determined part only
        let (_, d) = smallest;
        local -= d * d.dot(&local);
        Some(d)
    } else {
        None
    };
    let apex = Point3::from(reference.coords + local);
    let error = planes
        .iter()
        .map(|p| {
            let r = p.normal.dot(&apex.coords) + p.offset;
            if direction.is_some() {
                // distance of the plane to the axis line through apex
                r * r
            } else {
                r * r
            }
        })
        .sum::<f64>()
        .sqrt();
    ConeFit {
        apex,
        direction,
        error,
    }
}

/// Per-ruling error contributions e_i = (n_i . a + w_i)^2 (m^2).
fn contributions(planes: &[TangentPlane], fit: &ConeFit) -> Vec<f64> {
    planes
        .iter()
        .map(|p| {
            let r = p.normal.dot(&fit.apex.coords) + p.offset;
            r * r
        })
        .collect()
}

/// The iterative segmentation of sec. 6.2: ranges of consecutive rulings, each
/// approximated by one generalized cone with error <= `tolerance` (m).
pub fn segment_cones(
    planes: &[TangentPlane],
    reference: &Point3,
    scale: f64,
    tolerance: f64,
) -> Vec<(std::ops::Range<usize>, ConeFit)> {
    let mut out = Vec::new();
    let mut stack = Vec::new();
    stack.push(0..planes.len());
    while let Some(range) = stack.pop() {
        if range.is_empty() {
            continue;
        }
        let mut cur = range.clone();
        let mut front_end = range.start; // R_front = range.start..front_end
        let mut back_start = range.end; // R_back = back_start..range.end
        loop {
            let fit = fit_apex(&planes[cur.clone()], reference, scale);
            if fit.error <= tolerance || cur.len() <= 2 {
                out.push((cur.clone(), fit));
                break;
            }
            let e = contributions(&planes[cur.clone()], &fit);
            if e[0] >= e[e.len() - 1] {
                cur.start += 1;
                front_end = cur.start;
            } else {
                cur.end -= 1;
                back_start = cur.end;
            }
        }
        if front_end > range.start {
            stack.push(range.start..front_end);
        }
        if back_start < range.end {
            stack.push(back_start..range.end);
        }
    }
    out.sort_by_key(|(r, _)| r.start);
    out
}

/// The tangent plane along ruling (a, b) of S_G: the mean of its two faces' normals
/// through the ruling's midpoint.
pub fn ruling_plane(gmesh: &GeometricMesh, r: [u32; 2]) -> TangentPlane {
    let mut n = Vector3::zeros();
    for f in gmesh.edge_faces(r[0], r[1]).iter().flatten() {
        n += gmesh.normals[*f];
    }
    let n = if n.norm() > 1e-12 {
        n.normalize()
    } else {
        Vector3::z()
    };
    let mid = (gmesh.vertices[r[0] as usize].position.coords
        + gmesh.vertices[r[1] as usize].position.coords)
        * 0.5;
    TangentPlane {
        normal: n,
        offset: -n.dot(&mid),
    }
}

/// What the cone fitting did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ConeReport {
    /// Generalized cones found (sum over regions).
    pub cones: usize,
    /// Rulings moved to pass through their cone's apex.
    pub realigned: usize,
}

/// Sec. 6.2: segment every curved region without an interior singular apex into
/// generalized cones and realign its rulings through the apices (the boundary is
/// resampled: the ends of each 2D ruling move along ∂S̄ so that its line passes
/// through the apex image ā_proj; two successive cones whose extreme rulings cross
/// share a boundary vertex, the apex of the junction cone between them, fig. 15).
/// Returns the report and, when the structure changed, its new mesh.
pub fn fit_cones(
    ctx: &CrumpleContext,
    layer: &mut GeometricLayer,
    gmesh: &GeometricMesh,
) -> (ConeReport, Option<GeometricMesh>) {
    let mut report = ConeReport::default();
    let mut proposals = Vec::new();
    for ri in 0..layer.regions.len() {
        if let Some(proposal) = propose_realignment(ctx, layer, gmesh, ri, &mut report) {
            proposals.push(proposal);
        }
    }
    let moved: std::collections::BTreeMap<u64, usize> =
        proposals.iter().map(|(id, _, m)| (*id, *m)).collect();
    let before = layer.regions.clone();
    let mesh = apply_validated(
        ctx,
        layer,
        proposals.into_iter().map(|(id, r, _)| (id, r)).collect(),
    );
    for (r, b) in layer.regions.iter().zip(&before) {
        if r.rulings != b.rulings {
            report.realigned += moved.get(&r.id).copied().unwrap_or(0);
        }
    }
    (report, mesh)
}

/// Sec. 6.2 for curved region `ri`: segment it into generalized cones (counted in
/// `report.cones`) and realign each cone's rulings through its apex, then merge the
/// ends of rulings that now cross (junction cones, fig. 15). Returns the region's id,
/// its new rulings and how many moved; `None` when the region has an interior
/// singular apex or fewer than 3 rulings, nothing moved, or the result has fewer than
/// 2 rulings or one shorter than the minimal gap.
fn propose_realignment(
    ctx: &CrumpleContext,
    layer: &GeometricLayer,
    gmesh: &GeometricMesh,
    ri: usize,
    report: &mut ConeReport,
) -> Option<(u64, Vec<Ruling>, usize)> {
    let scale = ctx.pattern.paper_length();
    let tolerance = ctx.params.blaschke_tolerance * scale;
    if layer.regions[ri].singular_apex().is_some() || layer.regions[ri].rulings.len() < 3 {
        return None;
    }
    let rv = gmesh.ruling_vertices.get(ri)?;
    let planes: Vec<TangentPlane> = rv.iter().map(|&r| ruling_plane(gmesh, r)).collect();
    let reference = Point3::from(
        rv.iter()
            .map(|&[a, b]| {
                (gmesh.vertices[a as usize].position.coords
                    + gmesh.vertices[b as usize].position.coords)
                    * 0.5
            })
            .sum::<Vector3>()
            / rv.len() as f64,
    );
    let segments = segment_cones(&planes, &reference, scale, tolerance);
    report.cones += segments.len();
    let region = RegionRulings {
        gmesh,
        rv,
        old: &layer.regions[ri].rulings,
        planes: &planes,
    };
    let mut new = region.old.to_vec();
    let mut moved = 0;
    for (range, fit) in &segments {
        moved += region.realign_cone(ctx, range, fit, &mut new);
    }
    if moved == 0 {
        return None;
    }
    merge_crossing_rulings(ctx, layer, &mut new);
    // drop rulings that became identical or too short
    new.dedup();
    let ok = new.len() >= 2
        && new.iter().all(|r| {
            let p = layer.endpoint_material(ctx.pattern, &r.a);
            let q = layer.endpoint_material(ctx.pattern, &r.b);
            (p - q).norm() > ctx.params.min_gap()
        });
    ok.then(|| (layer.regions[ri].id, new, moved))
}

/// A curved region's rulings in S_G while sec. 6.2 realigns them.
struct RegionRulings<'r> {
    gmesh: &'r GeometricMesh,
    /// The S_G vertices [a, b] of each ruling.
    rv: &'r [[u32; 2]],
    /// The rulings before realignment.
    old: &'r [Ruling],
    /// The tangent plane along each ruling.
    planes: &'r [TangentPlane],
}

impl RegionRulings<'_> {
    /// Realign the rulings of the cone `fit` over `range` in `new`: every boundary
    /// ruling but r_j (the one the fit explains best) turns about its midpoint to pass
    /// through the apex's 2D image in r_j's frame (or to parallel r_j for a cylinder).
    /// Returns how many moved; none for a cone of fewer than 2 rulings or whose apex
    /// lies inside the sheet (a cone with an interior singular point: not the case of
    /// sec. 6.2).
    fn realign_cone(
        &self,
        ctx: &CrumpleContext,
        range: &std::ops::Range<usize>,
        fit: &ConeFit,
        new: &mut [Ruling],
    ) -> usize {
        if range.len() < 2 {
            return 0;
        }
        let gmesh = self.gmesh;
        let e = contributions(&self.planes[range.clone()], fit);
        let j = range.start
            + e.iter()
                .enumerate()
                .min_by(|x, y| x.1.total_cmp(y.1))
                .map(|(k, _)| k)
                .unwrap_or(0);
        let [ja, jb] = self.rv[j];
        let (pa, pb) = (
            gmesh.vertices[ja as usize].position,
            gmesh.vertices[jb as usize].position,
        );
        let (ma, mb) = (
            gmesh.vertices[ja as usize].material,
            gmesh.vertices[jb as usize].material,
        );
        // the 2D apex (or direction) in the frame of ruling r_j
        let apex_2d: Result<Point2, Vector2<f64>> = match fit.direction {
            Some(_) => Err((mb - ma).normalize()),
            None => {
                let d = pb - pa;
                let t = (fit.apex - pa).dot(&d) / d.norm_squared().max(1e-300);
                Ok(ma + (mb - ma) * t)
            }
        };
        if let Ok(a2) = apex_2d {
            if ctx.pattern.signed_inside_distance(&a2) > 1e-9 {
                return 0;
            }
        }
        let mut moved = 0;
        for k in range.clone() {
            if k == j {
                continue;
            }
            if let Some(r) = self.realigned_ruling(ctx, k, apex_2d) {
                new[k] = r;
                moved += 1;
            }
        }
        moved
    }

    /// Ruling k turned about its pattern midpoint towards `apex_2d` (Ok: the apex
    /// image, m; Err: the cylinder's direction), its new ends on ∂S̄ snapped to S_G
    /// boundary vertices within the minimum spacing; `None` when it is not a boundary
    /// ruling, its line misses the pattern or its ends move less than 1e-5 m.
    fn realigned_ruling(
        &self,
        ctx: &CrumpleContext,
        k: usize,
        apex_2d: Result<Point2, Vector2<f64>>,
    ) -> Option<Ruling> {
        let (gmesh, rv) = (self.gmesh, self.rv);
        let r = self.old[k];
        let (Endpoint::Boundary(_), Endpoint::Boundary(_)) = (r.a, r.b) else {
            return None;
        };
        let [ka, kb] = rv[k];
        let (qa, qb) = (
            gmesh.vertices[ka as usize].material,
            gmesh.vertices[kb as usize].material,
        );
        let mid = Point2::from((qa.coords + qb.coords) * 0.5);
        let dir = match apex_2d {
            Ok(a2) => (mid - a2).normalize(),
            Err(d) => d,
        };
        let [(s_lo, _), (s_hi, _)] = ctx.pattern.clip_line(&mid, &dir)?;
        let (p_lo, p_hi) = (ctx.pattern.point_at(s_lo), ctx.pattern.point_at(s_hi));
        // keep the sides: the new end nearer the old a end is a
        let (sa, sb) =
            if (p_lo - qa).norm() + (p_hi - qb).norm() <= (p_hi - qa).norm() + (p_lo - qb).norm() {
                (s_lo, s_hi)
            } else {
                (s_hi, s_lo)
            };
        // ends closer than the minimum spacing to another vertex join it
        let own: Vec<u32> = rv.iter().flat_map(|r| [r[0], r[1]]).collect();
        let tol = ctx.params.min_boundary_spacing();
        let sa = snap_to_vertex(ctx, gmesh, sa, tol, &own);
        let sb = snap_to_vertex(ctx, gmesh, sb, tol, &own);
        let moved_by = (ctx.pattern.point_at(sa) - qa)
            .norm()
            .max((ctx.pattern.point_at(sb) - qb).norm());
        if moved_by < 1e-5 {
            return None;
        }
        Some(Ruling {
            a: Endpoint::Boundary(sa),
            b: Endpoint::Boundary(sb),
        })
    }
}

/// Junction cones (fig. 15): consecutive boundary rulings of `new` that now cross
/// share a boundary vertex, on the side nearer the crossing, at the mean arc length
/// of their ends there.
fn merge_crossing_rulings(ctx: &CrumpleContext, layer: &GeometricLayer, new: &mut [Ruling]) {
    for k in 0..new.len().saturating_sub(1) {
        let (r0, r1) = (new[k], new[k + 1]);
        let p = [r0.a, r0.b, r1.a, r1.b].map(|e| layer.endpoint_material(ctx.pattern, &e));
        if super::pattern::segments_cross(&p[0], &p[1], &p[2], &p[3], 1e-9) {
            if let (
                Endpoint::Boundary(sa0),
                Endpoint::Boundary(sa1),
                Endpoint::Boundary(sb0),
                Endpoint::Boundary(sb1),
            ) = (r0.a, r1.a, r0.b, r1.b)
            {
                // the crossing is nearer one side: merge the ends there
                let da = (p[0] - p[2]).norm();
                let db = (p[1] - p[3]).norm();
                let mean = |x: f64, y: f64| {
                    let d = ctx.pattern.arc_ccw(x, y);
                    if d < 0.5 * ctx.pattern.perimeter() {
                        ctx.pattern.wrap(x + 0.5 * d)
                    } else {
                        ctx.pattern.wrap(y + 0.5 * (ctx.pattern.perimeter() - d))
                    }
                };
                if da <= db {
                    let j = Endpoint::Boundary(mean(sa0, sa1));
                    new[k].a = j;
                    new[k + 1].a = j;
                } else {
                    let j = Endpoint::Boundary(mean(sb0, sb1));
                    new[k].b = j;
                    new[k + 1].b = j;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_blaschke_fit_finds_the_apex_of_an_exact_cone() {
        // a circular cone: apex (0.02, -0.03, 0.05), axis z, half-angle 30 deg
        let apex = Vector3::new(0.02, -0.03, 0.05);
        let half = 30f64.to_radians();
        let planes: Vec<TangentPlane> = (0..8)
            .map(|i| {
                let phi = 0.2 * i as f64;
                // ruling direction and the tangent plane's normal along it
                let dir = Vector3::new(half.sin() * phi.cos(), half.sin() * phi.sin(), -half.cos());
                let n = Vector3::new(half.cos() * phi.cos(), half.cos() * phi.sin(), half.sin());
                assert!(n.dot(&dir).abs() < 1e-12);
                let p = apex + 0.07 * dir;
                TangentPlane {
                    normal: n,
                    offset: -n.dot(&p),
                }
            })
            .collect();
        let fit = fit_apex(&planes, &Point3::new(0.0, 0.0, 0.0), 0.1);
        assert!(fit.direction.is_none());
        // exact data: the normal equations are solved to round-off (condition ~ 10)
        assert!((fit.apex.coords - apex).norm() < 1e-12, "{:?}", fit.apex);
        assert!(fit.error < 1e-12);
        // one segment suffices
        let segs = segment_cones(&planes, &Point3::origin(), 0.1, 5e-4);
        assert_eq!(segs.len(), 1);
        assert_eq!(segs[0].0, 0..8);
    }

    #[test]
    fn a_cylinder_has_its_apex_at_infinity_and_two_cones_are_split() {
        // a cylinder along y: all normals in the x-z plane
        let planes: Vec<TangentPlane> = (0..6)
            .map(|i| {
                let phi = 0.3 * i as f64;
                let n = Vector3::new(phi.sin(), 0.0, phi.cos());
                let p = Vector3::new(0.02 * phi.sin(), 0.0, 0.02 * phi.cos());
                TangentPlane {
                    normal: n,
                    offset: -n.dot(&p),
                }
            })
            .collect();
        let fit = fit_apex(&planes, &Point3::new(0.0, 0.0, 0.0), 0.1);
        let d = fit.direction.expect("cylinder");
        assert!(d.y.abs() > 1.0 - 1e-9);
        // two different cones side by side need two segments
        let cone = |apex: Vector3, phis: &[f64]| -> Vec<TangentPlane> {
            phis.iter()
                .map(|&phi| {
                    let half = 0.5f64;
                    let n =
                        Vector3::new(half.cos() * phi.cos(), half.cos() * phi.sin(), half.sin());
                    let dir =
                        Vector3::new(half.sin() * phi.cos(), half.sin() * phi.sin(), -half.cos());
                    let p = apex + 0.05 * dir;
                    TangentPlane {
                        normal: n,
                        offset: -n.dot(&p),
                    }
                })
                .collect()
        };
        let mut planes = cone(Vector3::new(0.0, 0.0, 0.0), &[0.0, 0.2, 0.4, 0.6]);
        planes.extend(cone(Vector3::new(0.05, 0.0, 0.03), &[0.8, 1.0, 1.2, 1.4]));
        let segs = segment_cones(&planes, &Point3::origin(), 0.1, 5e-4);
        assert!(segs.len() >= 2, "{segs:?}");
        assert!(segs.iter().all(|(_, f)| f.error <= 5e-4));
    }
}
