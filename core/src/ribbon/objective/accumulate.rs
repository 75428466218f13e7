//! Per-element generalized forces: every term reports dF/dp at a world point or
//! direction of the element carrying it, and the accumulator turns that into the
//! element's wrench (moment, force) and local sliding derivatives (d/dc_e, d/dc_{e+1}),
//! plus, for the Hessian, the second-order sums of the geometric stiffness.

use super::{Mat3x8, Mat8, Vec8};
use crate::geometry::{skew, Matrix3, Point3, Vector3};
use crate::ribbon::reconstruct::{Coordinates, Frames, Strip};

/// A point gradient recorded for the chain-rule baseline: dF/dp = gamma for the point
/// with material coordinates `material` carried by element `element`; `direction` marks
/// a direction (normal, frame column) instead of a point (no translation part).
#[derive(Clone, Copy, Debug)]
pub(super) struct PointGradient {
    pub(super) element: usize,
    pub(super) material: Vector3,
    pub(super) gamma: Vector3,
    pub(super) direction: bool,
}

/// Second-order accumulators of one element.
#[derive(Clone, Copy, Debug)]
pub(super) struct SecondOrder {
    pub(super) p_gamma: Matrix3,
    pub(super) slide: [Vector3; 2],
}

impl Default for SecondOrder {
    fn default() -> Self {
        SecondOrder {
            p_gamma: Matrix3::zeros(),
            slide: [Vector3::zeros(); 2],
        }
    }
}

/// ∂u/∂c of a rim vertex: -w/2 on the bottom rim, +w/2 on the top rim (eq. 2).
#[inline]
pub(super) fn sliding_rate(width: f64, top: bool) -> f64 {
    if top {
        0.5 * width
    } else {
        -0.5 * width
    }
}

/// 3x8 Jacobian of a world point of element e w.r.t. [twist; c_e; c_{e+1}].
#[inline]
pub(super) fn point_jacobian(p: &Point3) -> Mat3x8 {
    let mut j = Mat3x8::zeros();
    j.fixed_view_mut::<3, 3>(0, 0)
        .copy_from(&(-skew(&p.coords)));
    j.fixed_view_mut::<3, 3>(0, 3)
        .copy_from(&Matrix3::identity());
    j
}

/// 3x8 Jacobian of a world direction of element e (rotates only).
#[inline]
pub(super) fn direction_jacobian(d: &Vector3) -> Mat3x8 {
    let mut j = Mat3x8::zeros();
    j.fixed_view_mut::<3, 3>(0, 0).copy_from(&(-skew(d)));
    j
}

/// Collects per-element generalized forces (and GN blocks, and recorded points).
pub(super) struct Accumulator<'b> {
    pub(super) strip: &'b Strip,
    pub(super) ws_gradient: &'b mut Vec<Vec8>,
    pub(super) ws_hessian: Option<&'b mut Vec<Mat8>>,
    pub(super) points: Option<&'b mut Vec<PointGradient>>,
    pub(super) second: Option<&'b mut Vec<SecondOrder>>,
    pub(super) frames: &'b Frames,
    pub(super) coords: &'b Coordinates,
    /// Whether generalized forces are collected at all: not for the value-only
    /// evaluations of a line search's backtracking (a third of all evaluations at
    /// n = 800 on the torsion), which need f alone.
    pub(super) forces: bool,
}

impl Accumulator<'_> {
    /// dF/dp = gamma at world point p of element e (material point `material`); when
    /// `vertex` = Some((j, du/dc)) the point is the rim vertex on crease j and slides
    /// along the rim with c_j. (Inlined: the kinetic term calls it four times per
    /// element per evaluation, and the call with its `Option` tests cost ~8 % of a step.)
    #[inline(always)]
    pub(super) fn add_point_gradient(
        &mut self,
        e: usize,
        material: &Point3,
        p: &Point3,
        gamma: &Vector3,
        vertex: Option<(usize, f64)>,
    ) {
        if !self.forces {
            return;
        }
        let g = &mut self.ws_gradient[e];
        let moment = p.coords.cross(gamma);
        g[0] += moment.x;
        g[1] += moment.y;
        g[2] += moment.z;
        g[3] += gamma.x;
        g[4] += gamma.y;
        g[5] += gamma.z;
        if let Some(second) = self.second.as_deref_mut() {
            second[e].p_gamma += p.coords * gamma.transpose();
        }
        if let Some((j, du)) = vertex {
            let n = self.strip.segments;
            if j != 0 && j != n {
                let s = self.frames.rotation[e].column(0) * du;
                let col = if j == e { 0 } else { 1 };
                g[6 + col] += s.dot(gamma);
                if let Some(second) = self.second.as_deref_mut() {
                    second[e].slide[col] += s.cross(gamma);
                }
            }
        }
        if let Some(points) = self.points.as_deref_mut() {
            points.push(PointGradient {
                element: e,
                material: material.coords,
                gamma: *gamma,
                direction: false,
            });
        }
        let _ = self.coords;
    }

    /// dF/dd = gamma for the world direction d = R_e * `material_dir` of element e.
    pub(super) fn add_direction_gradient(
        &mut self,
        e: usize,
        material_dir: &Vector3,
        d: &Vector3,
        gamma: &Vector3,
    ) {
        if !self.forces {
            return;
        }
        let g = &mut self.ws_gradient[e];
        let moment = d.cross(gamma);
        g[0] += moment.x;
        g[1] += moment.y;
        g[2] += moment.z;
        if let Some(second) = self.second.as_deref_mut() {
            second[e].p_gamma += d * gamma.transpose();
        }
        if let Some(points) = self.points.as_deref_mut() {
            points.push(PointGradient {
                element: e,
                material: *material_dir,
                gamma: *gamma,
                direction: true,
            });
        }
    }

    /// Explicit derivative w.r.t. c_e (col 6) and c_{e+1} (col 7) of element e.
    pub(super) fn add_local(&mut self, e: usize, d_ce: f64, d_ce1: f64) {
        if !self.forces {
            return;
        }
        let n = self.strip.segments;
        if e != 0 {
            self.ws_gradient[e][6] += d_ce;
        }
        if e + 1 != n {
            self.ws_gradient[e][7] += d_ce1;
        }
    }
}
