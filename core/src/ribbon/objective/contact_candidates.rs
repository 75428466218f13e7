//! The pairs a line search's path admits (docs/contact_barrier.md, "Cost"): found once
//! per line search from the sampled path, then read by the collision check's pieces and
//! by every evaluation on the path instead of a broad phase.
//!
//! IPC computes its constraint set once per line search the same way. The path's
//! meshes are the collision check's samples (α = 0 to the sampled end) with each vertex
//! grown by its margin for the curve's deviation from straight pieces. Cell pairs come
//! from those boxes (sort and sweep, other bodies' windows); of their primitive pairs
//! (vertex-triangle, edge-edge) a pair is kept unless its distance at the start, less
//! the most its points can approach each other on the path (for two parts of one
//! ribbon: their relative displacement, small where they move together), is beyond the
//! barrier's reach plus ŝ of slack, or its rim stations stay within the neighbour skip
//! all along the path. A pair left out is inactive at every trial and cannot reach a
//! collision floor: the evaluations test each kept pair's exact gap, so the same pairs
//! enter as with the broad phase; only their summation order differs.

use super::accumulate::Accumulator;
use super::contact_terms::{station_gap, CellGeometry, ContactTerms, Found};
use super::Objective;
use crate::contact::barrier::{edge_edge, point_triangle};
use crate::contact::obstacles::{apart, bounds, boxes_near, sort_boxes, window};
use crate::geometry::Vector3;

type Aabb = (Vector3, Vector3);

/// The most points of two cells approach each other along a path, m.
pub(super) type Approach<'a> = &'a dyn Fn(usize, usize) -> f64;

/// Candidate pairs of one line search (kept buffers: no allocation once warm).
#[derive(Clone, Debug, Default)]
pub struct Candidates {
    /// (collider solid, rim vertex).
    pub(super) solid: Vec<(u32, u32)>,
    /// (collider point, edge or triangle; ribbon cell).
    pub(super) point: Vec<(u32, u32)>,
    pub(super) edge: Vec<(u32, u32)>,
    pub(super) triangle: Vec<(u32, u32)>,
    /// Against other bodies: (body, rim vertex, its element, their cell), (body, their
    /// vertex, own cell), (body, own edge, its element, their edge).
    pub(super) body_vertex: Vec<(u32, u32, u32, u32)>,
    pub(super) body_triangle: Vec<(u32, u32, u32)>,
    pub(super) body_edge: Vec<(u32, [u32; 2], u32, [u32; 2])>,
    /// The ribbon against itself: (rim vertex, its element, cell), (edge, its element,
    /// edge, its element).
    pub(super) own_vertex: Vec<(u32, u32, u32)>,
    pub(super) own_edge: Vec<([u32; 2], u32, [u32; 2], u32)>,
    /// The cells' swept boxes, sorted along the obstacles' axis, and the widest, m.
    boxes: Vec<Aabb>,
    order: Vec<u32>,
    widest: f64,
    starts: Starts,
}

/// The own mesh at the start of the path, per vertex, cell and edge (kept buffers).
#[derive(Clone, Debug, Default)]
struct Starts {
    /// Per vertex: the diagonal of its box on the path (the most it moves), m.
    moves: Vec<f64>,
    /// Per cell of `ct.cells`.
    cells: Vec<PartStart<3>>,
    /// Per edge of `ct.cells.edges`.
    edges: Vec<PartStart<2>>,
}

/// A cell or an edge at the start of the path.
#[derive(Clone, Copy, Debug)]
struct PartStart<const N: usize> {
    /// Its corners, m.
    x: [Vector3; N],
    /// A sphere holding them (centre, radius), m.
    sphere: (Vector3, f64),
    /// Their box, m.
    bounds: Aabb,
    /// The most any corner moves on the path, m.
    most: f64,
    /// Their rim stations (lowest, highest) and the most any shifts on the path, m.
    stations: (f64, f64, f64),
}

