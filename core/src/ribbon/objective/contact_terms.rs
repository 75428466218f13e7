//! Contact as terms of the step objective (docs/contact_barrier.md): IPC's barrier
//! B(s) = κ A b(s) on the gap s of every pair of the reconstructed mesh closer than ŝ
//! (against colliders, other ribbons and the ribbon itself) and IPC's lagged friction
//! against colliders.
//!
//! Every point of a pair's ribbon side is carried by one element (the element of the
//! mesh cell that owns it), so a pair against something static is a point term: its
//! gradient goes into the element's wrench ([`Accumulator::add_point_gradient`], with the
//! sliding of a rim vertex along its rim), its Gauss-Newton Hessian B'' u u^T into the
//! element's 8x8 block. A pair between two elements of this ribbon is recorded as a
//! [`PairTerm`] (its Hessian is rank one across the chain: `chain::pairs`).

use std::sync::Arc;

use super::accumulate::{sliding_rate, Accumulator};
use super::{Objective, Vec8};
use crate::contact::barrier::{barrier, mollified_edge_edge, point_triangle, Closest, PairSource};
use crate::contact::obstacles::{
    apart, bounds, boxes_near, sort_boxes, window, CellMesh, Obstacles,
};
use crate::geometry::{Point3, Vector3};

/// Lagged friction of one ribbon vertex against one collider or another body (IPC):
/// fixed at the start of the step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrictionLag {
    /// Mesh vertex (2 j + top).
    pub vertex: u32,
    /// μ λ: the Coulomb coefficient times the normal force at the start of the step, N.
    pub mu_lambda: f64,
    /// An orthonormal basis of the contact's tangent plane at the start of the step.
    pub tangent: [Vector3; 2],
    /// The collider's (or the other body's) own displacement at the contact over the
    /// step, m.
    pub shift: Vector3,
    /// What the vertex slides on (for the work a moving one does).
    pub source: PairSource,
}

/// The contact data of one ribbon's step: the static world it sees, its own mesh
/// cells, the lagged friction, the barrier's constants. Built by the ribbon before its
/// solve; every evaluation reads it.
#[derive(Clone, Debug, Default)]
pub struct ContactTerms {
    pub obstacles: Obstacles,
    /// The ribbon's own mesh cells (constant topology) and the cell owning each vertex.
    pub cells: Arc<CellMesh>,
    pub vertex_cell: Vec<u32>,
    pub friction: Vec<FrictionLag>,
    /// κ A, J/m^2: the barrier's weight per pair (A the area a rim vertex stands for).
    pub weight: f64,
    /// ŝ, m.
    pub activation: f64,
    /// Offset of a pair between two mid-surfaces (ξ, m).
    pub thickness: f64,
    /// Neighbour skip along the centerline, m; the period of a loop's stations, m.
    pub skip: f64,
    pub period: Option<f64>,
    pub self_contact: bool,
    /// ε_u = ε_v h, m.
    pub friction_slip: f64,
}

impl ContactTerms {
    /// Set the ribbon's own cells (from its triangles over `vertex_count` vertices).
    pub fn set_cells(&mut self, cells: Arc<CellMesh>, vertex_count: usize) {
        self.vertex_cell.clear();
        self.vertex_cell.resize(vertex_count, 0);
        for t in 0..cells.len() {
            for &v in cells.owned_vertices(t) {
                self.vertex_cell[v as usize] = t as u32;
            }
        }
        self.cells = cells;
    }
}

/// A pair between two elements of the ribbon: its Gauss-Newton Hessian is
/// `weight` g g^T with g = P_{e1}^T u1 + P_{e2}^T u2 (u over (twist, c_e, c_{e+1})).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PairTerm {
    pub e1: u32,
    pub e2: u32,
    pub u1: Vec8,
    pub u2: Vec8,
    /// B''(s), J/m^2.
    pub weight: f64,
}

/// The ribbon's cells at one evaluation: boxes sorted along the obstacles' axis, rim
/// stations u of every vertex and each cell's interval of stations, m.
#[derive(Clone, Debug, Default)]
pub(super) struct CellGeometry {
    pub(super) boxes: Vec<(Vector3, Vector3)>,
    pub(super) order: Vec<u32>,
    pub(super) vertex_u: Vec<f64>,
    pub(super) cell_u: Vec<(f64, f64)>,
    pub(super) widest: f64,
}

