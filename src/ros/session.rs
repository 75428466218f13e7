//! A simulation session as the node sees it, without DDS: the scene, the handle inputs,
//! and the messages ("frames") each state produces. The node publishes frames, the
//! recorder writes them, `replay` recomputes and compares them.

use std::time::Instant;

use crate::geometry::{SurfaceMesh, VertexRegion};
use crate::scene::Scene;
use crate::sim::StepReport;

use super::convert::{point, pose};
use super::input::{HandleInput, InputPolicy, Rejection};
use super::msgs::{
    Clock, ColorRGBA, HandleStatus, Header, Marker, MarkerArray, Point, PoseStamped, SimStatus,
    SingularPoint, SingularPoints, Time, Vector3,
};

/// How markers look. Sizes in m.
#[derive(Clone, Debug, PartialEq)]
pub struct MarkerStyle {
    /// Width of the ruling lines, m (default 0.002).
    pub line_width: f64,
    /// Diameter of the singular-point spheres, m (default 0.012).
    pub sphere_diameter: f64,
    /// Vertex colors of flat, curved and singular regions.
    pub flat: ColorRGBA,
    pub curved: ColorRGBA,
    pub singular: ColorRGBA,
    pub ruling: ColorRGBA,
    /// Color of the colliders' markers.
    pub collider: ColorRGBA,
    /// Side of the square drawn for a ground plane, m (default 4).
    pub ground_size: f64,
}

impl Default for MarkerStyle {
    fn default() -> Self {
        MarkerStyle {
            line_width: 0.002,
            sphere_diameter: 0.012,
            flat: ColorRGBA::rgb(0.55, 0.72, 0.92),
            curved: ColorRGBA::rgb(0.96, 0.62, 0.22),
            singular: ColorRGBA::rgb(0.85, 0.1, 0.1),
            ruling: ColorRGBA::rgb(0.2, 0.2, 0.25),
            collider: ColorRGBA {
                r: 0.6,
                g: 0.6,
                b: 0.62,
                a: 0.6,
            },
            ground_size: 4.0,
        }
    }
}

/// Which messages a frame carries.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FrameContent {
    pub markers: bool,
    pub singular_points: bool,
    pub status: bool,
}

/// The messages of one object for one state.
#[derive(Clone, Debug, PartialEq)]
pub struct ObjectFrame {
    /// None when not asked for, or when the mesh is not finite (never published).
    pub markers: Option<MarkerArray>,
    pub singular_points: Option<SingularPoints>,
    pub status: Option<SimStatus>,
}

/// Every message produced by one state of the world (after a step, or step 0).
#[derive(Clone, Debug, PartialEq)]
pub struct Frame {
    /// Simulation time of the state.
    pub stamp: Time,
    pub clock: Clock,
    pub objects: Vec<ObjectFrame>,
    /// The scene's colliders (None when markers are not asked for or the scene has no
    /// colliders).
    pub colliders: Option<MarkerArray>,
}

/// A scene with its handle inputs and counters.
pub struct Session {
    pub scene: Scene,
    pub policy: InputPolicy,
    pub style: MarkerStyle,
    /// Resolved input topic of each handle (reported in status).
    pub handle_topics: Vec<String>,
    inputs: Vec<HandleInput>,
    /// Resets since start.
    pub episode: u32,
    pub paused: bool,
    /// Real-time ticks skipped because the simulation could not keep up.
    pub overrun_ticks: u64,
    /// Publications the node failed to send since start-up (all topics; the node
    /// counts them).
    pub dropped_publications: u64,
    /// Per object: steps whose solver stopped on an iteration limit, and steps whose
    /// result was not finite (rejected, previous state kept), since start-up.
    unconverged_steps: Vec<u64>,
    rejected_steps: Vec<u64>,
    targets: Vec<Option<crate::geometry::Pose>>,
}

