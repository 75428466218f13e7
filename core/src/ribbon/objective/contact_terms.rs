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
use super::kinetic::interpolate;
use super::{Objective, Vec8};
use crate::contact::barrier::{
    barrier, edge_edge, edge_mollifier, friction_mollifier, mollifier_threshold, point_triangle,
    Closest, PairSource,
};
use crate::contact::obstacles::{
    apart, bounds, boxes_near, sort_boxes, window, CellMesh, Obstacles,
};
use crate::geometry::{Point3, Vector3};

/// Lagged friction of one ribbon vertex against one collider (IPC): fixed at the start
/// of the step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrictionLag {
    /// Mesh vertex (2 j + top).
    pub vertex: u32,
    /// μ λ: the Coulomb coefficient times the normal force at the start of the step, N.
    pub mu_lambda: f64,
    /// An orthonormal basis of the contact's tangent plane at the start of the step.
    pub tangent: [Vector3; 2],
    /// The collider's own displacement at the contact over the step, m.
    pub shift: Vector3,
    /// The collider (for the work a moving one does).
    pub collider: usize,
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

/// The ribbon's side of a pair: its points (mesh vertices), their weights in the
/// gap's gradient (∂s/∂x_i = w_i n), how many, and the element carrying them all.
#[derive(Clone, Copy)]
struct Side {
    vertices: [u32; 3],
    weights: [f64; 3],
    count: usize,
    element: usize,
    /// An edge-edge pair's mollifier m and its gradient at this side's points (1 and 0
    /// for every other pair).
    mollifier: (f64, [Vector3; 3]),
}

