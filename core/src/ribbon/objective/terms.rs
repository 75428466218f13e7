//! The step's data (terms, constraints, multipliers) and the terms other than the
//! kinetic one: gravity with the consistent mass, normal guiding, point forces, the
//! augmented-Lagrangian equalities (handles, loops: sec. 5.1), and the terms written
//! directly in (c, psi): bending, the crease regularizer, the end-crease bound.

use super::accumulate::{direction_jacobian, point_jacobian, sliding_rate, Accumulator};
use super::kinetic::add_mass_rate_coupling;
use super::{ClosureRows, CrossBlock, Mat8, Mat9x8, Objective, Workspace};
use crate::geometry::{Matrix3, Point2, Point3, Vector3};
use crate::ribbon::mass::element_mass;
use crate::ribbon::params::{KineticModel, LoopKind};
use crate::ribbon::reconstruct::Coordinates;

/// K/2 |n_e - n_target|^2 on element `element` (normal guiding, sec. 5.1).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NormalGuide {
    pub material_point: Point2,
    pub target: Vector3,
    /// K, J.
    pub stiffness: f64,
}

/// A constant force (N) at a material point: potential -F.x.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointForce {
    pub material_point: Point2,
    pub force: Vector3,
}

/// An equality constraint C(X) = 0 enforced by the augmented Lagrangian.
#[derive(Clone, Debug, PartialEq)]
pub enum Equality {
    /// The grasp point at `material_point` (m) is at `target` (m) along the held axes.
    Position {
        material_point: Point2,
        target: Point3,
        axes: [bool; 3],
    },
    /// The element frame under `material_point` has rotation `target`.
    Orientation {
        material_point: Point2,
        target: Matrix3,
    },
    /// The two ends are joined (sec. 5.1).
    Loop(LoopKind),
}

impl Equality {
    /// Number of scalar constraint rows.
    pub fn rows(&self) -> usize {
        match self {
            Equality::Position { .. } => 3,
            Equality::Orientation { .. } | Equality::Loop(_) => 9,
        }
    }
    /// Whether residual row `i` is a rotation row (dimensionless) rather than a
    /// position row (m): every row of an orientation, rows 6.. of a loop (3 + 3
    /// position rows for the two rim points, then the normals).
    pub fn is_rotation_row(&self, i: usize) -> bool {
        match self {
            Equality::Position { .. } => false,
            Equality::Orientation { .. } => true,
            Equality::Loop(_) => i >= 6,
        }
    }
}

/// Everything that defines one step's objective except q.
#[derive(Clone, Debug)]
pub struct StepTerms {
    /// Time step h, s.
    pub h: f64,
    pub kinetic: KineticModel,
    pub density: f64,
    /// Bending weight of crease k (k = 1..n-1; n + 1 entries), J: the crease's energy
    /// is `crease_bending[k] (1 + c_k^2) psi_k^2`, alpha w / d_k with d_k the length of
    /// centerline the crease stands for (see [`crate::ribbon::bending`]).
    pub crease_bending: Vec<f64>,
    pub crease_regularizer: f64,
    pub gravity: Vector3,
    pub normal_guides: Vec<NormalGuide>,
    pub forces: Vec<PointForce>,
    pub equalities: Vec<Equality>,
    /// Multipliers λ of each equality (rows() entries each), J/m for positions.
    pub multipliers: Vec<Vec<f64>>,
    /// Multipliers (<= 0) of the two end-crease inequalities Δc_max -+ c_{n-1} >= 0.
    pub end_crease_multipliers: [f64; 2],
    /// Whether the solver holds |c_{n-1}| <= Δc_max exactly (the trust-region solver's
    /// slab): then the end crease has no augmented-Lagrangian term.
    pub end_crease_exact: bool,
    /// Augmented-Lagrangian penalty μ.
    pub penalty: f64,
    /// Δc_max of eq. (1).
    pub crease_bound: f64,
}

