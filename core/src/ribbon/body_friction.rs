//! IPC's lagged friction between two ribbons (`contact.ribbon_friction`,
//! docs/contact_barrier.md "Friction between ribbons"), lumped on this ribbon's rim
//! vertices.
//!
//! At the start of the ribbon's step, every pair with another body inside the barrier
//! (this ribbon's vertex against that body's cell, that body's vertex against this
//! ribbon's cell, edge against edge) carries the normal force λ = -κ A b'(s) (times the
//! edge pair's mollifier). Each pair's force is shared among this ribbon's points of
//! the pair by their weights, so the vertices' forces sum to the whole normal force
//! between the two bodies, and each vertex with a share slides against that body with
//! μ times it: Coulomb's law on the total, whatever kind of pair carries the load (two
//! ribbons lying flat carry much of it on edge pairs). The tangent plane is the pairs'
//! force-weighted normal, the other body's slip the force-weighted displacement of its
//! points of the pairs since the start of the world's step.

use super::objective::{ContactTerms, FrictionLag};
use crate::contact::barrier::{
    barrier, mollified_edge_edge, point_triangle, tangent_basis, PairSource,
};
use crate::contact::obstacles::{bounds, boxes_near, ObstacleBody};
use crate::geometry::Vector3;

type Aabb = (Vector3, Vector3);

/// Per own vertex: the normal force on it, N; the force-weighted normal; the
/// force-weighted displacement of the other body's points, N m.
#[derive(Clone, Default)]
struct Share {
    force: f64,
    normal: Vector3,
    shift: Vector3,
}

/// Append to `friction` the lagged friction of the vertices of `mesh` (this ribbon's
/// rim vertices at the start of its step, mesh order) against every other body of
/// `terms.obstacles`.
pub(super) fn lag(terms: &ContactTerms, mesh: &[Vector3], friction: &mut Vec<FrictionLag>) {
    let obs = &terms.obstacles;
    let mu = obs.settings.body_friction;
    if mu == 0.0 || obs.bodies.is_empty() {
        return;
    }
    let reach = terms.thickness + terms.activation;
    let own = bounds(mesh);
    let cells = &terms.cells;
    let cell_boxes: Vec<Aabb> = cells
        .triangles
        .iter()
        .map(|t| bounds(&t.map(|v| mesh[v as usize])))
        .collect();
    let mut shares = vec![Share::default(); mesh.len()];
    for (b, body) in obs.bodies.iter().enumerate() {
        if !boxes_near(&own, &(body.lo, body.hi), reach) {
            continue;
        }
        shares.iter_mut().for_each(|s| *s = Share::default());
        let mut add = |s: f64, v: u32, weight: f64, normal: &Vector3, shift: Vector3| {
            if !(s > 0.0 && s < terms.activation) || weight == 0.0 {
                return;
            }
            let (_, db, _) = barrier(s, terms.activation);
            let f = terms.weight * (-db) * weight.abs();
            let share = &mut shares[v as usize];
            share.force += f;
            // (the normal's sign does not matter for a tangent plane: align it)
            let n = if share.normal.dot(normal) < 0.0 {
                -normal
            } else {
                *normal
            };
            share.normal += n * f;
            share.shift += shift * f;
        };
        let shift_at = |vs: &[u32], w: &[f64]| {
            vs.iter().zip(w).fold(Vector3::zeros(), |m, (&i, &wi)| {
                m + body.shift[i as usize] * wi.abs()
            })
        };
        // this ribbon's vertices against the body's cells, and the body's vertices
        // against this ribbon's cells
        for (t, tri) in body.cells.triangles.iter().enumerate() {
            let corners = tri.map(|i| body.vertices[i as usize]);
            if !boxes_near(&own, &body.boxes[t], reach) {
                continue;
            }
            for (v, x) in mesh.iter().enumerate() {
                if !boxes_near(&(*x, *x), &body.boxes[t], reach) {
                    continue;
                }
                let c = point_triangle(x, &corners[0], &corners[1], &corners[2]);
                let shift = shift_at(tri, &c.weights[1..]);
                add(
                    c.distance - terms.thickness,
                    v as u32,
                    1.0,
                    &c.normal,
                    shift,
                );
            }
        }
        for &u in body_vertices_near(body, &own, reach).iter() {
            let p = body.vertices[u as usize];
            for (t, tri) in cells.triangles.iter().enumerate() {
                if !boxes_near(&(p, p), &cell_boxes[t], reach) {
                    continue;
                }
                let [a, bb, c] = tri.map(|v| mesh[v as usize]);
                let pair = point_triangle(&p, &a, &bb, &c);
                let s = pair.distance - terms.thickness;
                for (k, &v) in tri.iter().enumerate() {
                    add(
                        s,
                        v,
                        pair.weights[1 + k],
                        &pair.normal,
                        body.shift[u as usize],
                    );
                }
            }
        }
        edge_pairs(terms, mesh, body, &mut |s, v, w, n, shift| {
            add(s, v, w, n, shift)
        });
        for (v, share) in shares.iter().enumerate() {
            if share.force > 0.0 {
                friction.push(FrictionLag {
                    vertex: v as u32,
                    mu_lambda: mu * share.force,
                    tangent: tangent_basis(&share.normal.normalize()),
                    shift: share.shift / share.force,
                    source: PairSource::Body(b),
                });
            }
        }
    }
}

/// The body's vertices within `reach` of the box `own`.
fn body_vertices_near(body: &ObstacleBody, own: &Aabb, reach: f64) -> Vec<u32> {
    (0..body.vertices.len() as u32)
        .filter(|&u| {
            let p = body.vertices[u as usize];
            boxes_near(&(p, p), own, reach)
        })
        .collect()
}

/// Every edge pair of this ribbon's edges against the body's: `add(gap, own vertex,
/// its weight, normal, the body's displacement at its point)` for both own ends, the
/// gap's force scaled by the pair's mollifier.
fn edge_pairs(
    terms: &ContactTerms,
    mesh: &[Vector3],
    body: &ObstacleBody,
    add: &mut dyn FnMut(f64, u32, f64, &Vector3, Vector3),
) {
    let reach = terms.thickness + terms.activation;
    for e in &terms.cells.edges {
        let (a, b) = (mesh[e[0] as usize], mesh[e[1] as usize]);
        let eb = bounds(&[a, b]);
        if !boxes_near(&eb, &(body.lo, body.hi), reach) {
            continue;
        }
        for (t, other) in body.boxes.iter().enumerate() {
            if !boxes_near(&eb, other, reach) {
                continue;
            }
            for oe in body.cells.owned_edges(t) {
                let (p, q) = (body.vertices[oe[0] as usize], body.vertices[oe[1] as usize]);
                let (pair, m, _) = mollified_edge_edge(&a, &b, &p, &q);
                let s = pair.distance - terms.thickness;
                let w = &pair.weights;
                let shift = body.shift[oe[0] as usize] * w[2].abs()
                    + body.shift[oe[1] as usize] * w[3].abs();
                add(s, e[0], w[0] * m, &pair.normal, shift);
                add(s, e[1], w[1] * m, &pair.normal, shift);
            }
        }
    }
}