/// Per-evaluation buffers of the contact terms (no allocation once warm).
#[derive(Clone, Debug, Default)]
pub struct ContactWorkspace {
    pub(super) cells: CellGeometry,
    /// The cross-element pairs of the last evaluation with second-order data.
    pub pairs: Vec<PairTerm>,
    /// Pairs inside the barrier at the last evaluation, and the smallest gap, m.
    pub active: usize,
    pub min_gap: f64,
    /// What the pair of the smallest gap is against.
    pub min_source: PairSource,
    /// Barrier and friction energy of the last evaluation, J.
    pub barrier_energy: f64,
    pub friction_energy: f64,
    /// Per element: the contact forces' wrench (moment, force), left out of the chain's
    /// geometric stiffness (see `add_force`); empty when it is in.
    pub wrench: Vec<Vec8>,
    /// Per collider: the summed magnitude of the barrier forces on it at the last
    /// evaluation with forces, N (for the work a moving collider does).
    pub collider_force: Vec<f64>,
    /// A pair's dense gradient (the dense baseline's Hessian).
    pub(super) dense_g: Vec<f64>,
}

/// Finds an evaluation's pairs instead of the broad phase (the candidates of a checked
/// line-search path, `contact_candidates`).
pub(super) type PairFinder<'c> = &'c dyn Fn(&mut Accumulator, &CellGeometry, &mut Found);

/// The ribbon's side of a pair: its points (mesh vertices), their weights in the
/// gap's gradient (∂s/∂x_i = w_i n), how many, and the element carrying them all.
#[derive(Clone, Copy)]
pub(super) struct Side {
    pub(super) vertices: [u32; 3],
    pub(super) weights: [f64; 3],
    pub(super) count: usize,
    pub(super) element: usize,
    /// An edge-edge pair's mollifier m and its gradient at this side's points (1 and 0
    /// for every other pair).
    pub(super) mollifier: (f64, [Vector3; 3]),
}

impl Side {
    pub(super) fn vertex(v: u32, element: usize) -> Side {
        Side {
            vertices: [v, 0, 0],
            weights: [1.0, 0.0, 0.0],
            count: 1,
            element,
            mollifier: (1.0, [Vector3::zeros(); 3]),
        }
    }
    pub(super) fn edge(e: [u32; 2], w: [f64; 2], element: usize) -> Side {
        Side {
            vertices: [e[0], e[1], 0],
            weights: [w[0], w[1], 0.0],
            count: 2,
            element,
            mollifier: (1.0, [Vector3::zeros(); 3]),
        }
    }
    pub(super) fn triangle(t: [u32; 3], w: [f64; 3], element: usize) -> Side {
        Side {
            vertices: t,
            weights: w,
            count: 3,
            element,
            mollifier: (1.0, [Vector3::zeros(); 3]),
        }
    }
}

/// What the pairs of one evaluation add up to.
pub(super) struct Found<'p> {
    pub(super) value: f64,
    feasible: bool,
    active: usize,
    min_gap: f64,
    /// What the pair of the smallest gap is against.
    min_source: PairSource,
    pub(super) pairs: &'p mut Vec<PairTerm>,
    collider_force: &'p mut Vec<f64>,
    pub(super) wrench: &'p mut Vec<Vec8>,
}

impl Found<'_> {
    /// Counts a pair at gap s; false when it is outside the barrier or infeasible (then
    /// nothing more is to be added).
    pub(super) fn enter(&mut self, s: f64, activation: f64, source: PairSource) -> bool {
        if s >= activation {
            return false;
        }
        self.active += 1;
        if s < self.min_gap {
            self.min_gap = s;
            self.min_source = source;
        }
        if s <= 0.0 {
            self.feasible = false;
            return false;
        }
        true
    }
}

