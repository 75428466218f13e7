//! `developable_sim.Scene`: a scene file loaded, overridden and checked, ready to build
//! simulations from (one per seed).

use std::path::PathBuf;

use developable_sim::scene::{Scene as LoadedScene, SceneError as RustSceneError};
use pyo3::prelude::*;

use crate::errors::scene_error;
use crate::origin::Origin;
use crate::overrides;
use crate::simulation::Simulation;

/// A scene: a scene file (or YAML text) with overrides applied, checked and built once.
/// Build simulations from it with [`Scene::build`].
#[pyclass(module = "developable_sim", name = "Scene", frozen)]
pub struct Scene {
    origin: Origin,
    /// Built once with the file's seed: checks every key and is cloned by `build`.
    loaded: LoadedScene,
}

#[pymethods]
impl Scene {
    /// Load a scene file. `overrides` maps key paths to values as `--set` does
    /// (`{"ribbon.segments": 200, "solver.kind": "lbfgsb"}`). Raises SceneError (with
    /// `key` and `file`) for a bad scene, a missing or unreadable file included.
    #[staticmethod]
    #[pyo3(signature = (path, overrides = None))]
    fn load(py: Python<'_>, path: PathBuf, overrides: Option<&Bound<'_, PyAny>>) -> PyResult<Self> {
        let specs = overrides::specs(overrides)?;
        let text = std::fs::read_to_string(&path).map_err(|source| {
            scene_error(
                py,
                &RustSceneError::Io {
                    file: path.clone(),
                    source,
                },
            )
        })?;
        let file = std::fs::canonicalize(&path).unwrap_or(path);
        Self::new(py, text, file, specs)
    }

    /// A scene from YAML text; `name` stands for the file in messages, and relative mesh
    /// paths in the text are read from the working directory.
    #[staticmethod]
    #[pyo3(signature = (text, overrides = None, name = "<string>"))]
    fn from_yaml(
        py: Python<'_>,
        text: String,
        overrides: Option<&Bound<'_, PyAny>>,
        name: &str,
    ) -> PyResult<Self> {
        let specs = overrides::specs(overrides)?;
        Self::new(py, text, PathBuf::from(name), specs)
    }

    /// The same scene with more overrides (applied after this scene's own).
    fn with_overrides(&self, py: Python<'_>, overrides: &Bound<'_, PyAny>) -> PyResult<Self> {
        let mut specs = self.origin.overrides.clone();
        specs.extend(overrides::specs(Some(overrides))?);
        Self::new(
            py,
            self.origin.text.clone(),
            self.origin.file.clone(),
            specs,
        )
    }

    /// A simulation at t = 0. `seed` replaces the scene's `seed:` (the seeded
    /// imperfection of the initial shape, the paper's singular points, the camera
    /// noise); None keeps the file's.
    #[pyo3(signature = (seed = None))]
    fn build(&self, py: Python<'_>, seed: Option<u64>) -> PyResult<Simulation> {
        let loaded = match seed {
            Some(s) if s != self.loaded.source.seed => self.origin.load_py(py, Some(s))?,
            _ => self.loaded.clone(),
        };
        Ok(Simulation::new(self.origin.clone(), loaded))
    }

    /// The scene's name (`name:`, else the file's stem).
    #[getter]
    fn name(&self) -> &str {
        &self.loaded.name
    }
    /// Simulated duration of `developable_sim run`, s.
    #[getter]
    fn duration(&self) -> f64 {
        self.loaded.duration
    }
    /// Time step, s.
    #[getter]
    fn dt(&self) -> f64 {
        self.loaded.world.dt()
    }
    /// The file's `seed:` (after overrides).
    #[getter]
    fn seed(&self) -> u64 {
        self.loaded.source.seed
    }
    /// Object names, in the order `Simulation.state` indexes them.
    #[getter]
    fn objects(&self) -> Vec<String> {
        self.loaded.world.object_names().to_vec()
    }
    /// Handle names (the keys of `Simulation.step`'s targets).
    #[getter]
    fn handles(&self) -> Vec<String> {
        self.loaded
            .world
            .handles()
            .iter()
            .map(|h| h.name.clone())
            .collect()
    }
    /// Camera names (`Simulation.render_depth`).
    #[getter]
    fn cameras(&self) -> Vec<String> {
        self.loaded.cameras.iter().map(|c| c.name.clone()).collect()
    }
    /// The scene file's text, before overrides.
    #[getter]
    fn yaml(&self) -> &str {
        &self.origin.text
    }
    /// The file the scene was read from (or the name given to `from_yaml`).
    #[getter]
    fn file(&self) -> String {
        self.origin.file.display().to_string()
    }
    /// The overrides as `--set` specs (`key.path=value`), in order: the same strings
    /// on `developable_sim run --set` load the same scene.
    #[getter]
    fn overrides(&self) -> Vec<String> {
        self.origin.overrides.clone()
    }

    fn __repr__(&self) -> String {
        format!(
            "Scene(name={:?}, file={:?}, overrides={:?})",
            self.loaded.name,
            self.origin.file.display().to_string(),
            self.origin.overrides
        )
    }
}

impl Scene {
    fn new(py: Python<'_>, text: String, file: PathBuf, overrides: Vec<String>) -> PyResult<Self> {
        let origin = Origin {
            text,
            file,
            overrides,
        };
        let loaded = origin.load_py(py, None)?;
        Ok(Scene { origin, loaded })
    }
}
