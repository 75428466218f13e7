//! A sheet of paper as a simulated object: the three steps of each animation frame
//! (Schreck et al. sec. 3.3, fig. 3, fig. 16), exposed one by one so that an edge can
//! time them:
//! 1. [`PaperSim::simulate`]: handles moved, implicit FEM step on S_P (arrows a, b);
//! 2. [`PaperSim::remesh`]: S_G positions from S_P (c), compressed flat regions
//!    remeshed with new rulings and singular vertices (d);
//! 3. [`PaperSim::track`]: junction points (e), generalized cones (f), S_P rebuilt
//!    from S_G (g), edge lengths restored (h).

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use super::compression::flat_regions;
use super::crumpling::{crumple_flat_region, CrumpleContext, CrumpleEvent, FrameFlatRegions};
use super::diagnostics::AttemptContext;
pub use super::diagnostics::CrumpleAttempt;
use super::fem::{implicit_step, Dirichlet, FemReport, FemSystem, Spring, StrainLimit};
use super::geometric::{
    Crease, CreaseKind, Endpoint, FaceKind, GVertexKind, GeometricLayer, GeometricMesh,
};
use super::handle_set::{own_handles, PaperHandle};
use super::isometry::{limit_strains, mean_length_error, restore_lengths, IsometryReport};
use super::params::{LengthRestoration, PaperError, PaperParams};
use super::pattern::Pattern;
use super::physical::{build_physical, Interpolator, PhysicalMesh, Placement};
use super::reach::{reachable, HeldTarget};
use super::tracking::{fit_cones, update_junctions, ConeReport, JunctionReport};
use crate::geometry::{EdgeStrain, Point2, Point3, Pose, SurfaceMesh, SurfacePoint, Vector3};
use crate::sim::handle::{HandleSpec, OrientationMode};
use crate::sim::object::{
    CompressionStats, Energies, NoClock, ObjectSim, ObjectStepReport, Phase, PhaseClock,
    SingularPoint, StepContext, Wrench,
};
use nalgebra::Translation3;

/// Per-frame measurements (table IV, V of the paper).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PaperFrameStats {
    /// Edge strains of S_P against the pattern: compression as table IV measures it
    /// (mean of max(0, rest - length)/rest, share of edges over 1 %), and stretch.
    pub edges: EdgeStrain,
    /// Triangles of S_P (N_t).
    pub triangles: usize,
    /// Triangles and curved regions of S_G.
    pub geometric_triangles: usize,
    pub curved_regions: usize,
    pub fem: FemReport,
    /// Each remeshing attempt of step 2: T_comp's compression (1 - lambda_min), its
    /// pattern centroid (m) and ruling direction v_perp, and whether S_G changed.
    pub crumple_attempts: Vec<CrumpleAttempt>,
    pub crumple_events: Vec<CrumpleEvent>,
    pub junctions: JunctionReport,
    pub cones: ConeReport,
    pub isometry: IsometryReport,
}

/// One sheet of paper.
#[derive(Clone, Debug)]
pub struct PaperSim {
    pub params: PaperParams,
    pub(super) pattern: Pattern,
    pub(super) layer: GeometricLayer,
    pub(super) gmesh: GeometricMesh,
    pub(super) sp: PhysicalMesh,
    pub(super) fem: FemSystem,
    rng: ChaCha8Rng,
    pub(super) handles: Vec<PaperHandle>,
    last_targets: Vec<Option<Pose>>,
    /// Per entry of `handles`: what it felt in the last step 1 (None before one).
    pub(super) wrenches: Vec<Option<Wrench>>,
    /// Hard constraints of the current frame: vertex material point -> world target.
    held: Vec<(Point2, Point3)>,
    /// Per entry of `handles`: how far its target is moved to be reachable by an
    /// isometric sheet (m, world frame; zero when it is), and the largest such move
    /// with its handle's index in the world (see [`super::reach`]).
    reach_corrections: Vec<Vector3>,
    reach_excess: (f64, Option<usize>),
    time: f64,
    /// The time step of the last step 1, s (the inertia of step 3's relaxation).
    dt: f64,
    /// `gmesh` was built by step 2 from the current structure and S_P positions.
    pub(super) gmesh_fresh: bool,
    pub(super) mesh: SurfaceMesh,
    singular: Vec<SingularPoint>,
    frame: PaperFrameStats,
    /// S_P's positions at the start of the frame (before step 1), m.
    frame_start: Vec<Point3>,
}