impl Starts {
    fn fill(
        &mut self,
        ct: &ContactTerms,
        vertex_boxes: &[Aabb],
        x0: &[Vector3],
        stations: &[(f64, f64)],
    ) {
        self.moves.clear();
        self.moves
            .extend(vertex_boxes.iter().map(|(lo, hi)| (hi - lo).norm()));
        let moves = &self.moves;
        let part = |vs: [u32; 3]| part_start(vs, x0, moves, stations);
        self.cells.clear();
        self.cells
            .extend(ct.cells.triangles.iter().map(|&t| part(t)));
        let part = |vs: [u32; 2]| part_start(vs, x0, moves, stations);
        self.edges.clear();
        self.edges.extend(ct.cells.edges.iter().map(|&e| part(e)));
    }
}

/// Part `vs` (a cell's or an edge's vertices) at the start `x0`, with its vertices'
/// motions (m) and rim stations.
fn part_start<const N: usize>(
    vs: [u32; N],
    x0: &[Vector3],
    moves: &[f64],
    stations: &[(f64, f64)],
) -> PartStart<N> {
    let x = vs.map(|v| x0[v as usize]);
    PartStart {
        x,
        sphere: sphere(&x),
        bounds: bounds(&x),
        most: vs.iter().fold(0.0, |m: f64, &v| m.max(moves[v as usize])),
        stations: station_range(stations, &vs),
    }
}

/// The rim stations of vertices `vs` at the start (lowest, highest) and the most any of
/// them shifts along the path, m.
fn station_range(stations: &[(f64, f64)], vs: &[u32]) -> (f64, f64, f64) {
    vs.iter().fold(
        (f64::INFINITY, f64::NEG_INFINITY, 0.0),
        |(lo, hi, sh): (f64, f64, f64), &v| {
            let (u, shift) = stations[v as usize];
            (lo.min(u), hi.max(u), sh.max(shift))
        },
    )
}

impl Candidates {
    /// Every pair that may come within the barrier's reach while each rim vertex stays
    /// in its box of `vertex_boxes` (m; mesh order), starting from `x0`: the cells'
    /// swept boxes pick cell pairs, and of their primitive pairs those whose distance at
    /// the start, less the most their points can move inside their boxes, is within
    /// reach.
    /// `extra` (m) widens the reach for the collision check's floors (twice the
    /// largest margin of the path's curvature).
    pub(super) fn build(
        &mut self,
        ct: &ContactTerms,
        (vertex_boxes, x0): (&[Aabb], &[Vector3]),
        (relative, stations): (Approach, &[(f64, f64)]),
        extra: f64,
    ) {
        let obs = &ct.obstacles;
        let axis = obs.axis;
        let slack = ct.activation + extra;
        self.boxes.clear();
        for tri in &ct.cells.triangles {
            let b = tri.iter().fold(empty(), |(lo, hi), &v| {
                let (a, b) = vertex_boxes[v as usize];
                (lo.inf(&a), hi.sup(&b))
            });
            self.boxes.push(b);
        }
        sort_boxes(&self.boxes, axis, &mut self.order);
        self.widest = self
            .boxes
            .iter()
            .fold(0.0, |w: f64, (lo, hi)| w.max(hi[axis] - lo[axis]));
        self.solids(ct, vertex_boxes, slack);
        self.features(ct, slack);
        // each cell's and edge's start, bounds and motion once: a cell meets dozens of
        // others' cells (and its neighbours') in a build
        let mut starts = std::mem::take(&mut self.starts);
        starts.fill(ct, vertex_boxes, x0, stations);
        let probe = Probe {
            ct,
            x0,
            starts: &starts,
            relative,
            stations,
            reach: ct.thickness + ct.activation + slack,
        };
        self.bodies(&probe);
        self.own_vertex.clear();
        self.own_edge.clear();
        if ct.self_contact {
            self.own_cells(&probe);
        }
        self.starts = starts;
    }

