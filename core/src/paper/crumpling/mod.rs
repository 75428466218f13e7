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

use super::compression::{flat_regions, triangle_strain, TriangleStrain};
use super::geometric::{
    Crease, CreaseKind, EdgeKind, Endpoint, FaceKind, GVertexKind, GeometricLayer, GeometricMesh,
    Ruling,
};
use super::pattern::{point_segment, segments_cross};
use crate::geometry::Point2;

mod context;
mod outcome;
mod propagation;
mod singular;

use context::Band;
pub use context::CrumpleContext;
pub use outcome::{Unchanged, Via};

pub use propagation::{propagate, Border, Strip};
use singular::{insert_in_curved, split_fold};

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

/// Step 2 for the flat region of `strain.face`: propagate, resolve the borders
/// (creating singular vertices), insert the new curved region. Returns the events
/// (never empty); when nothing is added the structure is left unchanged and the
/// branch that added nothing is returned.
pub fn crumple_flat_region(
    ctx: &CrumpleContext,
    layer: &mut GeometricLayer,
    gmesh: &GeometricMesh,
    labels: &[usize],
    strain: &TriangleStrain,
    rng: &mut impl Rng,
) -> Result<Vec<CrumpleEvent>, Unchanged> {
    let saved = layer.clone();
    // appendix B, fig. 24(b, c): a border on a ruling of a cone whose apex is an
    // interior singular vertex is that apex (the d-cone absorbs the conflict); only when
    // no region can be built that way, a new singular point is created inside the cone
    // (sec. 5.2, fig. 6d). A region S_G has already (two apices joined by a crease) is
    // not a failure, but nothing is added (no new singular point either)
    let mut attracted = false;
    let reason = match crumple_inner(ctx, layer, gmesh, labels, strain, true, &mut attracted, rng) {
        Ok(events) => return Ok(events),
        Err(reason) => reason,
    };
    *layer = saved.clone();
    if !attracted || matches!(reason, Unchanged::CreaseExists(_)) {
        return Err(reason);
    }
    let mut again = false;
    crumple_inner(ctx, layer, gmesh, labels, strain, false, &mut again, rng).inspect_err(|_| {
        *layer = saved;
    })
}

/// One attempt of step 2 on a flat region (appendix B), once T_comp's strip and band
/// are known: what its borders are resolved against.
struct Attempt<'c, 'a> {
    ctx: &'c CrumpleContext<'a>,
    /// The band of imaginary rulings through T_comp.
    band: Band,
    /// The pattern centre (m) of the strip's last face on each side, the side of F a
    /// border is seen from (fig. 11).
    f_refs: [Point2; 2],
    /// Whether a border on a ruling of a cone of interior apex is that apex
    /// (appendix B, fig. 24b, c) rather than a new singular point (fig. 6d).
    attract: bool,
}

/// A border of the strip resolved into a terminal of the new curved region.
struct Terminal {
    /// None = the free boundary, Some(id) = a singular vertex the rulings pass through.
    singular: Option<u64>,
    /// The event, when the terminal is a singular vertex created for it (sec. 5.2).
    new_singular: Option<CrumpleEvent>,
    /// How an existing singular vertex became the terminal.
    via: Option<Via>,
    /// The border was a cone's ruling and the terminal is that cone's apex.
    attracted: bool,
}

/// A resolved border: the singular vertex the rulings pass through (None: the free
/// boundary) and, when it existed before the attempt, how it was found.
type End = (Option<u64>, Option<Via>);

