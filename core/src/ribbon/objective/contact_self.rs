//! The ribbon against itself and the lagged friction, terms of the step objective
//! (docs/contact_barrier.md): pairs between non-neighbouring cells of one ribbon (their
//! Hessian couples two elements: a [`PairTerm`]) and IPC's lagged dissipative potential
//! against colliders.

use super::accumulate::{sliding_rate, Accumulator};
use super::contact_terms::{
    add_force, element_of_vertex, jacobian_row, station_gap, vertex_position, CellGeometry,
    ContactTerms, Found, PairTerm, Side,
};
use super::kinetic::interpolate;
use super::{Objective, Vec8};
use crate::contact::barrier::{
    barrier, friction_mollifier, mollified_edge_edge, point_triangle, Closest, PairSource,
};
use crate::contact::obstacles::{apart, boxes_near};
use crate::geometry::Vector3;

impl Objective<'_> {
    /// Pairs between non-neighbouring cells of the ribbon itself: a sort-and-sweep over
    /// the cell boxes, then the vertex-triangle and edge-edge pairs the two cells own
    /// whose stations are more than the neighbour skip apart.
    pub(super) fn self_pairs(
        &self,
        acc: &mut Accumulator,
        ct: &ContactTerms,
        geo: &CellGeometry,
        found: &mut Found,
    ) {
        let axis = ct.obstacles.axis;
        let margin = ct.thickness + ct.activation;
        for i in 0..geo.order.len() {
            let t1 = geo.order[i] as usize;
            let top = geo.boxes[t1].1[axis] + margin;
            for &t2 in &geo.order[i + 1..] {
                let t2 = t2 as usize;
                if geo.boxes[t2].0[axis] > top {
                    break;
                }
                self.own_cells(acc, ct, geo, (t1, t2), found);
            }
        }
    }

    /// Cells `t1` and `t2` of the ribbon, unless they share an element, their boxes are
    /// beyond reach or their stations are within the neighbour skip.
    pub(super) fn own_cells(
        &self,
        acc: &mut Accumulator,
        ct: &ContactTerms,
        geo: &CellGeometry,
        (t1, t2): (usize, usize),
        found: &mut Found,
    ) {
        let margin = ct.thickness + ct.activation;
        if t1 / 2 == t2 / 2 || !boxes_near(&geo.boxes[t1], &geo.boxes[t2], margin) {
            return;
        }
        let (u1, u2) = (geo.cell_u[t1], geo.cell_u[t2]);
        let span = (u1.1 - u1.0) + (u2.1 - u2.0);
        if station_gap(u1, u2, ct.period) + span <= ct.skip {
            return;
        }
        self.cell_pair(acc, ct, geo, (t1, t2), found);
        self.cell_pair(acc, ct, geo, (t2, t1), found);
        let cells = &ct.cells;
        for e1 in cells.owned_edges(t1) {
            for e2 in cells.owned_edges(t2) {
                self.self_edge_pair(acc, ct, geo, (*e1, t1 / 2), (*e2, t2 / 2), found);
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
        for &v in ct.cells.owned_vertices(a) {
            self.own_vertex_triangle(acc, ct, geo, (v, a / 2, b), found);
        }
    }

    /// Vertex `v` (carried by element `e`) against cell `b`'s triangle, beyond the
    /// neighbour skip.
    pub(super) fn own_vertex_triangle(
        &self,
        acc: &mut Accumulator,
        ct: &ContactTerms,
        geo: &CellGeometry,
        (v, e, b): (u32, usize, usize),
        found: &mut Found,
    ) {
        let tri = ct.cells.triangles[b];
        let tu = tri.map(|v| geo.vertex_u[v as usize]);
        let tri_u = (tu[0].min(tu[1]).min(tu[2]), tu[0].max(tu[1]).max(tu[2]));
        let vu = geo.vertex_u[v as usize];
        if station_gap((vu, vu), tri_u, ct.period) <= ct.skip {
            return;
        }
        let p = vertex_position(acc, v);
        if !boxes_near(&(p, p), &geo.boxes[b], ct.thickness + ct.activation) {
            return;
        }
        let x = tri.map(|v| vertex_position(acc, v));
        let pair = point_triangle(&p, &x[0], &x[1], &x[2]);
        let w = [pair.weights[1], pair.weights[2], pair.weights[3]];
        let (first, second) = (Side::vertex(v, e), Side::triangle(tri, w, b / 2));
        self.self_pair(acc, ct, &pair, &first, &second, found);
    }

    pub(super) fn self_edge_pair(
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
        let (pair, m, gm) = mollified_edge_edge(&x[0], &x[1], &x[2], &x[3]);
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
    pub(super) fn friction_terms(
        &self,
        acc: &mut Accumulator,
        ct: &ContactTerms,
        wrench: &mut [Vec8],
    ) -> f64 {
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
