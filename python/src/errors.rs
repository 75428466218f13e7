//! The module's exceptions and the boundary rules: every error of the library becomes a
//! Python exception that says what and where (a scene's key path), and a panic inside
//! the library is caught here and raised as [`SimulationError`], never unwound into
//! the interpreter.

use std::panic::{catch_unwind, AssertUnwindSafe};

use developable_sim::scene::SceneError as RustSceneError;
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::{create_exception, PyErr};

create_exception!(
    developable_sim,
    SceneError,
    PyValueError,
    "A scene that cannot be loaded or built. `str(e)` names the file, the key and the \
     reason; `e.key` is the key path in `--set` syntax (`ribbon.segments`, \
     `handles.0.point`) or None when the error has no key (YAML syntax, a missing file); \
     `e.file` is the scene's path."
);

create_exception!(
    developable_sim,
    SimulationError,
    PyRuntimeError,
    "The simulation could not do what was asked: an internal error (a panic in the \
     library, caught at the boundary: the simulation must be reset), a saved state that \
     does not replay to the state it recorded, or a simulation used after such an error."
);

create_exception!(
    developable_sim,
    GraspError,
    PyValueError,
    "A grasp or release the world refused, and why: the point is off the object (a sheet \
     of paper is held on its boundary only), the nearest graspable point is farther than \
     max_distance, the object has no surface, or the handle drives a ribbon's prescribed \
     base and cannot let go. Nothing changed."
);

/// Add the exceptions to the module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("SceneError", py.get_type::<SceneError>())?;
    m.add("SimulationError", py.get_type::<SimulationError>())?;
    m.add("GraspError", py.get_type::<GraspError>())?;
    Ok(())
}

/// A scene error as [`SceneError`] with `key` and `file` set.
pub fn scene_error(py: Python<'_>, e: &RustSceneError) -> PyErr {
    let (file, key) = match e {
        RustSceneError::Io { file, .. } => (Some(file.display().to_string()), None),
        RustSceneError::Parse { file, message } => {
            (Some(file.display().to_string()), key_of_message(message))
        }
        RustSceneError::Invalid { file, key, .. } => {
            (Some(file.display().to_string()), Some(key.clone()))
        }
        RustSceneError::Override { spec, .. } => (
            None,
            spec.split_once('=').map(|(k, _)| k.trim().to_string()),
        ),
    };
    let err = SceneError::new_err(e.to_string());
    let value = err.value(py);
    // setting an attribute on a fresh exception instance cannot fail
    let _ = value.setattr("key", key);
    let _ = value.setattr("file", file);
    err
}

/// The key path a parse message starts with, in `--set` syntax: "`ribbon.segments`:
/// ..." (the path the scene loader adds) or "handles[0].point: ..." (serde_yaml's own),
/// `[i]` written `.i`. None when the message names no key (a YAML syntax error).
pub fn key_of_message(message: &str) -> Option<String> {
    let path = if let Some(rest) = message.strip_prefix('`') {
        let end = rest.find("`: ")?;
        &rest[..end]
    } else {
        let end = message.find(": ")?;
        &message[..end]
    };
    let is_key_char = |c: char| c.is_ascii_alphanumeric() || "_.[]".contains(c);
    if path.is_empty() || !path.chars().all(is_key_char) || path.starts_with('.') {
        return None;
    }
    Some(path.replace('[', ".").replace(']', ""))
}

/// Run `f`, turning a panic into a [`SimulationError`] naming `what` (the library's
/// panics are bugs: the message asks for a report).
pub fn guarded<T>(what: &str, f: impl FnOnce() -> T) -> Result<T, String> {
    catch_unwind(AssertUnwindSafe(f)).map_err(|payload| {
        let message = payload
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| payload.downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "unknown panic".to_string());
        format!("internal error in {what}: {message} (a bug in developable_sim: please report it)")
    })
}

/// [`SimulationError`] with `message`.
pub fn simulation_error(message: impl Into<String>) -> PyErr {
    SimulationError::new_err(message.into())
}

/// Deliberately panics inside [`guarded`]: the test of the boundary (a panic arrives as
/// a SimulationError, the interpreter goes on).
#[pyfunction]
pub fn _panic_for_test() -> PyResult<()> {
    guarded("_panic_for_test", || panic!("a panic raised on purpose")).map_err(simulation_error)
}
