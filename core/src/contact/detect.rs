//! Detection: which vertex-face, edge-edge and vertex-solid pairs are in contact over
//! the motion from the previous collision-free mesh (t = 0) to the current iterate
//! (t = 1), as linear constraints for the impact-zone QP.
//!
//! All vertices live in one global index space: the contact vertices of every ribbon
//! first (the QP's unknowns), then the feature vertices of the colliders (moved by
//! their poses, fixed in the QP). Each mesh is cut into *leaves* for the broad phase:
//! one per triangle, owning the vertices and edges it is the first to contain (then one
//! per edge and per vertex not in any triangle: capsules and spheres). Two leaves whose
//! swept boxes (inflated by the contact distance) overlap test the vertex-face and
//! edge-edge pairs they own, so every feature pair is tested exactly once. The broad
//! phase is a sort-and-sweep along the axis of largest spread (deterministic).

use super::ccd::{edge_edge, vertex_face, Location, Motion, PrimitiveContact};
use super::collider::ColliderGeometry;
use crate::geometry::{Pose, Vector3};

/// A mesh feature in global vertex ids (sorted), or a collider's solid.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub(crate) enum Feature {
    Vertex(u32),
    Edge(u32, u32),
    Face(u32, u32, u32),
    Solid(u32),
}

/// The closest-feature pair a contact is about (its identity across iterations).
pub(crate) type ContactKey = (Feature, Feature);

/// A linearized contact constraint: gap(X) = n · Σ w_i x_{v_i} + offset >= distance.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Contact {
    pub key: ContactKey,
    /// Global vertex ids (ribbon unknowns and collider vertices).
    pub vertices: [u32; 4],
    pub weights: [f64; 4],
    pub count: u8,
    /// Unit normal, oriented from the obstacle towards the side the first feature came
    /// from.
    pub normal: Vector3,
    /// Constant part of the gap, m (solids: -n · surface point).
    pub offset: f64,
    /// Required separation, m.
    pub distance: f64,
    /// The collider involved, if any (friction).
    pub collider: Option<u32>,
    /// Found by a continuous (crossing) test rather than end-of-step proximity.
    pub crossing: bool,
}

impl Contact {
    /// The gap at positions `x` (global ids), m.
    #[inline]
    pub fn gap(&self, x: &[Vector3]) -> f64 {
        let mut g = self.offset;
        for i in 0..self.count as usize {
            g += self.weights[i] * self.normal.dot(&x[self.vertices[i] as usize]);
        }
        g
    }
}

/// What a mesh is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum MeshKind {
    /// A ribbon: its vertices are QP unknowns.
    Deformable,
    /// The features of collider `collider`; `solid`: ribbon vertices are tested against
    /// its solid, so its feature contacts located at a ribbon vertex are redundant;
    /// `vertex_faces`: ribbon vertices are tested against its triangles.
    Kinematic {
        collider: u32,
        solid: bool,
        vertex_faces: bool,
    },
}

/// One mesh in the global vertex space with its broad-phase leaves.
#[derive(Clone, Debug)]
pub(crate) struct MeshBody {
    pub first: u32,
    pub edges: Vec<[u32; 2]>,
    pub triangles: Vec<[u32; 3]>,
    /// Half thickness plus rounding, m: two meshes are in contact closer than the sum.
    pub reach: f64,
    pub kind: MeshKind,
    /// Self contact (ribbons): pairs whose station intervals are closer than `skip`
    /// (cyclic with `period`) are topological neighbours and never tested.
    pub self_contact: bool,
    pub stations: Vec<f64>,
    pub period: Option<f64>,
    pub skip: f64,
    /// Station ranges (start, length) of every vertex, edge and triangle, precomputed
    /// for the neighbour filter.
    vertex_arc: Vec<(f64, f64)>,
    edge_arc: Vec<(f64, f64)>,
    triangle_arc: Vec<(f64, f64)>,
    leaf_face: Vec<Option<u32>>,
    leaf_vertex_start: Vec<u32>,
    leaf_vertices: Vec<u32>,
    leaf_edge_start: Vec<u32>,
    leaf_edges: Vec<u32>,
}

