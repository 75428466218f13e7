//! Sec. 5.2, fig. 6(c, d) and fig. 11 of Schreck et al.: the singular vertex a
//! conflict creates, on a fold between flat regions or inside a curved region, and the
//! remeshing of that region into cones around it.

use nalgebra::Vector2;
use rand::Rng;

use super::context::{normal, Band, CrumpleContext};
use super::outcome::{Unchanged, Via};
use crate::geometry::Point2;
use crate::paper::geometric::{
    Crease, CreaseKind, Endpoint, GeometricLayer, GeometricMesh, Ruling,
};
use crate::paper::params::PaperParams;
use crate::paper::pattern::{orient, point_segment};

/// The existing singular vertex nearest to `s` (pattern, m) closer than the S_G
/// resolution 1/rho_bound, if any. Fibers already broken there: a conflict this close
/// to a d-cone is absorbed by its apex instead of breaking the sheet again (sec. 5.2
/// places a new point within sigma of e_sing; two apices closer than one boundary
/// sample cannot be told apart by the coarse S_G).
fn nearby_singular(layer: &GeometricLayer, params: &PaperParams, s: &Point2) -> Option<u64> {
    layer
        .singular
        .iter()
        .map(|x| ((x.material - s).norm(), x.id))
        .filter(|(d, _)| *d < params.boundary_spacing())
        .min_by(|a, b| a.0.total_cmp(&b.0))
        .map(|(_, id)| id)
}

/// Fig. 6(c), sec. 5.2: a singular vertex on the fold (a, b) between two flat regions,
/// at a uniformly random position where the band meets it. The fold becomes a
/// degenerate curved region of one ruling: two plastic creases. Returns the point and,
/// when it is a singular end of the fold, how it was found (None: new).
pub(super) fn split_fold(
    ctx: &CrumpleContext,
    layer: &mut GeometricLayer,
    gmesh: &GeometricMesh,
    band: &Band,
    a: Endpoint,
    b: Endpoint,
    rng: &mut impl Rng,
) -> Result<(u64, Option<Via>), Unchanged> {
    let p = layer.endpoint_material(ctx.pattern, &a);
    let q = layer.endpoint_material(ctx.pattern, &b);
    let len = (q - p).norm();
    let gap = ctx.params.min_gap();
    if len < 3.0 * gap {
        return Err(Unchanged::FoldTooShort);
    }
    let (u0, u1) = band.clip_segment(&p, &q).unwrap_or((0.0, 1.0));
    let (u0, u1) = (u0.max(gap / len), u1.min(1.0 - gap / len));
    let (u0, u1) = if u1 > u0 {
        (u0, u1)
    } else {
        (gap / len, 1.0 - gap / len)
    };
    let u = rng.random_range(u0..=u1);
    let s = p + (q - p) * u;
    if let Some(old) = nearby_singular(layer, ctx.params, &s) {
        // an end of the fold that is already singular is the border; a singular vertex
        // off the fold cannot be one
        return [a, b]
            .contains(&Endpoint::Singular(old))
            .then_some((old, Some(Via::FoldEnd)))
            .ok_or(Unchanged::FoldNearSingular);
    }
    if ctx.pattern.signed_inside_distance(&s) < gap
        || gmesh.vertices.iter().any(|v| (v.material - s).norm() < gap)
    {
        return Err(Unchanged::FoldPointCrowded);
    }
    let id = layer.add_singular(s);
    let kind = match layer
        .creases
        .iter()
        .position(|c| (c.a == a && c.b == b) || (c.a == b && c.b == a))
    {
        Some(ci) => layer.creases.remove(ci).kind,
        None => CreaseKind::Plastic,
    };
    layer.creases.push(Crease {
        a,
        b: Endpoint::Singular(id),
        kind,
    });
    layer.creases.push(Crease {
        a: Endpoint::Singular(id),
        b,
        kind,
    });
    Ok((id, None))
}

/// Fig. 6(d), sec. 5.2 and fig. 11: the imaginary rulings meet ruling `ruling` of
/// curved region `region_id`. Continue along d_prop to e_sing, the first ruling with a
/// dihedral angle above theta_0; place the singular vertex s around e_sing by
/// chi(s) = exp(-d^2 / sigma^2); remove the rulings between e_lim and e_sup (the next
/// ruling sharper than theta_0) and replace them by cones of apex s, leaving the flat
/// transition triangle (s, e_sup). When `attract` and C is already a cone of interior
/// apex a, a is the border instead (appendix B, fig. 24b, c). Returns s and, when it
/// existed already, how it was found (None: new).
#[allow(clippy::too_many_arguments)]
pub(super) fn insert_in_curved(
    ctx: &CrumpleContext,
    layer: &mut GeometricLayer,
    gmesh: &GeometricMesh,
    band: &Band,
    region_id: u64,
    ruling: usize,
    f_ref: &Point2,
    dprop: &Vector2<f64>,
    attract: bool,
    rng: &mut impl Rng,
) -> Result<(u64, Option<Via>), Unchanged> {
    let ri = layer
        .regions
        .iter()
        .position(|r| r.id == region_id)
        .ok_or(Unchanged::NoRegion)?;
    let apex = layer.regions[ri].singular_apex();
    if let Some(a) = apex.filter(|_| attract) {
        return Ok((a, Some(Via::ConeApex)));
    }
    insert_new_singular(ctx, layer, gmesh, band, ri, ruling, f_ref, dprop, rng)
}

