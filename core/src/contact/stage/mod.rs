//! The contact stage of one time step (Pan et al. algorithm 1, line 5): from the
//! previous collision-free meshes X^n and the reconstructed predictions X~^{n+1} of all
//! ribbons, the closest collision-free meshes X^{n+1}.
//!
//! Rounds of detection and response until collision-free (non-rigid impact zones,
//! Harmon et al. 2008): detect contacts on the motion X^n -> X, add them to the
//! constraint set of this step (constraints are never dropped within a step, only
//! re-linearized when detected again), solve the QP from X~ with all of them, repeat.
//! The QP is split into independent zones (ribbons linked by constraints) and each is
//! solved in its dual (see [`super::qp`]) with the pre-factorized metric of
//! [`super::metric`]. Coulomb friction against colliders is applied to the converged
//! positions, followed by another round of detection and response.
//!
//! Files by job: this one the types, gathering the meshes, the rounds and the report;
//! `build` the construction (checks, meshes, metric factorizations); `zones` the
//! constraint set and the impact-zone QP; `friction` the Coulomb friction.

mod build;
mod friction;
mod zones;

use super::collider::{Collider, ColliderGeometry};
use super::detect::{Contact, DetectInput, Detector, MeshBody, MeshKind};
use super::metric::BodyMetric;
use super::qp::DualActiveSet;
use crate::geometry::{Point3, Pose, Vector3};

/// The closeness measure E(X) of the impact-zone QP.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Closeness {
    /// E = 1/2 ||X - X~||^2 + Σ_e K/2 ||(x_1 - x_2) - (x~_1 - x~_2)||^2 (Pan et al.,
    /// the default).
    Stiff,
    /// E = 1/2 ||X - X~||^2 (Harmon et al.): the baseline of the paper's fig. 6.
    Plain,
}

/// Parameters of the contact stage.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContactSettings {
    /// Ribbon thickness h, m: a ribbon's mid-surface stays h/2 from collider surfaces
    /// and h from another ribbon's mid-surface (or a non-neighbouring part of itself).
    /// Default 1e-3.
    pub thickness: f64,
    /// Artificial edge stiffness K of the stiff closeness (dimensionless, relative to
    /// the unit weight of 1/2 ||X - X~||^2). Paper: 1e2.
    pub stiffness: f64,
    pub closeness: Closeness,
    /// Detection/response rounds per step. Default 50.
    pub max_iterations: u32,
    /// Active-set changes per QP. Default 10000.
    pub max_qp_iterations: u32,
    /// Accepted violation of a contact distance, m. Default 1e-6.
    pub tolerance: f64,
    /// Contacts between non-neighbouring parts of one ribbon. Default true.
    pub self_contact: bool,
}

impl Default for ContactSettings {
    fn default() -> Self {
        ContactSettings {
            thickness: 1e-3,
            stiffness: 1e2,
            closeness: Closeness::Stiff,
            max_iterations: 50,
            max_qp_iterations: 10_000,
            tolerance: 1e-6,
            self_contact: true,
        }
    }
}

/// The contact mesh of one deformable body (a ribbon).
#[derive(Clone, Debug, PartialEq)]
pub struct BodyTopology {
    /// Contact vertex of each mesh vertex: several mesh vertices share one contact
    /// vertex where a loop closes (their positions are averaged and they move
    /// together).
    pub vertex_of: Vec<u32>,
    /// Number of contact vertices.
    pub vertices: usize,
    /// Triangles over contact vertices.
    pub triangles: Vec<[u32; 3]>,
    /// A 1-D coordinate of each contact vertex along the body (ribbons: the crease
    /// index), for the self-contact neighbour filter.
    pub stations: Vec<f64>,
    /// Period of `stations` for closed loops.
    pub period: Option<f64>,
    /// Features whose station intervals are at most this far apart are topological
    /// neighbours and never collide (ribbons: 2 elements).
    pub neighbour_skip: f64,
}