impl PaperSim {
    /// A flat sheet at `params.placement`. `handles` are the world's handles; those
    /// with `object == index` hold this sheet and must grasp it on its boundary.
    pub fn new(
        params: PaperParams,
        handles: &[HandleSpec],
        index: usize,
    ) -> Result<PaperSim, PaperError> {
        params.validate()?;
        let pattern = Pattern::rectangle(params.width, params.height);
        let mut layer = GeometricLayer {
            min_boundary_spacing: params.min_boundary_spacing(),
            ..Default::default()
        };
        let own = own_handles(&pattern, index, handles)?;
        layer.anchors.extend(own.iter().map(|h| h.arc));
        for c in &params.preset_creases {
            let (Some(a), Some(b)) = (pattern.arc_of(&c.from, 1e-9), pattern.arc_of(&c.to, 1e-9))
            else {
                return Err(PaperError::Invalid {
                    key: "creases",
                    message: "a preset crease must go from boundary to boundary".into(),
                });
            };
            layer.creases.push(Crease {
                a: Endpoint::Boundary(a),
                b: Endpoint::Boundary(b),
                kind: CreaseKind::Preset {
                    rest_angle: c.rest_angle,
                },
            });
        }
        let placement = params.placement;
        let flat = move |_: &GVertexKind, m: &Point2| placement * Point3::new(m.x, m.y, 0.0);
        let gmesh = GeometricMesh::build(&layer, &pattern, &flat)
            .map_err(|e| PaperError::Triangulation(e.to_string()))?;
        let on_sheet = |s: f64| {
            let m = pattern.point_at(s);
            placement * Point3::new(m.x, m.y, 0.0)
        };
        let flat_at = |m: &Point2| placement * Point3::new(m.x, m.y, 0.0);
        let samples = match params.length_restoration {
            LengthRestoration::Paper => Placement::OnGeometricLayer(&on_sheet),
            LengthRestoration::StrainLimit => Placement::Interpolated(&flat_at),
        };
        let mut sp = build_physical(&gmesh, &layer, &pattern, &params, samples)
            .map_err(PaperError::Triangulation)?;
        let mut rng = ChaCha8Rng::seed_from_u64(params.seed);
        if params.imperfection > 0.0 {
            use rand::Rng;
            let normal = placement.rotation * Vector3::z();
            for p in sp.position.iter_mut() {
                *p += normal * rng.random_range(-params.imperfection..=params.imperfection);
            }
        }
        let fem = FemSystem::new(&sp);
        let mut sim = PaperSim {
            last_targets: vec![None; handles.len()],
            reach_corrections: Vec::new(),
            reach_excess: (0.0, None),
            params,
            pattern,
            layer,
            gmesh,
            sp,
            fem,
            rng,
            wrenches: vec![None; own.len()],
            handles: own,
            held: Vec::new(),
            time: 0.0,
            dt: 0.0,
            gmesh_fresh: false,
            mesh: SurfaceMesh::default(),
            singular: Vec::new(),
            frame: PaperFrameStats::default(),
            frame_start: Vec::new(),
        };
        sim.rebuild_outputs();
        Ok(sim)
    }

    /// The displayed mesh: S_P (sec. 4: "S_P ... as the visual representation"), its
    /// S_G rulings and creases as index pairs, regions per vertex, pattern coordinates.
    pub fn mesh(&self) -> &SurfaceMesh {
        &self.mesh
    }
    pub fn singular_points(&self) -> &[SingularPoint] {
        &self.singular
    }
    pub fn geometric_layer(&self) -> &GeometricLayer {
        &self.layer
    }
    pub fn physical_mesh(&self) -> &PhysicalMesh {
        &self.sp
    }
    pub fn pattern(&self) -> &Pattern {
        &self.pattern
    }
    /// Measurements of the last frame.
    pub fn frame_stats(&self) -> &PaperFrameStats {
        &self.frame
    }
    /// Energies of the current state, J.
    pub fn energies(&self) -> Energies {
        let e = &self.frame.fem.energies;
        Energies {
            kinetic: e.kinetic,
            elastic: e.stretching + e.bending,
            gravity: e.gravity,
            external: e.collision + e.springs,
        }
    }