/// Objective value split by kind, J.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ObjectiveParts {
    pub kinetic: f64,
    pub elastic: f64,
    pub gravity: f64,
    pub external: f64,
    pub constraint: f64,
    /// Contact barrier and friction (+∞ where a pair touches or has crossed).
    pub contact: f64,
}

impl ObjectiveParts {
    pub fn total(&self) -> f64 {
        self.kinetic + self.elastic + self.gravity + self.external + self.constraint + self.contact
    }
}

impl Objective<'_> {
    /// Gravity with the consistent mass: -sum_v m_v(c) g.x_v.
    pub(super) fn gravity(&self, acc: &mut Accumulator) -> f64 {
        let n = self.strip.segments;
        let t = self.terms;
        let w = self.strip.width;
        let c = &acc.coords.crease_direction;
        let mut value = 0.0;
        for e in 0..n {
            let mass = element_mass(self.strip.length, w, n, c[e + 1] - c[e]);
            let verts = [(e, false), (e, true), (e + 1, false), (e + 1, true)];
            let mut dvalue = 0.0;
            // for the Hessian: positions, the mass-rate force -m'_a g and the sliding
            // of each vertex on a free crease (see `add_mass_rate_coupling`)
            let mut xs = [Vector3::zeros(); 4];
            let mut rate = [Vector3::zeros(); 4];
            let mut sigma = [Vector3::zeros(); 4];
            let mut column = [None::<usize>; 4];
            for (a, &(j, top)) in verts.iter().enumerate() {
                let m_a: f64 = t.density * mass.k[a].iter().sum::<f64>();
                let dm_a: f64 = t.density * mass.dk_ddelta_c[a].iter().sum::<f64>();
                let x = if top {
                    acc.frames.rim_top[j]
                } else {
                    acc.frames.rim_bottom[j]
                };
                let mat = if top {
                    self.strip.material_top(j, c[j])
                } else {
                    self.strip.material_bottom(j, c[j])
                };
                xs[a] = x.coords;
                rate[a] = -t.gravity * dm_a;
                if j != 0 && j != n {
                    sigma[a] = acc.frames.rotation[e].column(0) * sliding_rate(w, top);
                    column[a] = Some(if j == e { 6 } else { 7 });
                }
                value -= m_a * t.gravity.dot(&x.coords);
                dvalue -= dm_a * t.gravity.dot(&x.coords);
                acc.add_point_gradient(
                    e,
                    &mat,
                    &x,
                    &(-t.gravity * m_a),
                    Some((j, sliding_rate(w, top))),
                );
            }
            acc.add_local(e, -dvalue, dvalue);
            if let Some(hs) = acc.ws_hessian.as_deref_mut() {
                add_mass_rate_coupling(&mut hs[e], &xs, &rate, &sigma, &column, 1.0);
            }
        }
        value
    }

    /// Normal guiding K/2 |n_e - n_target|^2 (sec. 5.1) and point forces (potential
    /// -F.x): their summed value, J.
    pub(super) fn normal_guides_and_forces(&self, acc: &mut Accumulator) -> f64 {
        let t = self.terms;
        let mut external = 0.0;
        for guide in &t.normal_guides {
            let e = self
                .strip
                .element_of(&acc.coords.crease_direction, &guide.material_point);
            let normal = acc.frames.normals[e];
            let diff = normal - guide.target;
            external += 0.5 * guide.stiffness * diff.norm_squared();
            acc.add_direction_gradient(e, &Vector3::z(), &normal, &(diff * guide.stiffness));
            if let Some(hs) = acc.ws_hessian.as_deref_mut() {
                let j = direction_jacobian(&normal);
                hs[e] += j.transpose() * j * guide.stiffness;
            }
        }
        for force in &t.forces {
            let e = self
                .strip
                .element_of(&acc.coords.crease_direction, &force.material_point);
            let m = Point3::new(force.material_point.x, force.material_point.y, 0.0);
            let p = acc.frames.to_world(e, &m);
            external -= force.force.dot(&p.coords);
            acc.add_point_gradient(e, &m, &p, &(-force.force), None);
        }
        external
    }

    /// One augmented-Lagrangian equality term -λ.C + μ/2 |C|^2; returns its value.
    pub(super) fn equality(
        &self,
        acc: &mut Accumulator,
        cross: &mut Vec<CrossBlock>,
        eq: &Equality,
        lambda: &[f64],
        mu: f64,
    ) -> f64 {
        match eq {
            Equality::Position {
                material_point,
                target,
                axes,
            } => self.position_equality(acc, material_point, target, axes, lambda, mu),
            Equality::Orientation {
                material_point,
                target,
            } => self.orientation_equality(acc, material_point, target, lambda, mu),
            Equality::Loop(kind) => self.loop_equality(acc, cross, *kind, lambda, mu),
        }
    }

    /// The grasp point at `material_point` held at `target` along `axes`.
    fn position_equality(
        &self,
        acc: &mut Accumulator,
        material_point: &Point2,
        target: &Point3,
        axes: &[bool; 3],
        lambda: &[f64],
        mu: f64,
    ) -> f64 {
        let mut value = 0.0;
        let e = self
            .strip
            .element_of(&acc.coords.crease_direction, material_point);
        let m = Point3::new(material_point.x, material_point.y, 0.0);
        let p = acc.frames.to_world(e, &m);
        let mut gamma = Vector3::zeros();
        let mut jac = point_jacobian(&p);
        for i in 0..3 {
            if axes[i] {
                let ci = p[i] - target[i];
                value += -lambda[i] * ci + 0.5 * mu * ci * ci;
                gamma[i] = mu * ci - lambda[i];
            } else {
                jac.row_mut(i).fill(0.0);
            }
        }
        acc.add_point_gradient(e, &m, &p, &gamma, None);
        if let Some(hs) = acc.ws_hessian.as_deref_mut() {
            hs[e] += jac.transpose() * jac * mu;
        }
        value
    }

    /// The frame of the element under `material_point` held at rotation `target`.
    fn orientation_equality(
        &self,
        acc: &mut Accumulator,
        material_point: &Point2,
        target: &Matrix3,
        lambda: &[f64],
        mu: f64,
    ) -> f64 {
        let mut value = 0.0;
        let e = self
            .strip
            .element_of(&acc.coords.crease_direction, material_point);
        let r = acc.frames.rotation[e];
        for i in 0..3 {
            let col = r.column(i).into_owned();
            let ci = col - target.column(i);
            let lam = Vector3::new(lambda[3 * i], lambda[3 * i + 1], lambda[3 * i + 2]);
            value += -lam.dot(&ci) + 0.5 * mu * ci.norm_squared();
            let mut unit = Vector3::zeros();
            unit[i] = 1.0;
            acc.add_direction_gradient(e, &unit, &col, &(ci * mu - lam));
            if let Some(hs) = acc.ws_hessian.as_deref_mut() {
                let j = direction_jacobian(&col);
                hs[e] += j.transpose() * j * mu;
            }
        }
        value
    }

    /// The loop closure (sec. 5.1): the end rims joined (swapped for a Moebius band)
    /// and the end normals equal (opposite); its Gauss-Newton part couples elements
    /// n-1 and 0 (a cross block).
    fn loop_equality(
        &self,
        acc: &mut Accumulator,
        cross: &mut Vec<CrossBlock>,
        kind: LoopKind,
        lambda: &[f64],
        mu: f64,
    ) -> f64 {
        let n = self.strip.segments;
        let mut value = 0.0;
        let f = acc.frames;
        let c = &acc.coords.crease_direction;
        let last = n - 1;
        // (point of element n-1, point of element 0, sign) triples: C = a - s b; a
        // Moebius band joins each end rim to the other rim and flips the normal
        let (swap, normal_sign) = match kind {
            LoopKind::Orientable => (false, 1.0),
            LoopKind::NonOrientable => (true, -1.0),
        };
        let start_rim = |top: bool| {
            if top {
                (f.rim_top[0], self.strip.material_top(0, c[0]))
            } else {
                (f.rim_bottom[0], self.strip.material_bottom(0, c[0]))
            }
        };
        let (bottom0, bottom0_material) = start_rim(swap);
        let (top0, top0_material) = start_rim(!swap);
        let unit_z = Point3::new(0.0, 0.0, 1.0);
        let pairs: [(Point3, Point3, Point3, Point3, f64, bool); 3] = [
            (
                f.rim_bottom[n],
                self.strip.material_bottom(n, 0.0),
                bottom0,
                bottom0_material,
                1.0,
                false,
            ),
            (
                f.rim_top[n],
                self.strip.material_top(n, 0.0),
                top0,
                top0_material,
                1.0,
                false,
            ),
            (
                Point3::from(f.normals[last]),
                unit_z,
                Point3::from(f.normals[0]),
                unit_z,
                normal_sign,
                true,
            ),
        ];
        let mut block_a = Mat8::zeros();
        let mut block_b = Mat8::zeros();
        let mut block_ab = Mat8::zeros();
        let mut rows = ClosureRows {
            last: Mat9x8::zeros(),
            first: Mat9x8::zeros(),
            penalty: mu,
        };
        for (row, (pa, ma, pb, mb, sign, is_dir)) in pairs.iter().enumerate() {
            let ci = pa.coords - pb.coords * *sign;
            let lam = Vector3::new(lambda[3 * row], lambda[3 * row + 1], lambda[3 * row + 2]);
            value += -lam.dot(&ci) + 0.5 * mu * ci.norm_squared();
            let gamma = ci * mu - lam;
            let (ja, jb) = if *is_dir {
                acc.add_direction_gradient(last, &ma.coords, &pa.coords, &gamma);
                acc.add_direction_gradient(0, &mb.coords, &pb.coords, &(-gamma * *sign));
                (
                    direction_jacobian(&pa.coords),
                    direction_jacobian(&pb.coords) * *sign,
                )
            } else {
                acc.add_point_gradient(last, ma, pa, &gamma, None);
                acc.add_point_gradient(0, mb, pb, &(-gamma * *sign), None);
                (point_jacobian(pa), point_jacobian(pb) * *sign)
            };
            if acc.ws_hessian.is_some() {
                block_a += ja.transpose() * ja * mu;
                block_b += jb.transpose() * jb * mu;
                block_ab -= ja.transpose() * jb * mu;
                rows.last.fixed_rows_mut::<3>(3 * row).copy_from(&ja);
                rows.first.fixed_rows_mut::<3>(3 * row).copy_from(&jb);
            }
        }
        if let Some(hs) = acc.ws_hessian.as_deref_mut() {
            hs[last] += block_a;
            hs[0] += block_b;
            cross.push((last, 0, block_ab, Some(rows)));
        }
        value
    }

    /// Bending stiffness of crease k (1 <= k <= n-1) in the energy
    /// k_k (1 + c_k^2) psi_k^2, J: alpha n w / l (Pan et al. sec. 3) away from clamps,
    /// alpha w / d_k beside one ([`crate::ribbon::bending`] sets them). The one place
    /// the weight of a crease is read: the gradient, both Hessians and the chain
    /// solver read it here.
    #[inline]
    pub fn bending_weight(&self, k: usize) -> f64 {
        self.terms.crease_bending[k]
    }

    /// The terms written directly in (c, psi): bending k_k (1+c_k^2) psi_k^2 and the
    /// regularizer beta c_k^2 per crease (into `parts.elastic`), and the end-crease
    /// inequality (into `parts.constraint`); their gradient added to `g` if given.
    pub(super) fn crease_terms(
        &self,
        coords: &Coordinates,
        parts: &mut ObjectiveParts,
        mut g: Option<&mut [f64]>,
    ) {
        let n = self.strip.segments;
        let t = self.terms;
        let mut direct = |idx: usize, value: f64| {
            if let Some(gg) = g.as_deref_mut() {
                gg[idx] += value;
            }
        };
        for k in 1..n {
            let bend_k = self.bending_weight(k);
            let c = coords.crease_direction[k];
            let psi = coords.bending_angle[k];
            let s = 1.0 + c * c;
            parts.elastic += bend_k * s * psi * psi + t.crease_regularizer * c * c;
            let (ic, ip) = (self.layout.c(k), self.layout.psi(k));
            direct(
                ic,
                2.0 * bend_k * c * psi * psi + 2.0 * t.crease_regularizer * c,
            );
            direct(ip, 2.0 * bend_k * s * psi);
        }
        // |c_{n-1}| <= Δc_max, the inequality left after the substitution (sec. 5.1),
        // in the paper's form mu/2 min(C + λ/μ, 0)^2 (constant terms dropped).
        let c_last = coords.crease_direction[n - 1];
        if n >= 2 {
            for (sign, shifted) in self.end_crease_shifts(c_last) {
                if shifted < 0.0 {
                    parts.constraint += 0.5 * t.penalty * shifted * shifted;
                    let ic = self.layout.c(n - 1);
                    direct(ic, t.penalty * shifted * sign);
                }
            }
        }
    }

    /// The end-crease inequalities |c_{n-1}| <= Δc_max as C = Δc_max ∓ c_{n-1} >= 0: per
    /// side, the sign of c_{n-1} in C and min(C + λ/μ, 0), negative where the augmented-
    /// Lagrangian term mu/2 min(C + λ/μ, 0)^2 is active.
    pub(super) fn end_crease_shifts(&self, c_last: f64) -> [(f64, f64); 2] {
        let t = self.terms;
        if t.end_crease_exact {
            return [(-1.0, 0.0), (1.0, 0.0)];
        }
        [
            (-1.0, t.end_crease_multipliers[0]),
            (1.0, t.end_crease_multipliers[1]),
        ]
        .map(|(sign, lambda)| {
            let cval = t.crease_bound + sign * c_last;
            (sign, (cval + lambda / t.penalty).min(0.0))
        })
    }

    /// Residual C of an equality at the state in `ws` (after `prepare`/`evaluate`),
    /// written to `out[..eq.rows()]`. Position rows in m, rotation rows dimensionless.
    pub fn equality_residual(&self, ws: &Workspace, eq: &Equality, out: &mut [f64]) {
        let n = self.strip.segments;
        let f = &ws.frames;
        let c = &ws.coords.crease_direction;
        match eq {
            Equality::Position {
                material_point,
                target,
                axes,
            } => {
                let e = self.strip.element_of(c, material_point);
                let p = f.to_world(e, &Point3::new(material_point.x, material_point.y, 0.0));
                for i in 0..3 {
                    out[i] = if axes[i] { p[i] - target[i] } else { 0.0 };
                }
            }
            Equality::Orientation {
                material_point,
                target,
            } => {
                let e = self.strip.element_of(c, material_point);
                for i in 0..3 {
                    for r in 0..3 {
                        out[3 * i + r] = f.rotation[e][(r, i)] - target[(r, i)];
                    }
                }
            }
            Equality::Loop(kind) => {
                let (a, b, sign) = match kind {
                    LoopKind::Orientable => (
                        (f.rim_bottom[n], f.rim_top[n]),
                        (f.rim_bottom[0], f.rim_top[0]),
                        1.0,
                    ),
                    LoopKind::NonOrientable => (
                        (f.rim_bottom[n], f.rim_top[n]),
                        (f.rim_top[0], f.rim_bottom[0]),
                        -1.0,
                    ),
                };
                let rows = [a.0 - b.0, a.1 - b.1, f.normals[n - 1] - f.normals[0] * sign];
                for (i, r) in rows.iter().enumerate() {
                    out[3 * i..3 * i + 3].copy_from_slice(r.as_slice());
                }
            }
        }
    }
}
