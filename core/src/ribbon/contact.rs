//! A ribbon's step with contact inside it (`contact.method: barrier`,
//! docs/contact_barrier.md): the contact terms its solver minimizes with the rest of the
//! objective, the lagged friction fixed at the start of the step, and the rounds that
//! let a collider carried by a handle move without ever crossing the ribbon.
//!
//! A moving collider starts the step where it ended the last one. It is advanced by the
//! largest share of its motion that keeps a tenth of the current gap (conservative
//! advancement: no point of it moves faster than |Δt| + θ R per unit of the motion), the
//! step is solved with it there, and the advance repeats from the ribbon's new mesh
//! until the collider reaches its target or can go no further (a gripper cannot squeeze
//! a ribbon thinner than its thickness: reported as not resolved).

use std::sync::Arc;

use super::objective::{ContactTerms, FrictionLag, GradientMode, Objective, RimHistory, StepTerms};
use super::params::SolverSettings;
use super::reconstruct::{reconstruct, Coordinates, Frames, Strip};
use super::step::{SolveOutcome, StepSolver};
use crate::contact::barrier::{barrier, point_triangle, tangent_basis, BarrierOutcome, PairSource};
use crate::contact::obstacles::{interpolate_pose, CellMesh, ContactEnv};
use crate::geometry::{Pose, Vector3};

/// Most rounds of collider advance and solve in one step.
const MAX_ROUNDS: u32 = 32;

/// A ribbon's contact state across steps.
#[derive(Clone, Debug, Default)]
pub struct RibbonContact {
    pub terms: ContactTerms,
    /// Where each collider was at the end of the last step (empty before the first).
    reached: Vec<Pose>,
    /// This step's start and end poses of the colliders.
    start: Vec<Pose>,
    end: Vec<Pose>,
    /// Per collider: the most any of its points near the ribbon moves over the step, m.
    travel: Vec<f64>,
    coords: Option<Coordinates>,
    frames: Frames,
    mesh: Vec<Vector3>,
    gradient: Vec<f64>,
    pub last: BarrierOutcome,
}

/// What a contact step needs of the ribbon.
pub(super) struct ContactStep<'a> {
    pub solver: &'a mut StepSolver,
    pub strip: Strip,
    pub floating: bool,
    pub history: &'a RimHistory,
    pub base: Pose,
    pub terms: &'a mut StepTerms,
    pub settings: &'a SolverSettings,
    /// The ribbon's mesh triangles and, for a loop, the period of its stations (l, m).
    pub triangles: &'a [[u32; 3]],
    pub period: Option<f64>,
    /// The frames at the start of the step.
    pub frames: &'a Frames,
    pub dt: f64,
}

impl RibbonContact {
    /// One step with contact: rounds of collider advance and solve from `q` (written
    /// back). The outcome sums the rounds' iterations.
    pub(super) fn solve(
        &mut self,
        env: &ContactEnv,
        mut step: ContactStep,
        q: &mut [f64],
    ) -> SolveOutcome {
        self.prepare(env, &step);
        step.solver.workspace.reset_swept(&self.mesh);
        let env = ContactEnv {
            poses0: &self.start,
            poses1: &self.end,
            ..*env
        };
        let mut total = SolveOutcome::default();
        let mut tau = advance_colliders(&mut self.terms, &env, &self.mesh, 0.0, &self.travel);
        let mut rounds = 0;
        loop {
            rounds += 1;
            self.terms.obstacles.move_colliders(&env, tau);
            let outcome = step.solver.solve(
                step.strip,
                step.floating,
                step.history,
                step.base,
                step.terms,
                step.settings,
                Some(&self.terms),
                q,
            );
            total.iterations += outcome.iterations;
            total.outer_iterations += outcome.outer_iterations;
            total = SolveOutcome {
                iterations: total.iterations,
                outer_iterations: total.outer_iterations,
                ..outcome
            };
            if tau >= 1.0 || rounds >= MAX_ROUNDS || !q.iter().all(|x| x.is_finite()) {
                break;
            }
            mesh_at(&mut self.coords, &mut self.frames, &mut self.mesh, &step, q);
            let next = advance_colliders(&mut self.terms, &env, &self.mesh, tau, &self.travel);
            if next <= tau {
                break;
            }
            tau = next;
        }
        self.reached.clear();
        self.reached.extend(
            self.start
                .iter()
                .zip(&self.end)
                .map(|(a, b)| interpolate_pose(a, b, tau)),
        );
        self.finish(&mut step, q, rounds, tau);
        // the end of the step into the swept record (finish evaluated the frames at q)
        let ws = &mut step.solver.workspace;
        self.mesh.clear();
        for (b, t) in ws.frames.rim_bottom.iter().zip(&ws.frames.rim_top) {
            self.mesh.push(b.coords);
            self.mesh.push(t.coords);
        }
        ws.add_swept(&self.mesh);
        total
    }

