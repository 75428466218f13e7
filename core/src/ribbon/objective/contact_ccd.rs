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
//! rescaling (Li et al. 2021).

use super::contact_terms::{station_gap, ContactTerms};
use super::{Objective, Workspace};
use crate::contact::barrier::{advance_convex, advance_from, edge_edge, point_triangle};
use crate::contact::obstacles::{bounds, boxes_near, sort_boxes, window, Obstacles};
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
    boxes: Vec<(Vector3, Vector3)>,
    order: Vec<u32>,
    /// Boxes of every mesh the checked paths passed through since the last
    /// [`Workspace::reset_swept`], per run of [`SWEPT_CHUNK`] vertices, m: where the
    /// ribbon went during a step (the world steps ribbons whose swept boxes stay apart
    /// side by side).
    swept: Vec<(Vector3, Vector3)>,
    /// Per vertex: its box over the last checked path (up to the safe fraction), m.
    vertex_boxes: Vec<(Vector3, Vector3)>,
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
            boxes: Vec::new(),
            order: Vec::new(),
            swept: Vec::new(),
            vertex_boxes: Vec::new(),
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

    /// Samples 0..=`last` of the checked path: each vertex's box over them, grown by
    /// its margin, into `vertex_boxes` and the swept boxes.
    fn record_path(&mut self, last: usize) {
        let vertices = self.samples[0].x.len();
        self.vertex_boxes.clear();
        self.vertex_boxes.extend((0..vertices).map(|v| {
            let m = Vector3::repeat(self.margin.get(v).copied().unwrap_or(0.0));
            let (lo, hi) = self.samples[..=last].iter().fold(
                (
                    Vector3::repeat(f64::INFINITY),
                    Vector3::repeat(f64::NEG_INFINITY),
                ),
                |(lo, hi), s| (lo.inf(&s.x[v]), hi.sup(&s.x[v])),
            );
            (lo - m, hi + m)
        }));
        let chunks = vertices.div_ceil(SWEPT_CHUNK);
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
        let (fraction, last) = self.checked_fraction(ct, &mut ws.ccd, path);
        if let Some(last) = last {
            // where the path up to the safe fraction goes: the swept record and the
            // pairs its evaluations may meet
            ws.ccd.record_path(last);
            ws.candidates
                .build(ct, &ws.ccd.vertex_boxes, &ws.ccd.samples[0].x);
        }
        fraction
    }

    /// The safe fraction and the last sample of the path up to it (None: no step).
    fn checked_fraction(
        &self,
        ct: &ContactTerms,
        scratch: &mut CcdScratch,
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
            let mut cramped = None;
            for i in 0..pieces {
                let r = piece(ct, scratch, i);
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

/// The gap a pair of gap `g0` may close to on this piece: a tenth of g0 (of ŝ if
/// smaller) plus its points' `margin` for the deviation from a straight motion.
#[inline]
fn floor(g0: f64, activation: f64, margin: f64) -> f64 {
    (1.0 - CLOSE) * g0.min(activation) + margin
}

/// The straight motion from sample `i` to `i + 1`: the safe fraction of it.
fn piece(ct: &ContactTerms, scratch: &mut CcdScratch, i: usize) -> PieceResult {
    let obs = &ct.obstacles;
    let axis = obs.axis;
    let CcdScratch {
        samples,
        margin,
        boxes,
        order,
        ..
    } = scratch;
    let (a, b) = (&samples[i], &samples[i + 1]);
    let mut result = PieceResult {
        t: 1.0,
        cramped: false,
        shrink: 1.0,
    };
    let motion = Motion { a, b, margin };
    // the cheap pairs first: every later pair is only followed up to the earliest
    // fraction found so far (the horizon), over boxes swept that far
    solids(ct, obs, &motion, &mut result);
    let widest = sweep(ct, &motion, result.t, axis, boxes, order);
    let swept = Swept {
        boxes,
        order,
        widest,
        axis,
    };
    features(ct, obs, &motion, &swept, &mut result);
    for body in 0..obs.bodies.len() {
        other_body(ct, obs, body, &motion, &swept, &mut result);
    }
    if ct.self_contact && result.t > 0.0 {
        let widest = sweep(ct, &motion, result.t, axis, boxes, order);
        let swept = Swept {
            boxes,
            order,
            widest,
            axis,
        };
        self_pairs(ct, &motion, &swept, &mut result);
    }
    result
}

/// The cells' boxes swept over [0, `horizon`] of the piece, sorted along `axis`;
/// returns the widest extent along it, m.
fn sweep(
    ct: &ContactTerms,
    m: &Motion,
    horizon: f64,
    axis: usize,
    boxes: &mut Vec<(Vector3, Vector3)>,
    order: &mut Vec<u32>,
) -> f64 {
    boxes.clear();
    for tri in &ct.cells.triangles {
        let pts = [
            m.a.x[tri[0] as usize],
            m.a.x[tri[1] as usize],
            m.a.x[tri[2] as usize],
            m.at(tri[0], horizon),
            m.at(tri[1], horizon),
            m.at(tri[2], horizon),
        ];
        boxes.push(bounds(&pts));
    }
    sort_boxes(boxes, axis, order);
    boxes
        .iter()
        .fold(0.0, |w: f64, (lo, hi)| w.max(hi[axis] - lo[axis]))
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

/// The ribbon's swept cell boxes, sorted along `axis`.
struct Swept<'s> {
    boxes: &'s [(Vector3, Vector3)],
    order: &'s [u32],
    widest: f64,
    axis: usize,
}

impl Swept<'_> {
    fn near(&self, b: &(Vector3, Vector3), margin: f64) -> impl Iterator<Item = usize> + '_ {
        let range = window(
            self.boxes,
            self.order,
            self.axis,
            self.widest,
            b.0[self.axis],
            b.1[self.axis],
            margin,
        );
        let b = *b;
        self.order[range]
            .iter()
            .map(|&t| t as usize)
            .filter(move |&t| boxes_near(&self.boxes[t], &b, margin))
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

/// Every vertex against every solid: the signed distance is convex along a line.
fn solids(ct: &ContactTerms, obs: &Obstacles, m: &Motion, result: &mut PieceResult) {
    let half = 0.5 * ct.thickness;
    for solid in &obs.solids {
        for v in 0..m.a.x.len() as u32 {
            let (x0, x1) = (m.a.x[v as usize], m.b.x[v as usize]);
            // Nothing can pass through a half-space and come out on the other side:
            // its pairs need no margin for the path's bending between the samples (the
            // samples themselves are checked, and every evaluation rejects a vertex
            // inside). A bounded solid can be tunnelled through.
            let margin = if solid.aabb.is_some() {
                m.margin[v as usize]
            } else {
                0.0
            };
            if let Some((lo, hi)) = &solid.aabb {
                let reach = half + ct.activation + margin;
                let (slo, shi) = bounds(&[x0, x1]);
                if (0..3).any(|d| slo[d] > hi[d] + reach || shi[d] < lo[d] - reach) {
                    continue;
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
                continue;
            }
            let t = if f < g0 {
                advance_convex(gap, f, result.t)
            } else {
                0.0
            };
            record(result, g0, f, margin, t);
        }
    }
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
fn features(
    ct: &ContactTerms,
    obs: &Obstacles,
    m: &Motion,
    swept: &Swept,
    result: &mut PieceResult,
) {
    let cells = &ct.cells;
    let most = m.margin.iter().copied().fold(0.0, f64::max);
    let reach = |offset: f64| offset + (1.0 - CLOSE) * ct.activation + most;
    for f in &obs.points {
        for t in swept.near(&(f.lo, f.hi), reach(f.offset)) {
            let tri = cells.triangles[t];
            let gap = |s: f64| {
                let x = tri.map(|v| m.at(v, s));
                point_triangle(&f.x[0], &x[0], &x[1], &x[2]).distance - f.offset
            };
            pair_toi(ct, gap, m.most(&tri), m.bent(&tri), result);
        }
    }
    for f in &obs.edges {
        for t in swept.near(&(f.lo, f.hi), reach(f.offset)) {
            for e in cells.owned_edges(t) {
                let gap = |s: f64| {
                    edge_edge(&f.x[0], &f.x[1], &m.at(e[0], s), &m.at(e[1], s)).distance - f.offset
                };
                pair_toi(ct, gap, m.most(e), m.bent(e), result);
            }
        }
    }
    for f in &obs.triangles {
        for t in swept.near(&(f.lo, f.hi), reach(f.offset)) {
            for &v in cells.owned_vertices(t) {
                let gap = |s: f64| {
                    point_triangle(&m.at(v, s), &f.x[0], &f.x[1], &f.x[2]).distance - f.offset
                };
                pair_toi(ct, gap, m.travel(v), m.margin[v as usize], result);
            }
        }
    }
}

/// The moving ribbon against another (static) ribbon.
fn other_body(
    ct: &ContactTerms,
    obs: &Obstacles,
    body: usize,
    m: &Motion,
    swept: &Swept,
    result: &mut PieceResult,
) {
    let body = &obs.bodies[body];
    let most = m.margin.iter().copied().fold(0.0, f64::max);
    let reach = ct.thickness + (1.0 - CLOSE) * ct.activation + most;
    let own = &ct.cells;
    let other = |v: u32| body.vertices[v as usize];
    for t in swept.near(&(body.lo, body.hi), reach) {
        let bt = swept.boxes[t];
        let range = window(
            &body.boxes,
            &body.order,
            swept.axis,
            body.widest,
            bt.0[swept.axis],
            bt.1[swept.axis],
            reach,
        );
        let tri = own.triangles[t];
        for &o in &body.order[range] {
            let o = o as usize;
            if !boxes_near(&bt, &body.boxes[o], reach) {
                continue;
            }
            let ox = body.cells.triangles[o].map(other);
            for &v in own.owned_vertices(t) {
                let gap = |s: f64| {
                    point_triangle(&m.at(v, s), &ox[0], &ox[1], &ox[2]).distance - ct.thickness
                };
                pair_toi(ct, gap, m.travel(v), m.margin[v as usize], result);
            }
            for &ov in body.cells.owned_vertices(o) {
                let p = other(ov);
                let gap = |s: f64| {
                    let x = tri.map(|v| m.at(v, s));
                    point_triangle(&p, &x[0], &x[1], &x[2]).distance - ct.thickness
                };
                pair_toi(ct, gap, m.most(&tri), m.bent(&tri), result);
            }
            for e in own.owned_edges(t) {
                for oe in body.cells.owned_edges(o) {
                    let (p, q) = (other(oe[0]), other(oe[1]));
                    let gap = |s: f64| {
                        edge_edge(&m.at(e[0], s), &m.at(e[1], s), &p, &q).distance - ct.thickness
                    };
                    pair_toi(ct, gap, m.most(e), m.bent(e), result);
                }
            }
        }
    }
}

/// The ribbon against itself: the pairs whose stations (at the piece's start) are more
/// than the neighbour skip apart.
fn self_pairs(ct: &ContactTerms, m: &Motion, swept: &Swept, result: &mut PieceResult) {
    let most = m.margin.iter().copied().fold(0.0, f64::max);
    let reach = ct.thickness + (1.0 - CLOSE) * ct.activation + 2.0 * most;
    let cells = &ct.cells;
    let u = |vs: &[u32]| {
        vs.iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| {
                let x = m.a.u[v as usize];
                (lo.min(x), hi.max(x))
            })
    };
    for i in 0..swept.order.len() {
        let t1 = swept.order[i] as usize;
        let top = swept.boxes[t1].1[swept.axis] + reach;
        for &t2 in &swept.order[i + 1..] {
            let t2 = t2 as usize;
            if swept.boxes[t2].0[swept.axis] > top {
                break;
            }
            if t1 / 2 == t2 / 2 || !boxes_near(&swept.boxes[t1], &swept.boxes[t2], reach) {
                continue;
            }
            let (tri1, tri2) = (cells.triangles[t1], cells.triangles[t2]);
            let (u1, u2) = (u(&tri1), u(&tri2));
            if station_gap(u1, u2, ct.period) + (u1.1 - u1.0) + (u2.1 - u2.0) <= ct.skip {
                continue;
            }
            // the cells' distance at the start less the most their points approach
            // each other (their relative displacement): far enough, no pair of theirs
            // can reach the barrier
            let start = |t: [u32; 3]| bounds(&t.map(|v| m.a.x[v as usize]));
            let apart = box_distance(&start(tri1), &start(tri2));
            let approach = m.relative(&tri1, &tri2) * result.t + m.bent(&tri1) + m.bent(&tri2);
            if apart - approach > ct.thickness + (1.0 - CLOSE) * ct.activation {
                continue;
            }
            for (a, b) in [(t1, t2), (t2, t1)] {
                let tri = cells.triangles[b];
                for &v in cells.owned_vertices(a) {
                    if station_gap(u(&[v]), u(&tri), ct.period) <= ct.skip
                        || m.apart(&[v], &tri, ct, result.t)
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
            }
            for e1 in cells.owned_edges(t1) {
                for e2 in cells.owned_edges(t2) {
                    if station_gap(u(e1), u(e2), ct.period) <= ct.skip
                        || m.apart(e1, e2, ct, result.t)
                    {
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
                    pair_toi(ct, gap, m.relative(e1, e2), m.bent(e1) + m.bent(e2), result);
                }
            }
        }
    }
}
