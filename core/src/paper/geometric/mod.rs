//! The geometric layer S_G (Schreck et al. sec. 3.2): flat regions F (triangles
//! between singular and boundary vertices) and curved regions C (generalized cones
//! meshed along their rulings), with singular and junction vertices.
//!
//! S_G is kept in two forms:
//! - [`GeometricLayer`], the *structure*: singular vertices (persistent, stable ids),
//!   curved regions as ordered lists of rulings, creases, boundary anchors. All the
//!   remeshing of sections 5 and 6 edits this.
//! - [`GeometricMesh`], the *mesh* built from it: vertices with pattern and world
//!   positions, curved faces between consecutive rulings, and the flat triangles that
//!   a constrained Delaunay triangulation of the rest gives. Rebuilt after each edit.

mod mesh;

pub use mesh::{
    edge_key, EdgeKind, FaceKind, GEdge, GFace, GVertex, GVertexKind, GeometricMesh, MeshError,
};

use super::pattern::Pattern;
use crate::geometry::Point2;

/// Two boundary arc lengths closer than this are one S_G vertex, m.
pub const MERGE_ARC: f64 = 1e-7;

/// Where a ruling or a crease ends: on ∂S̄ (arc length, m) or at a singular vertex.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Endpoint {
    Boundary(f64),
    Singular(u64),
}

/// A ruling of a curved region: a straight segment of the surface, from side A to
/// side B of the region.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ruling {
    pub a: Endpoint,
    pub b: Endpoint,
}

/// A curved region C: a generalized cone (or a union of cones joined by common
/// rulings, sec. 6.2) given by its ordered rulings. Consecutive rulings bound one face
/// (a quadrangle, or a triangle when they share an endpoint: the apex).
#[derive(Clone, Debug, PartialEq)]
pub struct CurvedRegion {
    /// Stable id (for tracking and tests).
    pub id: u64,
    pub rulings: Vec<Ruling>,
}

impl CurvedRegion {
    /// The interior singular vertex all rulings pass through, if any (sec. 5.2: a
    /// curved region with an interior singular point is a single generalized cone).
    pub fn singular_apex(&self) -> Option<u64> {
        let first = self.rulings.first()?;
        for cand in [first.a, first.b] {
            if let Endpoint::Singular(id) = cand {
                if self
                    .rulings
                    .iter()
                    .all(|r| r.a == Endpoint::Singular(id) || r.b == Endpoint::Singular(id))
                {
                    return Some(id);
                }
            }
        }
        None
    }
}

/// Why a crease exists.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum CreaseKind {
    /// Set before the simulation (fig. 22), with its signed rest angle, rad.
    Preset { rest_angle: f64 },
    /// Made by fiber damage: an edge between two singular points (fig. 9, fig. 24c) or
    /// a flat-flat border split by a singular point (fig. 6c, "a degenerate curved
    /// region with only one ruling"). Rest angles come from eq. 1.
    Plastic,
}

/// A persistent straight fold.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Crease {
    pub a: Endpoint,
    pub b: Endpoint,
    pub kind: CreaseKind,
}

/// A singular vertex: the apex of a d-cone, where fibers broke. Never removed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SingularVertex {
    /// Stable id, assigned at creation, never reused.
    pub id: u64,
    /// Pattern position, m.
    pub material: Point2,
}

/// The structure of S_G (see the module doc).
#[derive(Clone, Debug, PartialEq, Default)]
pub struct GeometricLayer {
    pub singular: Vec<SingularVertex>,
    pub regions: Vec<CurvedRegion>,
    pub creases: Vec<Crease>,
    /// Boundary arc lengths that are always S_G vertices (handle grasp points), m.
    pub anchors: Vec<f64>,
    /// Smallest allowed distance between two S_G boundary vertices, m (0: no check).
    pub min_boundary_spacing: f64,
    pub next_singular_id: u64,
    pub next_region_id: u64,
}

impl GeometricLayer {
    pub fn singular_material(&self, id: u64) -> Option<Point2> {
        self.singular
            .iter()
            .find(|s| s.id == id)
            .map(|s| s.material)
    }

    /// Pattern position of an endpoint, m.
    pub fn endpoint_material(&self, pattern: &Pattern, e: &Endpoint) -> Point2 {
        match e {
            Endpoint::Boundary(s) => pattern.point_at(*s),
            Endpoint::Singular(id) => self
                .singular_material(*id)
                .unwrap_or_else(|| Point2::new(f64::NAN, f64::NAN)),
        }
    }

    /// Add a singular vertex at `material` and return its id.
    pub fn add_singular(&mut self, material: Point2) -> u64 {
        let id = self.next_singular_id;
        self.next_singular_id += 1;
        self.singular.push(SingularVertex { id, material });
        id
    }

    /// Add a curved region and return its id.
    pub fn add_region(&mut self, rulings: Vec<Ruling>) -> u64 {
        let id = self.next_region_id;
        self.next_region_id += 1;
        self.regions.push(CurvedRegion { id, rulings });
        id
    }

    /// All straight segments of the structure (rulings and creases) in the pattern.
    pub fn segments(&self, pattern: &Pattern) -> Vec<[Point2; 2]> {
        let mut out = Vec::new();
        for r in &self.regions {
            for ru in &r.rulings {
                out.push([
                    self.endpoint_material(pattern, &ru.a),
                    self.endpoint_material(pattern, &ru.b),
                ]);
            }
        }
        for c in &self.creases {
            out.push([
                self.endpoint_material(pattern, &c.a),
                self.endpoint_material(pattern, &c.b),
            ]);
        }
        out
    }
}