#[allow(clippy::too_many_arguments)]
fn crumple_inner(
    ctx: &CrumpleContext,
    layer: &mut GeometricLayer,
    gmesh: &GeometricMesh,
    labels: &[usize],
    strain: &TriangleStrain,
    attract: bool,
    attracted: &mut bool,
    rng: &mut impl Rng,
) -> Result<Vec<CrumpleEvent>, Unchanged> {
    let mut strip = propagate(gmesh, labels, strain.face, &strain.ruling_direction)?;
    borders_by_region_id(layer, &mut strip.borders).ok_or(Unchanged::NoRegion)?;
    let band = compression_band(ctx, gmesh, strain).ok_or(Unchanged::NarrowTriangle)?;
    let attempt = Attempt {
        ctx,
        band,
        f_refs: [
            face_center(gmesh, strip.last_faces[0]),
            face_center(gmesh, strip.last_faces[1]),
        ],
        attract,
    };
    let mut events = Vec::new();
    let (terminals, current) =
        attempt.resolve_borders(layer, gmesh, &strip.borders, attracted, &mut events, rng)?;
    attempt.insert_curved_region(layer, &current, terminals, &mut events)?;
    // the result must mesh
    GeometricMesh::build(layer, ctx.pattern, ctx.position).map_err(|_| Unchanged::MeshFailed)?;
    Ok(events)
}

/// Replace the region indices of curved-ruling borders by the regions' stable ids;
/// `None` when an index names no region.
fn borders_by_region_id(layer: &GeometricLayer, borders: &mut [Border; 2]) -> Option<()> {
    for b in borders.iter_mut() {
        if let Border::CurvedRuling { region, ruling } = *b {
            *b = Border::CurvedRuling {
                region: layer.regions.get(region as usize)?.id,
                ruling,
            };
        }
    }
    Some(())
}

/// The band of imaginary rulings through T_comp: the face's extent along the
/// compression direction v (m), less a tenth on each side; `None` when the face is
/// narrower than the minimal gap.
fn compression_band(
    ctx: &CrumpleContext,
    gmesh: &GeometricMesh,
    strain: &TriangleStrain,
) -> Option<Band> {
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
    if w < ctx.params.min_gap() {
        return None;
    }
    Some(Band {
        v: strain.direction,
        v_perp: strain.ruling_direction,
        t_min: t0 + 0.1 * w,
        t_max: t1 - 0.1 * w,
    })
}

/// The centroid of face `f` in the pattern (m).
pub(crate) fn face_center(g: &GeometricMesh, f: usize) -> Point2 {
    let vs = &g.faces[f].vertices;
    Point2::from(
        vs.iter()
            .map(|&v| g.vertices[v as usize].material.coords)
            .sum::<Vector2<f64>>()
            / vs.len() as f64,
    )
}

/// The counts that change when resolving a border changed the structure (singular
/// vertices, regions, creases, the next region id).
fn structure_counts(layer: &GeometricLayer) -> (usize, usize, usize, u64) {
    (
        layer.singular.len(),
        layer.regions.len(),
        layer.creases.len(),
        layer.next_region_id,
    )
}

impl Attempt<'_, '_> {
    /// Resolve the borders on the +v_perp and -v_perp sides into terminals, pushing
    /// the events of new singular vertices; S_G is rebuilt after a side that changed
    /// the structure. Returns the terminals (the singular vertex, if any, and how an
    /// existing one was found) and the S_G they were resolved in.
    fn resolve_borders(
        &self,
        layer: &mut GeometricLayer,
        gmesh: &GeometricMesh,
        borders: &[Border; 2],
        attracted: &mut bool,
        events: &mut Vec<CrumpleEvent>,
        rng: &mut impl Rng,
    ) -> Result<([End; 2], GeometricMesh), Unchanged> {
        let mut terminals = [(None, None); 2];
        let mut current = gmesh.clone();
        for side in 0..2 {
            let before = structure_counts(layer);
            let terminal = self.resolve_border(layer, &current, side, borders[side], rng)?;
            *attracted |= terminal.attracted;
            events.extend(terminal.new_singular);
            terminals[side] = (terminal.singular, terminal.via);
            if before != structure_counts(layer) {
                current = GeometricMesh::build(layer, self.ctx.pattern, self.ctx.position)
                    .map_err(|_| Unchanged::MeshFailed)?;
            }
        }
        Ok((terminals, current))
    }