    /// Rim vertices that may come within reach of a collider solid: the signed distance
    /// is 1-Lipschitz, so a vertex box whose centre is farther than its half diagonal
    /// plus the reach stays out.
    fn solids(&mut self, ct: &ContactTerms, vertex_boxes: &[Aabb], slack: f64) {
        let obs = &ct.obstacles;
        let reach = 0.5 * ct.thickness + ct.activation + slack;
        self.solid.clear();
        for (k, solid) in obs.solids.iter().enumerate() {
            for (v, b) in vertex_boxes.iter().enumerate() {
                if let Some(aabb) = &solid.aabb {
                    if !boxes_near(b, aabb, reach) {
                        continue;
                    }
                }
                let centre = (b.0 + b.1) * 0.5;
                let (sd, _) = obs.solid_distance(solid, &centre);
                if sd - 0.5 * (b.1 - b.0).norm() <= reach {
                    self.solid.push((k as u32, v as u32));
                }
            }
        }
    }

    /// Collider points, edges and triangles against the cells' swept boxes.
    fn features(&mut self, ct: &ContactTerms, slack: f64) {
        let obs = &ct.obstacles;
        let near = |lo: &Vector3, hi: &Vector3, margin: f64, k: usize, out: &mut Vec<_>| {
            let range = window(
                &self.boxes,
                &self.order,
                obs.axis,
                self.widest,
                lo[obs.axis],
                hi[obs.axis],
                margin,
            );
            for &t in &self.order[range] {
                if boxes_near(&self.boxes[t as usize], &(*lo, *hi), margin) {
                    out.push((k as u32, t));
                }
            }
        };
        let reach = ct.activation + slack;
        self.point.clear();
        for (k, f) in obs.points.iter().enumerate() {
            near(&f.lo, &f.hi, f.offset + reach, k, &mut self.point);
        }
        self.edge.clear();
        for (k, f) in obs.edges.iter().enumerate() {
            near(&f.lo, &f.hi, f.offset + reach, k, &mut self.edge);
        }
        self.triangle.clear();
        for (k, f) in obs.triangles.iter().enumerate() {
            near(&f.lo, &f.hi, f.offset + reach, k, &mut self.triangle);
        }
    }

    /// The cells against the other bodies' (static) cells.
    fn bodies(&mut self, probe: &Probe) {
        let ct = probe.ct;
        let obs = &ct.obstacles;
        let margin = probe.reach;
        self.body_vertex.clear();
        self.body_triangle.clear();
        self.body_edge.clear();
        // the whole swept ribbon first: most other bodies are far from all of it
        let whole = self
            .boxes
            .iter()
            .fold(empty(), |(lo, hi), b| (lo.inf(&b.0), hi.sup(&b.1)));
        for (b, body) in obs.bodies.iter().enumerate() {
            if !boxes_near(&whole, &(body.lo, body.hi), margin) {
                continue;
            }
            for t in 0..self.boxes.len() {
                let bt = self.boxes[t];
                let bt = &bt;
                if !boxes_near(bt, &(body.lo, body.hi), margin) {
                    continue;
                }
                let range = window(
                    &body.boxes,
                    &body.order,
                    obs.axis,
                    body.widest,
                    bt.0[obs.axis],
                    bt.1[obs.axis],
                    margin,
                );
                for &o in &body.order[range] {
                    if boxes_near(bt, &body.boxes[o as usize], margin) {
                        self.body_pairs(probe, b, t, o as usize);
                    }
                }
            }
        }
    }

