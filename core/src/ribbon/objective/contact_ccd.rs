//! The safe step fraction of a line search (docs/contact_barrier.md, "No iterate ever
//! crosses"): how far along the solver's path q(α) the ribbon's mesh can move before any
//! pair comes closer than its minimum separation.
//!
//! The mesh moves along a curve as q moves along a line, so the path is sampled: meshes
//! at α = 0, 1/2 and 1 estimate the curve's deviation from its chord (the midpoint's
//! distance from the chord, exact for a quadratic path), the path is cut into K pieces
//! whose deviation (∝ 1/K^2) is a small part of ŝ, and each piece's straight motion is
//! checked with the deviation added to every pair's minimum separation. A pair keeps at
//! least a tenth of its gap (of ŝ if its gap is larger): additive CCD's conservative
//! rescaling (Li et al. 2021). The pairs followed are the path's candidates
//! (`contact_candidates`), found once per sampled path.

use super::contact_candidates::Candidates;
use super::contact_terms::{station_gap, ContactTerms};
use super::{Objective, Workspace};
use crate::contact::barrier::{advance_convex, advance_from, edge_edge, point_triangle};
use crate::contact::obstacles::{bounds, ObstacleSolid};
use crate::geometry::Vector3;
use crate::ribbon::reconstruct::{reconstruct, Coordinates, Frames};

/// Most pieces a step's path is cut into; a step whose curve needs more is shortened.
const MAX_PIECES: usize = 16;
/// The share of a pair's gap (or of ŝ, if smaller) a step may close: additive CCD's
/// conservative rescaling 0.9.
const CLOSE: f64 = 0.9;

/// The mesh at one point of the path: vertex positions (mesh order), m, and their rim
/// stations u, m.
#[derive(Clone, Debug, Default)]
struct Sample {
    x: Vec<Vector3>,
    u: Vec<f64>,
}

/// Buffers of the safe-step computation (no allocation once warm).
#[derive(Clone, Debug)]
pub(crate) struct CcdScratch {
    coords: Coordinates,
    frames: Frames,
    q: Vec<f64>,
    samples: Vec<Sample>,
    /// Per vertex: twice its path's deviation from a straight piece, m (the margin
    /// its pairs add to their minimum separation).
    margin: Vec<f64>,
    /// Boxes of every mesh the checked paths passed through since the last
    /// [`Workspace::reset_swept`], per run of [`SWEPT_CHUNK`] vertices, m: where the
    /// ribbon went during a step (the world steps ribbons whose swept boxes stay apart
    /// side by side).
    swept: Vec<(Vector3, Vector3)>,
    /// Per vertex: its box over the last checked path (up to the safe fraction), m.
    vertex_boxes: Vec<(Vector3, Vector3)>,
    /// Per vertex: its rim station at the path's start and the most it moves, m.
    stations: Vec<(f64, f64)>,
    /// Per cell: its centroid's displacements and spread along the path
    /// (`cell_motions`).
    cell_motion: Vec<(Vector3, f64)>,
}

/// Mesh vertices per swept box (8 stations of a ribbon: 8 elements' worth, a few cm).
pub const SWEPT_CHUNK: usize = 16;

impl Default for CcdScratch {
    fn default() -> Self {
        CcdScratch {
            coords: Coordinates::flat(1, crate::geometry::Pose::identity()),
            frames: Frames::default(),
            q: Vec::new(),
            samples: Vec::new(),
            margin: Vec::new(),
            swept: Vec::new(),
            vertex_boxes: Vec::new(),
            stations: Vec::new(),
            cell_motion: Vec::new(),
        }
    }
}

impl CcdScratch {
    /// Grow the swept boxes by the mesh `x` (mesh order, m).
    fn add_swept(&mut self, x: &[Vector3]) {
        let chunks = x.len().div_ceil(SWEPT_CHUNK);
        let empty = (
            Vector3::repeat(f64::INFINITY),
            Vector3::repeat(f64::NEG_INFINITY),
        );
        self.swept.resize(chunks, empty);
        for (v, p) in x.iter().enumerate() {
            let b = &mut self.swept[v / SWEPT_CHUNK];
            b.0 = b.0.inf(p);
            b.1 = b.1.sup(p);
        }
    }

