//! What one ribbon's step sees of the rest of the world when contact is a barrier inside
//! the step (docs/contact_barrier.md): the colliders at their poses and the meshes of
//! the other ribbons, all static while the ribbon's own solve runs.
//!
//! - [`CellMesh`]: a triangle mesh cut into cells for the broad phase, one per
//!   triangle, each owning the vertices and edges it is the first to contain, so that
//!   every vertex-triangle and edge-edge pair of two meshes is met exactly once when
//!   the cells whose boxes overlap are paired.
//! - [`ContactEnv`]: what the world hands a ribbon's step (settings, colliders with
//!   their poses at the start and the end of the step, the other ribbons' meshes).
//! - [`Obstacles`]: the same, prepared for detection (features in world coordinates,
//!   boxes sorted along one axis); kept by the ribbon and refilled every step (no
//!   allocation once warm).

use std::sync::Arc;

use super::barrier::BarrierSettings;
use super::collider::{Collider, ColliderGeometry, ColliderShape};
use crate::geometry::{Point3, Pose, Vector3};

/// A triangle mesh's cells: triangle t owns `vertices[vertex_start[t]..vertex_start[t+1]]`
/// and `edges[edge_start[t]..edge_start[t+1]]` (the ones no earlier triangle contains).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CellMesh {
    pub triangles: Vec<[u32; 3]>,
    pub vertex_start: Vec<u32>,
    pub vertices: Vec<u32>,
    pub edge_start: Vec<u32>,
    pub edges: Vec<[u32; 2]>,
}

impl CellMesh {
    /// The cells of `triangles` over `vertex_count` vertices (deterministic: ownership by
    /// the lowest triangle index).
    pub fn new(triangles: &[[u32; 3]], vertex_count: usize) -> CellMesh {
        let mut owner = vec![u32::MAX; vertex_count];
        for (t, tri) in triangles.iter().enumerate() {
            for &v in tri {
                let o = &mut owner[v as usize];
                *o = (*o).min(t as u32);
            }
        }
        let mut edge_owner: Vec<([u32; 2], u32)> = triangles
            .iter()
            .enumerate()
            .flat_map(|(t, tri)| {
                [[tri[0], tri[1]], [tri[1], tri[2]], [tri[2], tri[0]]]
                    .map(|[a, b]| (if a < b { [a, b] } else { [b, a] }, t as u32))
            })
            .collect();
        edge_owner.sort_unstable();
        edge_owner.dedup_by_key(|(e, _)| *e);
        let mut cells = CellMesh {
            triangles: triangles.to_vec(),
            ..Default::default()
        };
        let mut per_cell_edges: Vec<Vec<[u32; 2]>> = vec![Vec::new(); triangles.len()];
        for (e, t) in edge_owner {
            per_cell_edges[t as usize].push(e);
        }
        for (t, tri) in triangles.iter().enumerate() {
            cells.vertex_start.push(cells.vertices.len() as u32);
            cells.edge_start.push(cells.edges.len() as u32);
            let mut seen = [u32::MAX; 3];
            for (i, &v) in tri.iter().enumerate() {
                if owner[v as usize] == t as u32 && !seen.contains(&v) {
                    cells.vertices.push(v);
                    seen[i] = v;
                }
            }
            cells.edges.extend_from_slice(&per_cell_edges[t]);
        }
        cells.vertex_start.push(cells.vertices.len() as u32);
        cells.edge_start.push(cells.edges.len() as u32);
        cells
    }

    pub fn len(&self) -> usize {
        self.triangles.len()
    }
    pub fn is_empty(&self) -> bool {
        self.triangles.is_empty()
    }
    /// The vertices cell `t` owns.
    #[inline]
    pub fn owned_vertices(&self, t: usize) -> &[u32] {
        &self.vertices[self.vertex_start[t] as usize..self.vertex_start[t + 1] as usize]
    }
    /// The edges cell `t` owns.
    #[inline]
    pub fn owned_edges(&self, t: usize) -> &[[u32; 2]] {
        &self.edges[self.edge_start[t] as usize..self.edge_start[t + 1] as usize]
    }
}

/// Another contact body's mesh as this step sees it.
#[derive(Clone, Copy, Debug)]
pub struct OtherMesh<'a> {
    /// World positions, m.
    pub vertices: &'a [Point3],
    /// The same vertices at the start of the world's step, m (equal to `vertices` when
    /// the body has not stepped yet): what it moved is what its friction drags along.
    pub start: &'a [Point3],
    pub cells: &'a Arc<CellMesh>,
}