    /// Resolve the border on `side` (0: +v_perp, 1: -v_perp): the free boundary, an
    /// existing singular vertex, a new one on a fold (fig. 6c) or one in a curved
    /// region (fig. 6d, or the cone's apex when attracting).
    fn resolve_border(
        &self,
        layer: &mut GeometricLayer,
        current: &GeometricMesh,
        side: usize,
        border: Border,
        rng: &mut impl Rng,
    ) -> Result<Terminal, Unchanged> {
        let ctx = self.ctx;
        let band = &self.band;
        let dir = if side == 0 { band.v_perp } else { -band.v_perp };
        let terminal = |singular, new_singular, via, attracted| Terminal {
            singular,
            new_singular,
            via,
            attracted,
        };
        Ok(match border {
            Border::Boundary => terminal(None, None, None, false),
            Border::Singular { id } => terminal(Some(id), None, Some(Via::Opposite), false),
            Border::FlatFold { a, b } => {
                let (id, via) = split_fold(ctx, layer, current, band, a, b, rng)?;
                let event = if via.is_none() {
                    Some(CrumpleEvent::NewSingular {
                        id,
                        material: layer.singular_material(id).ok_or(Unchanged::NoRegion)?,
                        on_fold: true,
                    })
                } else {
                    None
                };
                terminal(Some(id), event, via, false)
            }
            Border::CurvedRuling { region, ruling } => {
                let (id, via) = insert_in_curved(
                    ctx,
                    layer,
                    current,
                    band,
                    region,
                    ruling,
                    &self.f_refs[side],
                    &dir,
                    self.attract,
                    rng,
                )?;
                let attracted = via == Some(Via::ConeApex);
                let event = if via.is_none() {
                    Some(CrumpleEvent::NewSingular {
                        id,
                        material: layer.singular_material(id).ok_or(Unchanged::NoRegion)?,
                        on_fold: false,
                    })
                } else {
                    None
                };
                terminal(Some(id), event, via, attracted)
            }
        })
    }

