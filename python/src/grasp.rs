//! Grasp, release and the handle wrench from Python: the arguments of `sim.grasp`
//! checked and turned into the world's `GraspAt` and `Hold` (issue 44,
//! `World::grasp`, `World::release`, `World::handle_wrench`; docs/grasp.md), refusals
//! raised as [`GraspError`], and what a handle holds as a [`HandleState`].

use developable_sim::geometry::{Point2, Point3};
use developable_sim::sim::{GraspAt, GraspError as RustGraspError, Grasped, Hold, OrientationMode};
use developable_sim::sim::{World, Wrench};
use numpy::{PyArray1, PyArrayMethods};
use pyo3::exceptions::{PyKeyError, PyTypeError, PyValueError};
use pyo3::prelude::*;

use crate::errors::GraspError;

/// Normal-guiding stiffness K of a `normal` hold for a handle whose scene gives none, J
/// (the scene files' default; the node's `~/grasp` service uses the same).
const DEFAULT_NORMAL_STIFFNESS: f64 = 1.0;

/// The index of the handle named `name`, or a KeyError listing the handles.
pub fn handle_index(world: &World, name: &str) -> PyResult<usize> {
    let handles = world.handles();
    handles.iter().position(|h| h.name == name).ok_or_else(|| {
        let known: Vec<&str> = handles.iter().map(|h| h.name.as_str()).collect();
        PyKeyError::new_err(format!(
            "no handle `{name}` in this scene (handles: {})",
            if known.is_empty() {
                "none".to_string()
            } else {
                known.join(", ")
            }
        ))
    })
}

/// The hold `name` asks for: `position`, `normal` (with the handle's scene stiffness, or
/// 1 J), `full`; None: as the scene declared the handle.
pub fn hold(world: &World, handle: usize, name: Option<&str>) -> PyResult<Option<Hold>> {
    Ok(match name {
        None => None,
        Some("position") => Some(Hold::Position),
        Some("normal") => {
            let stiffness = match world.scene_handles()[handle].orientation {
                OrientationMode::Normal { stiffness } => stiffness,
                _ => DEFAULT_NORMAL_STIFFNESS,
            };
            Some(Hold::Normal { stiffness })
        }
        Some("full") => Some(Hold::Full),
        Some(other) => {
            return Err(PyValueError::new_err(format!(
                "unknown hold `{other}`: 'position', 'normal', 'full', or None for the \
                 handle's own"
            )))
        }
    })
}

/// Where to grasp: `point` ([u, v] of the flat pattern, m), or the graspable point
/// nearest `near` (m, scene frame) within `max_distance` (m); with neither, the point
/// nearest the handle's current target within its `grasp_radius` (a gripper closing).
pub fn at<'py>(
    world: &World,
    handle: usize,
    point: Option<&Bound<'py, PyAny>>,
    near: Option<&Bound<'py, PyAny>>,
    max_distance: Option<f64>,
) -> PyResult<GraspAt> {
    fn given<'a, 'py>(x: Option<&'a Bound<'py, PyAny>>) -> Option<&'a Bound<'py, PyAny>> {
        x.filter(|v| !v.is_none())
    }
    match (given(point), given(near)) {
        (Some(_), Some(_)) => Err(PyTypeError::new_err(
            "give point ([u, v], m) or near ([x, y, z], m), not both",
        )),
        (Some(point), None) => {
            if max_distance.is_some() {
                return Err(PyTypeError::new_err(
                    "max_distance goes with near (a grasp by material point has no distance)",
                ));
            }
            let [u, v] = finite::<2>(point, "point ([u, v], m)")?;
            Ok(GraspAt::Material(Point2::new(u, v)))
        }
        (None, near) => {
            let point = match near {
                Some(near) => Point3::from(finite::<3>(near, "near ([x, y, z], m)")?),
                None => Point3::from(world.current_targets()[handle].translation.vector),
            };
            let max_distance = max_distance.unwrap_or(world.handles()[handle].grasp_radius);
            if max_distance.is_nan() || max_distance < 0.0 {
                return Err(PyValueError::new_err(format!(
                    "max_distance must be >= 0 m, got {max_distance}"
                )));
            }
            Ok(GraspAt::Nearest {
                point,
                max_distance,
            })
        }
    }
}

/// `N` finite floats from a sequence.
fn finite<const N: usize>(value: &Bound<'_, PyAny>, what: &str) -> PyResult<[f64; N]> {
    let v: Vec<f64> = value
        .extract()
        .map_err(|_| PyTypeError::new_err(format!("{what} must be {N} numbers")))?;
    let v: [f64; N] = v.try_into().map_err(|v: Vec<f64>| {
        PyValueError::new_err(format!("{what} must be {N} numbers, got {}", v.len()))
    })?;
    if v.iter().any(|x| !x.is_finite()) {
        return Err(PyValueError::new_err(format!("{what} {v:?} is not finite")));
    }
    Ok(v)
}