/// One body's meshes for a step, in mesh-vertex order, m.
#[derive(Clone, Copy, Debug)]
pub struct BodyInput<'a> {
    /// X^n: the previous (collision-free) positions.
    pub previous: &'a [Point3],
    /// X~^{n+1}: the prediction of the optimization.
    pub predicted: &'a [Point3],
}

/// What the contact stage did in one step (time is measured by the caller).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ContactReport {
    /// Constraints with a positive multiplier at the end (active contacts).
    pub contacts: usize,
    /// Constraints in the final QP (the impact zones).
    pub constraints: usize,
    /// Detection/response rounds.
    pub iterations: u32,
    /// Active-set changes, summed over rounds and zones.
    pub qp_iterations: u32,
    /// Largest overlap of thickened surfaces left after the stage, m: the largest
    /// (distance - gap) over detected contacts, 0 when none.
    pub penetration_max: f64,
    /// The same for the optimizer's prediction X~, before the stage, m.
    pub predicted_penetration_max: f64,
    /// Largest |X^{n+1} - X~^{n+1}| over all vertices: how far the stage moved the mesh
    /// off the developable prediction, m.
    pub correction_max: f64,
    /// False when the round limit stopped the stage before it was collision-free.
    pub resolved: bool,
    /// Triangles whose normal the stage turned by more than 90 degrees against the
    /// prediction X~ (flipped), and triangles it shrank below a tenth of their area in
    /// X~ (degenerate): the failure mode of the plain closeness (Pan et al. fig. 6).
    pub flipped_triangles: usize,
    pub degenerate_triangles: usize,
}

struct DeformableBody {
    topology: BodyTopology,
    first: usize,
    metric: BodyMetric,
}

/// The contact stage of a scene: built once (topology, factorizations), run every step.
pub struct ContactStage {
    settings: ContactSettings,
    bodies: Vec<DeformableBody>,
    colliders: Vec<Collider>,
    geometry: Vec<ColliderGeometry>,
    meshes: Vec<MeshBody>,
    unknowns: usize,
    detector: Detector,
    // per-step buffers (global ids)
    x0: Vec<Vector3>,
    target: Vec<Vector3>,
    x: Vec<Vector3>,
    /// X~ on the contact vertices (welded average of the prediction).
    predicted: Vec<Vector3>,
    poses0: Vec<Pose>,
    poses1: Vec<Pose>,
    detected: Vec<Contact>,
    constraints: Vec<Contact>,
    merged: Vec<Contact>,
    lambda: Vec<f64>,
    // QP buffers
    zone_of_body: Vec<usize>,
    zone_constraints: Vec<usize>,
    columns: Vec<f64>,
    column_of: Vec<[(u32, u32); 2]>,
    dual_a: Vec<f64>,
    dual_b: Vec<f64>,
    dual_lambda: Vec<f64>,
    qp: DualActiveSet,
    body_columns: Vec<Vec<usize>>,
    body_offset: Vec<usize>,
    rhs: Vec<f64>,
}

impl std::fmt::Debug for ContactStage {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ContactStage")
            .field("settings", &self.settings)
            .field("bodies", &self.bodies.len())
            .field("colliders", &self.colliders)
            .finish()
    }
}

impl Clone for ContactStage {
    fn clone(&self) -> Self {
        let topologies = self.bodies.iter().map(|b| b.topology.clone()).collect();
        ContactStage::new(self.settings, topologies, self.colliders.clone())
            .expect("a stage that was built once builds again")
    }
}

impl ContactStage {
    /// The same stage (bodies, settings) with other colliders: a robot's links that
    /// arrived or changed. Builds the stage anew (meshes, leaves, factorizations).
    pub fn with_colliders(&self, colliders: Vec<Collider>) -> Result<Self, super::ContactError> {
        let topologies = self.bodies.iter().map(|b| b.topology.clone()).collect();
        ContactStage::new(self.settings, topologies, colliders)
    }