impl Session {
    pub fn new(scene: Scene, policy: InputPolicy, handle_topics: Vec<String>) -> Session {
        let n = scene.world.handles().len();
        let objects = scene.world.objects().len();
        Session {
            scene,
            policy,
            style: MarkerStyle::default(),
            handle_topics,
            inputs: vec![HandleInput::default(); n],
            episode: 0,
            paused: false,
            overrun_ticks: 0,
            dropped_publications: 0,
            unconverged_steps: vec![0; objects],
            rejected_steps: vec![0; objects],
            targets: vec![None; n],
        }
    }

    /// Offer a pose received for handle `handle` at `received_ns` (wall clock, ns since
    /// the Unix epoch).
    pub fn offer(
        &mut self,
        handle: usize,
        msg: &PoseStamped,
        received_ns: u64,
    ) -> Result<(), Rejection> {
        self.inputs[handle].offer(&self.policy, msg, received_ns)
    }

    /// Count a failed TF lookup for handle `handle` (its target stays).
    pub fn reject_tf(&mut self, handle: usize) {
        self.inputs[handle].rejected_tf_lookup += 1;
    }

    /// Advance the world one step with the newest targets. Returns the report and the
    /// wall time of the step, s.
    pub fn step(&mut self) -> (StepReport, f64) {
        for (t, input) in self.targets.iter_mut().zip(&self.inputs) {
            *t = input.target;
        }
        let start = Instant::now();
        let report = self.scene.world.step(&self.targets);
        let elapsed = start.elapsed().as_secs_f64();
        for (i, o) in report.objects.iter().enumerate() {
            self.unconverged_steps[i] += u64::from(!o.converged);
            self.rejected_steps[i] += u64::from(o.kept_previous_state);
        }
        (report, elapsed)
    }

    /// Back to t = 0: the world's initial state; handles follow the script until a new
    /// pose arrives (stamps are accepted afresh); counters are kept.
    pub fn reset(&mut self) {
        self.scene.world.reset();
        for i in &mut self.inputs {
            i.clear_target();
        }
        self.episode += 1;
    }

    /// The messages of the current state. `report` is the step that produced it (None
    /// for step 0); `step_duration` its wall time, s.
    pub fn frame(
        &self,
        report: Option<&StepReport>,
        step_duration: f64,
        content: FrameContent,
    ) -> Frame {
        self.frame_of(&self.scene, report, step_duration, content)
    }

    /// [`Session::frame`] of another copy of this session's scene (`run --record`
    /// reads the runner's scene instead of cloning its world into the session each
    /// step): the world's state from `scene`, the inputs and counters from `self`.
    pub fn frame_of(
        &self,
        scene: &Scene,
        report: Option<&StepReport>,
        step_duration: f64,
        content: FrameContent,
    ) -> Frame {
        let world = &scene.world;
        let stamp = Time::from_secs(world.time());
        let header = Header {
            stamp,
            frame_id: scene.frame_id.clone(),
        };
        let objects = world
            .object_names()
            .iter()
            .enumerate()
            .map(|(i, name)| {
                let mesh = world.mesh(i);
                let finite = mesh.is_finite();
                let singular = world.singular_points(i);
                let markers = (content.markers && finite)
                    .then(|| self.markers(name, &header, mesh, singular));
                let singular_points = (content.singular_points && finite).then(|| SingularPoints {
                    header: header.clone(),
                    object_name: name.clone(),
                    points: singular
                        .iter()
                        .filter(|s| {
                            s.position.coords.iter().all(|v| v.is_finite())
                                && s.material.coords.iter().all(|v| v.is_finite())
                        })
                        .map(|s| SingularPoint {
                            id: s.id,
                            position: point(&s.position),
                            material: [s.material.x, s.material.y],
                        })
                        .collect(),
                });
                let status = content
                    .status
                    .then(|| self.status(scene, i, name, &header, report, step_duration));
                ObjectFrame {
                    markers,
                    singular_points,
                    status,
                }
            })
            .collect();
        let colliders = if content.markers {
            self.collider_markers(scene, &header)
        } else {
            None
        };
        Frame {
            stamp,
            clock: Clock { clock: stamp },
            objects,
            colliders,
        }
    }