impl Objective<'_> {
    /// The contact terms at the frames in `acc`: their value (+∞ when a pair has
    /// crossed or touches), gradient and Hessian blocks through `acc`, cross-element
    /// pairs into `cw.pairs`.
    pub(super) fn contact_terms(
        &self,
        acc: &mut Accumulator,
        cw: &mut ContactWorkspace,
        cached: Option<PairFinder>,
    ) -> f64 {
        let Some(ct) = self.contact else {
            return 0.0;
        };
        cw.pairs.clear();
        cw.wrench.clear();
        if !CONTACT_GEOMETRIC_STIFFNESS && acc.second.is_some() {
            cw.wrench.resize(self.strip.segments, Vec8::zeros());
        }
        cw.collider_force.clear();
        cw.collider_force.resize(ct.obstacles.poses.len(), 0.0);
        self.cell_geometry(acc, ct, &mut cw.cells, cached.is_none());
        let geo = &cw.cells;
        let mut found = Found {
            value: 0.0,
            feasible: true,
            active: 0,
            min_gap: f64::INFINITY,
            min_source: PairSource::Itself,
            pairs: &mut cw.pairs,
            collider_force: &mut cw.collider_force,
            wrench: &mut cw.wrench,
        };
        if let Some(find) = cached {
            // the pairs the line search's path admits (`contact_candidates`)
            find(acc, geo, &mut found);
        } else {
            self.vertex_solid_pairs(acc, ct, &mut found);
            self.collider_feature_pairs(acc, ct, geo, &mut found);
            for b in 0..ct.obstacles.bodies.len() {
                self.other_body_pairs(acc, ct, geo, b, &mut found);
            }
            if ct.self_contact {
                self.self_pairs(acc, ct, geo, &mut found);
            }
        }
        let (value, feasible) = (found.value, found.feasible);
        cw.active = found.active;
        cw.min_gap = found.min_gap;
        cw.min_source = found.min_source;
        cw.barrier_energy = value;
        let friction = self.friction_terms(acc, ct, &mut cw.wrench);
        cw.friction_energy = friction;
        if feasible {
            value + friction
        } else {
            f64::INFINITY
        }
    }

    /// Cell boxes (sorted along the obstacles' axis), rim stations u of every vertex
    /// and the u-interval of every cell, m.
    fn cell_geometry(
        &self,
        acc: &Accumulator,
        ct: &ContactTerms,
        geo: &mut CellGeometry,
        sorted: bool,
    ) {
        let n = self.strip.segments;
        let c = &acc.coords.crease_direction;
        geo.vertex_u.clear();
        for j in 0..=n {
            geo.vertex_u.push(self.strip.material_bottom(j, c[j]).x);
            geo.vertex_u.push(self.strip.material_top(j, c[j]).x);
        }
        geo.boxes.clear();
        geo.cell_u.clear();
        let axis = ct.obstacles.axis;
        let mut widest: f64 = 0.0;
        for tri in &ct.cells.triangles {
            let x = tri.map(|v| vertex_position(acc, v));
            let b = bounds(&x);
            widest = widest.max(b.1[axis] - b.0[axis]);
            geo.boxes.push(b);
            let u = tri.map(|v| geo.vertex_u[v as usize]);
            geo.cell_u
                .push((u[0].min(u[1]).min(u[2]), u[0].max(u[1]).max(u[2])));
        }
        geo.widest = widest;
        if sorted {
            sort_boxes(&geo.boxes, axis, &mut geo.order);
        }
    }

    /// Every rim vertex against every collider solid (plane, box, sphere, capsule).
    fn vertex_solid_pairs(&self, acc: &mut Accumulator, ct: &ContactTerms, found: &mut Found) {
        for k in 0..ct.obstacles.solids.len() {
            for v in 0..ct.vertex_cell.len() as u32 {
                self.vertex_solid(acc, ct, k, v, found);
            }
        }
    }

    /// Rim vertex `v` against collider solid `k`.
    pub(super) fn vertex_solid(
        &self,
        acc: &mut Accumulator,
        ct: &ContactTerms,
        k: usize,
        v: u32,
        found: &mut Found,
    ) {
        let obs = &ct.obstacles;
        let solid = &obs.solids[k];
        let half = 0.5 * ct.thickness;
        let reach = half + ct.activation;
        let x = vertex_position(acc, v);
        if let Some((lo, hi)) = &solid.aabb {
            if (0..3).any(|d| x[d] < lo[d] - reach || x[d] > hi[d] + reach) {
                return;
            }
        }
        let (sd, normal) = obs.solid_distance(solid, &x);
        let pair = Closest {
            distance: sd,
            normal,
            weights: [1.0, 0.0, 0.0, 0.0],
        };
        let side = Side::vertex(v, element_of_vertex(ct, v));
        self.static_pair(
            acc,
            ct,
            &pair,
            (half, PairSource::Collider(solid.collider)),
            &side,
            found,
        );
    }

    /// The colliders' features (points, edges, mesh triangles) against the ribbon's
    /// triangles, edges and vertices.
    fn collider_feature_pairs(
        &self,
        acc: &mut Accumulator,
        ct: &ContactTerms,
        geo: &CellGeometry,
        found: &mut Found,
    ) {
        let obs = &ct.obstacles;
        for (k, f) in obs.points.iter().enumerate() {
            for t in cells_near(geo, &(f.lo, f.hi), obs.axis, f.offset + ct.activation) {
                self.point_feature(acc, ct, k, t, found);
            }
        }
        for (k, f) in obs.edges.iter().enumerate() {
            for t in cells_near(geo, &(f.lo, f.hi), obs.axis, f.offset + ct.activation) {
                self.edge_feature(acc, ct, k, t, found);
            }
        }
        for (k, f) in obs.triangles.iter().enumerate() {
            for t in cells_near(geo, &(f.lo, f.hi), obs.axis, f.offset + ct.activation) {
                self.triangle_feature(acc, ct, k, t, found);
            }
        }
    }

    /// Collider point `k` against the ribbon's cell `t`.
    pub(super) fn point_feature(
        &self,
        acc: &mut Accumulator,
        ct: &ContactTerms,
        k: usize,
        t: usize,
        found: &mut Found,
    ) {
        let f = &ct.obstacles.points[k];
        let tri = ct.cells.triangles[t];
        let x = tri.map(|v| vertex_position(acc, v));
        let pair = point_triangle(&f.x[0], &x[0], &x[1], &x[2]);
        let w = [pair.weights[1], pair.weights[2], pair.weights[3]];
        let side = Side::triangle(tri, w, t / 2);
        let source = PairSource::Collider(f.collider);
        self.static_pair(acc, ct, &pair, (f.offset, source), &side, found);
    }

    /// Collider edge `k` against the edges the ribbon's cell `t` owns.
    pub(super) fn edge_feature(
        &self,
        acc: &mut Accumulator,
        ct: &ContactTerms,
        k: usize,
        t: usize,
        found: &mut Found,
    ) {
        let f = &ct.obstacles.edges[k];
        for e in ct.cells.owned_edges(t) {
            let (a, b) = (vertex_position(acc, e[0]), vertex_position(acc, e[1]));
            if apart(&f.x, &[a, b], f.offset + ct.activation) {
                continue;
            }
            let (pair, m, gm) = mollified_edge_edge(&f.x[0], &f.x[1], &a, &b);
            let mut side = Side::edge(*e, [pair.weights[2], pair.weights[3]], t / 2);
            side.mollifier = (m, [gm[2], gm[3], Vector3::zeros()]);
            let source = PairSource::Collider(f.collider);
            self.static_pair(acc, ct, &pair, (f.offset, source), &side, found);
        }
    }

    /// Collider triangle `k` against the vertices the ribbon's cell `t` owns.
    pub(super) fn triangle_feature(
        &self,
        acc: &mut Accumulator,
        ct: &ContactTerms,
        k: usize,
        t: usize,
        found: &mut Found,
    ) {
        let f = &ct.obstacles.triangles[k];
        for &v in ct.cells.owned_vertices(t) {
            let x = vertex_position(acc, v);
            if apart(&[x], &f.x, f.offset + ct.activation) {
                continue;
            }
            let pair = point_triangle(&x, &f.x[0], &f.x[1], &f.x[2]);
            let side = Side::vertex(v, t / 2);
            let source = PairSource::Collider(f.collider);
            self.static_pair(acc, ct, &pair, (f.offset, source), &side, found);
        }
    }

    /// The ribbon's cells against another ribbon's (static) cells.
    fn other_body_pairs(
        &self,
        acc: &mut Accumulator,
        ct: &ContactTerms,
        geo: &CellGeometry,
        b: usize,
        found: &mut Found,
    ) {
        let body = &ct.obstacles.bodies[b];
        let axis = ct.obstacles.axis;
        let margin = ct.thickness + ct.activation;
        for t in 0..ct.cells.len() {
            let bt = geo.boxes[t];
            if !boxes_near(&bt, &(body.lo, body.hi), margin) {
                continue;
            }
            let range = window(
                &body.boxes,
                &body.order,
                axis,
                body.widest,
                bt.0[axis],
                bt.1[axis],
                margin,
            );
            for &o in &body.order[range] {
                self.body_cells(acc, ct, geo, (b, t, o as usize), found);
            }
        }
    }

    /// The ribbon's cell `t` against cell `o` of other body `b`: the vertices each owns
    /// against the other's triangle, their owned edges against each other.
    pub(super) fn body_cells(
        &self,
        acc: &mut Accumulator,
        ct: &ContactTerms,
        geo: &CellGeometry,
        (b, t, o): (usize, usize, usize),
        found: &mut Found,
    ) {
        let body = &ct.obstacles.bodies[b];
        let margin = ct.thickness + ct.activation;
        let own = &ct.cells;
        let bt = geo.boxes[t];
        if !boxes_near(&bt, &body.boxes[o], margin) {
            return;
        }
        for &v in own.owned_vertices(t) {
            let p = vertex_position(acc, v);
            if boxes_near(&(p, p), &body.boxes[o], margin) {
                self.body_vertex_triangle(acc, ct, (b, v, t / 2, o), found);
            }
        }
        for &ov in body.cells.owned_vertices(o) {
            let p = body.vertices[ov as usize];
            if boxes_near(&(p, p), &bt, margin) {
                self.body_triangle_vertex(acc, ct, (b, ov, t), found);
            }
        }
        for &edge in own.owned_edges(t) {
            for &oe in body.cells.owned_edges(o) {
                self.body_edges(acc, ct, (b, edge, t / 2, oe), found);
            }
        }
    }

    /// Rim vertex `v` (carried by element `e`) against cell `o` of body `b`.
    pub(super) fn body_vertex_triangle(
        &self,
        acc: &mut Accumulator,
        ct: &ContactTerms,
        (b, v, e, o): (usize, u32, usize, usize),
        found: &mut Found,
    ) {
        let body = &ct.obstacles.bodies[b];
        let ox = body.cells.triangles[o].map(|w| body.vertices[w as usize]);
        let p = vertex_position(acc, v);
        let pair = point_triangle(&p, &ox[0], &ox[1], &ox[2]);
        let source = (ct.thickness, PairSource::Body(b));
        self.static_pair(acc, ct, &pair, source, &Side::vertex(v, e), found);
    }

    /// Vertex `ov` of body `b` against the ribbon's cell `t`.
    pub(super) fn body_triangle_vertex(
        &self,
        acc: &mut Accumulator,
        ct: &ContactTerms,
        (b, ov, t): (usize, u32, usize),
        found: &mut Found,
    ) {
        let p = ct.obstacles.bodies[b].vertices[ov as usize];
        let tri = ct.cells.triangles[t];
        let x = tri.map(|v| vertex_position(acc, v));
        let pair = point_triangle(&p, &x[0], &x[1], &x[2]);
        let w = [pair.weights[1], pair.weights[2], pair.weights[3]];
        let source = (ct.thickness, PairSource::Body(b));
        self.static_pair(
            acc,
            ct,
            &pair,
            source,
            &Side::triangle(tri, w, t / 2),
            found,
        );
    }

    /// The ribbon's edge (carried by element `e`) against edge `oe` of body `b`.
    pub(super) fn body_edges(
        &self,
        acc: &mut Accumulator,
        ct: &ContactTerms,
        (b, edge, e, oe): (usize, [u32; 2], usize, [u32; 2]),
        found: &mut Found,
    ) {
        let body = &ct.obstacles.bodies[b];
        let (a, bb) = (vertex_position(acc, edge[0]), vertex_position(acc, edge[1]));
        let (oa, ob) = (body.vertices[oe[0] as usize], body.vertices[oe[1] as usize]);
        if apart(&[a, bb], &[oa, ob], ct.thickness + ct.activation) {
            return;
        }
        let (pair, m, gm) = mollified_edge_edge(&a, &bb, &oa, &ob);
        let mut side = Side::edge(edge, [pair.weights[0], pair.weights[1]], e);
        side.mollifier = (m, [gm[0], gm[1], Vector3::zeros()]);
        let source = (ct.thickness, PairSource::Body(b));
        self.static_pair(acc, ct, &pair, source, &side, found);
    }

    /// A pair with the ribbon's points in `side` against something static (`source`),
    /// at distance `pair.distance` keeping `offset` (m).
    pub(super) fn static_pair(
        &self,
        acc: &mut Accumulator,
        ct: &ContactTerms,
        pair: &Closest,
        (offset, source): (f64, PairSource),
        side: &Side,
        found: &mut Found,
    ) {
        let s = pair.distance - offset;
        if !found.enter(s, ct.activation, source) {
            return;
        }
        let (b, db, ddb) = barrier(s, ct.activation);
        let m = side.mollifier.0;
        found.value += ct.weight * m * b;
        if !acc.forces {
            return;
        }
        if let PairSource::Collider(k) = source {
            found.collider_force[k] += ct.weight * m * db.abs();
        }
        let u = self.side_gradient(acc, found, side, &pair.normal, ct.weight * m * db);
        self.mollifier_gradient(acc, found, side, ct.weight * b);
        if let Some(hs) = acc.ws_hessian.as_deref_mut() {
            hs[side.element] += u * u.transpose() * (ct.weight * m * ddb);
        }
    }

    /// Adds the gradient `db` ∂s/∂x of the points of `side` and returns
    /// u = Σ w_i J_i^T n over the element's (twist, c_e, c_{e+1}).
    pub(super) fn side_gradient(
        &self,
        acc: &mut Accumulator,
        found: &mut Found,
        side: &Side,
        normal: &Vector3,
        db: f64,
    ) -> Vec8 {
        let e = side.element;
        let mut u = Vec8::zeros();
        for i in 0..side.count {
            let (v, w) = (side.vertices[i], side.weights[i]);
            let (j, top) = ((v / 2) as usize, v % 2 == 1);
            let x = vertex_position(acc, v);
            let material = self.rim_material(acc, j, top);
            let du = sliding_rate(self.strip.width, top);
            add_force(
                acc,
                found.wrench,
                e,
                &material,
                &x,
                &(normal * (db * w)),
                (j, du),
            );
            u += jacobian_row(&x, normal, self.sliding_column(acc, e, j, top)) * w;
        }
        u
    }

    /// The gradient `value` ∇m of an edge-edge pair's mollifier at the points of `side`
    /// (nothing for other pairs). Its second-order terms are left out of the Newton
    /// matrix: they act only on nearly parallel edges, which the point-triangle pairs
    /// hold.
    pub(super) fn mollifier_gradient(
        &self,
        acc: &mut Accumulator,
        found: &mut Found,
        side: &Side,
        value: f64,
    ) {
        let (m, grad) = &side.mollifier;
        if *m >= 1.0 {
            return;
        }
        for i in 0..side.count {
            let v = side.vertices[i];
            let (j, top) = ((v / 2) as usize, v % 2 == 1);
            let x = vertex_position(acc, v);
            let material = self.rim_material(acc, j, top);
            let du = sliding_rate(self.strip.width, top);
            add_force(
                acc,
                found.wrench,
                side.element,
                &material,
                &x,
                &(grad[i] * value),
                (j, du),
            );
        }
    }

    /// Material position of rim vertex (j, top) at the current creases.
    pub(super) fn rim_material(&self, acc: &Accumulator, j: usize, top: bool) -> Point3 {
        let c = acc.coords.crease_direction[j];
        if top {
            self.strip.material_top(j, c)
        } else {
            self.strip.material_bottom(j, c)
        }
    }

    /// The local column (6 or 7) and world direction ∂x/∂c_j of rim vertex (j, top)
    /// carried by element e, if it slides (not on the square end creases).
    pub(super) fn sliding_column(
        &self,
        acc: &Accumulator,
        e: usize,
        j: usize,
        top: bool,
    ) -> Option<(usize, Vector3)> {
        let n = self.strip.segments;
        if j == 0 || j == n {
            return None;
        }
        let col = if j == e { 6 } else { 7 };
        Some((
            col,
            acc.frames.rotation[e].column(0) * sliding_rate(self.strip.width, top),
        ))
    }
}

