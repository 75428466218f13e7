//! Whole-run statistics (`run --stats OUT.json`): the contract other tools and checks
//! read. Medians and percentiles over steps; SI units with the unit in the key name.

use serde::Serialize;

use crate::geometry::EdgeStrain;
use crate::sim::{CompressionStats, ObjectSim, StepReport, World};

#[derive(Clone, Debug, Default, Serialize)]
pub struct Percentiles {
    pub median: f64,
    pub p95: f64,
    pub max: f64,
}

#[derive(Clone, Debug, Default, Serialize)]
pub struct MedianOnly {
    pub median: f64,
}

#[derive(Clone, Debug, Default, Serialize)]
pub struct SolverStats {
    pub kind: String,
    pub iterations_median: f64,
    pub outer_iterations_median: f64,
    pub unconverged_steps: usize,
    /// Steps whose result was not finite and the previous state was kept.
    pub rejected_steps: usize,
}

#[derive(Clone, Debug, Default, Serialize)]
pub struct ObjectFinal {
    pub name: String,
    pub vertices: Vec<[f64; 3]>,
    pub triangles: Vec<[u32; 3]>,
    pub material_vertices: Vec<[f64; 2]>,
    /// The object's named reduced coordinates (ribbons: `crease_direction`,
    /// `bending_angle`), one key each.
    #[serde(flatten)]
    pub coordinates: Coordinates,
    pub singular_points: Vec<[f64; 3]>,
}