    /// All three steps of one frame (see the module doc).
    pub fn step(
        &mut self,
        dt: f64,
        time: f64,
        index: usize,
        handles: &[HandleSpec],
        targets: &[Pose],
    ) -> ObjectStepReport {
        self.step_with_clock(dt, time, index, handles, targets, &NoClock)
    }

    /// [`PaperSim::step`] with each phase run inside `clock` (the edge times them).
    pub fn step_with_clock(
        &mut self,
        dt: f64,
        time: f64,
        index: usize,
        handles: &[HandleSpec],
        targets: &[Pose],
        clock: &dyn PhaseClock,
    ) -> ObjectStepReport {
        let mut fem = FemReport::default();
        clock.time(Some(index), Phase::Simulation, &mut || {
            fem = self.simulate(dt, time, handles, targets)
        });
        clock.time(Some(index), Phase::Remesh, &mut || self.remesh());
        clock.time(Some(index), Phase::Isometry, &mut || self.track());
        self.report(&fem)
    }

    fn report(&self, fem: &FemReport) -> ObjectStepReport {
        let mut violation: f64 = 0.0;
        for (m, target) in &self.held {
            if let Some(v) = self.vertex_at(m) {
                violation = violation.max((self.sp.position[v] - target).norm());
            }
        }
        // a target out of the sheet's reach counts as far as it was moved
        let (excess, excess_handle) = self.reach_excess;
        let violation_handle = if excess > violation {
            violation = excess;
            excess_handle
        } else {
            None
        };
        ObjectStepReport {
            iterations: fem.iterations,
            outer_iterations: 1,
            converged: fem.converged,
            kept_previous_state: fem.failed,
            energies: self.energies(),
            isometry_error: self.mesh.isometry_error(),
            constraint_violation: violation,
            violation_handle,
            singular_points: self.singular.len(),
            work_bound: fem.handle_work,
            contact: None,
        }
    }

    pub(super) fn vertex_at(&self, m: &Point2) -> Option<usize> {
        self.sp.material.iter().position(|x| (x - m).norm() < 1e-9)
    }

    /// The hard constraints of the handles at time `time`: each active handle holds its
    /// grasp vertex (the axes it holds) and, unless its orientation is free, the tangent
    /// plane through two neighbouring vertices placed rigidly in the gripper frame
    /// (sec. 4). Returns (dirichlet, springs, held points for the isometry step).
    fn handle_constraints(&self) -> (Vec<Dirichlet>, Vec<Spring>, Vec<(Point2, Point3)>) {
        let mut dirichlet = Vec::new();
        let mut springs = Vec::new();
        let mut held = Vec::new();
        for (k, h) in self.handles.iter().enumerate() {
            let Some(target) = self.grasp_frame(h) else {
                continue;
            };
            let Some(v) = self
                .sp
                .material
                .iter()
                .position(|x| (x - h.material).norm() < 1e-9)
            else {
                continue;
            };
            // moved onto the reachable set as a whole: the tangent plane keeps its
            // place relative to the grasp point
            let correction = self.reach_corrections.get(k).copied().unwrap_or_default();
            let target = Translation3::from(correction) * target;
            let p = Point3::from(target.translation.vector);
            for axis in 0..3 {
                if h.axes[axis] {
                    dirichlet.push(Dirichlet {
                        vertex: v as u32,
                        axis,
                        value: p[axis],
                    });
                }
            }
            if h.axes.iter().all(|&a| a) {
                held.push((h.material, p));
            }
            if h.orientation == OrientationMode::Free {
                continue;
            }
            for n in tangent_neighbours(&self.sp, v) {
                let off = self.sp.material[n] - h.material;
                let q = target * Point3::new(off.x, off.y, 0.0);
                match h.orientation {
                    OrientationMode::Full => {
                        for axis in 0..3 {
                            dirichlet.push(Dirichlet {
                                vertex: n as u32,
                                axis,
                                value: q[axis],
                            });
                        }
                        held.push((self.sp.material[n], q));
                    }
                    OrientationMode::Normal { stiffness } => springs.push(Spring {
                        vertex: n as u32,
                        target: q,
                        stiffness: stiffness / off.norm_squared().max(1e-12),
                    }),
                    OrientationMode::Free => {}
                }
            }
        }
        (dirichlet, springs, held)
    }