    /// Each vertex's box over samples 0..=`last` of the path and the point a share `t`
    /// of the way to sample `last + 1`, grown by its margin, into `vertex_boxes`.
    fn record_boxes(&mut self, last: usize, t: f64) {
        let vertices = self.samples[0].x.len();
        let next = self.samples.get(last + 1).map(|s| &s.x);
        self.vertex_boxes.clear();
        self.vertex_boxes.extend((0..vertices).map(|v| {
            let m = Vector3::repeat(self.margin.get(v).copied().unwrap_or(0.0));
            let (mut lo, mut hi) = self.samples[..=last].iter().fold(
                (
                    Vector3::repeat(f64::INFINITY),
                    Vector3::repeat(f64::NEG_INFINITY),
                ),
                |(lo, hi), s| (lo.inf(&s.x[v]), hi.sup(&s.x[v])),
            );
            if let (Some(next), true) = (next, t > 0.0) {
                let p = self.samples[last].x[v];
                let q = p + (next[v] - p) * t;
                (lo, hi) = (lo.inf(&q), hi.sup(&q));
            }
            (lo - m, hi + m)
        }));
    }

    /// Samples 0..=`last` of the checked path (up to the safe fraction) into the swept
    /// boxes.
    fn record_path(&mut self, last: usize) {
        self.record_boxes(last, 0.0);
        let chunks = self.vertex_boxes.len().div_ceil(SWEPT_CHUNK);
        let empty = (
            Vector3::repeat(f64::INFINITY),
            Vector3::repeat(f64::NEG_INFINITY),
        );
        self.swept.resize(chunks, empty);
        for (v, b) in self.vertex_boxes.iter().enumerate() {
            let s = &mut self.swept[v / SWEPT_CHUNK];
            s.0 = s.0.inf(&b.0);
            s.1 = s.1.sup(&b.1);
        }
    }
}

impl Workspace {
    /// Start a new swept record at `mesh` (mesh order, m).
    pub fn reset_swept(&mut self, mesh: &[Vector3]) {
        self.ccd.swept.clear();
        self.ccd.add_swept(mesh);
    }
    /// Whether the next evaluations lie on the last checked path (then they read its
    /// candidate pairs instead of running the broad phase).
    pub fn set_on_checked_path(&mut self, on: bool) {
        self.use_candidates = on;
    }
    /// Add `mesh` (mesh order, m) to the swept record.
    pub fn add_swept(&mut self, mesh: &[Vector3]) {
        self.ccd.add_swept(mesh);
    }
    /// The swept record: boxes covering every mesh since the last reset, m.
    pub fn swept_boxes(&self) -> &[(Vector3, Vector3)] {
        &self.ccd.swept
    }
}

/// How a piece of the path ended: the safe fraction of it, and whether a pair was held
/// only because the curve's deviation left it no room (then a shorter step helps).
struct PieceResult {
    t: f64,
    cramped: bool,
    /// When cramped: the factor on α that would leave the tightest such pair room (its
    /// margin scales as α^2).
    shrink: f64,
}