    /// The primitive pairs of own cell `t` and cell `o` of body `b` within reach.
    fn body_pairs(&mut self, probe: &Probe, b: usize, t: usize, o: usize) {
        let (ct, starts) = (probe.ct, probe.starts);
        let body = &ct.obstacles.bodies[b];
        let other = |v: u32| body.vertices[v as usize];
        let e = (t / 2) as u32;
        let own = &ct.cells;
        let ox = body.cells.triangles[o].map(other);
        let cell = &starts.cells[t];
        let (x, most) = (&cell.x, cell.most);
        let ((ca, ra), (cb, rb)) = (cell.sphere, sphere(&ox));
        if (ca - cb).norm() - ra - rb > probe.reach + most {
            return;
        }
        let obounds = bounds(&ox);
        for &v in own.owned_vertices(t) {
            let (p, m) = (probe.x0[v as usize], starts.moves[v as usize]);
            if !boxes_near(&(p, p), &obounds, probe.reach + m) {
                continue;
            }
            let d = point_triangle(&p, &ox[0], &ox[1], &ox[2]).distance;
            if d - m <= probe.reach {
                self.body_vertex.push((b as u32, v, e, o as u32));
            }
        }
        for &ov in body.cells.owned_vertices(o) {
            let q = other(ov);
            if !boxes_near(&(q, q), &cell.bounds, probe.reach + most) {
                continue;
            }
            let d = point_triangle(&q, &x[0], &x[1], &x[2]).distance;
            if d - most <= probe.reach {
                self.body_triangle.push((b as u32, ov, t as u32));
            }
        }
        for k in own.edge_start[t] as usize..own.edge_start[t + 1] as usize {
            let (edge, start) = (own.edges[k], &starts.edges[k]);
            let ([a, bb], most) = (start.x, start.most);
            for &oe in body.cells.owned_edges(o) {
                if apart(&[a, bb], &[other(oe[0]), other(oe[1])], probe.reach + most) {
                    continue;
                }
                let d = edge_edge(&a, &bb, &other(oe[0]), &other(oe[1])).distance;
                if d - most <= probe.reach {
                    self.body_edge.push((b as u32, edge, e, oe));
                }
            }
        }
    }

    /// Pairs of the ribbon's own cells on different elements (sort and sweep), then
    /// their primitive pairs within reach.
    fn own_cells(&mut self, probe: &Probe) {
        let axis = probe.ct.obstacles.axis;
        let margin = probe.reach;
        for i in 0..self.order.len() {
            let t1 = self.order[i] as usize;
            let top = self.boxes[t1].1[axis] + margin;
            for k in i + 1..self.order.len() {
                let t2 = self.order[k] as usize;
                if self.boxes[t2].0[axis] > top {
                    break;
                }
                if t1 / 2 != t2 / 2 && boxes_near(&self.boxes[t1], &self.boxes[t2], margin) {
                    self.own_pairs(probe, t1, t2);
                }
            }
        }
    }

    /// The primitive pairs of own cells `t1` and `t2` within reach (the neighbour skip
    /// is the evaluation's: stations move with the creases).
    ///
    /// Two parts of one ribbon mostly move together: the most their points approach
    /// each other along the path (`Probe::relative`) is far less than what each moves,
    /// so cells near along the ribbon but not in space drop out here.
    fn own_pairs(&mut self, probe: &Probe, t1: usize, t2: usize) {
        let (ct, starts) = (probe.ct, probe.starts);
        let cells = &ct.cells;
        let (c1, c2) = (&starts.cells[t1], &starts.cells[t2]);
        let ((ca, ra), (cb, rb)) = (c1.sphere, c2.sphere);
        if (ca - cb).norm() - ra - rb > probe.reach + c1.most + c2.most {
            return;
        }
        let approach = (probe.relative)(t1, t2);
        if !boxes_near(&c1.bounds, &c2.bounds, probe.reach + approach) {
            return;
        }
        // within the neighbour skip all along the path (stations move with the creases,
        // at most `shift`): the evaluations never take it
        let skipped = |(alo, ahi, ash): (f64, f64, f64), (blo, bhi, bsh): (f64, f64, f64)| {
            station_gap((alo, ahi), (blo, bhi), ct.period) + ash + bsh <= ct.skip
        };
        for (a, b) in [(t1, t2), (t2, t1)] {
            let cell = &starts.cells[b];
            let (x, (centre, radius)) = (&cell.x, cell.sphere);
            for &v in cells.owned_vertices(a) {
                let (u, shift) = probe.stations[v as usize];
                if skipped((u, u, shift), cell.stations) {
                    continue;
                }
                let p = probe.x0[v as usize];
                let m = approach.min(cell.most + starts.moves[v as usize]);
                if (p - centre).norm() - radius > probe.reach + m
                    || !boxes_near(&(p, p), &cell.bounds, probe.reach + m)
                {
                    continue;
                }
                let d = point_triangle(&p, &x[0], &x[1], &x[2]).distance;
                if d - m <= probe.reach {
                    self.own_vertex.push((v, (a / 2) as u32, b as u32));
                }
            }
        }
        let edges = |t: usize| cells.edge_start[t] as usize..cells.edge_start[t + 1] as usize;
        for k1 in edges(t1) {
            let e1 = &starts.edges[k1];
            for k2 in edges(t2) {
                let e2 = &starts.edges[k2];
                if skipped(e1.stations, e2.stations) {
                    continue;
                }
                let m = approach.min(e1.most + e2.most);
                let ((ca, ra), (cb, rb)) = (e1.sphere, e2.sphere);
                if (ca - cb).norm() - ra - rb > probe.reach + m
                    || !boxes_near(&e1.bounds, &e2.bounds, probe.reach + m)
                {
                    continue;
                }
                let (a, b) = (e1.x, e2.x);
                let d = edge_edge(&a[0], &a[1], &b[0], &b[1]).distance;
                if d - m <= probe.reach {
                    let (first, second) = (cells.edges[k1], cells.edges[k2]);
                    self.own_edge
                        .push((first, (t1 / 2) as u32, second, (t2 / 2) as u32));
                }
            }
        }
    }
}

