//! A ribbon as a simulated object: state, handles, one step, mesh and singular points.

use super::bending::{clamp_stations, crease_bending_weights};
use super::contact::{ContactStep, RibbonContact};
use super::handle_terms::{HandleConstraints, HandleRef};
use super::mass::element_mass;
use super::objective::{Equality, Layout, NormalGuide, PointForce, RimHistory, StepTerms};
use super::params::{BaseMode, KineticModel, RibbonParams};
use super::reconstruct::{reconstruct, Coordinates, Frames, Strip};
use super::step::StepSolver;
use crate::contact::barrier::PairSource;
use crate::contact::{BodyTopology, ContactEnv};
use crate::geometry::{Point2, Point3, Pose, SurfaceMesh, Vector3, VertexRegion};
use crate::sim::handle::HandleSpec;
use crate::sim::object::{
    ContactBody, Energies, ObjectSim, ObjectStepReport, Phase, SingularPoint, StepContext, Wrench,
};

/// A seeded random perturbation of every crease: c_k and psi_k (rad) each get a
/// uniform offset in [-amplitude, amplitude]. A perfectly flat strip twisted or spun
/// about its own axis sits on a bifurcation (the first-order response of every
/// coordinate is zero by symmetry); a real ribbon is never perfectly flat.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Imperfection {
    pub amplitude: f64,
    pub seed: u64,
}

/// The initial shape of a ribbon (in the base frame).
#[derive(Clone, Debug, PartialEq)]
pub enum RibbonInitialShape {
    /// Flat, square creases.
    Flat,
    /// Every crease with the same direction c and bending angle psi (rad): a helix.
    Helix {
        crease_direction: f64,
        bending_angle: f64,
    },
    /// A closed ring: every crease square (c = 0) and bent by 2 pi / n, so the
    /// polygon of elements closes on itself (the start guess of loops).
    Ring,
    /// Explicit per-crease values (length n-1 each, creases 1..n-1).
    Explicit {
        crease_direction: Vec<f64>,
        bending_angle: Vec<f64>,
    },
}

/// A point force on the ribbon, N, at a material point, m.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RibbonForce {
    pub material_point: Point2,
    pub force: Vector3,
}

/// One simulated ribbon.
#[derive(Clone, Debug)]
pub struct RibbonSim {
    pub params: RibbonParams,
    pub(super) strip: Strip,
    layout: Layout,
    pub(super) coords: Coordinates,
    pub(super) frames: Frames,
    history: RimHistory,
    /// The history before the last step (X^n, V^n): the contact stage moves from it,
    /// and velocities are recomputed from it after a contact correction.
    previous_history: RimHistory,
    pub(super) terms: StepTerms,
    /// Which world handle (and which of its attachments) drives each equality / normal
    /// guide (same order as built).
    pub(super) equality_handles: Vec<Option<HandleRef>>,
    pub(super) guide_handles: Vec<HandleRef>,
    /// Whether a step was taken since the handles last changed (the multipliers are
    /// then the constraint forces of that step's final state).
    pub(super) stepped: bool,
    pub(super) solver: StepSolver,
    q: Vec<f64>,
    mesh: SurfaceMesh,
    singular: Vec<SingularPoint>,
    /// q at the end minus q at the start of the last step (extrapolation).
    q_delta: Vec<f64>,
    /// Frames of the loaded material points at the start of a step (for the work bound).
    loaded_before: Vec<Pose>,
    /// Contact inside the step (`contact.method: barrier`), used when the world hands
    /// the step a [`ContactEnv`].
    contact: RibbonContact,
}