/// [`insert_in_curved`]'s new singular point inside region `ri` near the ruling in
/// conflict; the reason (structure untouched) when none fits.
#[allow(clippy::too_many_arguments)]
fn insert_new_singular(
    ctx: &CrumpleContext,
    layer: &mut GeometricLayer,
    gmesh: &GeometricMesh,
    band: &Band,
    ri: usize,
    ruling: usize,
    f_ref: &Point2,
    dprop: &Vector2<f64>,
    rng: &mut impl Rng,
) -> Result<(u64, Option<Via>), Unchanged> {
    let params = ctx.params;
    let c = ConflictRegion {
        gmesh,
        rv: gmesh.ruling_vertices.get(ri).ok_or(Unchanged::NoRegion)?,
    };
    let m = c.rv.len();
    if ruling >= m || m < 2 {
        return Err(Unchanged::NoRegion);
    }
    let (step, order) = c.walk_away_from_flat(ruling, dprop);
    // the imaginary rulings must really cross C's rulings: nearly parallel ones are
    // compatible (C can grow instead, sec. 6.1)
    let e_dir = (c.mat(c.rv[ruling][1]) - c.mat(c.rv[ruling][0])).normalize();
    let cross = (e_dir.x * dprop.y - e_dir.y * dprop.x).abs();
    if cross < params.conflict_angle.sin() {
        return Err(Unchanged::CompatibleRulings);
    }
    // sec. 5.2: singular points appear where the rulings meet a region of higher
    // curvature; a curved region flatter than theta_0 all along does not resist
    let e_sing = order
        .iter()
        .copied()
        .find(|&k| c.dihedral(k) > params.flat_angle)
        .ok_or(Unchanged::FlatCurvedRegion)?;
    let s = c
        .sample_singular(ctx, band, e_sing, rng)
        .ok_or(Unchanged::NoSingularSample)?;
    if let Some(old) = nearby_singular(layer, params, &s) {
        return Ok((old, Some(Via::Nearby)));
    }
    let (removed, e_sup) = c.rulings_to_replace(params, &order, e_sing, &s, f_ref);
    if removed.is_empty() {
        return Err(Unchanged::NoRulingsToReplace);
    }
    let id = replace_by_cones(layer, ri, s, step, &removed, e_sup);
    Ok((id, None))
}

/// The rulings of a curved region C in S_G, as a conflict of fig. 6(d) walks them.
struct ConflictRegion<'g> {
    gmesh: &'g GeometricMesh,
    /// The S_G vertices [a, b] of each ruling of C.
    rv: &'g [[u32; 2]],
}