impl MeshBody {
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn new(
        first: u32,
        vertex_count: u32,
        triangles: Vec<[u32; 3]>,
        extra_edges: &[[u32; 2]],
        reach: f64,
        kind: MeshKind,
        self_contact: bool,
        stations: Vec<f64>,
        period: Option<f64>,
        skip: f64,
    ) -> Self {
        let mut edges: Vec<[u32; 2]> = triangles
            .iter()
            .flat_map(|t| [[t[0], t[1]], [t[1], t[2]], [t[2], t[0]]])
            .chain(extra_edges.iter().copied())
            .filter(|[a, b]| a != b)
            .map(|[a, b]| if a < b { [a, b] } else { [b, a] })
            .collect();
        edges.sort_unstable();
        edges.dedup();
        let edge_index = |a: u32, b: u32| -> u32 {
            let key = if a < b { [a, b] } else { [b, a] };
            edges.binary_search(&key).expect("edge of a triangle") as u32
        };
        let mut vertex_owned = vec![false; vertex_count as usize];
        let mut edge_owned = vec![false; edges.len()];
        let mut body = MeshBody {
            first,
            edges: Vec::new(),
            triangles: Vec::new(),
            reach,
            kind,
            self_contact,
            stations,
            period,
            skip,
            vertex_arc: Vec::new(),
            edge_arc: Vec::new(),
            triangle_arc: Vec::new(),
            leaf_face: Vec::new(),
            leaf_vertex_start: vec![0],
            leaf_vertices: Vec::new(),
            leaf_edge_start: vec![0],
            leaf_edges: Vec::new(),
        };
        for (t, tri) in triangles.iter().enumerate() {
            body.leaf_face.push(Some(t as u32));
            for &v in tri {
                if !vertex_owned[v as usize] {
                    vertex_owned[v as usize] = true;
                    body.leaf_vertices.push(v);
                }
            }
            for (a, b) in [(tri[0], tri[1]), (tri[1], tri[2]), (tri[2], tri[0])] {
                if a == b {
                    continue;
                }
                let e = edge_index(a, b);
                if !edge_owned[e as usize] {
                    edge_owned[e as usize] = true;
                    body.leaf_edges.push(e);
                }
            }
            body.leaf_vertex_start.push(body.leaf_vertices.len() as u32);
            body.leaf_edge_start.push(body.leaf_edges.len() as u32);
        }
        for (e, &[a, b]) in edges.iter().enumerate() {
            if edge_owned[e] {
                continue;
            }
            edge_owned[e] = true;
            body.leaf_face.push(None);
            body.leaf_edges.push(e as u32);
            for v in [a, b] {
                if !vertex_owned[v as usize] {
                    vertex_owned[v as usize] = true;
                    body.leaf_vertices.push(v);
                }
            }
            body.leaf_vertex_start.push(body.leaf_vertices.len() as u32);
            body.leaf_edge_start.push(body.leaf_edges.len() as u32);
        }
        for v in 0..vertex_count {
            if !vertex_owned[v as usize] {
                body.leaf_face.push(None);
                body.leaf_vertices.push(v);
                body.leaf_vertex_start.push(body.leaf_vertices.len() as u32);
                body.leaf_edge_start.push(body.leaf_edges.len() as u32);
            }
        }
        body.vertex_arc = (0..vertex_count).map(|v| body.range(&[v])).collect();
        body.edge_arc = edges.iter().map(|e| body.range(e)).collect();
        body.triangle_arc = triangles.iter().map(|t| body.range(t)).collect();
        body.edges = edges;
        body.triangles = triangles;
        body
    }

    fn leaves(&self) -> usize {
        self.leaf_face.len()
    }
    fn owned_vertices(&self, leaf: usize) -> &[u32] {
        let (a, b) = (
            self.leaf_vertex_start[leaf] as usize,
            self.leaf_vertex_start[leaf + 1] as usize,
        );
        &self.leaf_vertices[a..b]
    }
    fn owned_edges(&self, leaf: usize) -> &[u32] {
        let (a, b) = (
            self.leaf_edge_start[leaf] as usize,
            self.leaf_edge_start[leaf + 1] as usize,
        );
        &self.leaf_edges[a..b]
    }
    fn is_deformable(&self) -> bool {
        self.kind == MeshKind::Deformable
    }
    #[inline]
    fn global(&self, v: u32) -> u32 {
        self.first + v
    }