/// What the world hands one ribbon's step when contact is a barrier.
#[derive(Clone, Copy, Debug)]
pub struct ContactEnv<'a> {
    pub settings: BarrierSettings,
    pub colliders: &'a [Collider],
    /// `world_from_collider` of each collider at the start and at the end of the step.
    pub poses0: &'a [Pose],
    pub poses1: &'a [Pose],
    /// The other contact bodies (ribbons), at their current positions.
    pub others: &'a [OtherMesh<'a>],
}

/// A collider's solid at its current pose (a ribbon vertex against it: signed distance).
#[derive(Clone, Debug)]
pub struct ObstacleSolid {
    pub collider: usize,
    pub pose: Pose,
    /// World box of the solid, m (None: a half-space).
    pub aabb: Option<(Vector3, Vector3)>,
    /// A half-space's world plane (outward normal, offset n . x on it, m).
    pub plane: Option<(Vector3, f64)>,
}

/// A static point, edge or triangle of a collider (world, m) with the gap offset it
/// keeps from a ribbon's mid-surface: ξ/2 plus the feature's radius, m.
#[derive(Clone, Copy, Debug)]
pub struct ObstacleFeature<const N: usize> {
    pub x: [Vector3; N],
    pub offset: f64,
    pub collider: usize,
    pub lo: Vector3,
    pub hi: Vector3,
}

impl<const N: usize> ObstacleFeature<N> {
    fn new(x: [Vector3; N], offset: f64, collider: usize) -> Self {
        let (lo, hi) = bounds(&x);
        ObstacleFeature {
            x,
            offset,
            collider,
            lo,
            hi,
        }
    }
}

/// Another ribbon's mesh, static during this ribbon's solve: its vertices and cells,
/// the cells' boxes and their order along the sorting axis.
#[derive(Clone, Debug, Default)]
pub struct ObstacleBody {
    pub vertices: Vec<Vector3>,
    /// Each vertex's displacement since the start of the world's step, m.
    pub shift: Vec<Vector3>,
    pub cells: Arc<CellMesh>,
    pub boxes: Vec<(Vector3, Vector3)>,
    /// Cells sorted by their box's minimum along `axis`.
    pub order: Vec<u32>,
    pub lo: Vector3,
    pub hi: Vector3,
    /// The largest extent of a cell box along `axis`, m.
    pub widest: f64,
}

/// The static world of one ribbon's step, prepared for detection.
#[derive(Clone, Debug, Default)]
pub struct Obstacles {
    pub settings: BarrierSettings,
    /// Collider geometries (prepared once; colliders do not change shape) and their
    /// Coulomb coefficients μ.
    pub(crate) geometry: Vec<ColliderGeometry>,
    /// The shapes `geometry` was prepared from.
    shapes: Vec<ColliderShape>,
    pub friction: Vec<f64>,
    /// Poses of the colliders this solve uses (between the start and the end pose).
    pub poses: Vec<Pose>,
    pub solids: Vec<ObstacleSolid>,
    pub points: Vec<ObstacleFeature<1>>,
    pub edges: Vec<ObstacleFeature<2>>,
    /// Collider mesh triangles (a ribbon vertex against them).
    pub triangles: Vec<ObstacleFeature<3>>,
    pub bodies: Vec<ObstacleBody>,
    /// Sorting axis of every box list (0, 1, 2).
    pub axis: usize,
}

/// `world_from_collider` a fraction `tau` of the way from `p0` to `p1` (translation
/// linear, rotation slerp).
pub fn interpolate_pose(p0: &Pose, p1: &Pose, tau: f64) -> Pose {
    if tau <= 0.0 {
        return *p0;
    }
    if tau >= 1.0 {
        return *p1;
    }
    let t = p0.translation.vector.lerp(&p1.translation.vector, tau);
    let r = p0.rotation.slerp(&p1.rotation, tau);
    Pose::from_parts(t.into(), r)
}