    /// The smallest gap (distance beyond the thickness, m) of any pair inside the
    /// barrier at `q` with the colliders at their start poses, and what that pair is
    /// against: +∞ when none is, <= 0 when something touches or overlaps (a scene cannot
    /// start like that).
    pub(super) fn gap_at(
        &mut self,
        env: &ContactEnv,
        step: ContactStep,
        q: &[f64],
    ) -> (f64, PairSource) {
        self.prepare(env, &step);
        let objective = Objective::new(
            step.strip,
            step.floating,
            step.terms,
            step.history,
            step.base,
        )
        .with_contact(Some(&self.terms));
        objective.evaluate(q, &mut step.solver.workspace, None, None);
        let c = &step.solver.workspace.contact;
        (c.min_gap, c.min_source)
    }

    /// Cells, constants, the colliders' poses, the sorting axis and the lagged friction
    /// at the start of the step.
    fn prepare(&mut self, env: &ContactEnv, step: &ContactStep) {
        let n = step.strip.segments;
        let vertices = 2 * (n + 1);
        if self.terms.vertex_cell.len() != vertices {
            self.terms
                .set_cells(Arc::new(CellMesh::new(step.triangles, vertices)), vertices);
        }
        let s = env.settings;
        let area = step.strip.length * step.strip.width / (2.0 * n as f64);
        let t = &mut self.terms;
        t.weight = s.stiffness() * area;
        t.activation = s.activation_distance;
        t.thickness = s.thickness;
        t.skip = s.neighbour_skip();
        t.period = step.period;
        t.self_contact = s.self_contact;
        t.friction_slip = s.friction_velocity * step.dt;
        self.start.clear();
        if self.reached.len() == env.poses0.len() {
            self.start.extend_from_slice(&self.reached);
        } else {
            self.start.extend_from_slice(env.poses0);
        }
        self.end.clear();
        self.end.extend_from_slice(env.poses1);
        self.mesh.clear();
        for (b, t) in step.frames.rim_bottom.iter().zip(&step.frames.rim_top) {
            self.mesh.push(b.coords);
            self.mesh.push(t.coords);
        }
        let (lo, hi) = crate::contact::obstacles::bounds(&self.mesh);
        let extent = hi - lo;
        let axis = (0..3)
            .max_by(|&a, &b| extent[a].total_cmp(&extent[b]))
            .unwrap_or(0);
        self.travel_bounds(&lo, &hi);
        let env = ContactEnv {
            poses0: &self.start,
            poses1: &self.end,
            ..*env
        };
        self.terms.obstacles.update(&env, 0.0, axis);
        self.lag_friction();
    }