/// Whether the contact forces' geometric stiffness (γ · ∂²x/∂q², the turning of the
/// chain under the force) enters the Newton matrix.
const CONTACT_GEOMETRIC_STIFFNESS: bool = true;

/// A contact force `gamma` (∂f/∂x, N) at rim vertex x (material point `material`) of
/// element e, sliding with c_j at `du` m per unit c: into the element's wrench. Without
/// the geometric stiffness, its wrench is also kept in `wrench` so that the chain's
/// geometric terms leave it out (they read the elements' summed forces): the contact
/// terms then enter the Newton matrix by their Gauss-Newton part alone.
pub(super) fn add_force(
    acc: &mut Accumulator,
    wrench: &mut [Vec8],
    e: usize,
    material: &Point3,
    x: &Vector3,
    gamma: &Vector3,
    (j, du): (usize, f64),
) {
    if CONTACT_GEOMETRIC_STIFFNESS {
        acc.add_point_gradient(e, material, &Point3::from(*x), gamma, Some((j, du)));
        return;
    }
    let second = acc.second.take();
    acc.add_point_gradient(e, material, &Point3::from(*x), gamma, Some((j, du)));
    acc.second = second;
    if let Some(w) = wrench.get_mut(e) {
        let moment = x.cross(gamma);
        for k in 0..3 {
            w[k] += moment[k];
            w[3 + k] += gamma[k];
        }
    }
}