/// Named coordinate vectors, written as one JSON key each in this order.
#[derive(Clone, Debug, Default)]
pub struct Coordinates(pub Vec<(&'static str, Vec<f64>)>);

impl Serialize for Coordinates {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        serializer.collect_map(self.0.iter().map(|(k, v)| (k, v)))
    }
}

#[derive(Clone, Debug, Default, Serialize)]
pub struct FinalState {
    /// Simulation time of the final state, s.
    pub time: f64,
    pub objects: Vec<ObjectFinal>,
    /// Every handle: what it holds and what it feels.
    pub handles: Vec<HandleFinal>,
}

/// A handle at the end of a run.
#[derive(Clone, Debug, Default, Serialize)]
pub struct HandleFinal {
    pub name: String,
    /// Whether it holds `object` at `material_point`.
    pub attached: bool,
    /// The object it holds (or held last).
    pub object: String,
    /// m, in the object's flat pattern.
    pub material_point: [f64; 2],
    /// What the object exerts on the gripper in the last step, in the scene frame: the
    /// force, N, and the torque about the grasp point, N m (absent while open, and
    /// before a step).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub force: Option<[f64; 3]>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub torque: Option<[f64; 3]>,
}

#[derive(Clone, Debug, Default, Serialize)]
pub struct EnergyStats {
    /// Total energy (kinetic + elastic + gravity + external) at the start and the
    /// end, and its maximum over the run, J.
    pub initial: f64,
    pub last: f64,
    pub max: f64,
}

/// The contact stage over a run (present only when the scene has one).
#[derive(Clone, Debug, Default, Serialize)]
pub struct ContactStats {
    /// Most active contacts in one step.
    pub contacts_max: usize,
    /// Most constraints (impact-zone size) in one step.
    pub constraints_max: usize,
    /// Detection/response rounds per step: median and max.
    pub iterations_median: f64,
    pub iterations_max: u32,
    /// Active-set changes of the dual QP per step, median.
    pub qp_iterations_median: f64,
    /// Steps the round limit stopped before collision-free.
    pub unresolved_steps: usize,
    /// Largest penetration of the optimizer's predictions X~ (before the stage), m.
    pub predicted_penetration_max: f64,
    /// Developability error after contact: the largest |X^{n+1} - X~^{n+1}| (how far
    /// the stage moved a vertex off the developable prediction), m; max over the run
    /// and the median over steps.
    pub correction_max: f64,
    pub correction_median: f64,
    /// Triangles the stage flipped (normal turned by more than 90 degrees against X~)
    /// or made degenerate (area below a tenth), summed over the steps (Pan et al. fig.
    /// 6: the plain closeness distorts, the stiff one does not), and the most in one
    /// step.
    pub flipped_triangles: usize,
    pub degenerate_triangles: usize,
    pub distorted_triangles_max: usize,
    /// Contact inside the steps with several bodies (docs/contact_barrier.md, "Several
    /// ribbons"), summed over the run: body steps taken side by side with another, and
    /// body steps taken again (after meeting one it did not wait for, after one it waited
    /// for stepped again, or held back by where a later one started).
    pub side_by_side: usize,
    pub stepped_again: usize,
}

/// The `--stats` JSON.
#[derive(Clone, Debug, Default, Serialize)]
pub struct RunStats {
    pub scene: String,
    /// s
    pub dt: f64,
    pub steps: usize,
    /// Simulated time, s.
    pub duration: f64,
    /// Every state finite.
    pub finite: bool,
    pub step_ms: Percentiles,
    pub solver: SolverStats,
    /// One objective + gradient evaluation (adjoint), microseconds.
    pub gradient_us: MedianOnly,
    pub isometry_error_max: f64,
    /// m
    pub constraint_violation_max: f64,
    pub singular_points_max: usize,
    pub energy: EnergyStats,
    /// Wall time of the contact stage per step, ms (0 without a contact stage).
    pub contact_ms: MedianOnly,
    /// Largest penetration depth over the run, m: the overlap of thickened surfaces
    /// left after the contact stage (ribbon mid-surface closer than thickness/2 to a
    /// collider or thickness to another ribbon), 0 when none.
    pub penetration_max: f64,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub contact: Option<ContactStats>,
    /// Wall time of the whole run, s.
    pub wall_s: f64,
    /// Paper objects (Schreck et al. table IV): mean over frames of the mean over S_P
    /// edges of max(0, rest - length)/rest, %; the final frame, which table IV
    /// measures, is `edge_strain.final`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub compression_mean_pct: Option<f64>,
    /// Paper objects: mean over frames of the share of S_P edges compressed by more
    /// than 1 %, %.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub compressed_edges_pct: Option<f64>,
    /// Paper objects: edge strains of S_P against the pattern (compression as table IV,
    /// and stretch), per frame, on the final frame, as the maximum over frames and as
    /// the mean over frames.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub edge_strain: Option<EdgeStrainStats>,
    /// Paper objects (table V, N_t): mean over frames of the S_P triangle count.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub triangles_mean: Option<f64>,
    /// Paper objects: singular vertices at the end (they persist).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub singular_vertices: Option<usize>,
    /// Paper objects: the first singular vertex created (fig. 17).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub first_singular_point: Option<FirstSingular>,
    /// Paper objects (table V): median wall time of each phase of a frame, ms.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub phase_ms: Option<PhaseMs>,
    #[serde(rename = "final")]
    pub final_state: FinalState,
}

/// Edge strains of one frame (the serializable counterpart of [`EdgeStrain`]), %:
/// strain = (l - l_rest) / l_rest per S_P edge.
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct EdgeStrainPct {
    /// Mean of max(0, -strain) (table IV's mean compression).
    pub compression_mean_pct: f64,
    /// Share of edges with strain < -1 % (table IV).
    pub compressed_edges_pct: f64,
    /// Mean of |strain|.
    pub strain_mean_pct: f64,
    /// Largest |strain|.
    pub strain_max_pct: f64,
    /// Largest stretch max(0, strain).
    pub stretch_max_pct: f64,
    /// Share of edges with |strain| > 1 %.
    pub strained_edges_pct: f64,
}

impl EdgeStrainPct {
    fn of(e: &EdgeStrain) -> Self {
        EdgeStrainPct {
            compression_mean_pct: e.compression_mean_pct,
            compressed_edges_pct: e.compressed_edges_pct,
            strain_mean_pct: e.strain_mean_pct,
            strain_max_pct: e.strain_max_pct,
            stretch_max_pct: e.stretch_max_pct,
            strained_edges_pct: e.strained_edges_pct,
        }
    }
    fn fields_mut(&mut self) -> [&mut f64; 6] {
        [
            &mut self.compression_mean_pct,
            &mut self.compressed_edges_pct,
            &mut self.strain_mean_pct,
            &mut self.strain_max_pct,
            &mut self.stretch_max_pct,
            &mut self.strained_edges_pct,
        ]
    }
    fn fields(mut self) -> [f64; 6] {
        self.fields_mut().map(|x| *x)
    }
    /// Several sheets in one frame: shares and means averaged, maxima the largest.
    fn combine(sheets: &[EdgeStrain]) -> Self {
        let n = sheets.len().max(1) as f64;
        let mut out = EdgeStrainPct::default();
        for e in sheets {
            let e = EdgeStrainPct::of(e);
            out.compression_mean_pct += e.compression_mean_pct / n;
            out.compressed_edges_pct += e.compressed_edges_pct / n;
            out.strain_mean_pct += e.strain_mean_pct / n;
            out.strained_edges_pct += e.strained_edges_pct / n;
            out.strain_max_pct = out.strain_max_pct.max(e.strain_max_pct);
            out.stretch_max_pct = out.stretch_max_pct.max(e.stretch_max_pct);
        }
        out
    }
}

/// One frame's edge strains with its simulation time.
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct FrameStrain {
    /// s
    pub time: f64,
    #[serde(flatten)]
    pub strain: EdgeStrainPct,
}

/// Edge strains over a run, each field taken over the frames (the step-0 flat sheet
/// is not a frame).
#[derive(Clone, Debug, Default, Serialize)]
pub struct EdgeStrainStats {
    /// The final frame (what a figure of the paper shows; compare with table IV).
    #[serde(rename = "final")]
    pub final_frame: EdgeStrainPct,
    /// Each field's maximum over frames.
    pub max: EdgeStrainPct,
    /// Each field's mean over frames.
    pub time_mean: EdgeStrainPct,
    pub frames: Vec<FrameStrain>,
}

impl EdgeStrainStats {
    fn summarize(frames: Vec<FrameStrain>) -> Self {
        let mut max = EdgeStrainPct::default();
        let mut mean = EdgeStrainPct::default();
        let n = frames.len().max(1) as f64;
        for f in &frames {
            for ((m, a), x) in max
                .fields_mut()
                .into_iter()
                .zip(mean.fields_mut())
                .zip(f.strain.fields())
            {
                *m = m.max(x);
                *a += x / n;
            }
        }
        EdgeStrainStats {
            final_frame: frames.last().map(|f| f.strain).unwrap_or_default(),
            max,
            time_mean: mean,
            frames,
        }
    }
}

/// Median wall time of the phases of a paper frame, ms.
#[derive(Clone, Debug, Default, Serialize)]
pub struct PhaseMs {
    /// Step 1: the FEM step on S_P.
    pub simulation: f64,
    /// Step 2: compression analysis, rulings, singular vertices.
    pub remesh: f64,
    /// Step 3: junctions, cones, S_P rebuild, length restoration.
    pub isometry: f64,
}

/// Where and when the first singular vertex appeared.
#[derive(Clone, Debug, Default, Serialize)]
pub struct FirstSingular {
    /// Simulation time, s.
    pub time: f64,
    /// Pattern position, m.
    pub material: [f64; 2],
    /// World position, m.
    pub position: [f64; 3],
}

/// Median, 95th percentile and max of a sample (0 for an empty one).
pub fn percentiles(values: &[f64]) -> Percentiles {
    if values.is_empty() {
        return Percentiles::default();
    }
    let mut v = values.to_vec();
    v.sort_by(f64::total_cmp);
    let at = |p: f64| v[((p * (v.len() - 1) as f64).round() as usize).min(v.len() - 1)];
    Percentiles {
        median: at(0.5),
        p95: at(0.95),
        max: v[v.len() - 1],
    }
}

/// Accumulates step reports into [`RunStats`].
#[derive(Clone, Debug, Default)]
pub struct StatsCollector {
    step_ms: Vec<f64>,
    iterations: Vec<f64>,
    outer: Vec<f64>,
    paper_strain: Vec<FrameStrain>,
    paper_triangles: Vec<f64>,
    phase_ms: [Vec<f64>; 3],
    contact_ms: Vec<f64>,
    contact_rounds: Vec<f64>,
    contact_qp: Vec<f64>,
    contact_correction: Vec<f64>,
    pub stats: RunStats,
}

impl StatsCollector {
    pub fn new(scene: &str, world: &World, solver_kind: &str) -> Self {
        let mut c = StatsCollector::default();
        c.stats.scene = scene.to_string();
        c.stats.dt = world.dt();
        c.stats.finite = true;
        c.stats.solver.kind = solver_kind.to_string();
        let e = total_energy(world);
        c.stats.energy = EnergyStats {
            initial: e,
            last: e,
            max: e,
        };
        c
    }

    pub fn record(&mut self, world: &World, report: &StepReport, step_ms: f64) {
        let s = &mut self.stats;
        s.steps += 1;
        self.step_ms.push(step_ms);
        let its: u32 = report.objects.iter().map(|o| o.iterations).sum();
        let outer: u32 = report
            .objects
            .iter()
            .map(|o| o.outer_iterations)
            .max()
            .unwrap_or(0);
        self.iterations.push(its as f64);
        self.outer.push(outer as f64);
        for (i, o) in report.objects.iter().enumerate() {
            if !o.converged {
                s.solver.unconverged_steps += 1;
            }
            if o.kept_previous_state {
                s.solver.rejected_steps += 1;
            }
            s.isometry_error_max = s.isometry_error_max.max(o.isometry_error);
            s.constraint_violation_max = s.constraint_violation_max.max(o.constraint_violation);
            s.singular_points_max = s.singular_points_max.max(o.singular_points);
            s.finite &= world.mesh(i).is_finite() && o.energies.total().is_finite();
        }
        // paper objects (those measuring their compression): per-frame measurements
        // averaged over the sheets
        let papers: Vec<(&dyn ObjectSim, CompressionStats)> = world
            .objects()
            .iter()
            .filter_map(|o| Some((o.as_ref(), o.compression_stats()?)))
            .collect();
        if !papers.is_empty() {
            let n = papers.len() as f64;
            let f = |g: &dyn Fn(&CompressionStats) -> f64| {
                papers.iter().map(|(_, c)| g(c)).sum::<f64>() / n
            };
            let sheets: Vec<EdgeStrain> = papers.iter().map(|(_, c)| c.edges).collect();
            self.paper_strain.push(FrameStrain {
                time: world.time(),
                strain: EdgeStrainPct::combine(&sheets),
            });
            self.paper_triangles.push(f(&|x| x.triangles as f64));
            if s.first_singular_point.is_none() {
                if let Some(sp) = papers.iter().find_map(|(p, _)| p.singular_points().first()) {
                    s.first_singular_point = Some(FirstSingular {
                        time: world.time(),
                        material: [sp.material.x, sp.material.y],
                        position: [sp.position.x, sp.position.y, sp.position.z],
                    });
                }
            }
            s.singular_vertices = Some(papers.iter().map(|(p, _)| p.singular_points().len()).sum());
        }
        if let Some(c) = &report.contact {
            let r = &c.report;
            self.contact_rounds.push(r.iterations as f64);
            self.contact_qp.push(r.qp_iterations as f64);
            self.contact_correction.push(r.correction_max);
            s.penetration_max = s.penetration_max.max(r.penetration_max);
            let cs = s.contact.get_or_insert_with(ContactStats::default);
            cs.contacts_max = cs.contacts_max.max(r.contacts);
            cs.constraints_max = cs.constraints_max.max(r.constraints);
            cs.iterations_max = cs.iterations_max.max(r.iterations);
            cs.unresolved_steps += usize::from(!r.resolved);
            cs.predicted_penetration_max = cs
                .predicted_penetration_max
                .max(r.predicted_penetration_max);
            cs.correction_max = cs.correction_max.max(r.correction_max);
            cs.flipped_triangles += r.flipped_triangles;
            cs.degenerate_triangles += r.degenerate_triangles;
            cs.distorted_triangles_max = cs
                .distorted_triangles_max
                .max(r.flipped_triangles + r.degenerate_triangles);
            cs.side_by_side += c.side_by_side;
            cs.stepped_again += c.stepped_again;
        }
        let e: f64 = report.objects.iter().map(|o| o.energies.total()).sum();
        s.energy.last = e;
        s.energy.max = s.energy.max.max(e);
        s.duration = world.time();
    }

    /// Wall time of the phases of the last step (simulation, remesh, isometry), ms,
    /// summed over the paper objects.
    pub fn record_phases(&mut self, phase_ms: [f64; 3]) {
        for (v, t) in self.phase_ms.iter_mut().zip(phase_ms) {
            v.push(t);
        }
    }

    /// The wall time of a step's contact stage, ms (measured by the caller around
    /// the contact phase of [`World::step_with_clock`]).
    pub fn record_contact_ms(&mut self, ms: f64) {
        self.contact_ms.push(ms);
    }

    pub fn finish(mut self, world: &World, gradient_us: f64, wall_s: f64) -> RunStats {
        let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len().max(1) as f64;
        if !self.paper_strain.is_empty() {
            let strain = EdgeStrainStats::summarize(std::mem::take(&mut self.paper_strain));
            self.stats.compression_mean_pct = Some(strain.time_mean.compression_mean_pct);
            self.stats.compressed_edges_pct = Some(strain.time_mean.compressed_edges_pct);
            self.stats.edge_strain = Some(strain);
            self.stats.triangles_mean = Some(mean(&self.paper_triangles));
            if !self.phase_ms[0].is_empty() {
                self.stats.phase_ms = Some(PhaseMs {
                    simulation: percentiles(&self.phase_ms[0]).median,
                    remesh: percentiles(&self.phase_ms[1]).median,
                    isometry: percentiles(&self.phase_ms[2]).median,
                });
            }
        }
        self.stats.step_ms = percentiles(&self.step_ms);
        self.stats.solver.iterations_median = percentiles(&self.iterations).median;
        self.stats.solver.outer_iterations_median = percentiles(&self.outer).median;
        self.stats.gradient_us = MedianOnly {
            median: gradient_us,
        };
        self.stats.contact_ms = MedianOnly {
            median: percentiles(&self.contact_ms).median,
        };
        if let Some(cs) = &mut self.stats.contact {
            cs.iterations_median = percentiles(&self.contact_rounds).median;
            cs.qp_iterations_median = percentiles(&self.contact_qp).median;
            cs.correction_median = percentiles(&self.contact_correction).median;
        }
        self.stats.wall_s = wall_s;
        self.stats.final_state = final_state(world);
        self.stats
    }
}

fn total_energy(world: &World) -> f64 {
    world.objects().iter().map(|o| o.energies().total()).sum()
}

/// The final meshes and coordinates.
pub fn final_state(world: &World) -> FinalState {
    let objects = world
        .object_names()
        .iter()
        .enumerate()
        .map(|(i, name)| {
            let mesh = world.mesh(i);
            ObjectFinal {
                name: name.clone(),
                vertices: mesh.vertices.iter().map(|p| [p.x, p.y, p.z]).collect(),
                triangles: mesh.triangles.clone(),
                material_vertices: mesh.material.iter().map(|p| [p.x, p.y]).collect(),
                coordinates: Coordinates(
                    world
                        .object(i)
                        .coordinates()
                        .into_iter()
                        .map(|(name, v)| (name, v.to_vec()))
                        .collect(),
                ),
                singular_points: world
                    .singular_points(i)
                    .iter()
                    .map(|s| [s.position.x, s.position.y, s.position.z])
                    .collect(),
            }
        })
        .collect();
    let handles = world
        .handles()
        .iter()
        .enumerate()
        .map(|(h, spec)| {
            let wrench = world.handle_wrench(h);
            HandleFinal {
                name: spec.name.clone(),
                attached: spec.attached,
                object: world.object_names()[spec.object].clone(),
                material_point: [spec.material_point.x, spec.material_point.y],
                force: wrench.map(|w| [w.force.x, w.force.y, w.force.z]),
                torque: wrench.map(|w| [w.torque.x, w.torque.y, w.torque.z]),
            }
        })
        .collect();
    FinalState {
        time: world.time(),
        objects,
        handles,
    }
}