    /// Per collider, the most any of its points within the ribbon's reach moves over
    /// the step: |Δt| + θ R, R bounding the distance of such a point from the
    /// collider's origin (the farthest corner of the ribbon's box, or the collider's own
    /// extent, plus the translation).
    fn travel_bounds(&mut self, lo: &Vector3, hi: &Vector3) {
        self.travel.clear();
        for (p0, p1) in self.start.iter().zip(&self.end) {
            let t0 = p0.translation.vector;
            let dt = (p1.translation.vector - t0).norm();
            let theta = (p1.rotation * p0.rotation.inverse()).angle();
            let mut r: f64 = 0.0;
            for corner in 0..8 {
                let c = Vector3::new(
                    if corner & 1 == 0 { lo.x } else { hi.x },
                    if corner & 2 == 0 { lo.y } else { hi.y },
                    if corner & 4 == 0 { lo.z } else { hi.z },
                );
                r = r.max((c - t0).norm());
            }
            self.travel.push(dt + theta * (r + dt));
        }
    }

    /// IPC's lagged friction: every rim vertex inside the barrier of a collider's
    /// solid or mesh triangle at the start of the step gets its normal force
    /// λ = -κ A b'(s), its tangent plane and the collider's motion there.
    fn lag_friction(&mut self) {
        let mut friction = std::mem::take(&mut self.terms.friction);
        friction.clear();
        let t = &self.terms;
        let obs = &t.obstacles;
        let half = 0.5 * t.thickness;
        let (start, end) = (&self.start, &self.end);
        let mut add = |v: usize, k: usize, s: f64, normal: Vector3, point: Vector3| {
            if !(s > 0.0 && s < t.activation) || obs.friction[k] == 0.0 {
                return;
            }
            let (_, db, _) = barrier(s, t.activation);
            let moved = end[k] * start[k].inverse_transform_point(&point.into());
            friction.push(FrictionLag {
                vertex: v as u32,
                mu_lambda: obs.friction[k] * t.weight * (-db),
                tangent: tangent_basis(&normal),
                shift: moved.coords - point,
                source: PairSource::Collider(k),
            });
        };
        for solid in &obs.solids {
            for (v, x) in self.mesh.iter().enumerate() {
                let (sd, normal) = obs.solid_distance(solid, x);
                add(v, solid.collider, sd - half, normal, x - normal * sd);
            }
        }
        for f in &obs.triangles {
            for (v, x) in self.mesh.iter().enumerate() {
                let c = point_triangle(x, &f.x[0], &f.x[1], &f.x[2]);
                add(
                    v,
                    f.collider,
                    c.distance - f.offset,
                    c.normal,
                    x - c.normal * c.distance,
                );
            }
        }
        super::body_friction::lag(&self.terms, &self.mesh, &mut friction);
        self.terms.friction = friction;
    }

    /// What the step ended with: one evaluation at the final q (active pairs, smallest
    /// gap, barrier energy, forces on the colliders) and the colliders' work.
    fn finish(&mut self, step: &mut ContactStep, q: &[f64], rounds: u32, tau: f64) {
        let objective = Objective::new(
            step.strip,
            step.floating,
            step.terms,
            step.history,
            step.base,
        )
        .with_contact(Some(&self.terms));
        self.gradient.resize(q.len(), 0.0);
        let ws = &mut step.solver.workspace;
        objective.evaluate(
            q,
            ws,
            Some((&mut self.gradient, GradientMode::Adjoint)),
            None,
        );
        let c = &ws.contact;
        let mut work = 0.0;
        for (k, travel) in self.travel.iter().enumerate() {
            if *travel == 0.0 {
                continue;
            }
            let friction: f64 = self
                .terms
                .friction
                .iter()
                .filter(|f| f.source == PairSource::Collider(k))
                .map(|f| f.mu_lambda)
                .sum();
            work += (c.collider_force.get(k).copied().unwrap_or(0.0) + friction) * travel * tau;
        }
        // another body's motion drags through friction: at most μλ over what it moved
        work += self
            .terms
            .friction
            .iter()
            .filter(|f| matches!(f.source, PairSource::Body(_)))
            .map(|f| f.mu_lambda * f.shift.norm())
            .sum::<f64>()
            * tau;
        self.last = BarrierOutcome {
            active: c.active,
            min_gap: c.min_gap,
            rounds,
            resolved: tau >= 1.0,
            barrier_energy: c.barrier_energy,
            collider_work: work,
        };
    }
}