impl Objective<'_> {
    /// The largest α in [0, 1] such that the mesh moves along the path q(α) (`path`
    /// writes q at α) keeping every pair at least its minimum separation; 1 without
    /// contact.
    pub fn safe_step_fraction(
        &self,
        ws: &mut Workspace,
        path: &mut dyn FnMut(f64, &mut [f64]),
    ) -> f64 {
        let Some(ct) = self.contact else {
            return 1.0;
        };
        // (the candidates of the last path sampled: the evaluations' pairs on the part of
        // it up to the safe fraction too)
        let (fraction, last) = self.checked_fraction(ct, &mut ws.ccd, &mut ws.candidates, path);
        if let Some(last) = last {
            // where the path up to the safe fraction goes: the swept record
            ws.ccd.record_path(last);
        }
        fraction
    }

    /// The safe fraction and the last sample of the path up to it (None: no step).
    fn checked_fraction(
        &self,
        ct: &ContactTerms,
        scratch: &mut CcdScratch,
        candidates: &mut Candidates,
        path: &mut dyn FnMut(f64, &mut [f64]),
    ) -> (f64, Option<usize>) {
        let mut alpha = 1.0;
        for _ in 0..24 {
            self.sample(scratch, 0, 0.0, path);
            self.sample(scratch, 1, 0.5 * alpha, path);
            self.sample(scratch, 2, alpha, path);
            let deviation = chord_deviation(scratch);
            // pieces whose deviation is at most 5 % of ŝ
            let pieces =
                ((deviation / (0.05 * ct.activation)).sqrt().ceil() as usize).clamp(1, MAX_PIECES);
            // a piece of 1/K of the path deviates 1/K^2 as much from its chord
            let scale = 1.0 / (pieces * pieces) as f64;
            scratch.margin.iter_mut().for_each(|m| *m *= scale);
            match pieces {
                // samples 0 and 1: the ends
                1 => scratch.samples.swap(1, 2),
                // 0, 1/2, 1 as they are
                2 => {}
                _ => {
                    for i in 1..=pieces {
                        self.sample(scratch, i, alpha * i as f64 / pieces as f64, path);
                    }
                }
            }
            // every pair that can come within reach on the sampled path, once, up to
            // where the solids (cheap: a signed distance per vertex) cut it: a landing's
            // step sweeps little of what it would
            let (last, t) = solids_horizon(ct, scratch, pieces);
            scratch.record_boxes(last, t);
            let most = scratch.margin.iter().copied().fold(0.0, f64::max);
            let (samples, margin) = (&scratch.samples[..=last + 1], &scratch.margin);
            cell_motions(ct, samples, margin, &mut scratch.cell_motion);
            let (motion, k) = (&scratch.cell_motion, samples.len());
            let relative = |t1: usize, t2: usize| relative_approach(motion, k, t1, t2);
            scratch.stations.clear();
            scratch
                .stations
                .extend(samples[0].u.iter().enumerate().map(|(v, &u0)| {
                    let shift = samples[1..]
                        .iter()
                        .fold(0.0, |m: f64, s| m.max((s.u[v] - u0).abs()));
                    (u0, shift)
                }));
            let boxes = (&scratch.vertex_boxes[..], &samples[0].x[..]);
            candidates.build(ct, boxes, (&relative, &scratch.stations), 2.0 * most);
            let mut cramped = None;
            for i in 0..pieces {
                let r = piece(ct, candidates, scratch, i);
                if r.cramped {
                    cramped = Some(r.shrink);
                }
                if r.t < 1.0 {
                    if r.t == 0.0 && cramped.is_some() && i == 0 {
                        break;
                    }
                    return (alpha * (i as f64 + r.t) / pieces as f64, Some(i + 1));
                }
            }
            let Some(shrink) = cramped else {
                return (alpha, Some(pieces));
            };
            // the curve is too bent for the gaps at hand: a shorter step bends less (its
            // deviation as α^2)
            if !(shrink > 0.0) {
                return (0.0, None);
            }
            alpha *= shrink.min(0.25);
        }
        (0.0, None)
    }

    /// The mesh at α into sample `i`.
    fn sample(
        &self,
        scratch: &mut CcdScratch,
        i: usize,
        alpha: f64,
        path: &mut dyn FnMut(f64, &mut [f64]),
    ) {
        let n = self.strip.segments;
        scratch.q.resize(self.layout.len(), 0.0);
        path(alpha, &mut scratch.q);
        if scratch.coords.segments() != n {
            scratch.coords = Coordinates::flat(n, self.base);
        }
        if !self.layout.floating {
            scratch.coords.base = self.base;
        }
        self.layout
            .unpack(&scratch.q, &self.base, &mut scratch.coords);
        reconstruct(&self.strip, &scratch.coords, &mut scratch.frames);
        if scratch.samples.len() <= i {
            scratch.samples.resize_with(i + 1, Sample::default);
        }
        let s = &mut scratch.samples[i];
        let (f, c) = (&scratch.frames, &scratch.coords.crease_direction);
        s.x.clear();
        s.u.clear();
        for j in 0..=n {
            s.x.push(f.rim_bottom[j].coords);
            s.x.push(f.rim_top[j].coords);
            s.u.push(self.strip.material_bottom(j, c[j]).x);
            s.u.push(self.strip.material_top(j, c[j]).x);
        }
    }
}