    /// The corrections that make this frame's targets reachable by an isometric sheet
    /// ([`super::reach`]): among the active handles that hold all three axes of their
    /// grasp point (one that holds fewer leaves the sheet a way out).
    fn update_reach(&mut self) {
        let mut index = Vec::new();
        let mut points = Vec::new();
        for (k, h) in self.handles.iter().enumerate() {
            if !h.axes.iter().all(|&a| a) {
                continue;
            }
            if let Some(target) = self.grasp_frame(h) {
                index.push(k);
                points.push(HeldTarget {
                    material: h.material,
                    target: Point3::from(target.translation.vector),
                });
            }
        }
        let reach = reachable(&points);
        self.reach_corrections = vec![Vector3::zeros(); self.handles.len()];
        for (&k, c) in index.iter().zip(&reach.corrections) {
            self.reach_corrections[k] = *c;
        }
        self.reach_excess = (
            reach.excess,
            reach.worst.map(|i| self.handles[index[i]].world),
        );
    }

    /// Step 1 (sec. 4): move the handles to `targets` (world handle order) and relax
    /// S_P by one implicit step of `dt` s ending at `time` s.
    pub fn simulate(
        &mut self,
        dt: f64,
        time: f64,
        _handles: &[HandleSpec],
        targets: &[Pose],
    ) -> FemReport {
        self.time = time;
        // `targets` are finite: the world keeps a handle's last target instead of a
        // non-finite one (see `StepContext::targets`)
        for (slot, t) in self.last_targets.iter_mut().zip(targets) {
            *slot = Some(*t);
        }
        self.frame_start.clone_from(&self.sp.position);
        self.update_reach();
        let (dirichlet, springs, held) = self.handle_constraints();
        self.held = held;
        if !self.fem.matches(&self.sp) {
            self.fem = FemSystem::new(&self.sp);
        }
        let report = implicit_step(
            &mut self.fem,
            &mut self.sp,
            &self.params,
            dt,
            &dirichlet,
            &springs,
            None,
        );
        self.dt = dt;
        self.gmesh_fresh = false;
        self.frame = PaperFrameStats {
            fem: report,
            ..Default::default()
        };
        self.measure_wrenches(&springs);
        report
    }

    /// Step 2 (sec. 5): S_G follows S_P; each compressed flat region (a triangle
    /// compressed by more than epsilon_c) is remeshed once with new rulings, creating
    /// singular vertices where the rulings meet constrained borders.
    pub fn remesh(&mut self) {
        // disjoint borrows: S_P and the pattern are read while the layer changes
        let PaperSim {
            params,
            pattern,
            sp,
            layer,
            rng,
            frame,
            gmesh: kept,
            gmesh_fresh,
            frame_start,
            held,
            ..
        } = self;
        let (params, pattern, sp): (&PaperParams, &Pattern, &PhysicalMesh) = (params, pattern, sp);
        let interp = Interpolator::new(sp, pattern);
        let position = |k: &GVertexKind, m: &Point2| interp.geometric_vertex(k, m);
        let ctx = CrumpleContext {
            pattern,
            params,
            position: &position,
        };
        let Ok(mut gmesh) = GeometricMesh::build(layer, pattern, &position) else {
            *kept = GeometricMesh::default();
            return;
        };
        // the flat regions of this frame, each remeshed at most once (sec. 5.1: "it is
        // applied to each flat region F"); later meshes map back to them by position
        let fold = params
            .split_flat_regions_at_folds
            .then_some(params.flat_angle);
        let mut regions = FrameFlatRegions::new(&gmesh, fold);
        for _ in 0..8 {
            let labels = flat_regions(&gmesh, fold);
            let Some(strain) =
                regions.next_compressed(&gmesh, &labels, params.compression_threshold)
            else {
                break;
            };
            let outcome = crumple_flat_region(&ctx, layer, &gmesh, &labels, &strain, rng);
            let seen = AttemptContext {
                gmesh: &gmesh,
                labels: &labels,
                sp,
                interp: &interp,
                frame_start,
                held,
            };
            frame
                .crumple_attempts
                .push(seen.attempt(&strain, outcome.as_ref().err().copied()));
            let Ok(events) = outcome else {
                continue;
            };
            frame.crumple_events.extend(events);
            match GeometricMesh::build(layer, pattern, &position) {
                Ok(g) => gmesh = g,
                Err(_) => {
                    gmesh = GeometricMesh::default();
                    break;
                }
            }
        }
        *gmesh_fresh = !gmesh.vertices.is_empty();
        *kept = gmesh;
    }