    pub fn settings(&self) -> &ContactSettings {
        &self.settings
    }
    pub fn colliders(&self) -> &[Collider] {
        &self.colliders
    }
    pub fn body_count(&self) -> usize {
        self.bodies.len()
    }

    /// Signed distance (m, negative inside) of world point `x` to collider `k` placed
    /// with the handle `targets`, and the outward normal; `None` for a mesh collider
    /// (a surface without inside).
    pub fn collider_signed_distance(
        &self,
        k: usize,
        targets: &[Pose],
        x: &Vector3,
    ) -> Option<(f64, Vector3)> {
        let pose = self.colliders[k].world_pose(targets);
        self.geometry[k].signed_distance(&pose, x)
    }

    /// The largest overlap (m; 0 when none) of the meshes `positions` (mesh-vertex order,
    /// one per body) with each other, themselves and the colliders at `targets`, and the
    /// contact key of the worst pair as (body or collider description). Used to check
    /// that a scene starts collision-free.
    pub fn overlap(&mut self, positions: &[&[Point3]], targets: &[Pose]) -> (f64, String) {
        let inputs: Vec<BodyInput> = positions
            .iter()
            .map(|p| BodyInput {
                previous: p,
                predicted: p,
            })
            .collect();
        self.gather(&inputs, targets, targets);
        self.detect();
        let mut worst = (0.0, String::new());
        for c in &self.detected {
            let o = c.distance - c.gap(&self.x);
            if o > worst.0 {
                let names: Vec<String> = c.vertices[..c.count as usize]
                    .iter()
                    .map(|&g| self.describe(g as usize))
                    .collect();
                worst = (o, names.join(" / "));
            }
        }
        worst
    }

    /// "body b" or "collider k" of a global vertex id.
    fn describe(&self, g: usize) -> String {
        if g < self.unknowns {
            format!("body {}", self.body_of(g))
        } else {
            let k = self
                .meshes
                .iter()
                .rev()
                .find(|m| m.first as usize <= g)
                .and_then(|m| match m.kind {
                    MeshKind::Kinematic { collider, .. } => Some(collider),
                    _ => None,
                })
                .unwrap_or(0);
            format!("collider {k}")
        }
    }

    /// Poses, X^n, X~ and the collider vertices into the global buffers; x = X~.
    fn gather(&mut self, inputs: &[BodyInput], targets0: &[Pose], targets1: &[Pose]) {
        self.poses0.clear();
        self.poses1.clear();
        for c in &self.colliders {
            self.poses0.push(c.world_pose(targets0));
            self.poses1.push(c.world_pose(targets1));
        }
        for (body, input) in self.bodies.iter().zip(inputs) {
            let t = &body.topology;
            let range = body.first..body.first + t.vertices;
            self.x0[range.clone()]
                .iter_mut()
                .for_each(|v| *v = Vector3::zeros());
            self.target[range.clone()]
                .iter_mut()
                .for_each(|v| *v = Vector3::zeros());
            self.rhs.clear();
            self.rhs.resize(t.vertices, 0.0);
            for (m, &v) in t.vertex_of.iter().enumerate() {
                let g = body.first + v as usize;
                self.x0[g] += input.previous[m].coords;
                self.target[g] += input.predicted[m].coords;
                self.rhs[v as usize] += 1.0;
            }
            for (i, count) in self.rhs.iter().enumerate() {
                let g = body.first + i;
                self.x0[g] /= *count;
                self.target[g] /= *count;
            }
        }
        for mesh in &self.meshes {
            if let MeshKind::Kinematic { collider, .. } = mesh.kind {
                let k = collider as usize;
                for (i, v) in self.geometry[k].vertices.iter().enumerate() {
                    let g = mesh.first as usize + i;
                    self.x0[g] = (self.poses0[k] * v).coords;
                    self.x[g] = (self.poses1[k] * v).coords;
                    self.target[g] = self.x[g];
                }
            }
        }
        self.x[..self.unknowns].copy_from_slice(&self.target[..self.unknowns]);
        self.predicted.clear();
        self.predicted
            .extend_from_slice(&self.target[..self.unknowns]);
    }