/// Per vertex, twice the distance of the path's midpoint (sample 1) from the chord of
/// its ends (samples 0, 2) into `scratch.margin`; returns the largest deviation, m.
fn chord_deviation(scratch: &mut CcdScratch) -> f64 {
    let (a, mid, b) = (
        &scratch.samples[0],
        &scratch.samples[1],
        &scratch.samples[2],
    );
    scratch.margin.clear();
    scratch.margin.extend(
        a.x.iter()
            .zip(&mid.x)
            .zip(&b.x)
            .map(|((p, m), q)| 2.0 * (m - (p + q) * 0.5).norm()),
    );
    0.5 * scratch.margin.iter().copied().fold(0.0, f64::max)
}

/// Per cell, along the sampled path: its centroid's displacement since sample 0 at each
/// sample after it, then the most any of its points strays from that (its turning and
/// bending, plus its largest curvature margin), m; `k` + 1 entries per cell (k samples).
fn cell_motions(
    ct: &ContactTerms,
    samples: &[Sample],
    margin: &[f64],
    out: &mut Vec<(Vector3, f64)>,
) {
    out.clear();
    let x0 = &samples[0].x;
    for tri in &ct.cells.triangles {
        let centre =
            |x: &[Vector3]| tri.iter().fold(Vector3::zeros(), |c, &v| c + x[v as usize]) / 3.0;
        let c0 = centre(x0);
        let mut spread: f64 = 0.0;
        let start = out.len();
        for s in &samples[1..] {
            let dc = centre(&s.x) - c0;
            for &v in tri {
                let dv = s.x[v as usize] - x0[v as usize];
                spread = spread.max((dv - dc).norm());
            }
            out.push((dc, 0.0));
        }
        let bent = tri.iter().fold(0.0, |m: f64, &v| m.max(margin[v as usize]));
        out.push((Vector3::zeros(), spread + bent));
        debug_assert_eq!(out.len() - start, samples.len());
    }
}

/// The most points of cells `t1` and `t2` approach each other along the path (the
/// relative displacement of their centroids, affine on each piece so largest at the
/// samples, plus both cells' spreads), m, from [`cell_motions`] over `k` samples.
fn relative_approach(motion: &[(Vector3, f64)], k: usize, t1: usize, t2: usize) -> f64 {
    let (a, b) = (&motion[t1 * k..(t1 + 1) * k], &motion[t2 * k..(t2 + 1) * k]);
    let most = a[..k - 1]
        .iter()
        .zip(&b[..k - 1])
        .fold(0.0, |m: f64, (p, q)| m.max((p.0 - q.0).norm()));
    most + a[k - 1].1 + b[k - 1].1
}

/// The gap a pair of gap `g0` may close to on this piece: a tenth of g0 (of ŝ if
/// smaller) plus its points' `margin` for the deviation from a straight motion.
#[inline]
fn floor(g0: f64, activation: f64, margin: f64) -> f64 {
    (1.0 - CLOSE) * g0.min(activation) + margin
}