/// The coordinates of a ribbon in `initial` shape with its base at `base_pose`, plus
/// the seeded `imperfection` (rad) on every crease's c_k and psi_k.
fn initial_coordinates(
    n: usize,
    base_pose: Pose,
    initial: &RibbonInitialShape,
    imperfection: Imperfection,
) -> Coordinates {
    let mut coords = Coordinates::flat(n, base_pose);
    match initial {
        RibbonInitialShape::Flat => {}
        RibbonInitialShape::Ring => {
            for k in 1..n {
                coords.bending_angle[k] = 2.0 * std::f64::consts::PI / n as f64;
            }
        }
        RibbonInitialShape::Helix {
            crease_direction,
            bending_angle,
        } => {
            for k in 1..n {
                coords.crease_direction[k] = *crease_direction;
                coords.bending_angle[k] = *bending_angle;
            }
        }
        RibbonInitialShape::Explicit {
            crease_direction,
            bending_angle,
        } => {
            coords.crease_direction[1..n].copy_from_slice(&crease_direction[..n - 1]);
            coords.bending_angle[1..n].copy_from_slice(&bending_angle[..n - 1]);
        }
    }
    if imperfection.amplitude > 0.0 {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(imperfection.seed);
        let a = imperfection.amplitude;
        for k in 1..n {
            coords.crease_direction[k] += rng.random_range(-a..=a);
            coords.bending_angle[k] += rng.random_range(-a..=a);
        }
    }
    coords
}

/// The step objective's data before the first step: the material (density, bending
/// weights per crease with the clamps, regularizer), gravity (m/s^2), the point forces
/// (N), the handles' equalities (zero multipliers) and normal guides, the scene's mu and
/// the crease bound Δc_max. h is a placeholder (0.01 s) that every step overwrites.
fn initial_terms(
    params: &RibbonParams,
    strip: &Strip,
    index: usize,
    handles: &[HandleSpec],
    forces: &[RibbonForce],
    equalities: Vec<Equality>,
    normal_guides: Vec<NormalGuide>,
) -> StepTerms {
    let multipliers = equalities.iter().map(|e| vec![0.0; e.rows()]).collect();
    let mut crease_bending = Vec::new();
    crease_bending_weights(
        params.bending_stiffness,
        strip,
        params.clamp,
        &clamp_stations(&params.base, handles, index),
        &mut crease_bending,
    );
    StepTerms {
        h: 0.01,
        kinetic: params.kinetic,
        density: params.density,
        crease_bending,
        crease_regularizer: params.crease_regularizer,
        gravity: Vector3::from(params.gravity),
        normal_guides,
        forces: forces
            .iter()
            .map(|f| PointForce {
                material_point: f.material_point,
                force: f.force,
            })
            .collect(),
        equalities,
        multipliers,
        end_crease_multipliers: [0.0, 0.0],
        end_crease_exact: false,
        penalty: params.solver.penalty,
        crease_bound: params.crease_bound(),
    }
}

impl RibbonSim {
    /// A ribbon at rest in `initial` shape. `handles` are the world's handles; those
    /// with `object == index` act on this ribbon.
    pub fn new(
        params: RibbonParams,
        initial: &RibbonInitialShape,
        imperfection: Imperfection,
        forces: &[RibbonForce],
        index: usize,
        handles: &[HandleSpec],
    ) -> RibbonSim {
        let n = params.segments;
        let strip = Strip {
            length: params.length,
            width: params.width,
            segments: n,
        };
        let base_pose = match &params.base {
            BaseMode::Prescribed { pose, .. } => *pose,
            BaseMode::Floating { initial } => *initial,
        };
        let coords = initial_coordinates(n, base_pose, initial, imperfection);
        let mut frames = Frames::default();
        reconstruct(&strip, &coords, &mut frames);
        let history = RimHistory::at_rest(&strip, &coords.crease_direction, &frames);
        let floating = matches!(params.base, BaseMode::Floating { .. });
        let layout = Layout {
            segments: n,
            floating,
        };
        let constraints = HandleConstraints::new(&params, index, handles);
        let terms = initial_terms(
            &params,
            &strip,
            index,
            handles,
            forces,
            constraints.equalities,
            constraints.normal_guides,
        );
        let mut q = vec![0.0; layout.len()];
        layout.pack(&coords, &base_pose, &mut q);
        let mut sim = RibbonSim {
            params,
            strip,
            layout,
            coords,
            frames,
            previous_history: history.clone(),
            history,
            terms,
            equality_handles: constraints.equality_handles,
            guide_handles: constraints.guide_handles,
            stepped: false,
            solver: StepSolver::default(),
            q,
            mesh: SurfaceMesh::default(),
            singular: Vec::new(),
            q_delta: Vec::new(),
            loaded_before: Vec::new(),
            contact: RibbonContact::default(),
        };
        sim.rebuild_outputs();
        sim
    }

