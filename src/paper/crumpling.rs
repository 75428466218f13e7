//! Step 2(b, c): bending and crumpling (Schreck et al. sec. 5.1, 5.2, appendices A
//! and B). From the most compressed triangle T_comp of a flat region F, imaginary
//! rulings along the direction of minimal compression v_perp are propagated through F
//! (appendix A, the four cases of fig. 6) until they reach a border on each side:
//! the free boundary, another flat region, a ruling of a curved region, or a singular
//! vertex. Free borders give parallel rulings; constrained borders create a singular
//! vertex (placed by chi(s) = exp(-d^2/sigma^2) around e_sing), which becomes the apex
//! of conical rulings (appendix B, the three cases of fig. 24); a curved region that
//! receives a singular vertex is remeshed around it with a transition flat triangle
//! (fig. 11).

use nalgebra::Vector2;
use rand::Rng;

use super::compression::TriangleStrain;
use super::geometric::{
    edge_key, Crease, CreaseKind, EdgeKind, Endpoint, FaceKind, GVertexKind, GeometricLayer,
    GeometricMesh, Ruling,
};
use super::params::PaperParams;
use super::pattern::{orient, point_segment, segments_cross, Pattern};
use crate::geometry::{Point2, Point3};

/// Where a propagated strip of imaginary rulings ends (fig. 6, fig. 23).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Border {
    /// Fig. 6(b): an edge of ∂S̄, free to bend.
    Boundary,
    /// Fig. 6(c): an edge shared with another flat region (dihedral > theta_0) or a
    /// crease, given by its ends.
    FlatFold { a: Endpoint, b: Endpoint },
    /// Fig. 6(d): ruling `ruling` of the curved region with id `region`.
    CurvedRuling { region: u64, ruling: usize },
    /// Fig. 23 (bottom): a singular vertex of T_comp opposite the crossed edge.
    Singular { id: u64 },
}

/// The triangle strip of appendix A.
#[derive(Clone, Debug, PartialEq)]
pub struct Strip {
    /// T_comp first, then the collected triangles of F.
    pub faces: Vec<usize>,
    /// Borders in the +v_perp and -v_perp directions.
    pub borders: [Border; 2],
    /// The last face of F on each side (the side of F a border is seen from).
    pub last_faces: [usize; 2],
}

/// Outward normal (pattern) of edge k of face f (vertices k -> k+1, counter-clockwise).
fn edge_outward(gmesh: &GeometricMesh, f: usize, k: usize) -> (u32, u32, Vector2<f64>) {
    let vs = &gmesh.faces[f].vertices;
    let (a, b) = (vs[k], vs[(k + 1) % vs.len()]);
    let d = gmesh.vertices[b as usize].material - gmesh.vertices[a as usize].material;
    (a, b, Vector2::new(d.y, -d.x))
}

/// |sin| of the angle between edge (a, b) and `dir`.
fn edge_angle(gmesh: &GeometricMesh, a: u32, b: u32, dir: &Vector2<f64>) -> f64 {
    let d = (gmesh.vertices[b as usize].material - gmesh.vertices[a as usize].material).normalize();
    (d.x * dir.y - d.y * dir.x).abs()
}