impl Obstacles {
    /// Refill from `env` with the colliders a fraction `tau` of the way through their
    /// motion, the other bodies as they are, boxes sorted along `axis`.
    pub fn update(&mut self, env: &ContactEnv, tau: f64, axis: usize) {
        self.axis = axis;
        self.move_colliders(env, tau);
        self.bodies
            .resize_with(env.others.len(), ObstacleBody::default);
        for (body, other) in self.bodies.iter_mut().zip(env.others) {
            body.fill(other, axis);
        }
    }

    /// Only the colliders a fraction `tau` of the way through their motion: the other
    /// bodies stand still during a body's step, so what [`Obstacles::update`] filled
    /// for this step holds (17 bodies of 100 cells each in the double chain, per
    /// contact round).
    pub fn move_colliders(&mut self, env: &ContactEnv, tau: f64) {
        self.settings = env.settings;
        // prepared again when the colliders change (a robot's links arrive)
        let same = self.shapes.len() == env.colliders.len()
            && self
                .shapes
                .iter()
                .zip(env.colliders)
                .all(|(s, c)| *s == c.shape);
        if !same {
            self.shapes = env.colliders.iter().map(|c| c.shape.clone()).collect();
            self.geometry = env
                .colliders
                .iter()
                .map(|c| ColliderGeometry::new(&c.shape))
                .collect();
        }
        self.friction.clear();
        self.friction
            .extend(env.colliders.iter().map(|c| c.friction));
        self.poses.clear();
        self.poses.extend(
            env.poses0
                .iter()
                .zip(env.poses1)
                .map(|(a, b)| interpolate_pose(a, b, tau)),
        );
        self.colliders_to_world();
    }

    /// The colliders' solids and features at `self.poses`.
    fn colliders_to_world(&mut self) {
        let half = 0.5 * self.settings.thickness;
        self.solids.clear();
        self.points.clear();
        self.edges.clear();
        self.triangles.clear();
        for (k, (geometry, pose)) in self.geometry.iter().zip(&self.poses).enumerate() {
            if geometry.solid.is_some() {
                self.solids.push(ObstacleSolid {
                    collider: k,
                    pose: *pose,
                    aabb: geometry.solid_aabb(pose),
                    plane: geometry.world_plane(pose),
                });
            }
            let world = |i: u32| (pose * geometry.vertices[i as usize]).coords;
            let offset = half + geometry.radius;
            for i in 0..geometry.vertices.len() as u32 {
                self.points
                    .push(ObstacleFeature::new([world(i)], offset, k));
            }
            for e in &geometry.edges {
                self.edges
                    .push(ObstacleFeature::new([world(e[0]), world(e[1])], offset, k));
            }
            if geometry.vertex_faces {
                for t in &geometry.triangles {
                    self.triangles.push(ObstacleFeature::new(
                        [world(t[0]), world(t[1]), world(t[2])],
                        offset,
                        k,
                    ));
                }
            }
        }
    }

    /// Signed distance (m) of world point `x` to solid `s` and its outward normal.
    #[inline]
    pub fn solid_distance(&self, s: &ObstacleSolid, x: &Vector3) -> (f64, Vector3) {
        if let Some((n, offset)) = s.plane {
            return (n.dot(x) - offset, n);
        }
        self.geometry[s.collider]
            .signed_distance(&s.pose, x)
            .expect("an obstacle solid has a solid")
    }
}

impl ObstacleBody {
    fn fill(&mut self, other: &OtherMesh, axis: usize) {
        self.vertices.clear();
        self.vertices
            .extend(other.vertices.iter().map(|p| p.coords));
        self.shift.clear();
        self.shift
            .extend(other.vertices.iter().zip(other.start).map(|(p, q)| p - q));
        self.cells = Arc::clone(other.cells);
        self.boxes.clear();
        let v = &self.vertices;
        self.boxes.extend(
            self.cells
                .triangles
                .iter()
                .map(|t| bounds(&[v[t[0] as usize], v[t[1] as usize], v[t[2] as usize]])),
        );
        sort_boxes(&self.boxes, axis, &mut self.order);
        self.widest = self
            .boxes
            .iter()
            .fold(0.0, |w, (lo, hi)| f64::max(w, hi[axis] - lo[axis]));
        let (lo, hi) = self.boxes.iter().fold(
            (
                Vector3::repeat(f64::INFINITY),
                Vector3::repeat(f64::NEG_INFINITY),
            ),
            |(lo, hi), (a, b)| (lo.inf(a), hi.sup(b)),
        );
        self.lo = lo;
        self.hi = hi;
    }
}