    pub fn coordinates(&self) -> &Coordinates {
        &self.coords
    }
    pub fn frames(&self) -> &Frames {
        &self.frames
    }
    pub fn strip(&self) -> &Strip {
        &self.strip
    }
    /// Forget what the step solver carries from step to step (the Newton solvers'
    /// damping, the trust region's radius): the next step solves as a newly built
    /// ribbon's solver would from this state. For comparing solver kinds from one state
    /// (tests/ribbon_chain_solver.rs); a clone keeps that history instead, so that it
    /// continues bit for bit.
    pub fn forget_solver_history(&mut self) {
        self.solver = StepSolver::default();
    }
    pub fn mesh(&self) -> &SurfaceMesh {
        &self.mesh
    }
    pub fn singular_points(&self) -> &[SingularPoint] {
        &self.singular
    }

    /// Overwrite the previous-step velocities (m/s) with a rigid motion: angular
    /// velocity `omega` (rad/s) about the point `center` (m), plus `linear` (m/s).
    pub fn set_rigid_velocity(&mut self, omega: Vector3, center: Point3, linear: Vector3) {
        for (x, v) in self
            .history
            .x_bottom
            .iter()
            .zip(self.history.v_bottom.iter_mut())
        {
            *v = omega.cross(&(x - center.coords)) + linear;
        }
        for (x, v) in self.history.x_top.iter().zip(self.history.v_top.iter_mut()) {
            *v = omega.cross(&(x - center.coords)) + linear;
        }
    }

    /// One implicit-Euler step of `dt` s to time `time`; `targets[h]` is the target of
    /// world handle h (`world_from_gripper`); with `contact`, contact is part of the
    /// step (docs/contact_barrier.md).
    pub fn step(
        &mut self,
        dt: f64,
        _time: f64,
        handles: &[HandleSpec],
        targets: &[Pose],
        contact: Option<&ContactEnv>,
    ) -> ObjectStepReport {
        // `targets` are finite: the world keeps a handle's last target instead of a
        // non-finite one (see `StepContext::targets`).
        self.terms.h = dt;
        let base = self.follow_targets(handles, targets);
        let mut q = self.q.clone();
        // (not into contact: the extrapolated start could cross something)
        if self.params.solver.extrapolate && self.q_delta.len() == q.len() && contact.is_none() {
            // start from the linear extrapolation of the last step (the solver clamps
            // it into the crease bounds)
            for (qi, di) in q.iter_mut().zip(&self.q_delta) {
                *qi += di;
            }
        }
        let q_start = self.q.clone();
        if !self.layout.floating {
            self.coords.base = base;
        }
        let saved_terms = self.terms.clone();
        let mut loaded_before = std::mem::take(&mut self.loaded_before);
        self.loaded_poses(&mut loaded_before);
        let outcome = match contact {
            None => self.solver.solve(
                self.strip,
                self.layout.floating,
                &self.history,
                base,
                &mut self.terms,
                &self.params.solver,
                None,
                &mut q,
            ),
            Some(env) => self.contact_step(base, dt, |c, step| c.solve(env, step, &mut q)),
        };
        let finite = q.iter().all(|x| x.is_finite()) && outcome.objective.is_finite();
        let mut report = ObjectStepReport {
            iterations: outcome.iterations,
            outer_iterations: outcome.outer_iterations,
            converged: outcome.converged && finite,
            kept_previous_state: !finite,
            constraint_violation: outcome.constraint_violation,
            violation_handle: outcome
                .worst_equality
                .and_then(|e| self.equality_handles.get(e).copied().flatten())
                .map(|r| r.handle),
            ..Default::default()
        };
        if finite {
            self.q_delta.clear();
            self.q_delta
                .extend(q.iter().zip(&q_start).map(|(a, b)| a - b));
            self.q = q;
            self.layout.unpack(&self.q, &base, &mut self.coords);
            reconstruct(&self.strip, &self.coords, &mut self.frames);
            self.update_history(dt);
            report.work_bound = self.work_bound(&loaded_before);
            if contact.is_some() {
                report.work_bound += self.contact.last.collider_work;
                report.contact = Some(self.contact.last);
            }
            self.stepped = true;
        } else {
            // Keep the last valid state and its multipliers; say so in the report.
            self.terms = saved_terms;
            self.previous_history.clone_from(&self.history);
            report.constraint_violation = f64::NAN;
            report.violation_handle = None;
        }
        self.loaded_before = loaded_before;
        self.rebuild_outputs();
        report.energies = self.energies();
        report.isometry_error = self.mesh.isometry_error();
        report.singular_points = self.singular.len();
        // a rejected step keeps its NaN violation: the new state is unknown, and 0 would
        // read as "every constraint met"
        report
    }