    /// The station range (start, length) of a set of local vertices: an interval on a
    /// line, or the shortest arc covering them on a circle of length `period`.
    fn range(&self, vs: &[u32]) -> (f64, f64) {
        match self.period {
            None => {
                let (lo, hi) =
                    vs.iter()
                        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| {
                            let s = self.stations[v as usize];
                            (lo.min(s), hi.max(s))
                        });
                (lo, hi - lo)
            }
            Some(p) => {
                let mut s = [0.0; 3];
                let k = vs.len().min(3);
                for i in 0..k {
                    s[i] = self.stations[vs[i] as usize].rem_euclid(p);
                }
                s[..k].sort_by(f64::total_cmp);
                // leave out the largest gap between cyclically consecutive stations
                let mut best = (s[0], 0.0);
                let mut largest = -1.0;
                for i in 0..k {
                    let next = if i + 1 < k { s[i + 1] } else { s[0] + p };
                    let gap = next - s[i];
                    if gap > largest {
                        largest = gap;
                        best = (next.rem_euclid(p), p - gap);
                    }
                }
                best
            }
        }
    }

    /// Distance between two station ranges (0 when they overlap).
    #[inline]
    fn range_gap(&self, a: (f64, f64), b: (f64, f64)) -> f64 {
        match self.period {
            None => (b.0 - (a.0 + a.1)).max(a.0 - (b.0 + b.1)).max(0.0),
            Some(p) => {
                // forward distance from `from` to `to` on the circle (both in [0, 2p))
                let fwd = |from: f64, to: f64| {
                    let mut d = to - from;
                    while d < 0.0 {
                        d += p;
                    }
                    while d >= p {
                        d -= p;
                    }
                    d
                };
                if fwd(a.0, b.0) <= a.1 || fwd(b.0, a.0) <= b.1 {
                    0.0
                } else {
                    fwd(a.0 + a.1, b.0).min(fwd(b.0 + b.1, a.0))
                }
            }
        }
    }
}

/// Reusable detection state.
#[derive(Clone, Debug, Default)]
pub(crate) struct Detector {
    /// (body, leaf) of each global leaf.
    leaf_refs: Vec<(u32, u32)>,
    boxes: Vec<(Vector3, Vector3)>,
    order: Vec<(f64, u32)>,
    active: Vec<u32>,
    pairs: Vec<(u32, u32)>,
}

/// Positions and poses the detection reads.
pub(crate) struct DetectInput<'a> {
    /// Start of the motion (previous collision-free state), global ids, m.
    pub x0: &'a [Vector3],
    /// End of the motion (current iterate), global ids, m.
    pub x1: &'a [Vector3],
    /// Number of global ids that are ribbon unknowns (the first ones).
    pub unknowns: usize,
    pub bodies: &'a [MeshBody],
    pub colliders: &'a [ColliderGeometry],
    pub poses0: &'a [Pose],
    pub poses1: &'a [Pose],
    /// Half thickness of the ribbons, m: the distance kept from a solid.
    pub half_thickness: f64,
    /// How close to a triangle (edge) a coplanar vertex (edge) must be to count as a
    /// crossing, m.
    pub crossing_eps: f64,
}

impl Detector {
    /// All contacts closer than their distance (or crossing) at `input.x1`, sorted by
    /// key, one per key.
    pub(crate) fn detect(&mut self, input: &DetectInput, out: &mut Vec<Contact>) {
        out.clear();
        self.solids(input, out);
        self.broad_phase(input);
        for p in 0..self.pairs.len() {
            let (la, lb) = self.pairs[p];
            let (ba, a) = self.leaf_refs[la as usize];
            let (bb, b) = self.leaf_refs[lb as usize];
            narrow_phase(input, ba as usize, a as usize, bb as usize, b as usize, out);
        }
        out.sort_by(|a, b| {
            a.key
                .cmp(&b.key)
                .then(b.crossing.cmp(&a.crossing))
                .then((a.gap(input.x1) - a.distance).total_cmp(&(b.gap(input.x1) - b.distance)))
        });
        out.dedup_by(|later, first| later.key == first.key);
    }