/// The straight motion from sample `i` to `i + 1`: the safe fraction of it, over the
/// path's candidate pairs.
fn piece(ct: &ContactTerms, c: &Candidates, scratch: &CcdScratch, i: usize) -> PieceResult {
    let (a, b) = (&scratch.samples[i], &scratch.samples[i + 1]);
    let mut result = PieceResult {
        t: 1.0,
        cramped: false,
        shrink: 1.0,
    };
    let m = Motion {
        a,
        b,
        margin: &scratch.margin,
    };
    // the cheap pairs first: every later pair is only followed up to the earliest
    // fraction found so far (the horizon)
    for &(k, v) in &c.solid {
        solid(ct, &ct.obstacles.solids[k as usize], v, &m, &mut result);
    }
    features(ct, c, &m, &mut result);
    other_bodies(ct, c, &m, &mut result);
    if ct.self_contact && result.t > 0.0 {
        self_pairs(ct, c, &m, &mut result);
    }
    result
}

/// The two ends of a straight piece of the path and every vertex's margin for the
/// path's deviation from it.
struct Motion<'s> {
    a: &'s Sample,
    b: &'s Sample,
    margin: &'s [f64],
}

impl Motion<'_> {
    #[inline]
    fn at(&self, v: u32, t: f64) -> Vector3 {
        let (p, q) = (self.a.x[v as usize], self.b.x[v as usize]);
        p + (q - p) * t
    }
    #[inline]
    fn travel(&self, v: u32) -> f64 {
        (self.b.x[v as usize] - self.a.x[v as usize]).norm()
    }
    /// The largest travel of the vertices of `vs`.
    fn most(&self, vs: &[u32]) -> f64 {
        vs.iter().fold(0.0, |m, &v| m.max(self.travel(v)))
    }
    /// The most two points of `a` and `b` move relative to each other over the piece:
    /// how fast the distance of two hulls moving linearly can change (the distance is
    /// that of the origin to their Minkowski difference, whose points move by
    /// Δ_i - Δ_j).
    fn relative(&self, a: &[u32], b: &[u32]) -> f64 {
        let delta = |v: u32| self.b.x[v as usize] - self.a.x[v as usize];
        let mut most: f64 = 0.0;
        for &i in a {
            for &j in b {
                most = most.max((delta(i) - delta(j)).norm());
            }
        }
        most
    }
    /// Whether the hulls of `a` and `b` (both moving) stay too far apart to reach a
    /// floor: their boxes' distance at the start, less their relative displacement and
    /// margins, beyond the thickness plus the largest floor (a tenth of ŝ).
    fn apart(&self, a: &[u32], b: &[u32], ct: &ContactTerms, horizon: f64) -> bool {
        let bx = |vs: &[u32]| {
            vs.iter().fold(
                (
                    Vector3::repeat(f64::INFINITY),
                    Vector3::repeat(f64::NEG_INFINITY),
                ),
                |(lo, hi), &v| (lo.inf(&self.a.x[v as usize]), hi.sup(&self.a.x[v as usize])),
            )
        };
        let approach = self.relative(a, b) * horizon + self.bent(a) + self.bent(b);
        box_distance(&bx(a), &bx(b)) - approach > ct.thickness + (1.0 - CLOSE) * ct.activation
    }
    /// The largest margin of the vertices of `vs`.
    fn bent(&self, vs: &[u32]) -> f64 {
        vs.iter().fold(0.0, |m, &v| m.max(self.margin[v as usize]))
    }
}

/// The distance between two boxes, m (0 when they overlap).
fn box_distance(a: &(Vector3, Vector3), b: &(Vector3, Vector3)) -> f64 {
    let mut d2 = 0.0;
    for k in 0..3 {
        let gap = (a.0[k] - b.1[k]).max(b.0[k] - a.1[k]).max(0.0);
        d2 += gap * gap;
    }
    d2.sqrt()
}

