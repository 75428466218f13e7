//! Positions and velocities of an S_P at any pattern point (S_P is rebuilt every
//! frame: the new vertices take their state from the old mesh).

use std::collections::BTreeMap;

use super::PhysicalMesh;
use crate::geometry::{Point2, Point3, Vector3};
use crate::paper::geometric::GVertexKind;
use crate::paper::pattern::{orient, Pattern};

fn quantize(p: &Point2) -> (i64, i64) {
    ((p.x * 1e9).round() as i64, (p.y * 1e9).round() as i64)
}

/// Interpolates positions and velocities of an S_P at pattern points: exact at its
/// vertices, barycentric inside its triangles, cubic (Catmull-Rom) along its boundary
/// curve (sec. 5, appendix B: "cubic interpolation along the boundary curve given by
/// the mesh S_P").
pub struct Interpolator<'a> {
    mesh: &'a PhysicalMesh,
    exact: BTreeMap<(i64, i64), u32>,
    pattern: &'a Pattern,
}

impl<'a> Interpolator<'a> {
    pub fn new(mesh: &'a PhysicalMesh, pattern: &'a Pattern) -> Self {
        let exact = mesh
            .material
            .iter()
            .enumerate()
            .map(|(i, m)| (quantize(m), i as u32))
            .collect();
        Interpolator {
            mesh,
            exact,
            pattern,
        }
    }

    /// The vertex at `m`, if any.
    pub fn vertex_at(&self, m: &Point2) -> Option<u32> {
        self.exact.get(&quantize(m)).copied()
    }

    /// Barycentric coordinates of `m` in the best triangle (smallest violation).
    fn locate(&self, m: &Point2) -> Option<([u32; 3], [f64; 3])> {
        let mut best: Option<(f64, [u32; 3], [f64; 3])> = None;
        for t in &self.mesh.triangles {
            let [a, b, c] = t.map(|i| self.mesh.material[i as usize]);
            let det = orient(&a, &b, &c);
            if det.abs() < 1e-18 {
                continue;
            }
            let l1 = orient(&a, m, &c) / det;
            let l2 = orient(&a, &b, m) / det;
            let l0 = 1.0 - l1 - l2;
            let out = (-l0).max(-l1).max(-l2).max(0.0);
            if best.as_ref().is_none_or(|(o, _, _)| out < *o) {
                best = Some((out, *t, [l0, l1, l2]));
                if out == 0.0 {
                    break;
                }
            }
        }
        best.map(|(_, t, l)| (t, l))
    }

    /// World position at pattern point `m`, m.
    pub fn position(&self, m: &Point2) -> Point3 {
        if let Some(v) = self.vertex_at(m) {
            return self.mesh.position[v as usize];
        }
        if self.pattern.signed_inside_distance(m) < 1e-9 {
            if let Some(s) = self.pattern.arc_of(m, 1e-7) {
                return self.boundary_position(s);
            }
        }
        match self.locate(m) {
            Some((t, l)) => Point3::from(
                self.mesh.position[t[0] as usize].coords * l[0]
                    + self.mesh.position[t[1] as usize].coords * l[1]
                    + self.mesh.position[t[2] as usize].coords * l[2],
            ),
            None => Point3::new(m.x, m.y, 0.0),
        }
    }

    /// World position of the S_G vertex of kind `k` at pattern point `m`, m: the S_P
    /// vertex there if any, else on the boundary curve (boundary vertices) or inside
    /// S_P (singular vertices).
    pub fn geometric_vertex(&self, k: &GVertexKind, m: &Point2) -> Point3 {
        match k {
            GVertexKind::Boundary { s } => match self.vertex_at(m) {
                Some(v) => self.mesh.position[v as usize],
                None => self.boundary_position(*s),
            },
            GVertexKind::Singular { .. } => self.position(m),
        }
    }

    /// Velocity at pattern point `m`, m/s.
    pub fn velocity(&self, m: &Point2) -> Vector3 {
        if let Some(v) = self.vertex_at(m) {
            return self.mesh.velocity[v as usize];
        }
        match self.locate(m) {
            Some((t, l)) => {
                self.mesh.velocity[t[0] as usize] * l[0]
                    + self.mesh.velocity[t[1] as usize] * l[1]
                    + self.mesh.velocity[t[2] as usize] * l[2]
            }
            None => Vector3::zeros(),
        }
    }

    /// World position of the boundary point at arc length `s` by Catmull-Rom
    /// interpolation of the S_P boundary vertices of the same side (corners are kept
    /// sharp: the tangent at a side's end is the one-sided difference).
    pub fn boundary_position(&self, s: f64) -> Point3 {
        let b = &self.mesh.boundary;
        let arc = &self.mesh.boundary_arc;
        let n = b.len();
        if n < 2 {
            let m = self.pattern.point_at(s);
            return Point3::new(m.x, m.y, 0.0);
        }
        let s = self.pattern.wrap(s);
        // segment k: arc[k] <= s < arc[k+1] (cyclic)
        let k = match arc.partition_point(|&x| x <= s) {
            0 => n - 1,
            i => i - 1,
        };
        let k1 = (k + 1) % n;
        let per = self.pattern.perimeter();
        let len = self.pattern.arc_ccw(arc[k], arc[k1]).max(1e-15);
        let t = (self.pattern.arc_ccw(arc[k], s) / len).clamp(0.0, 1.0);
        let p1 = self.mesh.position[b[k] as usize].coords;
        let p2 = self.mesh.position[b[k1] as usize].coords;
        if t == 0.0 {
            return Point3::from(p1);
        }
        let side = self.pattern.side_of(arc[k] + 0.5 * len);
        let same_side = |i: usize| {
            let a = arc[i];
            // a corner belongs to both sides
            let is_corner = (0..self.pattern.corners().len())
                .any(|c| (self.pattern.corner_arc(c) - a).abs() < 1e-9 || (per - a).abs() < 1e-9);
            is_corner || self.pattern.side_of(a) == side
        };
        let (k0, k2) = ((k + n - 1) % n, (k1 + 1) % n);
        let corner_k = !same_side(k0) || self.is_corner(arc[k]);
        let corner_k1 = !same_side(k2) || self.is_corner(arc[k1]);
        let p0 = if corner_k {
            2.0 * p1 - p2
        } else {
            self.mesh.position[b[k0] as usize].coords
        };
        let p3 = if corner_k1 {
            2.0 * p2 - p1
        } else {
            self.mesh.position[b[k2] as usize].coords
        };
        // uniform Catmull-Rom
        let t2 = t * t;
        let t3 = t2 * t;
        let v = 0.5
            * ((2.0 * p1)
                + (-p0 + p2) * t
                + (2.0 * p0 - 5.0 * p1 + 4.0 * p2 - p3) * t2
                + (-p0 + 3.0 * p1 - 3.0 * p2 + p3) * t3);
        Point3::from(v)
    }

    fn is_corner(&self, s: f64) -> bool {
        let per = self.pattern.perimeter();
        (0..self.pattern.corners().len()).any(|c| {
            let d = (self.pattern.corner_arc(c) - s).abs();
            d < 1e-9 || (per - d).abs() < 1e-9
        })
    }
}