/// Appendix A: propagate the imaginary rulings of `t_comp` (a flat triangle of the
/// region `labels[t_comp]`) along `v_perp` in both directions.
pub fn propagate(
    gmesh: &GeometricMesh,
    labels: &[usize],
    t_comp: usize,
    v_perp: &Vector2<f64>,
) -> Option<Strip> {
    let face = &gmesh.faces[t_comp];
    if face.vertices.len() != 3 || face.kind != FaceKind::Flat {
        return None;
    }
    // the two edges most crossed by the rulings (largest angle with v_perp), one
    // facing +v_perp and one facing -v_perp
    let edges: Vec<(usize, f64, f64)> = (0..3)
        .map(|k| {
            let (a, b, n) = edge_outward(gmesh, t_comp, k);
            (k, edge_angle(gmesh, a, b, v_perp), n.dot(v_perp))
        })
        .collect();
    let first = edges.iter().copied().max_by(|x, y| x.1.total_cmp(&y.1))?;
    let second = edges
        .iter()
        .copied()
        .filter(|e| e.0 != first.0 && e.2 * first.2 < 0.0)
        .max_by(|x, y| x.1.total_cmp(&y.1))?;
    let mut strip = Strip {
        faces: vec![t_comp],
        borders: [Border::Boundary, Border::Boundary],
        last_faces: [t_comp, t_comp],
    };
    for (k, _, facing) in [first, second] {
        let side = if facing > 0.0 { 0 } else { 1 };
        let dir = if facing > 0.0 { *v_perp } else { -v_perp };
        // fig. 23 bottom: the singular vertex opposite the largest-angle edge is the
        // border on the other side
        if k == first.0 {
            let opposite = face.vertices[(k + 2) % 3];
            if let GVertexKind::Singular { id } = gmesh.vertices[opposite as usize].kind {
                strip.borders[1 - side] = Border::Singular { id };
                strip.borders[side] = walk(
                    gmesh,
                    labels,
                    t_comp,
                    k,
                    &dir,
                    &mut strip.faces,
                    &mut strip.last_faces[side],
                )?;
                return Some(strip);
            }
        }
        strip.borders[side] = walk(
            gmesh,
            labels,
            t_comp,
            k,
            &dir,
            &mut strip.faces,
            &mut strip.last_faces[side],
        )?;
    }
    Some(strip)
}

/// Walk from face `f` through its edge `k` in direction `dir` (appendix A).
fn walk(
    gmesh: &GeometricMesh,
    labels: &[usize],
    f: usize,
    k: usize,
    dir: &Vector2<f64>,
    faces: &mut Vec<usize>,
    last: &mut usize,
) -> Option<Border> {
    let (mut cur, mut a, mut b) = {
        let (a, b, _) = edge_outward(gmesh, f, k);
        (f, a, b)
    };
    for _ in 0..10_000 {
        *last = cur;
        let e = gmesh.edges.get(&edge_key(a, b))?;
        let other = e.faces.iter().flatten().copied().find(|&g| g != cur);
        let Some(g) = other else {
            return Some(Border::Boundary); // fig. 6(b)
        };
        match (gmesh.faces[g].kind, e.kind) {
            (FaceKind::Curved { .. }, EdgeKind::Ruling { region, index })
            | (FaceKind::Flat, EdgeKind::Ruling { region, index }) => {
                return Some(Border::CurvedRuling {
                    region: region as u64, // region index, mapped to an id by the caller
                    ruling: index,
                }); // fig. 6(d)
            }
            (FaceKind::Curved { .. }, _) => return None,
            (FaceKind::Flat, EdgeKind::Crease { .. }) => {
                return Some(Border::FlatFold {
                    a: gmesh.endpoint_of(a),
                    b: gmesh.endpoint_of(b),
                });
            }
            (FaceKind::Flat, _) if labels[g] != labels[cur] => {
                return Some(Border::FlatFold {
                    a: gmesh.endpoint_of(a),
                    b: gmesh.endpoint_of(b),
                }); // fig. 6(c)
            }
            _ => {}
        }
        // fig. 6(a): same flat region, continue through the edge of g (other than e)
        // forming the greatest angle with dir, ahead of us
        if faces.contains(&g) {
            return None;
        }
        faces.push(g);
        let n = gmesh.faces[g].vertices.len();
        let mut best: Option<(bool, f64, u32, u32)> = None;
        for kk in 0..n {
            let (p, q, out) = edge_outward(gmesh, g, kk);
            if edge_key(p, q) == edge_key(a, b) {
                continue;
            }
            let ahead = out.dot(dir) > 0.0;
            let angle = edge_angle(gmesh, p, q, dir);
            let better = match best {
                None => true,
                Some((bahead, bangle, _, _)) => (ahead, angle) > (bahead, bangle),
            };
            if better {
                best = Some((ahead, angle, p, q));
            }
        }
        let (_, _, p, q) = best?;
        cur = g;
        a = p;
        b = q;
    }
    None
}