/// A refused grasp or release as a Python exception.
pub fn refused(e: &RustGraspError) -> PyErr {
    match e {
        RustGraspError::UnknownHandle(_) | RustGraspError::UnknownObject(_) => {
            PyKeyError::new_err(e.to_string())
        }
        _ => GraspError::new_err(e.to_string()),
    }
}

/// What a grasp did (`sim.grasp`).
#[pyclass(module = "developable_sim", name = "Grasp", frozen)]
pub struct GraspResult {
    /// The object held.
    #[pyo3(get)]
    object: String,
    /// The point held, [u, v] in the object's flat pattern, m.
    #[pyo3(get)]
    material_point: Py<PyArray1<f64>>,
    /// From the point asked for (`near`, or the handle's target) to the point held, m;
    /// 0 for a grasp by material point.
    #[pyo3(get)]
    distance: f64,
    /// False when the handle already held exactly this (nothing changed).
    #[pyo3(get)]
    changed: bool,
}

impl GraspResult {
    pub fn new(py: Python<'_>, world: &World, g: &Grasped) -> GraspResult {
        GraspResult {
            object: world.object_names()[g.object].clone(),
            material_point: pair(py, &g.material_point),
            distance: g.distance,
            changed: g.changed,
        }
    }
}

#[pymethods]
impl GraspResult {
    fn __repr__(&self, py: Python<'_>) -> String {
        let m = self.material_point.bind(py).to_vec().unwrap_or_default();
        format!(
            "Grasp(object={:?}, material_point={m:?}, distance={}, changed={})",
            self.object,
            self.distance,
            py_bool(self.changed)
        )
    }
}

/// What a handle holds now and what it feels (`sim.handle_state`).
#[pyclass(module = "developable_sim", name = "HandleState", frozen)]
pub struct HandleState {
    #[pyo3(get)]
    name: String,
    /// Whether the handle holds its object now.
    #[pyo3(get)]
    attached: bool,
    /// The object it holds (or held last, or the scene names for it).
    #[pyo3(get)]
    object: String,
    /// The point held (or held last), [u, v] in the object's flat pattern, m.
    #[pyo3(get)]
    material_point: Py<PyArray1<f64>>,
    /// Attachments so far: 0 the scene's own, + 1 at every grasp that changed the hold.
    #[pyo3(get)]
    generation: u64,
    /// Reach of a closing gripper (`sim.grasp(handle)` with neither point nor near), m.
    #[pyo3(get)]
    grasp_radius: f64,
    /// The force the object exerts on the gripper in the last step, N, scene frame; None
    /// when the handle holds nothing or has not stepped since it grasped.
    #[pyo3(get)]
    force: Option<Py<PyArray1<f64>>>,
    /// The torque the object exerts on the gripper about the grasp point, N m, scene
    /// frame; None as `force`.
    #[pyo3(get)]
    torque: Option<Py<PyArray1<f64>>>,
}

impl HandleState {
    pub fn new(py: Python<'_>, world: &World, handle: usize) -> HandleState {
        let spec = &world.handles()[handle];
        let (force, torque) = match world.handle_wrench(handle) {
            Some(w) => {
                let (f, t) = wrench_arrays(py, &w);
                (Some(f), Some(t))
            }
            None => (None, None),
        };
        HandleState {
            name: spec.name.clone(),
            attached: spec.attached,
            object: world.object_names()[spec.object].clone(),
            material_point: pair(py, &spec.material_point),
            generation: spec.generation,
            grasp_radius: spec.grasp_radius,
            force,
            torque,
        }
    }
}

#[pymethods]
impl HandleState {
    fn __repr__(&self, py: Python<'_>) -> String {
        let m = self.material_point.bind(py).to_vec().unwrap_or_default();
        format!(
            "HandleState(name={:?}, attached={}, object={:?}, material_point={m:?}, \
             generation={})",
            self.name,
            py_bool(self.attached),
            self.object,
            self.generation
        )
    }
}

/// (force (3,) N, torque (3,) N m) as NumPy arrays.
pub fn wrench_arrays(py: Python<'_>, w: &Wrench) -> (Py<PyArray1<f64>>, Py<PyArray1<f64>>) {
    let v = |x: &developable_sim::geometry::Vector3| {
        PyArray1::from_slice(py, &[x.x, x.y, x.z]).unbind()
    };
    (v(&w.force), v(&w.torque))
}

/// A bool as Python writes it.
fn py_bool(b: bool) -> &'static str {
    if b {
        "True"
    } else {
        "False"
    }
}

fn pair(py: Python<'_>, m: &Point2) -> Py<PyArray1<f64>> {
    PyArray1::from_slice(py, &[m.x, m.y]).unbind()
}