    /// Resolve one step. `inputs[i]` are body i's meshes; `targets0` / `targets1` the
    /// carrier poses (handle targets, then kinematic bodies) at the start and the end of
    /// the step (they carry attached colliders). Writes the collision-free positions into `corrected[i]` (mesh-vertex
    /// order).
    pub fn resolve(
        &mut self,
        inputs: &[BodyInput],
        targets0: &[Pose],
        targets1: &[Pose],
        corrected: &mut [Vec<Point3>],
    ) -> ContactReport {
        assert_eq!(inputs.len(), self.bodies.len());
        assert_eq!(corrected.len(), self.bodies.len());
        self.gather(inputs, targets0, targets1);

        let mut report = ContactReport::default();
        self.constraints.clear();
        self.lambda.clear();
        let first = self.project(&mut report, true);
        report.predicted_penetration_max = first;
        // Coulomb friction against colliders, then make sure it created no contact.
        if self.apply_friction() {
            self.target[..self.unknowns].copy_from_slice(&self.x[..self.unknowns]);
            self.project(&mut report, false);
        }

        // scatter back: every mesh vertex moves by its contact vertex's correction
        let mut correction_max: f64 = 0.0;
        for ((body, input), out) in self.bodies.iter().zip(inputs).zip(corrected.iter_mut()) {
            let t = &body.topology;
            out.clear();
            for (m, &v) in t.vertex_of.iter().enumerate() {
                let g = body.first + v as usize;
                let delta = self.x[g] - self.predicted[g];
                correction_max = correction_max.max(delta.norm());
                out.push(input.predicted[m] + delta);
            }
        }
        report.correction_max = correction_max;
        let (flipped, degenerate) = self.distorted_triangles();
        report.flipped_triangles = flipped;
        report.degenerate_triangles = degenerate;
        report
    }

    /// (flipped, degenerate) triangles of X against X~ (see [`ContactReport`]).
    fn distorted_triangles(&self) -> (usize, usize) {
        let (mut flipped, mut degenerate) = (0, 0);
        for body in &self.bodies {
            for t in &body.topology.triangles {
                let g = t.map(|v| body.first + v as usize);
                let normal = |x: &[Vector3]| (x[g[1]] - x[g[0]]).cross(&(x[g[2]] - x[g[0]]));
                let (n0, n1) = (normal(&self.predicted), normal(&self.x));
                if n0.dot(&n1) < 0.0 {
                    flipped += 1;
                } else if n1.norm() < 0.1 * n0.norm() {
                    degenerate += 1;
                }
            }
        }
        (flipped, degenerate)
    }

    /// Rounds of detection and response from `self.target`; returns the largest
    /// overlap of the first detection (the prediction's penetration).
    /// Contacts between the motion x0 -> x (this round's positions) and the colliders'
    /// poses0 -> poses1, into `self.detected`.
    fn detect(&mut self) {
        let input = DetectInput {
            x0: &self.x0,
            x1: &self.x,
            unknowns: self.unknowns,
            bodies: &self.meshes,
            colliders: &self.geometry,
            poses0: &self.poses0,
            poses1: &self.poses1,
            half_thickness: 0.5 * self.settings.thickness,
            crossing_eps: 1e-8,
        };
        self.detector.detect(&input, &mut self.detected);
    }