impl Side {
    fn vertex(v: u32, element: usize) -> Side {
        Side {
            vertices: [v, 0, 0],
            weights: [1.0, 0.0, 0.0],
            count: 1,
            element,
            mollifier: (1.0, [Vector3::zeros(); 3]),
        }
    }
    fn edge(e: [u32; 2], w: [f64; 2], element: usize) -> Side {
        Side {
            vertices: [e[0], e[1], 0],
            weights: [w[0], w[1], 0.0],
            count: 2,
            element,
            mollifier: (1.0, [Vector3::zeros(); 3]),
        }
    }
    fn triangle(t: [u32; 3], w: [f64; 3], element: usize) -> Side {
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
struct Found<'p> {
    value: f64,
    feasible: bool,
    active: usize,
    min_gap: f64,
    /// What the pair of the smallest gap is against.
    min_source: PairSource,
    pairs: &'p mut Vec<PairTerm>,
    collider_force: &'p mut Vec<f64>,
    wrench: &'p mut Vec<Vec8>,
}

impl Found<'_> {
    /// Counts a pair at gap s; false when it is outside the barrier or infeasible (then
    /// nothing more is to be added).
    fn enter(&mut self, s: f64, activation: f64, source: PairSource) -> bool {
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
    pub(super) fn contact_terms(&self, acc: &mut Accumulator, cw: &mut ContactWorkspace) -> f64 {
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
        self.cell_geometry(acc, ct, &mut cw.cells);
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
        self.vertex_solid_pairs(acc, ct, &mut found);
        self.collider_feature_pairs(acc, ct, geo, &mut found);
        for b in 0..ct.obstacles.bodies.len() {
            self.other_body_pairs(acc, ct, geo, b, &mut found);
        }
        if ct.self_contact {
            self.self_pairs(acc, ct, geo, &mut found);
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
    fn cell_geometry(&self, acc: &Accumulator, ct: &ContactTerms, geo: &mut CellGeometry) {
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
        sort_boxes(&geo.boxes, axis, &mut geo.order);
    }

    /// Every rim vertex against every collider solid (plane, box, sphere, capsule).
    fn vertex_solid_pairs(&self, acc: &mut Accumulator, ct: &ContactTerms, found: &mut Found) {
        let obs = &ct.obstacles;
        let half = 0.5 * ct.thickness;
        let reach = half + ct.activation;
        for solid in &obs.solids {
            for v in 0..ct.vertex_cell.len() as u32 {
                let x = vertex_position(acc, v);
                if let Some((lo, hi)) = &solid.aabb {
                    if (0..3).any(|d| x[d] < lo[d] - reach || x[d] > hi[d] + reach) {
                        continue;
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
        }
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
        let cells = &ct.cells;
        for f in &obs.points {
            for t in cells_near(geo, &(f.lo, f.hi), obs.axis, f.offset + ct.activation) {
                let tri = cells.triangles[t];
                let x = tri.map(|v| vertex_position(acc, v));
                let pair = point_triangle(&f.x[0], &x[0], &x[1], &x[2]);
                let w = [pair.weights[1], pair.weights[2], pair.weights[3]];
                let side = Side::triangle(tri, w, t / 2);
                self.static_pair(
                    acc,
                    ct,
                    &pair,
                    (f.offset, PairSource::Collider(f.collider)),
                    &side,
                    found,
                );
            }
        }
        for f in &obs.edges {
            for t in cells_near(geo, &(f.lo, f.hi), obs.axis, f.offset + ct.activation) {
                for e in cells.owned_edges(t) {
                    let (a, b) = (vertex_position(acc, e[0]), vertex_position(acc, e[1]));
                    if apart(&f.x, &[a, b], f.offset + ct.activation) {
                        continue;
                    }
                    let pair = edge_edge(&f.x[0], &f.x[1], &a, &b);
                    let eps = mollifier_threshold(&f.x[0], &f.x[1], &a, &b);
                    let (m, gm) = edge_mollifier(&f.x[0], &f.x[1], &a, &b, eps);
                    let mut side = Side::edge(*e, [pair.weights[2], pair.weights[3]], t / 2);
                    side.mollifier = (m, [gm[2], gm[3], Vector3::zeros()]);
                    self.static_pair(
                        acc,
                        ct,
                        &pair,
                        (f.offset, PairSource::Collider(f.collider)),
                        &side,
                        found,
                    );
                }
            }
        }
        for f in &obs.triangles {
            for t in cells_near(geo, &(f.lo, f.hi), obs.axis, f.offset + ct.activation) {
                for &v in cells.owned_vertices(t) {
                    let x = vertex_position(acc, v);
                    if apart(&[x], &f.x, f.offset + ct.activation) {
                        continue;
                    }
                    let pair = point_triangle(&x, &f.x[0], &f.x[1], &f.x[2]);
                    let side = Side::vertex(v, t / 2);
                    self.static_pair(
                        acc,
                        ct,
                        &pair,
                        (f.offset, PairSource::Collider(f.collider)),
                        &side,
                        found,
                    );
                }
            }
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
        let own = &ct.cells;
        for t in 0..own.len() {
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
            let (tri, e) = (own.triangles[t], t / 2);
            let x = tri.map(|v| vertex_position(acc, v));
            for &o in &body.order[range] {
                let o = o as usize;
                if !boxes_near(&bt, &body.boxes[o], margin) {
                    continue;
                }
                let other = |v: u32| body.vertices[v as usize];
                let ox = body.cells.triangles[o].map(other);
                for &v in own.owned_vertices(t) {
                    let p = vertex_position(acc, v);
                    if !boxes_near(&(p, p), &body.boxes[o], margin) {
                        continue;
                    }
                    let pair = point_triangle(&p, &ox[0], &ox[1], &ox[2]);
                    let side = Side::vertex(v, e);
                    self.static_pair(
                        acc,
                        ct,
                        &pair,
                        (ct.thickness, PairSource::Body(b)),
                        &side,
                        found,
                    );
                }
                for &ov in body.cells.owned_vertices(o) {
                    let p = other(ov);
                    if !boxes_near(&(p, p), &bt, margin) {
                        continue;
                    }
                    let pair = point_triangle(&p, &x[0], &x[1], &x[2]);
                    let w = [pair.weights[1], pair.weights[2], pair.weights[3]];
                    let side = Side::triangle(tri, w, e);
                    self.static_pair(
                        acc,
                        ct,
                        &pair,
                        (ct.thickness, PairSource::Body(b)),
                        &side,
                        found,
                    );
                }
                for edge in own.owned_edges(t) {
                    let (a, bb) = (vertex_position(acc, edge[0]), vertex_position(acc, edge[1]));
                    for oe in body.cells.owned_edges(o) {
                        let (oa, ob) = (other(oe[0]), other(oe[1]));
                        if apart(&[a, bb], &[oa, ob], margin) {
                            continue;
                        }
                        let pair = edge_edge(&a, &bb, &oa, &ob);
                        let eps = mollifier_threshold(&a, &bb, &oa, &ob);
                        let (m, gm) = edge_mollifier(&a, &bb, &oa, &ob, eps);
                        let mut side = Side::edge(*edge, [pair.weights[0], pair.weights[1]], e);
                        side.mollifier = (m, [gm[0], gm[1], Vector3::zeros()]);
                        self.static_pair(
                            acc,
                            ct,
                            &pair,
                            (ct.thickness, PairSource::Body(b)),
                            &side,
                            found,
                        );
                    }
                }
            }
        }
    }

    /// A pair with the ribbon's points in `side` against something static (`source`),
    /// at distance `pair.distance` keeping `offset` (m).
    fn static_pair(
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
    fn side_gradient(
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
    fn mollifier_gradient(
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
    fn rim_material(&self, acc: &Accumulator, j: usize, top: bool) -> Point3 {
        let c = acc.coords.crease_direction[j];
        if top {
            self.strip.material_top(j, c)
        } else {
            self.strip.material_bottom(j, c)
        }
    }

    /// The local column (6 or 7) and world direction ∂x/∂c_j of rim vertex (j, top)
    /// carried by element e, if it slides (not on the square end creases).
    fn sliding_column(
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
fn add_force(
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
fn element_of_vertex(ct: &ContactTerms, v: u32) -> usize {
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
fn jacobian_row(x: &Vector3, a: &Vector3, sigma: Option<(usize, Vector3)>) -> Vec8 {
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

impl Objective<'_> {
    /// Pairs between non-neighbouring cells of the ribbon itself: a sort-and-sweep over
    /// the cell boxes, then the vertex-triangle and edge-edge pairs the two cells own
    /// whose stations are more than the neighbour skip apart.
    fn self_pairs(
        &self,
        acc: &mut Accumulator,
        ct: &ContactTerms,
        geo: &CellGeometry,
        found: &mut Found,
    ) {
        let axis = ct.obstacles.axis;
        let margin = ct.thickness + ct.activation;
        let cells = &ct.cells;
        for i in 0..geo.order.len() {
            let t1 = geo.order[i] as usize;
            let top = geo.boxes[t1].1[axis] + margin;
            for &t2 in &geo.order[i + 1..] {
                let t2 = t2 as usize;
                if geo.boxes[t2].0[axis] > top {
                    break;
                }
                if t1 / 2 == t2 / 2 || !boxes_near(&geo.boxes[t1], &geo.boxes[t2], margin) {
                    continue;
                }
                let (u1, u2) = (geo.cell_u[t1], geo.cell_u[t2]);
                let span = (u1.1 - u1.0) + (u2.1 - u2.0);
                if station_gap(u1, u2, ct.period) + span <= ct.skip {
                    continue;
                }
                self.cell_pair(acc, ct, geo, (t1, t2), found);
                self.cell_pair(acc, ct, geo, (t2, t1), found);
                for e1 in cells.owned_edges(t1) {
                    for e2 in cells.owned_edges(t2) {
                        self.self_edge_pair(acc, ct, geo, (*e1, t1 / 2), (*e2, t2 / 2), found);
                    }
                }
            }
        }
    }

    /// The vertices cell `a` owns against cell `b`'s triangle.
    fn cell_pair(
        &self,
        acc: &mut Accumulator,
        ct: &ContactTerms,
        geo: &CellGeometry,
        (a, b): (usize, usize),
        found: &mut Found,
    ) {
        let tri = ct.cells.triangles[b];
        let tu = tri.map(|v| geo.vertex_u[v as usize]);
        let tri_u = (tu[0].min(tu[1]).min(tu[2]), tu[0].max(tu[1]).max(tu[2]));
        let x = tri.map(|v| vertex_position(acc, v));
        for &v in ct.cells.owned_vertices(a) {
            let vu = geo.vertex_u[v as usize];
            if station_gap((vu, vu), tri_u, ct.period) <= ct.skip {
                continue;
            }
            let p = vertex_position(acc, v);
            if !boxes_near(&(p, p), &geo.boxes[b], ct.thickness + ct.activation) {
                continue;
            }
            let pair = point_triangle(&p, &x[0], &x[1], &x[2]);
            let w = [pair.weights[1], pair.weights[2], pair.weights[3]];
            let (first, second) = (Side::vertex(v, a / 2), Side::triangle(tri, w, b / 2));
            self.self_pair(acc, ct, &pair, &first, &second, found);
        }
    }

    fn self_edge_pair(
        &self,
        acc: &mut Accumulator,
        ct: &ContactTerms,
        geo: &CellGeometry,
        (e1, el1): ([u32; 2], usize),
        (e2, el2): ([u32; 2], usize),
        found: &mut Found,
    ) {
        let u = |e: [u32; 2]| {
            let (a, b) = (geo.vertex_u[e[0] as usize], geo.vertex_u[e[1] as usize]);
            (a.min(b), a.max(b))
        };
        if station_gap(u(e1), u(e2), ct.period) <= ct.skip {
            return;
        }
        let p = |v: u32| vertex_position(acc, v);
        let x = [p(e1[0]), p(e1[1]), p(e2[0]), p(e2[1])];
        if apart(&x[..2], &x[2..], ct.thickness + ct.activation) {
            return;
        }
        let pair = edge_edge(&x[0], &x[1], &x[2], &x[3]);
        let eps = mollifier_threshold(&x[0], &x[1], &x[2], &x[3]);
        let (m, gm) = edge_mollifier(&x[0], &x[1], &x[2], &x[3], eps);
        let mut first = Side::edge(e1, [pair.weights[0], pair.weights[1]], el1);
        let mut second = Side::edge(e2, [pair.weights[2], pair.weights[3]], el2);
        first.mollifier = (m, [gm[0], gm[1], Vector3::zeros()]);
        second.mollifier = (m, [gm[2], gm[3], Vector3::zeros()]);
        self.self_pair(acc, ct, &pair, &first, &second, found);
    }

    /// A pair between two parts of the ribbon (sides on two elements): gradient through
    /// both elements, Hessian as a [`PairTerm`].
    fn self_pair(
        &self,
        acc: &mut Accumulator,
        ct: &ContactTerms,
        pair: &Closest,
        first: &Side,
        second: &Side,
        found: &mut Found,
    ) {
        let s = pair.distance - ct.thickness;
        if !found.enter(s, ct.activation, PairSource::Itself) {
            return;
        }
        let (b, db, ddb) = barrier(s, ct.activation);
        let m = first.mollifier.0;
        found.value += ct.weight * m * b;
        if !acc.forces {
            return;
        }
        let u1 = self.side_gradient(acc, found, first, &pair.normal, ct.weight * m * db);
        let u2 = self.side_gradient(acc, found, second, &pair.normal, ct.weight * m * db);
        self.mollifier_gradient(acc, found, first, ct.weight * b);
        self.mollifier_gradient(acc, found, second, ct.weight * b);
        if acc.ws_hessian.is_some() {
            found.pairs.push(PairTerm {
                e1: first.element as u32,
                e2: second.element as u32,
                u1,
                u2,
                weight: ct.weight * m * ddb,
            });
        }
    }

    /// IPC's lagged friction D = μλ f0(|T^T (x - x̂ - Δc)|) of every lagged contact;
    /// returns its value, J.
    fn friction_terms(&self, acc: &mut Accumulator, ct: &ContactTerms, wrench: &mut [Vec8]) -> f64 {
        let mut value = 0.0;
        let hist = self.history;
        for f in &ct.friction {
            let (j, top) = ((f.vertex / 2) as usize, f.vertex % 2 == 1);
            let x = vertex_position(acc, f.vertex);
            let material = self.rim_material(acc, j, top);
            // the same material point at the start of the step (the resampling R)
            let (us, xs) = if top {
                (&hist.u_top, &hist.x_top)
            } else {
                (&hist.u_bottom, &hist.x_bottom)
            };
            let (previous, slope) = interpolate(us, xs, material.x, j);
            let slip = x - previous - f.shift;
            let u = [f.tangent[0].dot(&slip), f.tangent[1].dot(&slip)];
            let y = (u[0] * u[0] + u[1] * u[1]).sqrt();
            let (f0, f1_over_y, df1) = friction_mollifier(y, ct.friction_slip);
            value += f.mu_lambda * f0;
            if !acc.forces {
                continue;
            }
            let e = element_of_vertex(ct, f.vertex);
            let gamma = (f.tangent[0] * u[0] + f.tangent[1] * u[1]) * (f.mu_lambda * f1_over_y);
            let du = sliding_rate(self.strip.width, top);
            add_force(acc, wrench, e, &material, &x, &gamma, (j, du));
            let column = self.sliding_column(acc, e, j, top);
            if let Some((col, _)) = column {
                // x̂ slides along the old rim with c_j too
                let local = -gamma.dot(&slope) * du;
                if col == 6 {
                    acc.add_local(e, local, 0.0);
                } else {
                    acc.add_local(e, 0.0, local);
                }
            }
            if let Some(hs) = acc.ws_hessian.as_deref_mut() {
                // the 2x2 Hessian of f0 has eigen-directions along the slip (f1') and
                // across it (f1/y), both >= 0
                let (along, across) = if y > 0.0 {
                    (
                        (f.tangent[0] * u[0] + f.tangent[1] * u[1]) / y,
                        (f.tangent[1] * u[0] - f.tangent[0] * u[1]) / y,
                    )
                } else {
                    (f.tangent[0], f.tangent[1])
                };
                let sigma = column.map(|(col, s)| (col, s - slope * du));
                for (dir, eig) in [(along, df1), (across, f1_over_y)] {
                    let a = jacobian_row(&x, &dir, sigma);
                    hs[e] += a * a.transpose() * (f.mu_lambda * eig);
                }
            }
        }
        value
    }
}