    fn status(
        &self,
        scene: &Scene,
        object: usize,
        name: &str,
        header: &Header,
        report: Option<&StepReport>,
        step_duration: f64,
    ) -> SimStatus {
        let world = &scene.world;
        let mut s = SimStatus {
            header: header.clone(),
            object_name: name.to_string(),
            scene_name: scene.name.clone(),
            sim_time: world.time(),
            step: world.steps_taken(),
            episode: self.episode,
            dt: world.dt(),
            paused: self.paused,
            step_duration,
            overrun_ticks: self.overrun_ticks,
            dropped_publications: self.dropped_publications,
            unconverged_steps: self.unconverged_steps[object],
            rejected_steps: self.rejected_steps[object],
            ..SimStatus::default()
        };
        match report.and_then(|r| r.objects.get(object)) {
            Some(o) => {
                s.solver_iterations = o.iterations;
                s.outer_iterations = o.outer_iterations;
                s.converged = o.converged;
                s.kept_previous_state = o.kept_previous_state;
                s.kinetic_energy = o.energies.kinetic;
                s.elastic_energy = o.energies.elastic;
                s.gravity_energy = o.energies.gravity;
                s.external_energy = o.energies.external;
                s.total_energy = o.energies.total();
                s.isometry_error = o.isometry_error;
                s.constraint_violation = o.constraint_violation;
                s.singular_point_count = o.singular_points as u32;
            }
            None => {
                // step 0: the initial state
                let e = world.objects()[object].energies();
                s.converged = true;
                s.kinetic_energy = e.kinetic;
                s.elastic_energy = e.elastic;
                s.gravity_energy = e.gravity;
                s.external_energy = e.external;
                s.total_energy = e.total();
                s.isometry_error = world.mesh(object).isometry_error();
                s.singular_point_count = world.singular_points(object).len() as u32;
            }
        }
        let strain = world.mesh(object).edge_strain();
        s.compression_mean_pct = strain.compression_mean_pct;
        s.compressed_edges_pct = strain.compressed_edges_pct;
        s.strain_mean_pct = strain.strain_mean_pct;
        s.strain_max_pct = strain.strain_max_pct;
        s.strained_edges_pct = strain.strained_edges_pct;
        for (h, spec) in world.handles().iter().enumerate() {
            if spec.object != object {
                continue;
            }
            let input = &self.inputs[h];
            let target = input
                .target
                .unwrap_or_else(|| world.scripted_target(h, world.time()));
            let mut hs = HandleStatus {
                name: spec.name.clone(),
                topic: self.handle_topics.get(h).cloned().unwrap_or_default(),
                tf_frame: scene
                    .handle_tf_frames
                    .get(h)
                    .cloned()
                    .flatten()
                    .unwrap_or_default(),
                target: pose(&target),
                ..HandleStatus::default()
            };
            input.fill_status(&mut hs);
            s.rejected_inputs += input.rejected();
            s.handles.push(hs);
        }
        s
    }

    /// Whether the scene has colliders to draw.
    pub fn has_colliders(&self) -> bool {
        !self.scene.world.colliders().is_empty()
    }