/// Records one pair's safe fraction (`margin`: the part of its floor that is the
/// path's deviation).
fn record(result: &mut PieceResult, g0: f64, floor: f64, margin: f64, t: f64) {
    if floor >= g0 {
        // no room left by the curve's deviation: α times sqrt(room / margin) halves it
        result.cramped = true;
        result.t = 0.0;
        let room = 0.5 * (g0 - (floor - margin));
        let shrink = if room > 0.0 && margin > 0.0 {
            (room / margin).sqrt()
        } else {
            0.0
        };
        result.shrink = result.shrink.min(shrink);
    } else {
        result.t = result.t.min(t);
    }
}

/// Where the solids alone cut the sampled path of `pieces` pieces: the piece and the
/// share of it (the last piece and 1 when they do not).
fn solids_horizon(ct: &ContactTerms, scratch: &CcdScratch, pieces: usize) -> (usize, f64) {
    for i in 0..pieces {
        let m = Motion {
            a: &scratch.samples[i],
            b: &scratch.samples[i + 1],
            margin: &scratch.margin,
        };
        let mut result = PieceResult {
            t: 1.0,
            cramped: false,
            shrink: 1.0,
        };
        for s in &ct.obstacles.solids {
            for v in 0..m.a.x.len() as u32 {
                solid(ct, s, v, &m, &mut result);
            }
        }
        if result.t < 1.0 {
            return (i, result.t);
        }
    }
    (pieces - 1, 1.0)
}

/// Vertex `v` against a solid: the signed distance is convex along a line.
fn solid(ct: &ContactTerms, solid: &ObstacleSolid, v: u32, m: &Motion, result: &mut PieceResult) {
    let obs = &ct.obstacles;
    let half = 0.5 * ct.thickness;
    let (x0, x1) = (m.a.x[v as usize], m.b.x[v as usize]);
    // Nothing can pass through a half-space and come out on the other side: its pairs
    // need no margin for the path's bending between the samples (the samples themselves
    // are checked, and every evaluation rejects a vertex inside). A bounded solid can be
    // tunnelled through.
    let margin = if solid.aabb.is_some() {
        m.margin[v as usize]
    } else {
        0.0
    };
    if let Some((lo, hi)) = &solid.aabb {
        let reach = half + ct.activation + margin;
        let (slo, shi) = bounds(&[x0, x1]);
        if (0..3).any(|d| slo[d] > hi[d] + reach || shi[d] < lo[d] - reach) {
            return;
        }
    }
    let delta = x1 - x0;
    let gap = |t: f64| {
        let (sd, n) = obs.solid_distance(solid, &(x0 + delta * t));
        (sd - half, n.dot(&delta))
    };
    let g0 = gap(0.0).0;
    let f = floor(g0, ct.activation, margin);
    if g0 - delta.norm() * result.t > f {
        return;
    }
    let t = if f < g0 {
        advance_convex(gap, f, result.t)
    } else {
        0.0
    };
    record(result, g0, f, margin, t);
}

/// A pair's gap along the piece from `gap`, its rate bound and its margin.
fn pair_toi(
    ct: &ContactTerms,
    gap: impl Fn(f64) -> f64,
    rate: f64,
    margin: f64,
    result: &mut PieceResult,
) {
    let g0 = gap(0.0);
    let f = floor(g0, ct.activation, margin);
    if g0 - rate * result.t > f {
        // it cannot come down to its floor before the horizon
        return;
    }
    let t = if f < g0 {
        advance_from(g0, &gap, rate, f, result.t)
    } else {
        0.0
    };
    record(result, g0, f, margin, t);
}

