//! `Simulation.state(object)`: one object's state as NumPy arrays (copies), with the
//! last step's solver report. Units are SI, as in the scene files.

use developable_sim::sim::{ObjectStepReport, World};
use numpy::prelude::*;
use numpy::{PyArray1, PyArray2};
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// The state of one object after the last step (or at t = 0 before any step).
///
/// Arrays are float64 unless said and are copies (changing them changes nothing in the
/// simulation). Vertex i of `vertices`, `material` and `regions` is the same vertex.
#[pyclass(module = "developable_sim", name = "ObjectState", frozen, get_all)]
pub struct ObjectState {
    /// The object's name in the scene (`ribbon` for a `ribbon:` section).
    name: String,
    /// Its kind: the scene-file section that declares it (`ribbon`, `paper`).
    kind: String,
    /// Simulation time of this state, s.
    time: f64,
    /// (N, 3) vertex positions in the scene frame, m.
    vertices: Py<PyArray2<f64>>,
    /// (T, 3) uint32 vertex indices of each triangle, counter-clockwise seen from the
    /// material +z side.
    triangles: Py<PyArray2<u32>>,
    /// (N, 2) material (flat-pattern) coordinates [u, v] of each vertex, m.
    material: Py<PyArray2<f64>>,
    /// (R, 2) uint32 vertex index pairs of the ruling and crease segments.
    rulings: Py<PyArray2<u32>>,
    /// (N,) uint8 region of each vertex: 0 flat, 1 curved (ruled), 2 singular.
    regions: Py<PyArray1<u8>>,
    /// (K,) uint64 stable ids of the singular points (where rulings meet).
    singular_ids: Py<PyArray1<u64>>,
    /// (K, 3) singular points in the scene frame, m.
    singular_positions: Py<PyArray2<f64>>,
    /// (K, 2) singular points in the flat pattern [u, v], m.
    singular_material: Py<PyArray2<f64>>,
    /// Energies of the state, J: `kinetic`, `elastic` (bending and crease regularizer
    /// for ribbons, stretching and bending for paper), `gravity` (-m g.x, zero at the
    /// origin), `external` (handle terms and forces), `total`.
    energies: Py<PyDict>,
    /// Largest |edge length - material length| / material length over the mesh's
    /// edges (dimensionless; ribbons are isometric by construction: round-off).
    isometry_error: f64,
    /// Named reduced coordinates (ribbons: `crease_direction` c, dimensionless, and
    /// `bending_angle` psi, rad, each n + 1 entries for creases k = 0..n, the ends
    /// c_0 = c_n = 0); empty for paper.
    coordinates: Py<PyDict>,
    /// Inner solver iterations of the last step, summed over augmented-Lagrangian
    /// rounds (None before the first step).
    iterations: Option<u32>,
    /// Augmented-Lagrangian (outer) rounds of the last step.
    outer_iterations: Option<u32>,
    /// Whether the last step's solver converged (False: it stopped on its iteration
    /// limit; the state is still the best finite one found).
    converged: Option<bool>,
    /// Whether the last step's result was not finite and the previous state was kept.
    kept_previous_state: Option<bool>,
    /// Largest handle or loop constraint violation after the last step, m.
    constraint_violation: Option<f64>,
}

#[pymethods]
impl ObjectState {
    fn __repr__(&self, py: Python<'_>) -> String {
        format!(
            "ObjectState(name={:?}, kind={:?}, time={}, vertices={}, singular_points={})",
            self.name,
            self.kind,
            self.time,
            self.vertices.bind(py).shape()[0],
            self.singular_ids.bind(py).shape()[0]
        )
    }
}

/// The state of object `o` of `world`; `report` is its last step's (None before one).
pub fn object_state(
    py: Python<'_>,
    world: &World,
    o: usize,
    report: Option<&ObjectStepReport>,
) -> PyResult<ObjectState> {
    let object = world.object(o);
    let mesh = object.mesh();
    let flat3 = |ps: &mut dyn Iterator<Item = [f64; 3]>| ps.flatten().collect::<Vec<f64>>();
    let vertices = flat3(&mut mesh.vertices.iter().map(|p| [p.x, p.y, p.z]));
    let material: Vec<f64> = mesh.material.iter().flat_map(|p| [p.x, p.y]).collect();
    let triangles: Vec<u32> = mesh.triangles.iter().flatten().copied().collect();
    let rulings: Vec<u32> = mesh.rulings.iter().flatten().copied().collect();
    let regions: Vec<u8> = mesh.regions.iter().map(|r| *r as u8).collect();
    let singular = object.singular_points();
    let ids: Vec<u64> = singular.iter().map(|s| s.id).collect();
    let sp = flat3(
        &mut singular
            .iter()
            .map(|s| [s.position.x, s.position.y, s.position.z]),
    );
    let sm: Vec<f64> = singular
        .iter()
        .flat_map(|s| [s.material.x, s.material.y])
        .collect();
    let e = object.energies();
    let energies = PyDict::new(py);
    for (k, v) in [
        ("kinetic", e.kinetic),
        ("elastic", e.elastic),
        ("gravity", e.gravity),
        ("external", e.external),
        ("total", e.total()),
    ] {
        energies.set_item(k, v)?;
    }
    let coordinates = PyDict::new(py);
    for (k, v) in object.coordinates() {
        coordinates.set_item(k, PyArray1::from_slice(py, v))?;
    }
    Ok(ObjectState {
        name: world.object_names()[o].clone(),
        kind: object.kind().to_string(),
        time: world.time(),
        vertices: matrix(py, vertices, 3)?,
        triangles: matrix(py, triangles, 3)?,
        material: matrix(py, material, 2)?,
        rulings: matrix(py, rulings, 2)?,
        regions: PyArray1::from_vec(py, regions).unbind(),
        singular_ids: PyArray1::from_vec(py, ids).unbind(),
        singular_positions: matrix(py, sp, 3)?,
        singular_material: matrix(py, sm, 2)?,
        energies: energies.unbind(),
        isometry_error: mesh.isometry_error(),
        coordinates: coordinates.unbind(),
        iterations: report.map(|r| r.iterations),
        outer_iterations: report.map(|r| r.outer_iterations),
        converged: report.map(|r| r.converged),
        kept_previous_state: report.map(|r| r.kept_previous_state),
        constraint_violation: report.map(|r| r.constraint_violation),
    })
}

/// A (len / cols, cols) array of `flat`.
pub fn matrix<T: numpy::Element>(
    py: Python<'_>,
    flat: Vec<T>,
    cols: usize,
) -> PyResult<Py<PyArray2<T>>> {
    let rows = flat.len() / cols;
    Ok(PyArray1::from_vec(py, flat).reshape([rows, cols])?.unbind())
}