    /// Appendix B: the new curved region between the terminals, pushed to `layer`
    /// with its event: a crease between two singular vertices (fig. 24c), parallel
    /// rulings between free borders (fig. 24a) or conical rulings from a singular
    /// vertex to the free border (fig. 24b). The reason when it does not fit.
    fn insert_curved_region(
        &self,
        layer: &mut GeometricLayer,
        current: &GeometricMesh,
        terminals: [End; 2],
        events: &mut Vec<CrumpleEvent>,
    ) -> Result<(), Unchanged> {
        let ctx = self.ctx;
        let band = &self.band;
        let via = terminals.map(|t| t.1);
        match terminals.map(|t| t.0) {
            [Some(s1), Some(s2)] => {
                // fig. 24(c): a degenerate region, the crease (s1, s2)
                if s1 == s2 {
                    return Err(Unchanged::SameSingular(via));
                }
                // appendix B: the strip's region degenerates into the edge (s1, s2);
                // where S_G had that crease already (no border made a new point), the
                // compression is the one it takes up, and the paper generates no new
                // region ("let the physical simulation further deform this region")
                if events.is_empty() && has_crease(layer, s1, s2) {
                    return Err(Unchanged::CreaseExists(via));
                }
                let (p, q) = layer
                    .singular_material(s1)
                    .zip(layer.singular_material(s2))
                    .ok_or(Unchanged::NoRegion)?;
                if !segment_is_free(ctx, layer, current, &p, &q, &[]) {
                    return Err(Unchanged::CreaseBlocked);
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
                let rulings = band_rulings(ctx, layer, current, band, |t| {
                    let (o, d) = band.line(t);
                    let [(s_lo, _), (s_hi, _)] = ctx.pattern.clip_line(&o, &d)?;
                    Some((Endpoint::Boundary(s_hi), Endpoint::Boundary(s_lo)))
                });
                if rulings.len() < 2 {
                    return Err(Unchanged::TooFewRulings);
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
                let s_on_plus = terminals[0].0.is_some();
                let rulings = band_rulings(ctx, layer, current, band, |t| {
                    let (o, d) = band.line(t);
                    let [(s_lo, _), (s_hi, _)] = ctx.pattern.clip_line(&o, &d)?;
                    Some(if s_on_plus {
                        (Endpoint::Singular(s), Endpoint::Boundary(s_lo))
                    } else {
                        (Endpoint::Boundary(s_hi), Endpoint::Singular(s))
                    })
                });
                if rulings.len() < 2 {
                    return Err(Unchanged::TooFewRulings);
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
        Ok(())
    }
}

/// True when `layer` has a crease joining singular vertices `s1` and `s2`.
fn has_crease(layer: &GeometricLayer, s1: u64, s2: u64) -> bool {
    let (a, b) = (Endpoint::Singular(s1), Endpoint::Singular(s2));
    layer
        .creases
        .iter()
        .any(|c| (c.a == a && c.b == b) || (c.a == b && c.b == a))
}

/// The flat regions of one frame's S_G before step 2 changes it: each is remeshed at
/// most once (sec. 5.1: "it is applied to each flat region F"); the flat regions of
/// later meshes map back to them by position.
pub struct FrameFlatRegions {
    /// S_G at the start of the frame.
    original: GeometricMesh,
    /// Its flat-region label per face (`usize::MAX`: not flat).
    labels: Vec<usize>,
    /// The labels of the regions already remeshed.
    processed: Vec<usize>,
}

impl FrameFlatRegions {
    /// The flat regions of `gmesh`, split at folds sharper than `fold` (rad) if given.
    pub fn new(gmesh: &GeometricMesh, fold: Option<f64>) -> Self {
        let original = gmesh.clone();
        let labels = flat_regions(&original, fold);
        FrameFlatRegions {
            original,
            labels,
            processed: Vec::new(),
        }
    }

    /// The frame's flat region under the centroid of `strain`'s face of `gmesh`.
    fn origin_of(&self, gmesh: &GeometricMesh, strain: &TriangleStrain) -> Option<usize> {
        let c = face_center(gmesh, strain.face);
        self.original.face_at(&c).map(|f| self.labels[f])
    }

    /// T_comp of the next region to remesh: among the most compressed triangles of
    /// the flat regions `labels` of `gmesh` (one per region), the most compressed one
    /// above `threshold` whose frame region is not remeshed yet; that region is then
    /// marked remeshed.
    pub fn next_compressed(
        &mut self,
        gmesh: &GeometricMesh,
        labels: &[usize],
        threshold: f64,
    ) -> Option<TriangleStrain> {
        let worst = most_compressed_per_region(gmesh, labels);
        let candidate = worst
            .iter()
            .flatten()
            .filter(|w| w.compression > threshold)
            .filter(|w| {
                self.origin_of(gmesh, w)
                    .is_some_and(|o| o != usize::MAX && !self.processed.contains(&o))
            })
            .max_by(|a, b| a.compression.total_cmp(&b.compression))
            .copied();
        let strain = candidate?;
        if let Some(o) = self.origin_of(gmesh, &strain) {
            self.processed.push(o);
        }
        Some(strain)
    }
}

/// The most compressed triangle of each flat region `labels` of `gmesh` (indexed by
/// label; the first of equals).
fn most_compressed_per_region(
    gmesh: &GeometricMesh,
    labels: &[usize],
) -> Vec<Option<TriangleStrain>> {
    let n_labels = labels
        .iter()
        .filter(|&&l| l != usize::MAX)
        .max()
        .map_or(0, |m| m + 1);
    let mut worst: Vec<Option<TriangleStrain>> = vec![None; n_labels];
    for (f, &l) in labels.iter().enumerate() {
        if l == usize::MAX {
            continue;
        }
        if let Some(s) = triangle_strain(gmesh, f) {
            if worst[l].is_none_or(|w| s.compression > w.compression) {
                worst[l] = Some(s);
            }
        }
    }
    worst
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Point3;
    use crate::paper::compression::{flat_regions, triangle_strain};
    use crate::paper::params::PaperParams;
    use crate::paper::pattern::Pattern;
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
        let events = crumple_flat_region(&ctx, &mut layer, &gmesh, &labels, &strain, &mut rng)
            .expect("S_G changes");
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
        let outcome = crumple_flat_region(&ctx, &mut layer, &gmesh, &labels, &strain, &mut rng);
        assert!(layer.singular.is_empty());
        // the strip meets the curved band, whose rulings are flatter than theta_0
        assert_eq!(outcome, Err(Unchanged::FlatCurvedRegion));
    }
}