impl ConflictRegion<'_> {
    /// The pattern position (m) of S_G vertex `v`.
    fn mat(&self, v: u32) -> Point2 {
        self.gmesh.vertices[v as usize].material
    }

    /// The dihedral angle (rad) along ruling k, 0 where it has no two faces.
    fn dihedral(&self, k: usize) -> f64 {
        self.gmesh
            .dihedral(self.rv[k][0], self.rv[k][1])
            .unwrap_or(0.0)
    }

    /// The walk through C away from F, starting at ruling `ruling`: its step (+1 or
    /// -1 in ruling index; inner rulings step along d_prop) and the rulings in order.
    fn walk_away_from_flat(&self, ruling: usize, dprop: &Vector2<f64>) -> (i64, Vec<usize>) {
        let (rv, m) = (self.rv, self.rv.len());
        let step: i64 = if ruling == 0 {
            1
        } else if ruling == m - 1 {
            -1
        } else {
            let next = (ruling + 1).min(m - 1);
            let mid =
                Point2::from((self.mat(rv[next][0]).coords + self.mat(rv[next][1]).coords) * 0.5);
            let here = Point2::from(
                (self.mat(rv[ruling][0]).coords + self.mat(rv[ruling][1]).coords) * 0.5,
            );
            if (mid - here).dot(dprop) >= 0.0 {
                1
            } else {
                -1
            }
        };
        let mut order = Vec::new();
        let mut k = ruling as i64;
        while k >= 0 && (k as usize) < m {
            order.push(k as usize);
            k += step;
        }
        (step, order)
    }

    /// The singular point s drawn by chi(s) = exp(-d^2/sigma^2) around ruling
    /// `e_sing`: uniform along it (where the band meets it), normal across with
    /// standard deviation sigma / sqrt(2); up to 32 draws for one at least the minimal
    /// gap inside the sheet and from every S_G vertex, and off C's rulings.
    fn sample_singular(
        &self,
        ctx: &CrumpleContext,
        band: &Band,
        e_sing: usize,
        rng: &mut impl Rng,
    ) -> Option<Point2> {
        let params = ctx.params;
        let rv = self.rv;
        let (pa, pb) = (self.mat(rv[e_sing][0]), self.mat(rv[e_sing][1]));
        let len = (pb - pa).norm();
        if len < 1e-9 {
            return None;
        }
        let across = Vector2::new(-(pb - pa).y, (pb - pa).x) / len;
        let (u0, u1) = band.clip_segment(&pa, &pb).unwrap_or((0.0, 1.0));
        let gap = params.min_gap();
        for _ in 0..32 {
            let u = rng.random_range(u0..=u1);
            let d = normal(rng) * params.singularity_sigma / std::f64::consts::SQRT_2;
            let cand = pa + (pb - pa) * u + across * d;
            if ctx.pattern.signed_inside_distance(&cand) < gap {
                continue;
            }
            if self
                .gmesh
                .vertices
                .iter()
                .any(|v| (v.material - cand).norm() < gap)
            {
                continue;
            }
            // not on another ruling of C
            if rv
                .iter()
                .any(|&[a, b]| point_segment(&cand, &self.mat(a), &self.mat(b)).0 < 1e-6)
            {
                continue;
            }
            return Some(cand);
        }
        None
    }

    /// Fig. 11: the rulings along the walk `order` that the cones of apex `s` replace
    /// (those between F and s, between s and e_sing, and the ones flatter than theta_0
    /// after it) and e_sup, the first one sharper than theta_0 past s, if any.
    fn rulings_to_replace(
        &self,
        params: &PaperParams,
        order: &[usize],
        e_sing: usize,
        s: &Point2,
        f_ref: &Point2,
    ) -> (Vec<usize>, Option<usize>) {
        let rv = self.rv;
        // which rulings separate s from F
        let side =
            |k: usize, p: &Point2| orient(&self.mat(rv[k][0]), &self.mat(rv[k][1]), p).signum();
        let mut removed = Vec::new();
        let mut e_sup = None;
        let mut past_sing = false;
        for &k in order {
            let separates = side(k, s) != side(k, f_ref);
            if separates || !past_sing {
                // between F and s, or between s and e_sing (all flatter than theta_0)
                removed.push(k);
                past_sing |= k == e_sing;
                continue;
            }
            if self.dihedral(k) <= params.flat_angle {
                removed.push(k);
                continue;
            }
            e_sup = Some(k);
            break;
        }
        (removed, e_sup)
    }
}

/// Fig. 11: add the singular vertex `s` (pattern, m) and replace the `removed`
/// rulings of region `ri` by cones of apex s towards both sides of C (a fan per side
/// of at least 2 rulings, through the boundary ends of the removed rulings and of
/// e_sup); C keeps the rulings from e_sup on (along the walk's `step`) if at least 2,
/// else it is removed. Returns the new vertex's id.
fn replace_by_cones(
    layer: &mut GeometricLayer,
    ri: usize,
    s: Point2,
    step: i64,
    removed: &[usize],
    e_sup: Option<usize>,
) -> u64 {
    let old = layer.regions[ri].rulings.clone();
    let kept: Vec<Ruling> = match e_sup {
        Some(k) if step > 0 => old[k..].to_vec(),
        Some(k) => old[..=k].to_vec(),
        None => Vec::new(),
    };
    let id = layer.add_singular(s);
    // the cones of apex s towards both sides of C
    let mut fan_a = Vec::new();
    let mut fan_b = Vec::new();
    let ends: Vec<usize> = removed.iter().copied().chain(e_sup).collect();
    for k in ends {
        if let e @ Endpoint::Boundary(_) = old[k].a {
            fan_a.push(Ruling {
                a: Endpoint::Singular(id),
                b: e,
            });
        }
        if let e @ Endpoint::Boundary(_) = old[k].b {
            fan_b.push(Ruling {
                a: Endpoint::Singular(id),
                b: e,
            });
        }
    }
    if kept.len() >= 2 {
        layer.regions[ri].rulings = kept;
    } else {
        layer.regions.remove(ri);
    }
    for fan in [fan_a, fan_b] {
        if fan.len() >= 2 {
            layer.add_region(fan);
        }
    }
    id
}