/// What step 2 did to one flat region.
#[derive(Clone, Debug, PartialEq)]
pub enum CrumpleEvent {
    /// Appendix B, fig. 24(a): a curved region of parallel rulings.
    ParallelRulings { region: u64, rulings: usize },
    /// Fig. 24(b): conical rulings to singular vertex `apex`.
    ConicalRulings {
        region: u64,
        apex: u64,
        rulings: usize,
    },
    /// Fig. 24(c): a degenerate curved region (one crease between two singular points).
    Crease { from: u64, to: u64 },
    /// Sec. 5.2: a new singular vertex, on a fold between flat regions (fig. 6c) or
    /// in a curved region (fig. 6d).
    NewSingular {
        id: u64,
        material: Point2,
        on_fold: bool,
    },
}

/// Everything the remeshing needs besides the structure.
pub struct CrumpleContext<'a> {
    pub pattern: &'a Pattern,
    pub params: &'a PaperParams,
    /// World position of an S_G vertex from its kind and pattern position (the S_P of
    /// step 1, interpolated; cubic along the boundary).
    pub position: &'a dyn Fn(&GVertexKind, &Point2) -> Point3,
}

/// The band of imaginary rulings through T_comp: offsets along v (m).
#[derive(Clone, Copy, Debug)]
struct Band {
    v: Vector2<f64>,
    v_perp: Vector2<f64>,
    t_min: f64,
    t_max: f64,
}

impl Band {
    fn line(&self, t: f64) -> (Point2, Vector2<f64>) {
        (Point2::from(self.v * t), self.v_perp)
    }
    /// Parameter range [u0, u1] of segment [p, q] inside the band, if any.
    fn clip_segment(&self, p: &Point2, q: &Point2) -> Option<(f64, f64)> {
        let tp = p.coords.dot(&self.v);
        let tq = q.coords.dot(&self.v);
        if (tq - tp).abs() < 1e-15 {
            return (tp >= self.t_min && tp <= self.t_max).then_some((0.0, 1.0));
        }
        let u_a = (self.t_min - tp) / (tq - tp);
        let u_b = (self.t_max - tp) / (tq - tp);
        let (lo, hi) = (u_a.min(u_b).max(0.0), u_a.max(u_b).min(1.0));
        (hi > lo).then_some((lo, hi))
    }
}