    /// Every ribbon vertex against every solid.
    fn solids(&mut self, input: &DetectInput, out: &mut Vec<Contact>) {
        let d = input.half_thickness;
        for (k, geometry) in input.colliders.iter().enumerate() {
            if geometry.solid.is_none() {
                continue;
            }
            let (pose0, pose1) = (&input.poses0[k], &input.poses1[k]);
            let bounds = match (geometry.solid_aabb(pose0), geometry.solid_aabb(pose1)) {
                (Some(a), Some(b)) => Some((a.0.inf(&b.0), a.1.sup(&b.1))),
                _ => None,
            };
            for g in 0..input.unknowns {
                let (x0, x1) = (&input.x0[g], &input.x1[g]);
                if let Some((lo, hi)) = bounds {
                    let (vlo, vhi) = (x0.inf(x1), x0.sup(x1));
                    let outside = (0..3).any(|i| vhi[i] + d < lo[i] || vlo[i] - d > hi[i]);
                    if outside {
                        continue;
                    }
                }
                if let Some(c) = geometry.vertex_contact(pose0, pose1, x0, x1, d) {
                    out.push(Contact {
                        key: (Feature::Vertex(g as u32), Feature::Solid(k as u32)),
                        vertices: [g as u32, 0, 0, 0],
                        weights: [1.0, 0.0, 0.0, 0.0],
                        count: 1,
                        normal: c.normal,
                        offset: -c.normal.dot(&c.point),
                        distance: d,
                        collider: Some(k as u32),
                        crossing: c.crossing,
                    });
                }
            }
        }
    }

    fn broad_phase(&mut self, input: &DetectInput) {
        self.leaf_refs.clear();
        self.boxes.clear();
        for (bi, body) in input.bodies.iter().enumerate() {
            for leaf in 0..body.leaves() {
                let mut lo = Vector3::repeat(f64::INFINITY);
                let mut hi = Vector3::repeat(f64::NEG_INFINITY);
                let mut add = |v: u32| {
                    let g = body.global(v) as usize;
                    for x in [&input.x0[g], &input.x1[g]] {
                        lo = lo.inf(x);
                        hi = hi.sup(x);
                    }
                };
                if let Some(t) = body.leaf_face[leaf] {
                    body.triangles[t as usize].iter().for_each(|&v| add(v));
                }
                for &e in body.owned_edges(leaf) {
                    body.edges[e as usize].iter().for_each(|&v| add(v));
                }
                for &v in body.owned_vertices(leaf) {
                    add(v);
                }
                let r = Vector3::repeat(body.reach);
                self.leaf_refs.push((bi as u32, leaf as u32));
                self.boxes.push((lo - r, hi + r));
            }
        }
        // sweep axis: largest spread of the box centres
        let mut lo = Vector3::repeat(f64::INFINITY);
        let mut hi = Vector3::repeat(f64::NEG_INFINITY);
        for (a, b) in &self.boxes {
            let c = (a + b) * 0.5;
            lo = lo.inf(&c);
            hi = hi.sup(&c);
        }
        let spread = hi - lo;
        let axis = if spread.x >= spread.y && spread.x >= spread.z {
            0
        } else if spread.y >= spread.z {
            1
        } else {
            2
        };
        self.order.clear();
        self.order.extend(
            self.boxes
                .iter()
                .enumerate()
                .map(|(i, (a, _))| (a[axis], i as u32)),
        );
        self.order
            .sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        self.active.clear();
        self.pairs.clear();
        for k in 0..self.order.len() {
            let (start, i) = self.order[k];
            let boxes = &self.boxes;
            self.active.retain(|&j| boxes[j as usize].1[axis] >= start);
            let (ilo, ihi) = self.boxes[i as usize];
            let (bi, _) = self.leaf_refs[i as usize];
            let deformable_i = input.bodies[bi as usize].is_deformable();
            for &j in &self.active {
                let (bj, _) = self.leaf_refs[j as usize];
                if !deformable_i && !input.bodies[bj as usize].is_deformable() {
                    continue;
                }
                if bi == bj && !input.bodies[bi as usize].self_contact {
                    continue;
                }
                let (jlo, jhi) = self.boxes[j as usize];
                if (0..3).all(|d| ilo[d] <= jhi[d] && jlo[d] <= ihi[d]) {
                    self.pairs.push((i.min(j), i.max(j)));
                }
            }
            self.active.push(i);
        }
    }
}

fn motion(input: &DetectInput, g: u32) -> Motion {
    Motion {
        x0: input.x0[g as usize],
        x1: input.x1[g as usize],
    }
}