/// The colliders' points, edges and mesh triangles against the moving ribbon.
fn features(ct: &ContactTerms, c: &Candidates, m: &Motion, result: &mut PieceResult) {
    let (obs, cells) = (&ct.obstacles, &ct.cells);
    for &(k, t) in &c.point {
        let (f, tri) = (&obs.points[k as usize], cells.triangles[t as usize]);
        let gap = |s: f64| {
            let x = tri.map(|v| m.at(v, s));
            point_triangle(&f.x[0], &x[0], &x[1], &x[2]).distance - f.offset
        };
        pair_toi(ct, gap, m.most(&tri), m.bent(&tri), result);
    }
    for &(k, t) in &c.edge {
        let f = &obs.edges[k as usize];
        for e in cells.owned_edges(t as usize) {
            let gap = |s: f64| {
                edge_edge(&f.x[0], &f.x[1], &m.at(e[0], s), &m.at(e[1], s)).distance - f.offset
            };
            pair_toi(ct, gap, m.most(e), m.bent(e), result);
        }
    }
    for &(k, t) in &c.triangle {
        let f = &obs.triangles[k as usize];
        for &v in cells.owned_vertices(t as usize) {
            let gap =
                |s: f64| point_triangle(&m.at(v, s), &f.x[0], &f.x[1], &f.x[2]).distance - f.offset;
            pair_toi(ct, gap, m.travel(v), m.margin[v as usize], result);
        }
    }
}

/// The moving ribbon against the other (static) ribbons.
fn other_bodies(ct: &ContactTerms, c: &Candidates, m: &Motion, result: &mut PieceResult) {
    let bodies = &ct.obstacles.bodies;
    let h = ct.thickness;
    for &(b, v, _, o) in &c.body_vertex {
        let body = &bodies[b as usize];
        let ox = body.cells.triangles[o as usize].map(|w| body.vertices[w as usize]);
        let gap = |s: f64| point_triangle(&m.at(v, s), &ox[0], &ox[1], &ox[2]).distance - h;
        pair_toi(ct, gap, m.travel(v), m.margin[v as usize], result);
    }
    for &(b, ov, t) in &c.body_triangle {
        let p = bodies[b as usize].vertices[ov as usize];
        let tri = ct.cells.triangles[t as usize];
        let gap = |s: f64| {
            let x = tri.map(|v| m.at(v, s));
            point_triangle(&p, &x[0], &x[1], &x[2]).distance - h
        };
        pair_toi(ct, gap, m.most(&tri), m.bent(&tri), result);
    }
    for &(b, e, _, oe) in &c.body_edge {
        let body = &bodies[b as usize];
        let (p, q) = (body.vertices[oe[0] as usize], body.vertices[oe[1] as usize]);
        let gap = |s: f64| edge_edge(&m.at(e[0], s), &m.at(e[1], s), &p, &q).distance - h;
        pair_toi(ct, gap, m.most(&e), m.bent(&e), result);
    }
}

/// The ribbon against itself: the pairs whose stations (at the piece's start) are more
/// than the neighbour skip apart.
fn self_pairs(ct: &ContactTerms, c: &Candidates, m: &Motion, result: &mut PieceResult) {
    let cells = &ct.cells;
    let u = |vs: &[u32]| {
        vs.iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| {
                let x = m.a.u[v as usize];
                (lo.min(x), hi.max(x))
            })
    };
    for &(v, _, b) in &c.own_vertex {
        let tri = cells.triangles[b as usize];
        if station_gap(u(&[v]), u(&tri), ct.period) <= ct.skip || m.apart(&[v], &tri, ct, result.t)
        {
            continue;
        }
        let gap = |s: f64| {
            let x = tri.map(|w| m.at(w, s));
            point_triangle(&m.at(v, s), &x[0], &x[1], &x[2]).distance - ct.thickness
        };
        let margin = m.margin[v as usize] + m.bent(&tri);
        pair_toi(ct, gap, m.relative(&[v], &tri), margin, result);
    }
    for &(e1, _, e2, _) in &c.own_edge {
        if station_gap(u(&e1), u(&e2), ct.period) <= ct.skip || m.apart(&e1, &e2, ct, result.t) {
            continue;
        }
        let gap = |s: f64| {
            edge_edge(
                &m.at(e1[0], s),
                &m.at(e1[1], s),
                &m.at(e2[0], s),
                &m.at(e2[1], s),
            )
            .distance
                - ct.thickness
        };
        pair_toi(
            ct,
            gap,
            m.relative(&e1, &e2),
            m.bent(&e1) + m.bent(&e2),
            result,
        );
    }
}