    /// `f` with the ribbon's contact state and what a step with contact needs of it.
    fn contact_step<R>(
        &mut self,
        base: Pose,
        dt: f64,
        f: impl FnOnce(&mut RibbonContact, ContactStep) -> R,
    ) -> R {
        let step = ContactStep {
            solver: &mut self.solver,
            strip: self.strip,
            floating: self.layout.floating,
            history: &self.history,
            base,
            terms: &mut self.terms,
            settings: &self.params.solver,
            triangles: &self.mesh.triangles,
            period: self.params.loop_closure.map(|_| self.strip.length),
            frames: &self.frames,
            dt,
        };
        f(&mut self.contact, step)
    }

    /// Move what the handles drive to their `targets` (`world_from_gripper`): a driven
    /// prescribed base, the position / orientation equalities and the normal guides.
    /// Returns the base pose of this step (for a floating base, the current one: the
    /// reference rotation, w restarting at 0, with `q` repacked about it).
    fn follow_targets(&mut self, handles: &[HandleSpec], targets: &[Pose]) -> Pose {
        if let BaseMode::Prescribed {
            pose,
            driven_by: Some(h),
        } = &mut self.params.base
        {
            if let Some(target) = targets.get(*h).copied() {
                let grasp = handles[*h].material_point;
                // world_from_base = world_from_gripper * gripper_from_base; the gripper
                // sits at the grasp point with axes along the material axes.
                *pose = target * Pose::translation(-grasp.x, -grasp.y, 0.0);
            }
        }
        // floating: the current base is the reference rotation, w restarts at 0
        let base = match &self.params.base {
            BaseMode::Prescribed { pose, .. } => *pose,
            BaseMode::Floating { .. } => self.coords.base,
        };
        if self.layout.floating {
            self.layout.pack(&self.coords, &base, &mut self.q);
        }
        for (eq, h) in self.terms.equalities.iter_mut().zip(&self.equality_handles) {
            let Some(h) = h.map(|r| r.handle) else {
                continue;
            };
            let Some(target) = targets.get(h).map(|t| handles[h].grasp_frame(t)) else {
                continue;
            };
            match eq {
                Equality::Position { target: t, .. } => {
                    *t = Point3::from(target.translation.vector)
                }
                Equality::Orientation { target: r, .. } => {
                    *r = *target.rotation.to_rotation_matrix().matrix()
                }
                Equality::Loop(_) => {}
            }
        }
        for (guide, h) in self.terms.normal_guides.iter_mut().zip(&self.guide_handles) {
            if let Some(target) = targets
                .get(h.handle)
                .map(|t| handles[h.handle].grasp_frame(t))
            {
                guide.target = target.rotation * Vector3::z();
            }
        }
        base
    }

    /// New velocities at the new material points: V = (X^{n+1} - R(X̄^{n+1}, X^n)) / h
    /// (the same difference the kinetic term used), then the new history.
    fn update_history(&mut self, h: f64) {
        let n = self.strip.segments;
        let c = &self.coords.crease_direction;
        let old = &self.history;
        let mut new = RimHistory::at_rest(&self.strip, c, &self.frames);
        for j in 0..=n {
            let (xb, _) =
                super::objective::interpolate(&old.u_bottom, &old.x_bottom, new.u_bottom[j], j);
            let (xt, _) = super::objective::interpolate(&old.u_top, &old.x_top, new.u_top[j], j);
            new.v_bottom[j] = (new.x_bottom[j] - xb) / h;
            new.v_top[j] = (new.x_top[j] - xt) / h;
        }
        if self.params.kinetic == KineticModel::QuasiStatic {
            // no inertia: velocities are reported, not carried
            for v in new.v_bottom.iter_mut().chain(new.v_top.iter_mut()) {
                *v = Vector3::zeros();
            }
        }
        self.previous_history = std::mem::replace(&mut self.history, new);
    }