/// The vertex-face and edge-edge pairs owned by leaves `a` of body `ba` and `b` of body
/// `bb`.
fn narrow_phase(
    input: &DetectInput,
    ba: usize,
    a: usize,
    bb: usize,
    b: usize,
    out: &mut Vec<Contact>,
) {
    let (body_a, body_b) = (&input.bodies[ba], &input.bodies[bb]);
    let same = ba == bb;
    if same && a == b {
        return;
    }
    if same {
        // every feature pair of two leaves of neighbouring elements is a neighbour pair
        if let (Some(fa), Some(fb)) = (body_a.leaf_face[a], body_a.leaf_face[b]) {
            let (ra, rb) = (
                body_a.triangle_arc[fa as usize],
                body_a.triangle_arc[fb as usize],
            );
            if body_a.range_gap(ra, rb) + ra.1 + rb.1 <= body_a.skip {
                return;
            }
        }
    }
    let distance = body_a.reach + body_b.reach;
    // vertex-face, both ways
    for (bv, lv, bf, lf) in [(body_a, a, body_b, b), (body_b, b, body_a, a)] {
        let Some(f) = bf.leaf_face[lf] else { continue };
        if let MeshKind::Kinematic {
            vertex_faces: false,
            ..
        } = bf.kind
        {
            if bv.is_deformable() {
                continue;
            }
        }
        let tri = bf.triangles[f as usize];
        for &v in bv.owned_vertices(lv) {
            if same
                && bv.range_gap(bv.vertex_arc[v as usize], bv.triangle_arc[f as usize]) <= bv.skip
            {
                continue;
            }
            let ids = [
                bv.global(v),
                bf.global(tri[0]),
                bf.global(tri[1]),
                bf.global(tri[2]),
            ];
            let pts = ids.map(|g| motion(input, g));
            if let Some(pc) = vertex_face(&pts, distance, input.crossing_eps) {
                push(bv, bf, ids, &pc, distance, out);
            }
        }
    }
    // edge-edge
    for &ea in body_a.owned_edges(a) {
        let e1 = body_a.edges[ea as usize];
        for &eb in body_b.owned_edges(b) {
            let e2 = body_b.edges[eb as usize];
            if same
                && body_a.range_gap(body_a.edge_arc[ea as usize], body_a.edge_arc[eb as usize])
                    <= body_a.skip
            {
                continue;
            }
            let ids = [
                body_a.global(e1[0]),
                body_a.global(e1[1]),
                body_b.global(e2[0]),
                body_b.global(e2[1]),
            ];
            let pts = ids.map(|g| motion(input, g));
            if let Some(pc) = edge_edge(&pts, distance, input.crossing_eps) {
                push(body_a, body_b, ids, &pc, distance, out);
            }
        }
    }
}

fn feature(ids: &[u32; 4], loc: Location, face: bool) -> Feature {
    match loc {
        Location::Vertex(i) => Feature::Vertex(ids[i as usize]),
        Location::Edge(i, j) => {
            let (a, b) = (ids[i as usize], ids[j as usize]);
            Feature::Edge(a.min(b), a.max(b))
        }
        Location::Face => {
            debug_assert!(face);
            let mut t = [ids[1], ids[2], ids[3]];
            t.sort_unstable();
            Feature::Face(t[0], t[1], t[2])
        }
    }
}

/// Record a primitive contact between the first feature (of `first`) and the second
/// (of `second`), unless it duplicates a vertex-solid contact.
fn push(
    first: &MeshBody,
    second: &MeshBody,
    ids: [u32; 4],
    pc: &PrimitiveContact,
    distance: f64,
    out: &mut Vec<Contact>,
) {
    let fa = feature(&ids, pc.first, false);
    let fb = feature(&ids, pc.second, true);
    // A collider feature touching a ribbon vertex duplicates the vertex-solid contact
    // (when the collider has a solid): drop it.
    let mut collider = None;
    for (kinematic, ribbon, ribbon_feature) in [(first, second, &fb), (second, first, &fa)] {
        if let MeshKind::Kinematic {
            collider: k, solid, ..
        } = kinematic.kind
        {
            collider = Some(k);
            if solid && ribbon.is_deformable() && matches!(ribbon_feature, Feature::Vertex(_)) {
                return;
            }
        }
    }
    let key = if fa <= fb { (fa, fb) } else { (fb, fa) };
    let mut c = Contact {
        key,
        vertices: [0; 4],
        weights: [0.0; 4],
        count: 0,
        normal: pc.normal,
        offset: 0.0,
        distance,
        collider,
        crossing: pc.time_of_impact.is_some(),
    };
    for i in 0..4 {
        if pc.weights[i] != 0.0 {
            let k = c.count as usize;
            c.vertices[k] = ids[i];
            c.weights[k] = pc.weights[i];
            c.count += 1;
        }
    }
    out.push(c);
}
