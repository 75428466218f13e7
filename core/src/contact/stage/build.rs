//! Building a contact stage: checks of the settings and topologies, the deformable
//! bodies' meshes and closeness metrics, the colliders' meshes.

use super::{Closeness, ContactSettings, ContactStage, DeformableBody};
use crate::contact::collider::{Collider, ColliderGeometry};
use crate::contact::detect::{Detector, MeshBody, MeshKind};
use crate::contact::metric::BodyMetric;
use crate::contact::qp::DualActiveSet;
use crate::contact::{BodyTopology, ContactError};
use crate::geometry::Vector3;

/// Thickness h > 0 m and edge stiffness K >= 0, both finite.
fn check_settings(settings: &ContactSettings) -> Result<(), ContactError> {
    if !(settings.thickness > 0.0 && settings.thickness.is_finite()) {
        return Err(ContactError::Invalid(format!(
            "thickness must be > 0 m, got {}",
            settings.thickness
        )));
    }
    if !(settings.stiffness >= 0.0 && settings.stiffness.is_finite()) {
        return Err(ContactError::Invalid(format!(
            "stiffness must be >= 0, got {}",
            settings.stiffness
        )));
    }
    Ok(())
}

/// Body `i`'s topology is consistent: one station per contact vertex, every mesh and
/// triangle vertex a contact vertex.
fn check_topology(i: usize, t: &BodyTopology) -> Result<(), ContactError> {
    let check = |ok: bool, what: &str| {
        if ok {
            Ok(())
        } else {
            Err(ContactError::Invalid(format!("body {i}: {what}")))
        }
    };
    check(
        t.stations.len() == t.vertices,
        "one station per contact vertex",
    )?;
    check(
        t.vertex_of.iter().all(|&v| (v as usize) < t.vertices),
        "vertex_of out of range",
    )?;
    check(
        t.triangles
            .iter()
            .flatten()
            .all(|&v| (v as usize) < t.vertices),
        "triangle vertex out of range",
    )
}

/// The deformable bodies' contact meshes (half thickness h/2, m) pushed to `meshes`,
/// with their closeness metrics (edge stiffness `stiffness`, 0 for the plain
/// closeness), numbered from global vertex 0 in body order. Returns the bodies and the
/// number of unknown (contact) vertices.
fn deformable_bodies(
    settings: &ContactSettings,
    bodies: Vec<BodyTopology>,
    stiffness: f64,
    meshes: &mut Vec<MeshBody>,
) -> Result<(Vec<DeformableBody>, usize), ContactError> {
    let half = 0.5 * settings.thickness;
    let mut deformable = Vec::new();
    let mut first = 0usize;
    for (i, t) in bodies.into_iter().enumerate() {
        check_topology(i, &t)?;
        let mesh = MeshBody::new(
            first as u32,
            t.vertices as u32,
            t.triangles.clone(),
            &[],
            half,
            MeshKind::Deformable,
            settings.self_contact,
            t.stations.clone(),
            t.period,
            t.neighbour_skip,
        );
        let metric = BodyMetric::new(t.vertices, &mesh.edges, stiffness)?;
        meshes.push(mesh);
        deformable.push(DeformableBody {
            topology: t,
            first,
            metric,
        });
        first += deformable.last().map(|b| b.topology.vertices).unwrap_or(0);
    }
    Ok((deformable, first))
}

/// The colliders' geometries, and the kinematic contact meshes of those that have
/// vertices pushed to `meshes`, numbered from global vertex `first` on. Returns the
/// geometries and the total number of global vertices.
fn collider_geometry(
    colliders: &[Collider],
    mut first: usize,
    meshes: &mut Vec<MeshBody>,
) -> Result<(Vec<ColliderGeometry>, usize), ContactError> {
    let mut geometry = Vec::new();
    for (k, c) in colliders.iter().enumerate() {
        if !(c.friction >= 0.0 && c.friction.is_finite()) {
            return Err(ContactError::Invalid(format!(
                "collider {k}: friction must be >= 0, got {}",
                c.friction
            )));
        }
        let g = ColliderGeometry::new(&c.shape);
        if !g.vertices.is_empty() {
            let n = g.vertices.len();
            meshes.push(MeshBody::new(
                first as u32,
                n as u32,
                g.triangles.clone(),
                &g.edges,
                g.radius,
                MeshKind::Kinematic {
                    collider: k as u32,
                    solid: g.solid.is_some(),
                    vertex_faces: g.vertex_faces,
                },
                false,
                vec![0.0; n],
                None,
                0.0,
            ));
            first += n;
        }
        geometry.push(g);
    }
    Ok((geometry, first))
}

impl ContactStage {
    /// Build the stage for `bodies` (the ribbons, in world object order) and
    /// `colliders`: meshes, broad-phase leaves and the metric factorizations.
    pub fn new(
        settings: ContactSettings,
        bodies: Vec<BodyTopology>,
        colliders: Vec<Collider>,
    ) -> Result<Self, ContactError> {
        check_settings(&settings)?;
        let stiffness = match settings.closeness {
            Closeness::Stiff => settings.stiffness,
            Closeness::Plain => 0.0,
        };
        let mut meshes = Vec::new();
        let (deformable, unknowns) = deformable_bodies(&settings, bodies, stiffness, &mut meshes)?;
        let (geometry, first) = collider_geometry(&colliders, unknowns, &mut meshes)?;
        let n_bodies = deformable.len();
        Ok(ContactStage {
            settings,
            bodies: deformable,
            colliders,
            geometry,
            meshes,
            unknowns,
            detector: Detector::default(),
            x0: vec![Vector3::zeros(); first],
            target: vec![Vector3::zeros(); first],
            x: vec![Vector3::zeros(); first],
            predicted: Vec::new(),
            poses0: Vec::new(),
            poses1: Vec::new(),
            detected: Vec::new(),
            constraints: Vec::new(),
            merged: Vec::new(),
            lambda: Vec::new(),
            zone_of_body: vec![0; n_bodies],
            zone_constraints: Vec::new(),
            columns: Vec::new(),
            column_of: Vec::new(),
            dual_a: Vec::new(),
            dual_b: Vec::new(),
            dual_lambda: Vec::new(),
            qp: DualActiveSet::new(),
            body_columns: vec![Vec::new(); n_bodies],
            body_offset: Vec::new(),
            rhs: Vec::new(),
        })
    }
}
