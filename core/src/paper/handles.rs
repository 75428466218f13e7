//! What the world's handles hold on a sheet, and what they feel.
//!
//! A handle holds a vertex of S_P on the sheet's boundary (Schreck et al. sec. 3.3:
//! the handles are on ∂S), as hard constraints of the FEM step, with the tangent plane
//! through two neighbouring vertices for a full hold or springs for a normal one. A
//! grasp at run time on a boundary point that is not yet a vertex adds it as an anchor
//! of S_G and rebuilds S_P around it (positions interpolated, nothing moves). The
//! wrench a handle feels is the reaction of its constraints in the FEM step.

use crate::geometry::{Point2, Point3, Pose, SurfacePoint, Vector3};
use crate::sim::handle::{HandleSpec, OrientationMode};
use crate::sim::object::Wrench;

use super::fem::Spring;
use super::geometric::GeometricMesh;
use super::handle_set::{own_handles, PaperHandle};
use super::physical::{build_physical, Interpolator, Placement};
use super::sim::PaperSim;
use super::LengthRestoration;

/// The tolerance on "on the boundary", m: a grasp by material point must be this close
/// to the pattern's outline.
const ON_BOUNDARY: f64 = 1e-6;

impl PaperSim {
    /// `world_from_grasp` of handle `h` this frame: its target, moved by its run-time
    /// grasp offset (None before the handle's first target).
    pub(super) fn grasp_frame(&self, h: &PaperHandle) -> Option<Pose> {
        let target = self.last_target(h.world)?;
        Some(match &h.offset {
            Some(offset) => target * offset,
            None => target,
        })
    }

    /// The handles changed (a grasp or a release): the ones holding this sheet (object
    /// `index`) now; a grasp point that is not an anchor of S_G yet becomes one, and
    /// S_P is rebuilt with a vertex there.
    pub(super) fn rebuild_handles(&mut self, index: usize, handles: &[HandleSpec]) {
        let Ok(own) = own_handles(&self.pattern, index, handles) else {
            // the world only grasps points `graspable` accepted: keep the last set
            return;
        };
        let new_anchor = own.iter().any(|h| {
            !self
                .layer
                .anchors
                .iter()
                .any(|&s| (self.pattern.wrap(s) - self.pattern.wrap(h.arc)).abs() < 1e-12)
        });
        if new_anchor {
            for h in &own {
                if !self.layer.anchors.contains(&h.arc) {
                    self.layer.anchors.push(h.arc);
                }
            }
            self.rebuild_physical();
        }
        self.wrenches = vec![None; own.len()];
        self.handles = own;
    }

    /// S_G's mesh and S_P built anew from the current structure, positions and
    /// velocities interpolated from the current S_P (as step 3 does, without moving
    /// junctions or refitting cones): a new anchor gets its vertex.
    fn rebuild_physical(&mut self) {
        let interp = Interpolator::new(&self.sp, &self.pattern);
        let position = |k: &_, m: &Point2| interp.geometric_vertex(k, m);
        let Ok(gmesh) = GeometricMesh::build(&self.layer, &self.pattern, &position) else {
            return;
        };
        let curve = |s: f64| interp.boundary_position(s);
        let at = |m: &Point2| interp.position(m);
        let placement = match self.params.length_restoration {
            LengthRestoration::Paper => Placement::OnGeometricLayer(&curve),
            LengthRestoration::StrainLimit => Placement::Interpolated(&at),
        };
        let Ok(mut sp) =
            build_physical(&gmesh, &self.layer, &self.pattern, &self.params, placement)
        else {
            return;
        };
        for (v, m) in sp.velocity.iter_mut().zip(&sp.material) {
            *v = interp.velocity(m);
        }
        self.gmesh = gmesh;
        self.gmesh_fresh = false;
        self.sp = sp;
        self.rebuild_display();
    }

    /// `m` moved onto the pattern's outline, if it is within [`ON_BOUNDARY`] of it.
    pub(super) fn graspable_point(&self, m: &Point2) -> Result<Point2, String> {
        match self.pattern.arc_of(m, ON_BOUNDARY) {
            Some(s) if m.coords.iter().all(|x| x.is_finite()) => Ok(self.pattern.point_at(s)),
            _ => Err(format!(
                "[{}, {}] is not on the sheet's boundary (m): a sheet is held on its boundary \
                 (Schreck et al. sec. 3.3)",
                m.x, m.y
            )),
        }
    }

    /// The boundary point nearest the world point `p`: on the mesh's edges along the
    /// pattern's outline.
    pub(super) fn nearest_boundary_point(&self, p: &Point3) -> Option<SurfacePoint> {
        let on_outline = |a: &Point2, b: &Point2| {
            let mid = Point2::from((a.coords + b.coords) * 0.5);
            [a, b, &mid]
                .iter()
                .all(|m| self.pattern.arc_of(m, 1e-9).is_some())
        };
        let found = self.mesh.nearest_edge_point(p, &on_outline)?;
        // exactly on the outline (the edge's interpolation rounds)
        let s = self.pattern.arc_of(&found.material, ON_BOUNDARY)?;
        Some(SurfacePoint {
            material: self.pattern.point_at(s),
            ..found
        })
    }

    /// The wrenches of this frame's FEM step: per handle, the reactions of the vertices
    /// it holds (its grasp vertex, and the tangent plane's vertices of a full hold) and
    /// the forces of its springs (a normal hold), about the grasp vertex; what the
    /// sheet exerts on the gripper is their opposite.
    pub(super) fn measure_wrenches(&mut self, springs: &[Spring]) {
        let reactions = &self.fem.reactions;
        let mut out = Vec::with_capacity(self.handles.len());
        for h in &self.handles {
            let vertex = self.vertex_at(&h.material);
            let wrench = vertex
                .filter(|_| reactions.len() == self.sp.position.len())
                .map(|v| {
                    let at = self.sp.position[v];
                    let (mut force, mut torque) = (Vector3::zeros(), Vector3::zeros());
                    let mut add = |x: Point3, f: Vector3| {
                        force += f;
                        torque += (x - at).cross(&f);
                    };
                    add(at, reactions[v]);
                    if h.orientation != OrientationMode::Free {
                        for n in super::sim::tangent_neighbours(&self.sp, v) {
                            let x = self.sp.position[n];
                            add(x, reactions[n]);
                            for s in springs.iter().filter(|s| s.vertex as usize == n) {
                                add(x, (s.target - x) * s.stiffness);
                            }
                        }
                    }
                    Wrench {
                        force: -force,
                        torque: -torque,
                    }
                });
            out.push(wrench);
        }
        self.wrenches = out;
    }

    /// What world handle `handle` felt in the last FEM step.
    pub(super) fn wrench_on(&self, handle: usize) -> Option<Wrench> {
        let k = self.handles.iter().position(|h| h.world == handle)?;
        self.wrenches.get(k).copied().flatten()
    }
}