    /// Step 3 (sec. 6): junction points, generalized cones, S_P from S_G, lengths.
    pub fn track(&mut self) {
        let Some((gmesh, sp)) = self.track_structure() else {
            return;
        };
        // the held vertices (handles and their tangent-plane neighbours, found anew in
        // the new S_P) sit at their targets and stay fixed
        let mut fixed = vec![false; sp.material.len()];
        self.sp = sp;
        let (_, _, held) = self.handle_constraints();
        for (m, p) in &held {
            if let Some(v) = self.vertex_at(m) {
                self.sp.position[v] = *p;
                fixed[v] = true;
            }
        }
        self.held = held;
        self.frame.isometry = match self.params.length_restoration {
            LengthRestoration::Paper => {
                restore_lengths(&mut self.sp, &fixed, self.params.isometry_max_iterations)
            }
            LengthRestoration::StrainLimit => self.limit_strains(&fixed),
        };
        self.gmesh = gmesh;
        // S_G vertices are the first S_P vertices: their final positions
        for (v, g) in self.gmesh.vertices.iter_mut().enumerate() {
            g.position = self.sp.position[v];
        }
        self.rebuild_outputs();
    }

    /// Step 3(h), ours ([`LengthRestoration::StrainLimit`]): every edge of S_P within
    /// `strain_limit` of its pattern length, `fixed` vertices (the held ones) still.
    /// The limit alone leaves what the FEM then sees as energy (a bend pushed into a
    /// few short edges, caps of the old S_P): a relaxation, one implicit step from
    /// rest of the FEM's own energy with the limit as a penalty and the handles held,
    /// lowers it; the limit once more removes the excess the penalty let through.
    /// Velocities are the interpolated ones: the restoration moves positions only.
    fn limit_strains(&mut self, fixed: &[bool]) -> IsometryReport {
        const ITERATIONS: u32 = 50;
        const RELAXATION_ITERATIONS: u32 = 6;
        let limit = self.params.strain_limit;
        let before = mean_length_error(&self.sp);
        let first = limit_strains(&mut self.sp, fixed, limit, ITERATIONS);
        if self.dt > 0.0 {
            let velocity = vec![Vector3::zeros(); self.sp.material.len()];
            let velocity = std::mem::replace(&mut self.sp.velocity, velocity);
            let (dirichlet, springs, _) = self.handle_constraints();
            if !self.fem.matches(&self.sp) {
                self.fem = FemSystem::new(&self.sp);
            }
            let penalty = StrainLimit {
                limit,
                stiffness: self.params.strain_limit_stiffness,
            };
            // a few Newton iterations: the relaxation smooths what the limit handed
            // over, it need not converge (6, against the FEM's then 20, met the stress
            // suite's energy bound on 59 of 60 runs, 2026-12-04)
            let params = PaperParams {
                newton_max_iterations: RELAXATION_ITERATIONS,
                ..self.params.clone()
            };
            implicit_step(
                &mut self.fem,
                &mut self.sp,
                &params,
                self.dt,
                &dirichlet,
                &springs,
                Some(penalty),
            );
            // a failed relaxation keeps the positions; the second limit applies anyway
            self.sp.velocity = velocity;
        }
        let last = limit_strains(&mut self.sp, fixed, limit, ITERATIONS);
        IsometryReport {
            iterations: first.iterations + last.iterations,
            length_error_before: before,
            length_error_after: mean_length_error(&self.sp),
            strain_before: first.strain_before,
            strain_after: last.strain_after,
            ..Default::default()
        }
    }