    /// Energies of the current state, J.
    pub fn energies(&self) -> Energies {
        let n = self.strip.segments;
        let c = &self.coords.crease_direction;
        let psi = &self.coords.bending_angle;
        let rho = self.params.density;
        let g = Vector3::from(self.params.gravity);
        let mut e = Energies::default();
        for el in 0..n {
            let m = element_mass(self.strip.length, self.strip.width, n, c[el + 1] - c[el]);
            let v = [
                self.history.v_bottom[el],
                self.history.v_top[el],
                self.history.v_bottom[el + 1],
                self.history.v_top[el + 1],
            ];
            let x = [
                self.history.x_bottom[el],
                self.history.x_top[el],
                self.history.x_bottom[el + 1],
                self.history.x_top[el + 1],
            ];
            for a in 0..4 {
                for b in 0..4 {
                    e.kinetic += 0.5 * rho * m.k[a][b] * v[a].dot(&v[b]);
                }
                e.gravity -= rho * m.k[a].iter().sum::<f64>() * g.dot(&x[a]);
            }
        }
        for k in 1..n {
            e.elastic += self.terms.crease_bending[k] * (1.0 + c[k] * c[k]) * psi[k] * psi[k]
                + self.params.crease_regularizer * c[k] * c[k];
        }
        // the contact barrier's potential (docs/contact_barrier.md), 0 without one
        e.external += self.contact.last.barrier_energy;
        e
    }

    /// Linear momentum of the current velocities, kg m/s: sum over elements of
    /// rho K v (the consistent mass of each trapezoid, appendix B).
    pub fn momentum(&self) -> Vector3 {
        let n = self.strip.segments;
        let c = &self.coords.crease_direction;
        let rho = self.params.density;
        let mut p = Vector3::zeros();
        for el in 0..n {
            let m = element_mass(self.strip.length, self.strip.width, n, c[el + 1] - c[el]);
            let v = [
                self.history.v_bottom[el],
                self.history.v_top[el],
                self.history.v_bottom[el + 1],
                self.history.v_top[el + 1],
            ];
            for a in 0..4 {
                for b in 0..4 {
                    p += v[b] * (rho * m.k[a][b]);
                }
            }
        }
        p
    }

    /// Mesh, rulings, regions and singular points from the current frames.
    fn rebuild_outputs(&mut self) {
        let n = self.strip.segments;
        let c = &self.coords.crease_direction;
        let psi = &self.coords.bending_angle;
        let mesh = &mut self.mesh;
        mesh.vertices.clear();
        mesh.material.clear();
        mesh.regions.clear();
        mesh.triangles.clear();
        mesh.rulings.clear();
        for j in 0..=n {
            mesh.vertices.push(self.frames.rim_bottom[j]);
            mesh.vertices.push(self.frames.rim_top[j]);
            let (b, t) = (
                self.strip.material_bottom(j, c[j]),
                self.strip.material_top(j, c[j]),
            );
            mesh.material.push(Point2::new(b.x, b.y));
            mesh.material.push(Point2::new(t.x, t.y));
            let bent = (1..n).contains(&j) && psi[j].abs() > 1e-6;
            let region = if bent {
                VertexRegion::Curved
            } else {
                VertexRegion::Flat
            };
            mesh.regions.push(region);
            mesh.regions.push(region);
        }
        for e in 0..n as u32 {
            let (xb, yb, xn, yn) = (2 * e, 2 * e + 1, 2 * e + 2, 2 * e + 3);
            mesh.triangles.push([xb, xn, yn]);
            mesh.triangles.push([xb, yn, yb]);
        }
        for k in 1..n as u32 {
            mesh.rulings.push([2 * k, 2 * k + 1]);
        }
        // Singular points (eq. 1 active): creases k and k+1 meet at a rim when
        // |c_{k+1} - c_k| reaches Δc_max: at the bottom rim when c_{k+1} > c_k.
        self.singular.clear();
        let bound = self.params.crease_bound();
        for k in 0..n {
            let d = c[k + 1] - c[k];
            if d.abs() >= bound * (1.0 - 1e-6) {
                let top = d < 0.0;
                let (a, b) = if top {
                    (self.frames.rim_top[k], self.frames.rim_top[k + 1])
                } else {
                    (self.frames.rim_bottom[k], self.frames.rim_bottom[k + 1])
                };
                let (ma, mb) = (
                    mesh.material[2 * k + top as usize],
                    mesh.material[2 * k + 2 + top as usize],
                );
                self.singular.push(SingularPoint {
                    id: 2 * k as u64 + top as u64,
                    position: Point3::from((a.coords + b.coords) * 0.5),
                    material: Point2::from((ma.coords + mb.coords) * 0.5),
                });
                for v in [2 * k + top as usize, 2 * k + 2 + top as usize] {
                    mesh.regions[v] = VertexRegion::Singular;
                }
            }
        }
    }
}