/// What the primitive tests of a build share: the start mesh, how far each vertex can
/// move on the path (m) and the reach a pair must stay beyond (m).
struct Probe<'a> {
    ct: &'a ContactTerms,
    x0: &'a [Vector3],
    /// The own mesh's parts at the start and how far they move.
    starts: &'a Starts,
    /// The most points of two cells approach each other along the path, m.
    relative: Approach<'a>,
    /// Per vertex: its rim station at the start and the most it moves along the path, m.
    stations: &'a [(f64, f64)],
    reach: f64,
}

/// A sphere holding the points `x`: their centroid and the largest distance from it, m.
fn sphere(x: &[Vector3]) -> (Vector3, f64) {
    let centre = x.iter().fold(Vector3::zeros(), |c, p| c + p) / x.len() as f64;
    let radius = x.iter().fold(0.0, |r: f64, p| r.max((p - centre).norm()));
    (centre, radius)
}

fn empty() -> Aabb {
    (
        Vector3::repeat(f64::INFINITY),
        Vector3::repeat(f64::NEG_INFINITY),
    )
}

impl Objective<'_> {
    /// The contact pairs of the candidates (each tested exactly, as the broad phase's).
    pub(super) fn candidate_pairs(
        &self,
        acc: &mut Accumulator,
        ct: &ContactTerms,
        geo: &CellGeometry,
        c: &Candidates,
        found: &mut Found,
    ) {
        for &(k, v) in &c.solid {
            self.vertex_solid(acc, ct, k as usize, v, found);
        }
        for &(k, t) in &c.point {
            self.point_feature(acc, ct, k as usize, t as usize, found);
        }
        for &(k, t) in &c.edge {
            self.edge_feature(acc, ct, k as usize, t as usize, found);
        }
        for &(k, t) in &c.triangle {
            self.triangle_feature(acc, ct, k as usize, t as usize, found);
        }
        for &(b, v, e, o) in &c.body_vertex {
            self.body_vertex_triangle(acc, ct, (b as usize, v, e as usize, o as usize), found);
        }
        for &(b, ov, t) in &c.body_triangle {
            self.body_triangle_vertex(acc, ct, (b as usize, ov, t as usize), found);
        }
        for &(b, edge, e, oe) in &c.body_edge {
            self.body_edges(acc, ct, (b as usize, edge, e as usize, oe), found);
        }
        for &(v, e, b) in &c.own_vertex {
            self.own_vertex_triangle(acc, ct, geo, (v, e as usize, b as usize), found);
        }
        for &(e1, el1, e2, el2) in &c.own_edge {
            let (first, second) = ((e1, el1 as usize), (e2, el2 as usize));
            self.self_edge_pair(acc, ct, geo, first, second, found);
        }
    }
}