    /// Step 3 (e)-(g): junction points and generalized cones update the structure
    /// from S_G's mesh (step 2's, or built anew), then S_P is rebuilt from it with
    /// positions and velocities interpolated from the current S_P. Returns S_G's mesh
    /// and the new S_P; None (S_G's mesh left empty) when the structure gives no mesh.
    fn track_structure(&mut self) -> Option<(GeometricMesh, PhysicalMesh)> {
        // disjoint borrows: the current S_P is read while the layer changes
        let PaperSim {
            params,
            pattern,
            sp: old,
            layer,
            frame,
            gmesh: kept,
            gmesh_fresh,
            ..
        } = self;
        let (params, pattern, old): (&PaperParams, &Pattern, &PhysicalMesh) =
            (params, pattern, old);
        let interp = Interpolator::new(old, pattern);
        let position = |k: &GVertexKind, m: &Point2| interp.geometric_vertex(k, m);
        let ctx = CrumpleContext {
            pattern,
            params,
            position: &position,
        };
        // the mesh of S_G that step 2 left (same structure, same S_P positions)
        let mut gmesh = std::mem::take(kept);
        if !std::mem::take(gmesh_fresh) || gmesh.vertices.is_empty() {
            gmesh = GeometricMesh::build(layer, pattern, &position).ok()?;
        }
        let (report, changed) = update_junctions(&ctx, layer, &gmesh);
        frame.junctions = report;
        if let Some(g) = changed {
            gmesh = g;
        }
        let (report, changed) = fit_cones(&ctx, layer, &gmesh);
        frame.cones = report;
        if let Some(g) = changed {
            gmesh = g;
        }
        let curve = |s: f64| interp.boundary_position(s);
        let at = |m: &Point2| interp.position(m);
        let placement = match params.length_restoration {
            LengthRestoration::Paper => Placement::OnGeometricLayer(&curve),
            LengthRestoration::StrainLimit => Placement::Interpolated(&at),
        };
        let mut sp = build_physical(&gmesh, layer, pattern, params, placement).ok()?;
        for (v, m) in sp.velocity.iter_mut().zip(&sp.material) {
            *v = interp.velocity(m);
        }
        Some((gmesh, sp))
    }

    /// The target of world handle `h` this frame (None before its first).
    pub(super) fn last_target(&self, h: usize) -> Option<Pose> {
        self.last_targets.get(h).copied().flatten()
    }

    /// The display mesh and singular points after S_P changed outside a frame.
    pub(super) fn rebuild_display(&mut self) {
        self.rebuild_outputs();
    }

    /// Display mesh, singular points, frame statistics from S_P and S_G.
    fn rebuild_outputs(&mut self) {
        let sp = &self.sp;
        // copied into the display mesh's own buffers (clone_from reuses them: no
        // allocation per frame once the mesh has reached its size)
        let mesh = &mut self.mesh;
        mesh.vertices.clone_from(&sp.position);
        mesh.triangles.clone_from(&sp.triangles);
        mesh.material.clone_from(&sp.material);
        mesh.rulings.clone_from(&sp.rulings);
        mesh.regions.clone_from(&sp.region);
        self.singular = self
            .layer
            .singular
            .iter()
            .filter_map(|s| {
                let v = sp
                    .material
                    .iter()
                    .position(|m| (m - s.material).norm() < 1e-9)?;
                Some(SingularPoint {
                    id: s.id,
                    position: sp.position[v],
                    material: s.material,
                })
            })
            .collect();
        self.frame.edges = self.mesh.edge_strain();
        self.frame.triangles = sp.triangles.len();
        self.frame.geometric_triangles = self
            .gmesh
            .faces
            .iter()
            .filter(|f| f.kind == FaceKind::Flat)
            .count();
        self.frame.curved_regions = self.layer.regions.len();
    }
}

