//! What step 2 saw on each remeshing attempt ([`CrumpleAttempt`], in
//! [`super::PaperFrameStats::crumple_attempts`]): T_comp, how much of its
//! compression was there before this frame's FEM step, how much of it is S_P's own
//! membrane strain rather than bending, the strip's borders and whether the paper
//! calls them constrained (sec. 5.2: dihedral angle above theta_0). It answers "is
//! this compression the sheet's or our pipeline's" frame by frame
//! (docs/paper_simulator.md, "Where the extra singular points come from"; printed by
//! `cargo run --release --example paper_scene_debug SCENE`).

use nalgebra::{Matrix2, Matrix3x2};

use super::compression::TriangleStrain;
use super::crumpling::{face_center, propagate, Border, Unchanged};
use super::geometric::{Endpoint, GeometricMesh};
use super::pattern::in_convex_polygon;
use super::physical::{Interpolator, PhysicalMesh};
use crate::geometry::{Point2, Point3};

/// One remeshing attempt of step 2.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CrumpleAttempt {
    /// T_comp's compression 1 - lambda_min against the pattern (dimensionless).
    pub compression: f64,
    /// T_comp's pattern centroid (m) and the ruling direction v_perp.
    pub centroid: Point2,
    pub ruling_direction: nalgebra::Vector2<f64>,
    /// Whether S_G changed.
    pub changed: bool,
    /// When it did not, the branch of step 2 that added nothing.
    pub unchanged: Option<Unchanged>,
    /// T_comp's pattern corners (m).
    pub corners: [Point2; 3],
    /// T_comp's compression with the positions S_P had at the start of the frame
    /// (what step 3 of the last frame handed over), before this frame's FEM step;
    /// NaN when a corner was no S_P vertex then.
    pub compression_at_start: f64,
    /// S_P's own in-plane compression along v inside T_comp (area-weighted mean of
    /// 1 - |F v| over the S_P triangles whose centroid lies in it): the part of
    /// `compression` that is membrane strain rather than bending.
    pub membrane: f64,
    /// The strip's borders (appendix A), when it propagates.
    pub borders: Option<[Border; 2]>,
    /// A corner of T_comp is a held vertex (a handle or its tangent-plane neighbour).
    pub touches_held: bool,
    /// Per border: the dihedral angle (rad) of the edge met, and the largest of its
    /// curved region's rulings (NaN for the free boundary or a singular vertex). Sec.
    /// 5.2 calls a border constrained when they exceed theta_0 (fig. 6c, d).
    pub border_dihedral: [[f64; 2]; 2],
}

/// What an attempt is measured in: S_G as step 2 saw it, S_P after the FEM step and
/// its positions at the start of the frame, the held vertices.
pub(super) struct AttemptContext<'a> {
    pub gmesh: &'a GeometricMesh,
    pub labels: &'a [usize],
    pub sp: &'a PhysicalMesh,
    pub interp: &'a Interpolator<'a>,
    /// S_P's positions before this frame's step 1 (same vertices), m.
    pub frame_start: &'a [Point3],
    pub held: &'a [(Point2, Point3)],
}

impl AttemptContext<'_> {
    /// The attempt on T_comp = `strain.face`; `unchanged`: why S_G did not change
    /// (None: it changed).
    pub fn attempt(&self, strain: &TriangleStrain, unchanged: Option<Unchanged>) -> CrumpleAttempt {
        let g = self.gmesh;
        let tri = &g.faces[strain.face].vertices;
        let corners = [0, 1, 2].map(|k| g.vertices[tri[k] as usize].material);
        let borders = propagate(g, self.labels, strain.face, &strain.ruling_direction)
            .ok()
            .map(|s| s.borders);
        CrumpleAttempt {
            compression: strain.compression,
            centroid: face_center(g, strain.face),
            ruling_direction: strain.ruling_direction,
            changed: unchanged.is_none(),
            unchanged,
            corners,
            compression_at_start: self.compression_at_start(&corners),
            membrane: self.membrane(&corners, strain),
            borders,
            touches_held: corners
                .iter()
                .any(|c| self.held.iter().any(|(m, _)| (m - c).norm() < 1e-9)),
            border_dihedral: borders.map_or([[f64::NAN; 2]; 2], |b| b.map(|b| self.dihedral(&b))),
        }
    }

    /// 1 - lambda_min of the triangle `corners` with S_P's positions at the start of
    /// the frame; NaN when a corner was no S_P vertex.
    fn compression_at_start(&self, corners: &[Point2; 3]) -> f64 {
        let at = |m: &Point2| {
            self.interp
                .vertex_at(m)
                .and_then(|v| self.frame_start.get(v as usize).copied())
        };
        let (Some(a), Some(b), Some(c)) = (at(&corners[0]), at(&corners[1]), at(&corners[2]))
        else {
            return f64::NAN;
        };
        let dm = Matrix2::from_columns(&[corners[1] - corners[0], corners[2] - corners[0]]);
        dm.try_inverse().map_or(f64::NAN, |inv| {
            let f = Matrix3x2::from_columns(&[b - a, c - a]) * inv;
            let e = (f.transpose() * f).symmetric_eigen();
            1.0 - e.eigenvalues.min().max(0.0).sqrt()
        })
    }

    /// S_P's membrane compression along `strain.direction` inside `corners`.
    fn membrane(&self, corners: &[Point2; 3], strain: &TriangleStrain) -> f64 {
        let sp = self.sp;
        let (mut sum, mut area) = (0.0, 0.0);
        for t in &sp.triangles {
            let m = t.map(|i| sp.material[i as usize]);
            let c = Point2::from((m[0].coords + m[1].coords + m[2].coords) / 3.0);
            if !in_convex_polygon(corners, &c, 0.0) {
                continue;
            }
            let x = t.map(|i| sp.position[i as usize]);
            let dm = Matrix2::from_columns(&[m[1] - m[0], m[2] - m[0]]);
            let Some(inv) = dm.try_inverse() else {
                continue;
            };
            let f = Matrix3x2::from_columns(&[x[1] - x[0], x[2] - x[0]]) * inv;
            let a = 0.5 * dm.determinant().abs();
            sum += a * (1.0 - (f * strain.direction).norm());
            area += a;
        }
        if area > 0.0 {
            sum / area
        } else {
            f64::NAN
        }
    }

    /// [`CrumpleAttempt::border_dihedral`] of one border.
    fn dihedral(&self, border: &Border) -> [f64; 2] {
        let g = self.gmesh;
        let angle = |[a, b]: [u32; 2]| g.dihedral(a, b).unwrap_or(0.0);
        match border {
            Border::CurvedRuling { region, ruling } => {
                let Some(rv) = g.ruling_vertices.get(*region as usize) else {
                    return [f64::NAN; 2];
                };
                let met = rv.get(*ruling).map_or(f64::NAN, |r| angle(*r));
                [met, rv.iter().map(|r| angle(*r)).fold(0.0, f64::max)]
            }
            Border::FlatFold { a, b } => {
                let vertex =
                    |e: &Endpoint| (0..g.vertices.len() as u32).find(|&v| g.endpoint_of(v) == *e);
                let d = vertex(a)
                    .zip(vertex(b))
                    .and_then(|(a, b)| g.dihedral(a, b))
                    .unwrap_or(f64::NAN);
                [d, d]
            }
            Border::Boundary | Border::Singular { .. } => [f64::NAN; 2],
        }
    }
}