/// The box of a few points.
#[inline]
pub fn bounds(x: &[Vector3]) -> (Vector3, Vector3) {
    x.iter().fold(
        (
            Vector3::repeat(f64::INFINITY),
            Vector3::repeat(f64::NEG_INFINITY),
        ),
        |(lo, hi), p| (lo.inf(p), hi.sup(p)),
    )
}

/// Whether two boxes come within `margin` of each other on every axis.
#[inline]
pub fn boxes_near(a: &(Vector3, Vector3), b: &(Vector3, Vector3), margin: f64) -> bool {
    (0..3).all(|d| a.0[d] - b.1[d] <= margin && b.0[d] - a.1[d] <= margin)
}

/// Whether the points `a` and `b` are more than `reach` apart along some axis: then
/// so are their convex hulls (a pair's exact distance is not needed to know it is
/// beyond the barrier).
pub fn apart(a: &[Vector3], b: &[Vector3], reach: f64) -> bool {
    !boxes_near(&bounds(a), &bounds(b), reach)
}

/// Indices of `boxes` sorted by their minimum along `axis` (ties by index:
/// deterministic).
pub fn sort_boxes(boxes: &[(Vector3, Vector3)], axis: usize, order: &mut Vec<u32>) {
    order.clear();
    order.extend(0..boxes.len() as u32);
    order.sort_unstable_by(|&a, &b| {
        boxes[a as usize].0[axis]
            .total_cmp(&boxes[b as usize].0[axis])
            .then(a.cmp(&b))
    });
}

/// The range of `order` (sorted by box minimum along `axis`) whose boxes may come
/// within `margin` of the interval [lo, hi] along `axis`, given that no box is wider
/// than `widest`: minima in [lo - widest - margin, hi + margin].
pub fn window(
    boxes: &[(Vector3, Vector3)],
    order: &[u32],
    axis: usize,
    widest: f64,
    lo: f64,
    hi: f64,
    margin: f64,
) -> std::ops::Range<usize> {
    let min_of = |i: &u32| boxes[*i as usize].0[axis];
    let start = order.partition_point(|i| min_of(i) < lo - widest - margin);
    let end = order.partition_point(|i| min_of(i) <= hi + margin);
    start..end.max(start)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_vertex_and_edge_has_exactly_one_owning_cell() {
        // a strip of 3 quads, two triangles each (the ribbon's pattern)
        let mut tris = Vec::new();
        for e in 0..3u32 {
            let (xb, yb, xn, yn) = (2 * e, 2 * e + 1, 2 * e + 2, 2 * e + 3);
            tris.push([xb, xn, yn]);
            tris.push([xb, yn, yb]);
        }
        let cells = CellMesh::new(&tris, 8);
        let mut vertices: Vec<u32> = cells.vertices.clone();
        vertices.sort_unstable();
        assert_eq!(vertices, (0..8).collect::<Vec<_>>());
        let mut edges = cells.edges.clone();
        edges.sort_unstable();
        let before = edges.len();
        edges.dedup();
        assert_eq!(edges.len(), before, "an edge owned twice");
        // 3 quads: 4 rungs + 6 rim edges + 3 diagonals
        assert_eq!(edges.len(), 13);
        for t in 0..cells.len() {
            for v in cells.owned_vertices(t) {
                assert!(tris[t].contains(v));
            }
            for e in cells.owned_edges(t) {
                assert!(tris[t].contains(&e[0]) && tris[t].contains(&e[1]));
            }
        }
    }

    #[test]
    fn the_window_holds_every_box_that_can_come_near() {
        let boxes: Vec<(Vector3, Vector3)> = (0..50)
            .map(|i| {
                let x = (i as f64 * 0.37).sin();
                (Vector3::new(x, 0.0, 0.0), Vector3::new(x + 0.05, 0.1, 0.1))
            })
            .collect();
        let mut order = Vec::new();
        sort_boxes(&boxes, 0, &mut order);
        let widest = 0.05;
        let (lo, hi, margin) = (0.2, 0.3, 0.01);
        let w = window(&boxes, &order, 0, widest, lo, hi, margin);
        for (i, b) in boxes.iter().enumerate() {
            let near = b.0.x - hi <= margin && lo - b.1.x <= margin;
            let inside = order[w.clone()].contains(&(i as u32));
            assert!(!near || inside, "box {i} missed");
        }
    }
}