/// Two neighbours of vertex `v` spanning the tangent plane best (most orthogonal
/// pattern offsets).
pub(super) fn tangent_neighbours(sp: &PhysicalMesh, v: usize) -> Vec<usize> {
    let mut nbrs: Vec<usize> = sp
        .edges
        .iter()
        .filter_map(|[a, b]| {
            if *a as usize == v {
                Some(*b as usize)
            } else if *b as usize == v {
                Some(*a as usize)
            } else {
                None
            }
        })
        .collect();
    nbrs.sort_unstable();
    let mut best: Option<(f64, usize, usize)> = None;
    for (i, &a) in nbrs.iter().enumerate() {
        for &b in &nbrs[i + 1..] {
            let da = (sp.material[a] - sp.material[v]).normalize();
            let db = (sp.material[b] - sp.material[v]).normalize();
            let cross = (da.x * db.y - da.y * db.x).abs();
            if best.is_none_or(|(c, _, _)| cross > c + 1e-12) {
                best = Some((cross, a, b));
            }
        }
    }
    best.map(|(_, a, b)| vec![a, b]).unwrap_or_default()
}

impl ObjectSim for PaperSim {
    fn kind(&self) -> &'static str {
        "paper"
    }
    fn solver_name(&self) -> &'static str {
        "paper_newton"
    }
    fn step(&mut self, ctx: &StepContext<'_>) -> ObjectStepReport {
        self.step_with_clock(
            ctx.dt,
            ctx.time,
            ctx.index,
            ctx.handles,
            ctx.targets,
            ctx.clock,
        )
    }
    fn mesh(&self) -> &SurfaceMesh {
        PaperSim::mesh(self)
    }
    fn singular_points(&self) -> &[SingularPoint] {
        PaperSim::singular_points(self)
    }
    fn energies(&self) -> Energies {
        PaperSim::energies(self)
    }
    /// `world_from_material_point`: the pose of pattern point `m` on the flat sheet at
    /// its placement (the default handle target).
    fn material_pose(&self, m: &Point2) -> Pose {
        self.params.placement * Pose::translation(m.x, m.y, 0.0)
    }
    fn handles_changed(&mut self, index: usize, handles: &[HandleSpec]) {
        self.rebuild_handles(index, handles);
    }
    fn graspable(&self, m: &Point2) -> Result<Point2, String> {
        self.graspable_point(m)
    }
    fn nearest_graspable(&self, p: &Point3) -> Option<SurfacePoint> {
        self.nearest_boundary_point(p)
    }
    fn handle_wrench(&self, handle: usize) -> Option<Wrench> {
        self.wrench_on(handle)
    }
    fn compression_stats(&self) -> Option<CompressionStats> {
        let f = &self.frame;
        Some(CompressionStats {
            edges: f.edges,
            triangles: f.triangles,
        })
    }
    fn clone_box(&self) -> Box<dyn ObjectSim> {
        Box::new(self.clone())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::{Motion, Trajectory};

    /// Handles at the middle of the left and right sides of a 10 cm sheet, tangent
    /// planes held; they move towards each other by `squeeze` (m) and turn by `tilt`
    /// (rad) about the y axis over 1 s.
    pub(crate) fn two_handles(squeeze: f64, tilt: f64) -> Vec<HandleSpec> {
        let mk = |name: &str, u: f64, sign: f64| HandleSpec {
            orientation: OrientationMode::Full,
            ..HandleSpec::new(
                name,
                0,
                Point2::new(u, 0.05),
                Trajectory {
                    initial: Pose::translation(u, 0.05, 0.0),
                    motions: vec![Motion {
                        start: 0.0,
                        end: 1.0,
                        translation: Vector3::new(sign * squeeze / 2.0, 0.0, 0.0),
                        axis: Vector3::y(),
                        angle: -sign * tilt,
                    }],
                },
            )
        };
        vec![mk("left", 0.0, 1.0), mk("right", 0.1, -1.0)]
    }

    pub(crate) fn run(
        sim: &mut PaperSim,
        handles: &[HandleSpec],
        steps: usize,
        dt: f64,
    ) -> Vec<ObjectStepReport> {
        (1..=steps)
            .map(|k| {
                let t = k as f64 * dt;
                let targets: Vec<Pose> = handles.iter().map(|h| h.trajectory.pose_at(t)).collect();
                sim.step(dt, t, 0, handles, &targets)
            })
            .collect()
    }

    /// The |y| component of the ruling passing nearest the centre of the sheet, and the
    /// median of its region's, after `steps` frames of `dt` s of [`two_handles`].
    fn middle_ruling(restoration: LengthRestoration, steps: usize, dt: f64) -> (f64, f64) {
        let handles = two_handles(0.01, 0.6);
        let params = PaperParams {
            length_restoration: restoration,
            ..PaperParams::default()
        };
        let mut sim = PaperSim::new(params, &handles, 0).unwrap();
        assert!(sim.geometric_layer().regions.is_empty());
        let reports = run(&mut sim, &handles, steps, dt);
        assert!(reports.iter().all(|r| r.converged), "{reports:?}");
        assert!(sim.mesh().is_finite());
        let layer = sim.geometric_layer();
        assert!(!layer.regions.is_empty(), "a curved region appears");
        let centre = Point2::new(0.05, 0.05);
        let ends = |r: &super::super::geometric::Ruling| {
            [r.a, r.b].map(|e| layer.endpoint_material(sim.pattern(), &e))
        };
        let direction = |r: &super::super::geometric::Ruling| {
            let [p, q] = ends(r);
            (q - p).normalize()
        };
        let distance = |r: &super::super::geometric::Ruling| {
            let [p, q] = ends(r);
            super::super::pattern::point_segment(&centre, &p, &q).0
        };
        let (region, ruling) = layer
            .regions
            .iter()
            .flat_map(|g| g.rulings.iter().map(move |r| (g, r)))
            .min_by(|a, b| distance(a.1).total_cmp(&distance(b.1)))
            .unwrap();
        assert!(distance(ruling) < 0.01, "a ruling crosses the middle");
        let mut dy: Vec<f64> = region
            .rulings
            .iter()
            .map(|r| direction(r).y.abs())
            .collect();
        dy.sort_by(f64::total_cmp);
        (direction(ruling).y.abs(), median(&dy))
    }

    fn median(sorted: &[f64]) -> f64 {
        0.5 * (sorted[(sorted.len() - 1) / 2] + sorted[sorted.len() / 2])
    }

    #[test]
    fn a_compressed_flat_sheet_grows_a_curved_region() {
        // The rulings of a sheet bent about y run along y (v_perp of the compression)
        // where the sheet bends as a cylinder: in the middle, away from the handles.
        // Not every ruling does: the first compression analysis measures the strain of
        // a coarse S_G triangle between both handle anchors and a corner (sec. 5.1,
        // "standard method based on stretch tensors" on the triangles of F), whose
        // v_perp leans ~20 deg; the next frames' rulings near the pinched handles
        // conflict with that band and make singular vertices (sec. 5.2), and the
        // border rulings of the band then end at the d-cones' fans (a band ruling
        // shares its end with a cone ruling, fig. 6d): those legitimately lean. Which
        // ruling ends up in the middle changes with the frame rate (one frame rate is
        // one sample of a chaotic process: at 26 frames/s the middle ruling leans 31
        // deg with the paper's restoration, at 30 frames/s 4 deg), so: the median over
        // nine frame rates of the ruling passing nearest the sheet's centre, and of
        // its region's median.
        let rates = [26.0, 27.0, 28.0, 29.0, 30.0, 31.0, 32.0, 33.0, 34.0];
        let sample = |restoration| {
            let (mut mid, mut region): (Vec<f64>, Vec<f64>) = rates
                .iter()
                .map(|r| middle_ruling(restoration, 15, 1.0 / r))
                .unzip();
            mid.sort_by(f64::total_cmp);
            region.sort_by(f64::total_cmp);
            (median(&mid), median(&region))
        };
        // the paper's length restoration: within 18 deg (0.968 and 0.960 on
        // 2026-12-04)
        let (mid, region) = sample(LengthRestoration::Paper);
        assert!(mid > 0.95 && region > 0.95, "paper: {mid} {region}");
        // the strain limit keeps the first band's lean in the middle more often: 24
        // deg (0.912 and 0.933 on 2026-12-04; docs/paper_simulator.md, known gaps);
        // this guards it from growing past 28 deg
        let (mid, region) = sample(LengthRestoration::StrainLimit);
        assert!(mid > 0.88 && region > 0.88, "strain limit: {mid} {region}");
    }
}