    /// One marker per collider, at its current pose (attached colliders follow their
    /// handle's target): the ground as a thin square of `style.ground_size`, boxes,
    /// spheres, capsules (a cylinder and its two end spheres) and triangle meshes.
    fn collider_markers(&self, scene: &Scene, header: &Header) -> Option<MarkerArray> {
        use crate::contact::ColliderShape;
        let world = &scene.world;
        let colliders = world.colliders();
        if colliders.is_empty() {
            return None;
        }
        let style = &self.style;
        let targets = world.current_targets();
        let mut markers = Vec::with_capacity(colliders.len() + 1);
        for (i, c) in colliders.iter().enumerate() {
            let world_from_collider = c.world_pose(targets);
            let mut m = Marker {
                header: header.clone(),
                ns: "colliders".into(),
                id: i as i32,
                action: Marker::ADD,
                pose: pose(&world_from_collider),
                color: style.collider,
                ..Marker::default()
            };
            let uniform = |d: f64| Vector3 { x: d, y: d, z: d };
            match &c.shape {
                ColliderShape::HalfSpace => {
                    // the surface is z = 0 of the collider frame; a 1 mm slab below it
                    m.type_ = Marker::CUBE;
                    let below =
                        world_from_collider * nalgebra::Translation3::new(0.0, 0.0, -0.0005);
                    m.pose = pose(&below);
                    m.scale = Vector3 {
                        x: style.ground_size,
                        y: style.ground_size,
                        z: 0.001,
                    };
                }
                ColliderShape::Cuboid { half_extents } => {
                    m.type_ = Marker::CUBE;
                    m.scale = Vector3 {
                        x: 2.0 * half_extents.x,
                        y: 2.0 * half_extents.y,
                        z: 2.0 * half_extents.z,
                    };
                }
                ColliderShape::Ball { radius } => {
                    m.type_ = Marker::SPHERE;
                    m.scale = uniform(2.0 * radius);
                }
                ColliderShape::Capsule {
                    half_height,
                    radius,
                } => {
                    m.type_ = Marker::CYLINDER;
                    m.scale = Vector3 {
                        x: 2.0 * radius,
                        y: 2.0 * radius,
                        z: 2.0 * half_height,
                    };
                    // the end caps, in the same frame (ids after the colliders')
                    let mut caps = m.clone();
                    caps.id = (colliders.len() + i) as i32;
                    caps.type_ = Marker::SPHERE_LIST;
                    caps.scale = uniform(2.0 * radius);
                    caps.points = [-half_height, *half_height]
                        .iter()
                        .map(|z| Point {
                            x: 0.0,
                            y: 0.0,
                            z: *z,
                        })
                        .collect();
                    markers.push(caps);
                }
                ColliderShape::TriMesh {
                    vertices,
                    triangles,
                } => {
                    m.type_ = Marker::TRIANGLE_LIST;
                    m.scale = uniform(1.0);
                    m.points = triangles
                        .iter()
                        .flat_map(|t| t.iter().map(|&v| point(&vertices[v as usize])))
                        .collect();
                }
            }
            markers.push(m);
        }
        Some(MarkerArray { markers })
    }

    fn markers(
        &self,
        name: &str,
        header: &Header,
        mesh: &SurfaceMesh,
        singular: &[crate::sim::SingularPoint],
    ) -> MarkerArray {
        let style = &self.style;
        let base = |ns: &str, type_: i32, scale: f64, color: ColorRGBA| Marker {
            header: header.clone(),
            ns: format!("{name}/{ns}"),
            id: 0,
            type_,
            action: Marker::ADD,
            scale: Vector3 {
                x: scale,
                y: scale,
                z: scale,
            },
            color,
            ..Marker::default()
        };
        let region_color = |r: VertexRegion| match r {
            VertexRegion::Flat => style.flat,
            VertexRegion::Curved => style.curved,
            VertexRegion::Singular => style.singular,
        };
        let mut surface = base("surface", Marker::TRIANGLE_LIST, 1.0, style.flat);
        surface.points.reserve(mesh.triangles.len() * 3);
        surface.colors.reserve(mesh.triangles.len() * 3);
        for t in &mesh.triangles {
            for &v in t {
                let v = v as usize;
                surface.points.push(point(&mesh.vertices[v]));
                surface.colors.push(
                    mesh.regions
                        .get(v)
                        .map(|r| region_color(*r))
                        .unwrap_or(style.flat),
                );
            }
        }
        let mut rulings = base("rulings", Marker::LINE_LIST, style.line_width, style.ruling);
        for r in &mesh.rulings {
            rulings.points.push(point(&mesh.vertices[r[0] as usize]));
            rulings.points.push(point(&mesh.vertices[r[1] as usize]));
        }
        let mut spheres = base(
            "singular_points",
            Marker::SPHERE_LIST,
            style.sphere_diameter,
            style.singular,
        );
        spheres.points = singular
            .iter()
            .filter(|s| s.position.coords.iter().all(|v| v.is_finite()))
            .map(|s| point(&s.position))
            .collect();
        MarkerArray {
            markers: vec![surface, rulings, spheres],
        }
    }
}