/// A standard normal deviate (Box-Muller) from the seeded generator.
fn normal(rng: &mut impl Rng) -> f64 {
    let u1: f64 = 1.0 - rng.random::<f64>();
    let u2: f64 = rng.random::<f64>();
    (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
}

/// Step 2 for the flat region of `strain.face`: propagate, resolve the borders
/// (creating singular vertices), insert the new curved region. On any failure the
/// structure is left unchanged and no event is returned.
pub fn crumple_flat_region(
    ctx: &CrumpleContext,
    layer: &mut GeometricLayer,
    gmesh: &GeometricMesh,
    labels: &[usize],
    strain: &TriangleStrain,
    rng: &mut impl Rng,
) -> Vec<CrumpleEvent> {
    let saved = layer.clone();
    // appendix B, fig. 24(b, c): a border on a ruling of a cone whose apex is an
    // interior singular vertex is that apex (the d-cone absorbs the conflict); only when
    // no region can be built that way, a new singular point is created inside the cone
    // (sec. 5.2, fig. 6d)
    let mut attracted = false;
    if let Some(events) =
        crumple_inner(ctx, layer, gmesh, labels, strain, true, &mut attracted, rng)
    {
        if !events.is_empty() {
            return events;
        }
    }
    *layer = saved.clone();
    if attracted {
        let mut again = false;
        if let Some(events) =
            crumple_inner(ctx, layer, gmesh, labels, strain, false, &mut again, rng)
        {
            if !events.is_empty() {
                return events;
            }
        }
        *layer = saved;
    }
    Vec::new()
}

fn crumple_inner(
    ctx: &CrumpleContext,
    layer: &mut GeometricLayer,
    gmesh: &GeometricMesh,
    labels: &[usize],
    strain: &TriangleStrain,
    attract: bool,
    attracted: &mut bool,
    rng: &mut impl Rng,
) -> Option<Vec<CrumpleEvent>> {
    let params = ctx.params;
    let Some(mut strip) = propagate(gmesh, labels, strain.face, &strain.ruling_direction) else {
        return None;
    };
    // region indices -> stable ids
    for b in strip.borders.iter_mut() {
        if let Border::CurvedRuling { region, ruling } = *b {
            *b = Border::CurvedRuling {
                region: layer.regions.get(region as usize)?.id,
                ruling,
            };
        }
    }
    let tri = &gmesh.faces[strain.face].vertices;
    let ts: Vec<f64> = tri
        .iter()
        .map(|&v| {
            gmesh.vertices[v as usize]
                .material
                .coords
                .dot(&strain.direction)
        })
        .collect();
    let (t0, t1) = (
        ts.iter().copied().fold(f64::INFINITY, f64::min),
        ts.iter().copied().fold(f64::NEG_INFINITY, f64::max),
    );
    let w = t1 - t0;
    if w < params.min_gap() {
        return None;
    }
    let band = Band {
        v: strain.direction,
        v_perp: strain.ruling_direction,
        t_min: t0 + 0.1 * w,
        t_max: t1 - 0.1 * w,
    };
    let face_center = |f: usize, g: &GeometricMesh| {
        let vs = &g.faces[f].vertices;
        Point2::from(
            vs.iter()
                .map(|&v| g.vertices[v as usize].material.coords)
                .sum::<Vector2<f64>>()
                / vs.len() as f64,
        )
    };
    let f_refs = [
        face_center(strip.last_faces[0], gmesh),
        face_center(strip.last_faces[1], gmesh),
    ];

    // resolve the borders into terminals: None = the free boundary, Some(id) = a
    // singular vertex the rulings pass through
    let mut events = Vec::new();
    let mut terminals: [Option<u64>; 2] = [None, None];
    let mut current = gmesh.clone();
    for side in 0..2 {
        let dir = if side == 0 { band.v_perp } else { -band.v_perp };
        let before = (
            layer.singular.len(),
            layer.regions.len(),
            layer.creases.len(),
            layer.next_region_id,
        );
        terminals[side] = match strip.borders[side] {
            Border::Boundary => None,
            Border::Singular { id } => Some(id),
            Border::FlatFold { a, b } => {
                let Some((id, new)) = split_fold(ctx, layer, &current, &band, a, b, rng) else {
                    return None;
                };
                if new {
                    events.push(CrumpleEvent::NewSingular {
                        id,
                        material: layer.singular_material(id)?,
                        on_fold: true,
                    });
                }
                Some(id)
            }
            Border::CurvedRuling { region, ruling } => {
                let cone_apex = layer
                    .regions
                    .iter()
                    .find(|r| r.id == region)
                    .and_then(|r| r.singular_apex());
                let Some((id, new)) = insert_in_curved(
                    ctx,
                    layer,
                    &current,
                    &band,
                    region,
                    ruling,
                    &f_refs[side],
                    &dir,
                    attract,
                    rng,
                ) else {
                    return None;
                };
                *attracted |= attract && !new && Some(id) == cone_apex;
                if new {
                    events.push(CrumpleEvent::NewSingular {
                        id,
                        material: layer.singular_material(id)?,
                        on_fold: false,
                    });
                }
                Some(id)
            }
        };
        if before
            != (
                layer.singular.len(),
                layer.regions.len(),
                layer.creases.len(),
                layer.next_region_id,
            )
        {
            let Ok(c) = GeometricMesh::build(layer, ctx.pattern, ctx.position) else {
                return None;
            };
            current = c;
        }
    }

    // appendix B: the new curved region
    match terminals {
        [Some(s1), Some(s2)] => {
            // fig. 24(c): a degenerate region, the crease (s1, s2)
            if s1 == s2 {
                return None;
            }
            let (p, q) = (layer.singular_material(s1)?, layer.singular_material(s2)?);
            if !segment_is_free(ctx, layer, &current, &p, &q, &[]) {
                return None;
            }
            layer.creases.push(Crease {
                a: Endpoint::Singular(s1),
                b: Endpoint::Singular(s2),
                kind: CreaseKind::Plastic,
            });
            events.push(CrumpleEvent::Crease { from: s1, to: s2 });
        }
        [None, None] => {
            // fig. 24(a): parallel rulings along d_prop
            let rulings = band_rulings(ctx, layer, &current, &band, |t| {
                let (o, d) = band.line(t);
                let [(s_lo, _), (s_hi, _)] = ctx.pattern.clip_line(&o, &d)?;
                Some((Endpoint::Boundary(s_hi), Endpoint::Boundary(s_lo)))
            });
            if rulings.len() < 2 {
                return None;
            }
            let n = rulings.len();
            let id = layer.add_region(rulings);
            events.push(CrumpleEvent::ParallelRulings {
                region: id,
                rulings: n,
            });
        }
        [Some(s), None] | [None, Some(s)] => {
            // fig. 24(b): conical rulings from s to the free border
            let s_on_plus = terminals[0].is_some();
            let rulings = band_rulings(ctx, layer, &current, &band, |t| {
                let (o, d) = band.line(t);
                let [(s_lo, _), (s_hi, _)] = ctx.pattern.clip_line(&o, &d)?;
                Some(if s_on_plus {
                    (Endpoint::Singular(s), Endpoint::Boundary(s_lo))
                } else {
                    (Endpoint::Boundary(s_hi), Endpoint::Singular(s))
                })
            });
            if rulings.len() < 2 {
                return None;
            }
            let n = rulings.len();
            let id = layer.add_region(rulings);
            events.push(CrumpleEvent::ConicalRulings {
                region: id,
                apex: s,
                rulings: n,
            });
        }
    }
    // the result must mesh
    GeometricMesh::build(layer, ctx.pattern, ctx.position).ok()?;
    Some(events)
}

/// Snap a boundary arc length to an existing S_G boundary vertex within a third of
/// the boundary spacing.
fn snap(ctx: &CrumpleContext, gmesh: &GeometricMesh, s: f64) -> f64 {
    snap_to_vertex(ctx, gmesh, s, ctx.params.boundary_spacing() / 3.0, &[])
}

/// The arc length of the S_G boundary vertex nearest to `s` within `tol` (m), not in
/// `exclude`, or `s` itself.
pub(crate) fn snap_to_vertex(
    ctx: &CrumpleContext,
    gmesh: &GeometricMesh,
    s: f64,
    tol: f64,
    exclude: &[u32],
) -> f64 {
    let per = ctx.pattern.perimeter();
    let mut best = (tol, s);
    for &v in &gmesh.boundary {
        if exclude.contains(&v) {
            continue;
        }
        if let GVertexKind::Boundary { s: x } = gmesh.vertices[v as usize].kind {
            let d = (x - s).abs().min(per - (x - s).abs());
            if d < best.0 {
                best = (d, x);
            }
        }
    }
    best.1
}

/// The rulings of the band (appendix B): `make(t)` gives the two ends of the ruling at
/// offset t; the largest run of consecutive valid rulings is kept.
fn band_rulings(
    ctx: &CrumpleContext,
    layer: &GeometricLayer,
    gmesh: &GeometricMesh,
    band: &Band,
    make: impl Fn(f64) -> Option<(Endpoint, Endpoint)>,
) -> Vec<Ruling> {
    let width = band.t_max - band.t_min;
    // the number of rulings respects rho_bound
    let n = ((width * ctx.params.boundary_density).ceil() as usize + 1).max(2);
    let mut runs: Vec<Vec<Ruling>> = vec![Vec::new()];
    for k in 0..n {
        let t = band.t_min + width * k as f64 / (n - 1) as f64;
        let candidate = make(t).and_then(|(a, b)| {
            let snap_end = |e: Endpoint| match e {
                Endpoint::Boundary(s) => Endpoint::Boundary(snap(ctx, gmesh, s)),
                other => other,
            };
            let (a, b) = (snap_end(a), snap_end(b));
            let p = layer.endpoint_material(ctx.pattern, &a);
            let q = layer.endpoint_material(ctx.pattern, &b);
            if (p - q).norm() < ctx.params.min_gap() {
                return None;
            }
            let ends: Vec<Point2> = vec![p, q];
            segment_is_free(ctx, layer, gmesh, &p, &q, &ends).then_some(Ruling { a, b })
        });
        match candidate {
            Some(r) => {
                let run = runs.last_mut().expect("non-empty");
                // drop a ruling identical to the previous one after snapping
                if run.last() != Some(&r) {
                    run.push(r);
                }
            }
            None => runs.push(Vec::new()),
        }
    }
    runs.into_iter().max_by_key(|r| r.len()).unwrap_or_default()
}

/// True when the segment [p, q] can be added to S_G: it crosses no ruling, crease or
/// fold (flat-flat edge sharper than theta_0), passes through no S_G vertex other
/// than its ends, and does not lie inside a curved face.
pub(crate) fn segment_is_free(
    ctx: &CrumpleContext,
    layer: &GeometricLayer,
    gmesh: &GeometricMesh,
    p: &Point2,
    q: &Point2,
    _ends: &[Point2],
) -> bool {
    let tol = 1e-9;
    for [a, b] in layer.segments(ctx.pattern) {
        if segments_cross(p, q, &a, &b, tol) {
            return false;
        }
        // collinear overlap
        if point_segment(&a, p, q).0 < tol && point_segment(&b, p, q).0 < tol {
            return false;
        }
    }
    for (&(a, b), e) in &gmesh.edges {
        if e.kind != EdgeKind::Plain || !ctx.params.split_flat_regions_at_folds {
            continue;
        }
        if gmesh.dihedral(a, b).unwrap_or(0.0) <= ctx.params.flat_angle {
            continue;
        }
        let (pa, pb) = (
            gmesh.vertices[a as usize].material,
            gmesh.vertices[b as usize].material,
        );
        if segments_cross(p, q, &pa, &pb, tol) {
            return false;
        }
    }
    let clearance = 0.05 * ctx.params.boundary_spacing();
    for v in &gmesh.vertices {
        if (v.material - p).norm() < 1e-9 || (v.material - q).norm() < 1e-9 {
            continue;
        }
        if point_segment(&v.material, p, q).0 < clearance {
            return false;
        }
    }
    let mid = Point2::from((p.coords + q.coords) * 0.5);
    for f in &gmesh.faces {
        if f.kind == FaceKind::Flat {
            continue;
        }
        let poly: Vec<Point2> = f
            .vertices
            .iter()
            .map(|&v| gmesh.vertices[v as usize].material)
            .collect();
        if super::pattern::in_convex_polygon(&poly, &mid, 1e-9) {
            return false;
        }
    }
    true
}

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
/// degenerate curved region of one ruling: two plastic creases.
fn split_fold(
    ctx: &CrumpleContext,
    layer: &mut GeometricLayer,
    gmesh: &GeometricMesh,
    band: &Band,
    a: Endpoint,
    b: Endpoint,
    rng: &mut impl Rng,
) -> Option<(u64, bool)> {
    let p = layer.endpoint_material(ctx.pattern, &a);
    let q = layer.endpoint_material(ctx.pattern, &b);
    let len = (q - p).norm();
    let gap = ctx.params.min_gap();
    if len < 3.0 * gap {
        return None;
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
            .then_some((old, false));
    }
    if ctx.pattern.signed_inside_distance(&s) < gap
        || gmesh.vertices.iter().any(|v| (v.material - s).norm() < gap)
    {
        return None;
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
    Some((id, true))
}

/// Fig. 6(d), sec. 5.2 and fig. 11: the imaginary rulings meet ruling `ruling` of
/// curved region `region_id`. Continue along d_prop to e_sing, the first ruling with a
/// dihedral angle above theta_0; place the singular vertex s around e_sing by
/// chi(s) = exp(-d^2 / sigma^2); remove the rulings between e_lim and e_sup (the next
/// ruling sharper than theta_0) and replace them by cones of apex s, leaving the flat
/// transition triangle (s, e_sup). When `attract` and C is already a cone of interior
/// apex a, a is the border instead (appendix B, fig. 24b, c). Returns s and whether it
/// is new.
#[allow(clippy::too_many_arguments)]
fn insert_in_curved(
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
) -> Option<(u64, bool)> {
    let ri = layer.regions.iter().position(|r| r.id == region_id)?;
    let apex = layer.regions[ri].singular_apex();
    if let Some(a) = apex.filter(|_| attract) {
        return Some((a, false));
    }
    insert_new_singular(ctx, layer, gmesh, band, ri, ruling, f_ref, dprop, rng)
}

/// [`insert_in_curved`]'s new singular point inside region `ri` near the ruling in
/// conflict; `None` (structure untouched) when none fits.
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
) -> Option<(u64, bool)> {
    let params = ctx.params;
    let rv = gmesh.ruling_vertices.get(ri)?.clone();
    let m = rv.len();
    if ruling >= m || m < 2 {
        return None;
    }
    let mat = |v: u32| gmesh.vertices[v as usize].material;
    // walk direction through C: away from F
    let step: i64 = if ruling == 0 {
        1
    } else if ruling == m - 1 {
        -1
    } else {
        let next = (ruling + 1).min(m - 1);
        let mid = Point2::from((mat(rv[next][0]).coords + mat(rv[next][1]).coords) * 0.5);
        let here = Point2::from((mat(rv[ruling][0]).coords + mat(rv[ruling][1]).coords) * 0.5);
        if (mid - here).dot(dprop) >= 0.0 {
            1
        } else {
            -1
        }
    };
    let order: Vec<usize> = {
        let mut o = Vec::new();
        let mut k = ruling as i64;
        while k >= 0 && (k as usize) < m {
            o.push(k as usize);
            k += step;
        }
        o
    };
    let dihedral = |k: usize| gmesh.dihedral(rv[k][0], rv[k][1]).unwrap_or(0.0);
    // the imaginary rulings must really cross C's rulings: nearly parallel ones are
    // compatible (C can grow instead, sec. 6.1)
    let e_dir = (mat(rv[ruling][1]) - mat(rv[ruling][0])).normalize();
    let cross = (e_dir.x * dprop.y - e_dir.y * dprop.x).abs();
    if cross < params.conflict_angle.sin() {
        return None;
    }
    // sec. 5.2: singular points appear where the rulings meet a region of higher
    // curvature; a curved region flatter than theta_0 all along does not resist
    let e_sing = order
        .iter()
        .copied()
        .find(|&k| dihedral(k) > params.flat_angle)?;

    // chi(s) = exp(-d^2/sigma^2): uniform along e_sing (where the band meets it),
    // normal across with standard deviation sigma / sqrt(2)
    let (pa, pb) = (mat(rv[e_sing][0]), mat(rv[e_sing][1]));
    let len = (pb - pa).norm();
    if len < 1e-9 {
        return None;
    }
    let across = Vector2::new(-(pb - pa).y, (pb - pa).x) / len;
    let (u0, u1) = band.clip_segment(&pa, &pb).unwrap_or((0.0, 1.0));
    let gap = params.min_gap();
    let mut s = None;
    for _ in 0..32 {
        let u = rng.random_range(u0..=u1);
        let d = normal(rng) * params.singularity_sigma / std::f64::consts::SQRT_2;
        let cand = pa + (pb - pa) * u + across * d;
        if ctx.pattern.signed_inside_distance(&cand) < gap {
            continue;
        }
        if gmesh
            .vertices
            .iter()
            .any(|v| (v.material - cand).norm() < gap)
        {
            continue;
        }
        // not on another ruling of C
        if rv
            .iter()
            .any(|&[a, b]| point_segment(&cand, &mat(a), &mat(b)).0 < 1e-6)
        {
            continue;
        }
        s = Some(cand);
        break;
    }
    let s = s?;
    if let Some(old) = nearby_singular(layer, params, &s) {
        return Some((old, false));
    }
    // which rulings separate s from F
    let side = |k: usize, p: &Point2| orient(&mat(rv[k][0]), &mat(rv[k][1]), p).signum();
    let mut removed = Vec::new();
    let mut e_sup = None;
    let mut past_sing = false;
    for &k in &order {
        let separates = side(k, &s) != side(k, f_ref);
        if separates || !past_sing {
            // between F and s, or between s and e_sing (all flatter than theta_0)
            removed.push(k);
            past_sing |= k == e_sing;
            continue;
        }
        if dihedral(k) <= params.flat_angle {
            removed.push(k);
            continue;
        }
        e_sup = Some(k);
        break;
    }
    if removed.is_empty() {
        return None;
    }
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
    Some((id, true))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::paper::compression::{flat_regions, triangle_strain};
    use rand::SeedableRng;

    /// A 10 cm sheet whose band u in [0.04, 0.08] is a curved region of rulings along
    /// v, bent about the v axis by `bend` rad per ruling gap; the whole sheet is
    /// shortened along v by `squeeze` (dimensionless).
    fn bent_and_squeezed(
        bend: f64,
        squeeze: f64,
    ) -> (
        Pattern,
        GeometricLayer,
        impl Fn(&GVertexKind, &Point2) -> Point3,
    ) {
        let pattern = Pattern::rectangle(0.1, 0.1);
        let mut layer = GeometricLayer::default();
        let us = [0.04, 0.05, 0.06, 0.07, 0.08];
        layer.add_region(
            us.iter()
                .map(|&u| Ruling {
                    a: Endpoint::Boundary(0.3 - u), // top side, arc runs right to left
                    b: Endpoint::Boundary(u),       // bottom side
                })
                .collect(),
        );
        let position = move |_: &GVertexKind, m: &Point2| {
            // polygonal arc through the rulings: turn by `bend` at each ruling
            let mut x = 0.0;
            let mut z = 0.0;
            let mut angle: f64 = 0.0;
            let mut u0 = 0.0;
            for &u in &us {
                if m.x <= u {
                    break;
                }
                x += (u - u0) * angle.cos();
                z += (u - u0) * angle.sin();
                angle += bend;
                u0 = u;
            }
            x += (m.x - u0) * angle.cos();
            z += (m.x - u0) * angle.sin();
            Point3::new(x, m.y * (1.0 - squeeze), z)
        };
        (pattern, layer, position)
    }

    #[test]
    fn a_conflict_creates_a_singular_vertex() {
        // rulings of the new region would run along u (v is compressed) and cross the
        // curved region's rulings (along v) at 90 deg, in a region bent by 0.1 rad per
        // ruling (> theta_0): sec. 5.2 inserts a singular vertex
        let (pattern, mut layer, position) = bent_and_squeezed(0.1, 0.02);
        let params = PaperParams::default();
        let gmesh = GeometricMesh::build(&layer, &pattern, &position).unwrap();
        let labels = flat_regions(&gmesh, None);
        let strain = (0..gmesh.faces.len())
            .filter(|&f| labels[f] != usize::MAX)
            .filter_map(|f| triangle_strain(&gmesh, f))
            .max_by(|a, b| a.compression.total_cmp(&b.compression))
            .unwrap();
        assert!(
            strain.compression > params.compression_threshold,
            "{strain:?}"
        );
        assert!(
            strain.ruling_direction.x.abs() > 0.9,
            "v_perp along u: {strain:?}"
        );
        let ctx = CrumpleContext {
            pattern: &pattern,
            params: &params,
            position: &position,
        };
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let events = crumple_flat_region(&ctx, &mut layer, &gmesh, &labels, &strain, &mut rng);
        let new: Vec<&CrumpleEvent> = events
            .iter()
            .filter(|e| matches!(e, CrumpleEvent::NewSingular { .. }))
            .collect();
        assert_eq!(new.len(), 1, "{events:?}");
        assert_eq!(layer.singular.len(), 1);
        let s = layer.singular[0].material;
        // inside the curved band (where the rulings bend), within a few sigma of a ruling
        assert!(
            s.x > 0.04 - 4.0 * params.singularity_sigma && s.x < 0.08,
            "{s:?}"
        );
        // the conical rulings of s reach the free border of the flat region
        assert!(
            events
                .iter()
                .any(|e| matches!(e, CrumpleEvent::ConicalRulings { apex: 0, .. })),
            "{events:?}"
        );
        // and the structure still meshes
        assert!(GeometricMesh::build(&layer, &pattern, &position).is_ok());
    }

    #[test]
    fn no_singular_vertex_where_the_curved_region_is_flat() {
        // the same compression against rulings bent by less than theta_0: no conflict
        let (pattern, mut layer, position) = bent_and_squeezed(0.001, 0.02);
        let params = PaperParams::default();
        let gmesh = GeometricMesh::build(&layer, &pattern, &position).unwrap();
        let labels = flat_regions(&gmesh, None);
        let strain = (0..gmesh.faces.len())
            .filter(|&f| labels[f] != usize::MAX)
            .filter_map(|f| triangle_strain(&gmesh, f))
            .max_by(|a, b| a.compression.total_cmp(&b.compression))
            .unwrap();
        let ctx = CrumpleContext {
            pattern: &pattern,
            params: &params,
            position: &position,
        };
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        crumple_flat_region(&ctx, &mut layer, &gmesh, &labels, &strain, &mut rng);
        assert!(layer.singular.is_empty());
    }
}