    fn project(&mut self, report: &mut ContactReport, first_call: bool) -> f64 {
        let tol = self.settings.tolerance;
        let mut first_overlap = 0.0;
        report.resolved = false;
        for round in 0..self.settings.max_iterations.max(1) {
            self.detect();
            let mut overlap: f64 = 0.0;
            for c in &self.detected {
                overlap = overlap.max(c.distance - c.gap(&self.x));
            }
            if round == 0 {
                first_overlap = overlap;
            }
            report.penetration_max = overlap.max(0.0);
            if first_call || round > 0 {
                report.iterations += 1;
            }
            self.merge_detected();
            if overlap <= tol {
                report.resolved = true;
                break;
            }
            let qi = self.solve_qp();
            report.qp_iterations += qi;
        }
        report.constraints = self.constraints.len();
        report.contacts = self.lambda.iter().filter(|&&l| l > 0.0).count();
        first_overlap.max(0.0)
    }

    fn body_of(&self, g: usize) -> usize {
        // bodies are few and ordered by `first`
        match self.bodies.binary_search_by(|b| b.first.cmp(&g)) {
            Ok(i) => i,
            Err(i) => i - 1,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::ColliderShape;

    fn triangle_body() -> BodyTopology {
        BodyTopology {
            vertex_of: vec![0, 1, 2],
            vertices: 3,
            triangles: vec![[0, 1, 2]],
            stations: vec![0.0, 1.0, 2.0],
            period: None,
            neighbour_skip: 2.0,
        }
    }

    fn ground() -> Collider {
        Collider {
            shape: ColliderShape::HalfSpace,
            pose: Pose::identity(),
            friction: 0.0,
            attached_to: None,
        }
    }

    fn p(x: f64, y: f64, z: f64) -> Point3 {
        Point3::new(x, y, z)
    }

    /// One vertex pushed below the ground: the QP's solution is the analytic
    /// projection x = x~ + λ H^-1 e_0 n with λ = (h/2 - z~_0) / (H^-1)_00.
    #[test]
    fn single_vertex_plane_contact_has_the_analytic_projection() {
        let h = 0.002;
        let previous = [p(0.0, 0.0, 0.01), p(0.1, 0.0, 0.01), p(0.0, 0.1, 0.01)];
        let predicted = [p(0.0, 0.0, -0.003), p(0.1, 0.0, 0.01), p(0.0, 0.1, 0.01)];
        for (closeness, k) in [(Closeness::Plain, 0.0), (Closeness::Stiff, 100.0)] {
            let settings = ContactSettings {
                thickness: h,
                closeness,
                stiffness: 100.0,
                ..Default::default()
            };
            let mut stage =
                ContactStage::new(settings, vec![triangle_body()], vec![ground()]).unwrap();
            let mut out = vec![Vec::new()];
            let report = stage.resolve(
                &[BodyInput {
                    previous: &previous,
                    predicted: &predicted,
                }],
                &[],
                &[],
                &mut out,
            );
            assert!(report.resolved);
            assert_eq!(report.contacts, 1);
            // H_s = I + K L of the triangle
            let mut hs = nalgebra::Matrix3::<f64>::identity();
            for (a, b) in [(0, 1), (1, 2), (0, 2)] {
                hs[(a, a)] += k;
                hs[(b, b)] += k;
                hs[(a, b)] -= k;
                hs[(b, a)] -= k;
            }
            let z = hs.try_inverse().unwrap().column(0).into_owned();
            let lambda = (0.5 * h - predicted[0].z) / z[0];
            for i in 0..3 {
                let want = predicted[i] + Vector3::z() * (lambda * z[i]);
                assert!(
                    (out[0][i] - want).norm() < 1e-12,
                    "{closeness:?} vertex {i}: {} vs {}",
                    out[0][i],
                    want
                );
            }
            assert!((out[0][0].z - 0.5 * h).abs() < 1e-12);
            assert!(report.predicted_penetration_max > 0.0039);
            assert!(report.penetration_max <= settings.tolerance);
        }
    }

    /// A box corner moving up through the middle of a ribbon triangle (no ribbon vertex
    /// near the box): the vertex-face test of the box's feature catches it.
    #[test]
    fn a_box_corner_cannot_poke_through_a_triangle() {
        let h = 0.002;
        let tri = [p(-0.2, -0.2, 0.0), p(0.4, -0.2, 0.0), p(-0.2, 0.4, 0.0)];
        // a cube with a corner pointing up, carried by handle 0 from z = -0.05 to +0.02
        let corner_up =
            nalgebra::UnitQuaternion::rotation_between(&Vector3::new(1.0, 1.0, 1.0), &Vector3::z())
                .unwrap();
        let half = 0.05;
        let top = half * 3f64.sqrt();
        let at =
            |z: f64| Pose::from_parts(nalgebra::Translation3::new(0.0, 0.0, z - top), corner_up);
        let cube = Collider {
            shape: ColliderShape::Cuboid {
                half_extents: Vector3::repeat(half),
            },
            pose: Pose::identity(),
            friction: 0.0,
            attached_to: Some(0),
        };
        let settings = ContactSettings {
            thickness: h,
            ..Default::default()
        };
        let mut stage = ContactStage::new(settings, vec![triangle_body()], vec![cube]).unwrap();
        let mut out = vec![Vec::new()];
        let report = stage.resolve(
            &[BodyInput {
                previous: &tri,
                predicted: &tri,
            }],
            &[at(-0.05)],
            &[at(0.02)],
            &mut out,
        );
        assert!(report.resolved, "{report:?}");
        // the corner is at (0, 0, 0.02): the triangle must lie above it by h/2
        let (a, b, c) = (out[0][0], out[0][1], out[0][2]);
        let n = (b - a).cross(&(c - a)).normalize();
        let corner = Vector3::new(0.0, 0.0, 0.02);
        let d = n.dot(&(corner - a.coords)).abs();
        let above = n.dot(&(a.coords - corner)) * n.z.signum();
        assert!(above > 0.0, "the triangle went below the corner: {out:?}");
        assert!(d >= 0.5 * h - 1e-6, "distance {d}");
    }

    /// Two ribbon triangles: one falls through the other's edge region; after the stage
    /// their vertices and edges keep the thickness h.
    #[test]
    fn two_bodies_crossing_are_separated_by_the_thickness() {
        let h = 0.002;
        let lower = [p(0.0, 0.0, 0.0), p(0.2, 0.0, 0.0), p(0.0, 0.2, 0.0)];
        let upper0 = [p(0.05, 0.05, 0.01), p(0.3, 0.05, 0.01), p(0.05, 0.3, 0.01)];
        let upper1 = upper0.map(|q| q - Vector3::new(0.0, 0.0, 0.03));
        let mut stage = ContactStage::new(
            ContactSettings {
                thickness: h,
                ..Default::default()
            },
            vec![triangle_body(), triangle_body()],
            vec![],
        )
        .unwrap();
        let mut out = vec![Vec::new(), Vec::new()];
        let report = stage.resolve(
            &[
                BodyInput {
                    previous: &lower,
                    predicted: &lower,
                },
                BodyInput {
                    previous: &upper0,
                    predicted: &upper1,
                },
            ],
            &[],
            &[],
            &mut out,
        );
        assert!(report.resolved, "{report:?}");
        assert!(report.contacts > 0);
        // the upper vertex over the lower triangle's interior stays above it by h
        let (a, b, c) = (out[0][0], out[0][1], out[0][2]);
        let mut n = (b - a).cross(&(c - a)).normalize();
        if n.z < 0.0 {
            n = -n;
        }
        let d = n.dot(&(out[1][0] - a));
        assert!(
            d >= h - 1e-6,
            "upper vertex at {d} m from the lower triangle: {out:?}"
        );
        let (overlap, _) = stage.overlap(&[&out[0], &out[1]], &[]);
        assert!(overlap <= 1e-6, "overlap {overlap}");
    }
}
