//! Scene files (YAML, serde): what a scene declares, how `--set` overrides apply, how
//! values are validated, and how the core [`World`] is built from them. Only what a
//! scene declares is built.
//!
//! This is an edge module: it reads files; the core never sees serde.

mod camera_file;
mod check;
mod contact;
mod file;
mod handle_file;
mod mesh_file;
mod overrides;
mod paper_file;
mod ribbon_file;
mod robot_file;
pub mod urdf;

use std::path::{Path, PathBuf};

pub use camera_file::{CameraFile, CameraMount, SceneCamera};
pub use contact::{ColliderFile, ContactFile};
pub use file::{OutputsFile, SceneFile};
pub use mesh_file::load_mesh;
pub use overrides::apply_override;
pub use paper_file::{CreaseFile, PaperFile};
pub use robot_file::{RobotColliders, RobotCollidersFile};

use crate::sim::World;

/// Why a scene could not be loaded: the file, the key and the reason.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    #[error("{file}: cannot read: {source}")]
    Io {
        file: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{file}: {message}")]
    Parse { file: PathBuf, message: String },
    #[error("{file}: `{key}`: {message}")]
    Invalid {
        file: PathBuf,
        key: String,
        message: String,
    },
    #[error("--set {spec}: {message}")]
    Override { spec: String, message: String },
}

/// A loaded scene: the core world plus what the edges need (names, topics, outputs).
#[derive(Clone, Debug)]
pub struct Scene {
    /// Scene name (file stem unless `name:` is given).
    pub name: String,
    pub file: PathBuf,
    /// Simulated duration, s.
    pub duration: f64,
    pub world: World,
    /// The fixed frame of every pose and marker (REP 103), e.g. `world`.
    pub frame_id: String,
    /// Input topic of each handle before name resolution (same order as
    /// `world.handles()`): the scene's absolute `topic:`, or `handles/<name>`, relative
    /// to the node's namespace. The one source of handle topics (`session::names`
    /// resolves them).
    pub handle_topics: Vec<String>,
    pub outputs: Outputs,
    /// TF frame each handle follows instead of its topic (same order as
    /// `world.handles()`; None: the topic).
    pub handle_tf_frames: Vec<Option<String>>,
    /// The simulated RGB-D cameras (`cameras:`), in file order.
    pub cameras: Vec<SceneCamera>,
    /// A robot's links as colliders (`robot_colliders:`): where its description comes
    /// from and what to take of it. None: the scene has none.
    pub robot: Option<RobotColliders>,
    /// The scene as parsed after overrides, for provenance (stats, bags).
    pub source: SceneFile,
}

/// Which outputs the scene asks for (nothing else is published).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Outputs {
    pub markers: bool,
    pub singular_points: bool,
    pub status: bool,
    pub clock: bool,
    /// Grasp and end frames on `/tf`.
    pub tf: bool,
    /// Each handle's grasp state on `/handles/<handle>/state`.
    pub grasp_state: bool,
    /// What each handle feels on `/<object>/<handle>/wrench`.
    pub wrench: bool,
    /// Each object's mesh vertices (ground truth) on `/<object>/points`.
    pub points: bool,
    /// Hz, the most markers messages per second per object (None: every tick).
    pub markers_rate: Option<f64>,
}

/// Read, override (`key.path=value`, value parsed as YAML), validate and build.
pub fn load(path: &Path, overrides: &[String]) -> Result<Scene, SceneError> {
    let text = std::fs::read_to_string(path).map_err(|source| SceneError::Io {
        file: path.to_path_buf(),
        source,
    })?;
    load_str(&text, path, overrides)
}

/// Like [`load`] from text; `path` names the file in messages.
pub fn load_str(text: &str, path: &Path, overrides: &[String]) -> Result<Scene, SceneError> {
    let mut value: serde_yaml::Value =
        serde_yaml::from_str(text).map_err(|e| SceneError::Parse {
            file: path.to_path_buf(),
            message: e.to_string(),
        })?;
    if value.is_null() {
        return Err(SceneError::Parse {
            file: path.to_path_buf(),
            message: "the scene file is empty".into(),
        });
    }
    for spec in overrides {
        apply_override(&mut value, spec)?;
    }
    // Deserialize from the text when nothing was overridden (messages keep line and
    // column), from the overridden tree otherwise; both name the key path.
    let parse_error = |path_in_scene: String, inner: String| SceneError::Parse {
        file: path.to_path_buf(),
        // serde_yaml already names the path in some messages: say it once
        message: if path_in_scene.is_empty()
            || path_in_scene == "."
            || inner.starts_with(&format!("{path_in_scene}: "))
        {
            inner
        } else {
            format!("`{path_in_scene}`: {inner}")
        },
    };
    let parsed: SceneFile = if overrides.is_empty() {
        serde_path_to_error::deserialize(serde_yaml::Deserializer::from_str(text))
            .map_err(|e| parse_error(e.path().to_string(), e.into_inner().to_string()))?
    } else {
        serde_path_to_error::deserialize(value)
            .map_err(|e| parse_error(e.path().to_string(), e.into_inner().to_string()))?
    };
    parsed.build(path)
}
