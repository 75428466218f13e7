//! `developable_sim._native`: the Python bindings of developable_sim (PyO3), built
//! into the wheel by maturin (python/pyproject.toml). The package `developable_sim`
//! (python/developable_sim/) re-exports these classes and adds the gymnasium
//! environment; docs/python.md is the API.
//!
//! Built on the library without its `node` and `tools` features: scene files, the
//! core's world and camera, and nothing that speaks ROS, DDS or writes bags
//! (tests/wheel_purity.rs checks the dependency tree). Every call checks its input and
//! raises a Python exception; a panic inside the library is caught at this boundary
//! (errors.rs).

mod batch;
mod camera;
mod errors;
mod grasp;
mod origin;
mod overrides;
mod save;
mod scene;
mod simulation;
mod state;
mod targets;

use pyo3::prelude::*;

#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<scene::Scene>()?;
    m.add_class::<simulation::Simulation>()?;
    m.add_class::<state::ObjectState>()?;
    m.add_class::<camera::CameraFrame>()?;
    m.add_class::<grasp::GraspResult>()?;
    m.add_class::<grasp::HandleState>()?;
    m.add_function(wrap_pyfunction!(batch::step_many, m)?)?;
    m.add_function(wrap_pyfunction!(errors::_panic_for_test, m)?)?;
    errors::register(m)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
