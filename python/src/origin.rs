//! Where a simulation comes from: the scene text, its file and the overrides. What
//! `Simulation.save()` stores and what a reset with another seed loads again.

use std::path::PathBuf;

use developable_sim::scene::{self, Scene as LoadedScene, SceneError as RustSceneError};
use pyo3::prelude::*;

use crate::errors::{guarded, scene_error, simulation_error};

/// Where a simulation comes from: what `Simulation.save()` stores and what a reset
/// with another seed rebuilds.
#[derive(Clone, Debug)]
pub struct Origin {
    /// The scene file's YAML text as read (before overrides).
    pub text: String,
    /// The file's path (absolute when it was loaded from a file: mesh files it names
    /// are found beside it from any working directory); it names the scene in messages.
    pub file: PathBuf,
    /// `--set` specs (`key.path=value`), applied in order.
    pub overrides: Vec<String>,
}

impl Origin {
    /// Load the scene, with `seed` (when given) overriding the file's `seed:`. The
    /// library's scene loader, the one `developable_sim run` uses.
    pub fn load(&self, seed: Option<u64>) -> Result<LoadedScene, RustSceneError> {
        let mut specs = self.overrides.clone();
        if let Some(seed) = seed {
            specs.push(format!("seed={seed}"));
        }
        scene::load_str(&self.text, &self.file, &specs)
    }

    /// [`Origin::load`] with panics caught and errors raised as Python exceptions.
    pub fn load_py(&self, py: Python<'_>, seed: Option<u64>) -> PyResult<LoadedScene> {
        guarded("loading the scene", || self.load(seed))
            .map_err(simulation_error)?
            .map_err(|e| scene_error(py, &e))
    }
}
