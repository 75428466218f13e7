//! Validation of scene values with their key paths: every failure names the file, the
//! key (`ribbons.1.length`) and why.

use std::path::Path;

use super::SceneError;
use crate::geometry::{Pose, Vector3};

/// Collects validation errors with their key paths.
pub(crate) struct Check<'a> {
    pub(crate) file: &'a Path,
}

impl Check<'_> {
    pub(crate) fn fail(&self, key: &str, message: impl Into<String>) -> SceneError {
        SceneError::Invalid {
            file: self.file.to_path_buf(),
            key: key.to_string(),
            message: message.into(),
        }
    }
    pub(crate) fn finite(&self, key: &str, v: f64) -> Result<f64, SceneError> {
        if v.is_finite() {
            Ok(v)
        } else {
            Err(self.fail(key, format!("must be a finite number, got {v}")))
        }
    }
    pub(crate) fn positive(&self, key: &str, v: f64) -> Result<f64, SceneError> {
        self.finite(key, v)?;
        if v > 0.0 {
            Ok(v)
        } else {
            Err(self.fail(key, format!("must be > 0, got {v}")))
        }
    }
    pub(crate) fn non_negative(&self, key: &str, v: f64) -> Result<f64, SceneError> {
        self.finite(key, v)?;
        if v >= 0.0 {
            Ok(v)
        } else {
            Err(self.fail(key, format!("must be >= 0, got {v}")))
        }
    }
    pub(crate) fn vec3(&self, key: &str, v: [f64; 3]) -> Result<Vector3, SceneError> {
        for (i, x) in v.iter().enumerate() {
            self.finite(&format!("{key}.{i}"), *x)?;
        }
        Ok(Vector3::from(v))
    }
    pub(crate) fn choice<'s>(
        &self,
        key: &str,
        v: &'s str,
        allowed: &[&str],
    ) -> Result<&'s str, SceneError> {
        if allowed.contains(&v) {
            Ok(v)
        } else {
            Err(self.fail(
                key,
                format!(
                    "unknown value `{v}`, expected one of: {}",
                    allowed.join(", ")
                ),
            ))
        }
    }
}

pub(crate) fn pose_from(position: Vector3, rotation: Vector3) -> Pose {
    Pose::new(position, rotation)
}