/// The mesh at `q` into `mesh` (mesh order, m), through `coords` and `frames`.
fn mesh_at(
    coords: &mut Option<Coordinates>,
    frames: &mut Frames,
    mesh: &mut Vec<Vector3>,
    step: &ContactStep,
    q: &[f64],
) {
    let layout = super::objective::Layout {
        segments: step.strip.segments,
        floating: step.floating,
    };
    let n = step.strip.segments;
    let coords = coords.get_or_insert_with(|| Coordinates::flat(n, step.base));
    if coords.segments() != n {
        *coords = Coordinates::flat(n, step.base);
    }
    if !step.floating {
        coords.base = step.base;
    }
    layout.unpack(q, &step.base, coords);
    reconstruct(&step.strip, coords, frames);
    mesh.clear();
    for (b, t) in frames.rim_bottom.iter().zip(&frames.rim_top) {
        mesh.push(b.coords);
        mesh.push(t.coords);
    }
}

/// The largest share τ (from `tau0`) of the moving colliders' motion that keeps a
/// tenth of their gap to the static mesh `mesh` (or of ŝ, if smaller): conservative
/// advancement, no point of collider k moving more than `travel[k]` per unit τ.
/// 1 when no collider moves.
fn advance_colliders(
    terms: &mut ContactTerms,
    env: &ContactEnv,
    mesh: &[Vector3],
    tau0: f64,
    travel: &[f64],
) -> f64 {
    let rate = travel.iter().copied().fold(0.0, f64::max);
    if rate == 0.0 || tau0 >= 1.0 {
        return 1.0;
    }
    let mut tau = tau0;
    let mut floor = None;
    for _ in 0..64 {
        terms.obstacles.move_colliders(env, tau);
        let g = moving_gap(terms, travel, mesh);
        let f = *floor.get_or_insert(0.1 * g.min(terms.activation));
        if g <= f * (1.0 + 1e-3) || g <= 0.0 {
            return tau;
        }
        tau += (g - f) / rate;
        if tau >= 1.0 {
            return 1.0;
        }
    }
    tau
}

/// The smallest gap between the mesh and the colliders that move, m.
fn moving_gap(terms: &ContactTerms, travel: &[f64], mesh: &[Vector3]) -> f64 {
    let obs = &terms.obstacles;
    let half = 0.5 * terms.thickness;
    let moving = |k: usize| travel[k] > 0.0;
    let mut g = f64::INFINITY;
    for solid in obs.solids.iter().filter(|s| moving(s.collider)) {
        for x in mesh {
            g = g.min(obs.solid_distance(solid, x).0 - half);
        }
    }
    let cells = &terms.cells;
    let tri_at = |t: &[u32; 3]| t.map(|v| mesh[v as usize]);
    for f in obs.points.iter().filter(|f| moving(f.collider)) {
        for tri in &cells.triangles {
            let x = tri_at(tri);
            g = g.min(point_triangle(&f.x[0], &x[0], &x[1], &x[2]).distance - f.offset);
        }
    }
    for f in obs.edges.iter().filter(|f| moving(f.collider)) {
        for e in &cells.edges {
            let (a, b) = (mesh[e[0] as usize], mesh[e[1] as usize]);
            g = g.min(
                crate::contact::barrier::edge_edge(&f.x[0], &f.x[1], &a, &b).distance - f.offset,
            );
        }
    }
    for f in obs.triangles.iter().filter(|f| moving(f.collider)) {
        for x in mesh {
            g = g.min(point_triangle(x, &f.x[0], &f.x[1], &f.x[2]).distance - f.offset);
        }
    }
    g
}