impl RibbonSim {
    /// The frames of the points where handles and point forces act, in the order
    /// equalities (a loop gets a placeholder), normal guides, point forces.
    fn loaded_poses(&self, out: &mut Vec<Pose>) {
        out.clear();
        for eq in &self.terms.equalities {
            out.push(match eq {
                Equality::Position { material_point, .. }
                | Equality::Orientation { material_point, .. } => {
                    self.material_pose(material_point)
                }
                Equality::Loop(_) => Pose::identity(),
            });
        }
        for guide in &self.terms.normal_guides {
            out.push(self.material_pose(&guide.material_point));
        }
        for force in &self.terms.forces {
            out.push(self.material_pose(&force.material_point));
        }
    }

    /// Upper bound on the work done on the ribbon over the step just taken by the
    /// handles and point forces, J (see [`ObjectStepReport::work_bound`]): the force
    /// at the end of the step times the displacement of the point it acts on, with
    /// |F . Δx| <= |F| |Δx| where only the force's norm is known. A handle's
    /// constraint force is its updated augmented-Lagrangian multiplier (the objective
    /// holds -λ.C + μ/2 |C|^2, so the force is λ - μ C = the new λ); a rotation
    /// constraint's generalized force is λ (J) against the change of the frame matrix.
    /// A driven base moves the ribbon kinematically and is not counted.
    fn work_bound(&self, before: &[Pose]) -> f64 {
        let mut after = Vec::with_capacity(before.len());
        self.loaded_poses(&mut after);
        if after.len() != before.len() {
            return 0.0;
        }
        let norm = |v: &[f64]| v.iter().map(|x| x * x).sum::<f64>().sqrt();
        let mut work = 0.0;
        let mut i = 0;
        for (eq, lambda) in self.terms.equalities.iter().zip(&self.terms.multipliers) {
            let (a, b) = (&before[i], &after[i]);
            work += match eq {
                Equality::Position { axes, .. } => {
                    let d = b.translation.vector - a.translation.vector;
                    let mut dd = 0.0;
                    for k in 0..3 {
                        if axes[k] {
                            dd += d[k] * d[k];
                        }
                    }
                    norm(lambda) * dd.sqrt()
                }
                Equality::Orientation { .. } => {
                    let d = b.rotation.to_rotation_matrix().into_inner()
                        - a.rotation.to_rotation_matrix().into_inner();
                    norm(lambda) * d.norm()
                }
                // a loop joins the ribbon to itself: internal forces do no net work
                Equality::Loop(_) => 0.0,
            };
            i += 1;
        }
        for guide in &self.terms.normal_guides {
            // the guide's force on the normal: -K (n - n_target)
            let n0 = before[i].rotation * Vector3::z();
            let n1 = after[i].rotation * Vector3::z();
            work += guide.stiffness * (n1 - guide.target).norm() * (n1 - n0).norm();
            i += 1;
        }
        for force in &self.terms.forces {
            let d = after[i].translation.vector - before[i].translation.vector;
            work += force.force.dot(&d).abs();
            i += 1;
        }
        work
    }