/// The cells whose boxes come within `margin` of box `b`.
fn cells_near<'g>(
    geo: &'g CellGeometry,
    b: &(Vector3, Vector3),
    axis: usize,
    margin: f64,
) -> impl Iterator<Item = usize> + 'g {
    let range = window(
        &geo.boxes, &geo.order, axis, geo.widest, b.0[axis], b.1[axis], margin,
    );
    let b = *b;
    geo.order[range]
        .iter()
        .map(|&t| t as usize)
        .filter(move |&t| boxes_near(&geo.boxes[t], &b, margin))
}

/// World position of mesh vertex v (2 j + top) at the frames in `acc`, m.
#[inline]
pub(super) fn vertex_position(acc: &Accumulator, v: u32) -> Vector3 {
    let j = (v / 2) as usize;
    if v % 2 == 1 {
        acc.frames.rim_top[j].coords
    } else {
        acc.frames.rim_bottom[j].coords
    }
}

/// The element carrying mesh vertex v: that of the cell owning it (two cells per
/// element).
#[inline]
pub(super) fn element_of_vertex(ct: &ContactTerms, v: u32) -> usize {
    (ct.vertex_cell[v as usize] / 2) as usize
}

/// The gap between two intervals of rim stations, m, around a loop of `period` if any.
#[inline]
pub(super) fn station_gap(a: (f64, f64), b: (f64, f64), period: Option<f64>) -> f64 {
    let linear = |shift: f64| (b.0 + shift - a.1).max(a.0 - b.1 - shift).max(0.0);
    match period {
        None => linear(0.0),
        Some(l) => linear(0.0).min(linear(l)).min(linear(-l)),
    }
}

/// J^T a for a point x with sliding column `sigma` (column, ∂x/∂c): [x × a; a; σ · a].
pub(super) fn jacobian_row(x: &Vector3, a: &Vector3, sigma: Option<(usize, Vector3)>) -> Vec8 {
    let mut r = Vec8::zeros();
    let m = x.cross(a);
    for k in 0..3 {
        r[k] = m[k];
        r[3 + k] = a[k];
    }
    if let Some((col, s)) = sigma {
        r[col] = s.dot(a);
    }
    r
}