    /// `world_from_material_point`: the frame of the element under material point
    /// `m` (m), translated to the point.
    pub fn material_pose(&self, m: &Point2) -> Pose {
        let e = self.strip.element_of(&self.coords.crease_direction, m);
        let p = self.frames.to_world(e, &Point3::new(m.x, m.y, 0.0));
        let r = nalgebra::Rotation3::from_matrix_unchecked(self.frames.rotation[e]);
        Pose::from_parts(
            p.coords.into(),
            nalgebra::UnitQuaternion::from_rotation_matrix(&r),
        )
    }
}

impl RibbonSim {
    /// One evaluation of the current step objective and its gradient at the current
    /// state (what one solver iteration costs); returns the objective, J. Used by the
    /// `gradient_us` statistic and the gradient benchmarks.
    pub fn evaluate_gradient(
        &mut self,
        mode: super::objective::GradientMode,
        gradient: &mut Vec<f64>,
    ) -> f64 {
        let base = self.coords.base;
        let mut q = self.q.clone();
        self.layout.pack(&self.coords, &base, &mut q);
        let objective = super::objective::Objective::new(
            self.strip,
            self.layout.floating,
            &self.terms,
            &self.history,
            base,
        );
        gradient.resize(q.len(), 0.0);
        objective.evaluate(&q, &mut self.solver.workspace, Some((gradient, mode)), None)
    }
}

impl ContactBody for RibbonSim {
    /// The contact mesh: one contact vertex per rim point, the two end pairs welded
    /// when the ribbon is a loop (x_n on x_0 and y_n on y_0; crossed for a Moebius
    /// loop), stations = crease index, topological neighbours within 2 elements.
    fn contact_topology(&self) -> BodyTopology {
        let n = self.strip.segments;
        let mesh_vertices = 2 * (n + 1);
        let mut vertex_of: Vec<u32> = (0..mesh_vertices as u32).collect();
        let (vertices, period) = match self.params.loop_closure {
            None => (mesh_vertices, None),
            Some(kind) => {
                let (b, t) = match kind {
                    super::params::LoopKind::Orientable => (0, 1),
                    super::params::LoopKind::NonOrientable => (1, 0),
                };
                vertex_of[2 * n] = b;
                vertex_of[2 * n + 1] = t;
                (2 * n, Some(n as f64))
            }
        };
        let triangles = self
            .mesh
            .triangles
            .iter()
            .map(|t| t.map(|v| vertex_of[v as usize]))
            .collect();
        BodyTopology {
            vertex_of,
            vertices,
            triangles,
            stations: (0..vertices).map(|v| (v / 2) as f64).collect(),
            period,
            neighbour_skip: 2.0,
        }
    }

    /// Mesh vertices of the state before the last step (X^n), m, in mesh order.
    fn previous_mesh_vertices(&self, out: &mut Vec<Point3>) {
        out.clear();
        let h = &self.previous_history;
        for (b, t) in h.x_bottom.iter().zip(&h.x_top) {
            out.push(Point3::from(*b));
            out.push(Point3::from(*t));
        }
    }

    /// The smallest gap of the current state against `env` (see
    /// [`ContactBody::barrier_gap`]).
    fn barrier_gap(&mut self, env: &ContactEnv) -> (f64, PairSource) {
        let base = match &self.params.base {
            BaseMode::Prescribed { pose, .. } => *pose,
            BaseMode::Floating { .. } => self.coords.base,
        };
        let q = self.q.clone();
        let dt = self.terms.h;
        self.contact_step(base, dt, |c, step| c.gap_at(env, step, &q))
    }

    /// The last step's start, end and line searches' paths (the collision checks').
    fn swept_boxes(&self) -> &[(Vector3, Vector3)] {
        self.solver.workspace.swept_boxes()
    }

    /// Replace the reconstructed mesh of the last step by the collision-free one
    /// (Pan et al. sec. 5.2): it becomes X^{n+1} of the kinetic term, with velocities
    /// V = (X^{n+1} - R(X̄^{n+1}, X^n)) / h from the corrected positions; the next
    /// optimization starts from it. `h` is the step, s.
    fn apply_contact_correction(&mut self, corrected: &[Point3], h: f64) {
        let n = self.strip.segments;
        assert_eq!(corrected.len(), 2 * (n + 1));
        let old = &self.previous_history;
        let new = &mut self.history;
        let carry = self.params.kinetic != KineticModel::QuasiStatic;
        for j in 0..=n {
            let (xb, xt) = (corrected[2 * j].coords, corrected[2 * j + 1].coords);
            new.x_bottom[j] = xb;
            new.x_top[j] = xt;
            if carry {
                let (ob, _) =
                    super::objective::interpolate(&old.u_bottom, &old.x_bottom, new.u_bottom[j], j);
                let (ot, _) =
                    super::objective::interpolate(&old.u_top, &old.x_top, new.u_top[j], j);
                new.v_bottom[j] = (xb - ob) / h;
                new.v_top[j] = (xt - ot) / h;
            }
        }
        self.mesh.vertices.clear();
        self.mesh.vertices.extend_from_slice(corrected);
        for s in &mut self.singular {
            let a = s.id as usize;
            s.position = Point3::from(
                (self.mesh.vertices[a].coords + self.mesh.vertices[a + 2].coords) * 0.5,
            );
        }
    }
}

impl ObjectSim for RibbonSim {
    fn kind(&self) -> &'static str {
        "ribbon"
    }
    fn solver_name(&self) -> &'static str {
        match self.params.solver.kind {
            super::SolverKind::GaussNewton => "gauss_newton",
            super::SolverKind::Lbfgsb => "lbfgsb",
            super::SolverKind::Chain => "chain",
            super::SolverKind::TrustRegion => "trust_region",
            super::SolverKind::InteriorPoint => "interior_point",
        }
    }
    /// One implicit-Euler step, timed as one [`Phase::Simulation`].
    fn step(&mut self, ctx: &StepContext<'_>) -> ObjectStepReport {
        let mut report = ObjectStepReport::default();
        ctx.clock.time(Some(ctx.index), Phase::Simulation, &mut || {
            report = RibbonSim::step(
                self,
                ctx.dt,
                ctx.time,
                ctx.handles,
                ctx.targets,
                ctx.contact,
            )
        });
        report
    }
    fn mesh(&self) -> &SurfaceMesh {
        RibbonSim::mesh(self)
    }
    fn singular_points(&self) -> &[SingularPoint] {
        RibbonSim::singular_points(self)
    }
    fn energies(&self) -> Energies {
        RibbonSim::energies(self)
    }
    fn material_pose(&self, m: &Point2) -> Pose {
        RibbonSim::material_pose(self, m)
    }
    fn handles_changed(&mut self, index: usize, handles: &[HandleSpec]) {
        self.rebuild_handle_terms(index, handles);
    }
    fn graspable(&self, m: &Point2) -> Result<Point2, String> {
        self.graspable_point(m)
    }
    fn drives_base(&self, handle: usize) -> bool {
        matches!(
            self.params.base,
            BaseMode::Prescribed {
                driven_by: Some(h),
                ..
            } if h == handle
        )
    }
    fn handle_wrench(&self, handle: usize) -> Option<Wrench> {
        self.wrench_on(handle)
    }
    fn coordinates(&self) -> Vec<(&'static str, &[f64])> {
        vec![
            ("crease_direction", &self.coords.crease_direction),
            ("bending_angle", &self.coords.bending_angle),
        ]
    }
    fn evaluate_gradient(&mut self, gradient: &mut Vec<f64>) -> Option<f64> {
        Some(RibbonSim::evaluate_gradient(
            self,
            super::objective::GradientMode::Adjoint,
            gradient,
        ))
    }
    fn contact_body(&self) -> Option<&dyn ContactBody> {
        Some(self)
    }
    fn contact_body_mut(&mut self) -> Option<&mut dyn ContactBody> {
        Some(self)
    }
    fn clone_box(&self) -> Box<dyn ObjectSim> {
        Box::new(self.clone())
    }
}
