//! The `cameras:` section of a scene file: simulated RGB-D cameras, RealSense-style
//! (issue 48). Each is checked here with its key paths and becomes a [`SceneCamera`];
//! the core's [`crate::camera`] renders it.

use serde::{Deserialize, Serialize};

use super::check::Check;
use super::SceneError;
use crate::camera::{look_at, Camera, Intrinsics, Noise, NoiseKey, MAX_SIDE};
use crate::geometry::Pose;

fn d_width() -> u32 {
    640
}
fn d_height() -> u32 {
    480
}
fn d_fov_y() -> f64 {
    0.75
}
fn d_rate() -> f64 {
    15.0
}
fn d_near() -> f64 {
    0.1
}
fn d_far() -> f64 {
    4.0
}
fn d_noise() -> String {
    "none".into()
}

/// A simulated RGB-D camera.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct CameraFile {
    /// Name ([A-Za-z0-9_], unique): its topics are `/<name>/...`, its optical frame
    /// `<name>_color_optical_frame`. Required.
    pub name: String,
    /// Image width, px (1..=8192). Default 640.
    #[serde(default = "d_width")]
    pub width: u32,
    /// Image height, px (1..=8192). Default 480.
    #[serde(default = "d_height")]
    pub height: u32,
    /// Vertical field of view, rad, in (0, pi) (fx = fy, the principal point at the
    /// centre). Default 0.75.
    #[serde(default = "d_fov_y")]
    pub fov_y: f64,
    /// Where the camera is, m, scene frame. Required unless `tf_frame` is given.
    #[serde(default)]
    pub position: Option<[f64; 3]>,
    /// What it looks at, m, scene frame; the image's up is the scene's +z projected
    /// (+y when looking straight up or down). Required with `position`.
    #[serde(default)]
    pub look_at: Option<[f64; 3]>,
    /// A TF frame that carries the camera instead of `position` and `look_at`: a REP 103
    /// body frame (x forward, y left, z up, like a RealSense's `camera_link`). Default
    /// none.
    #[serde(default)]
    pub tf_frame: Option<String>,
    /// Frames per second of simulated time, Hz (> 0). Default 15.
    #[serde(default = "d_rate")]
    pub rate: f64,
    /// Nearest depth, m (> 0): nearer surfaces are cut away. Default 0.1.
    #[serde(default = "d_near")]
    pub near: f64,
    /// Farthest depth, m (> near): depth beyond is NaN. Default 4.0.
    #[serde(default = "d_far")]
    pub far: f64,
    /// Depth noise: `none` or `d435` (the RealSense D435 model, seeded from the scene's
    /// `seed`). Default none.
    #[serde(default = "d_noise")]
    pub noise: String,
}

/// Where a camera is.
#[derive(Clone, Debug, PartialEq)]
pub enum CameraMount {
    /// `world_from_optical`, fixed (from `position` and `look_at`).
    Fixed(Pose),
    /// Carried by this TF frame (a REP 103 body frame): `world_from_optical` is
    /// `world_from_frame * camera::body_from_optical()`, looked up per frame.
    TfFrame(String),
}

/// A camera of a loaded scene.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneCamera {
    pub name: String,
    /// Intrinsics and noise model.
    pub camera: Camera,
    pub mount: CameraMount,
    /// Frames per second of simulated time, Hz.
    pub rate: f64,
    /// Its index in the scene's `cameras:` list: its noise stream.
    pub index: u32,
}

impl SceneCamera {
    /// The TF frame of its images and cloud: `<name>_color_optical_frame` (x right, y
    /// down, z forward).
    pub fn optical_frame(&self) -> String {
        format!("{}_color_optical_frame", self.name)
    }

    /// The noise key of frame `frame` (its tick count) in a scene seeded with `seed`.
    pub fn noise_key(&self, seed: u64, frame: u64) -> NoiseKey {
        NoiseKey {
            seed,
            camera: self.index,
            frame,
        }
    }
}

/// The `cameras:` list checked, in order.
pub(super) fn build_cameras(
    ck: &Check,
    files: &[CameraFile],
) -> Result<Vec<SceneCamera>, SceneError> {
    let mut cameras: Vec<SceneCamera> = Vec::with_capacity(files.len());
    for (index, cf) in files.iter().enumerate() {
        let key = format!("cameras.{index}");
        let name = &cf.name;
        if name.is_empty() || !name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') {
            return Err(ck.fail(
                &format!("{key}.name"),
                format!("`{name}` must be non-empty [A-Za-z0-9_] (it names topics and frames)"),
            ));
        }
        if cameras.iter().any(|c| &c.name == name) {
            return Err(ck.fail(
                &format!("{key}.name"),
                format!("duplicate camera name `{name}`"),
            ));
        }
        let camera = Camera {
            intrinsics: intrinsics(ck, &key, cf)?,
            noise: match ck.choice(&format!("{key}.noise"), &cf.noise, &["none", "d435"])? {
                "d435" => Noise::D435,
                _ => Noise::None,
            },
        };
        cameras.push(SceneCamera {
            name: name.clone(),
            camera,
            mount: mount(ck, &key, cf)?,
            rate: ck.positive(&format!("{key}.rate"), cf.rate)?,
            index: index as u32,
        });
    }
    Ok(cameras)
}

fn intrinsics(ck: &Check, key: &str, cf: &CameraFile) -> Result<Intrinsics, SceneError> {
    for (k, v) in [("width", cf.width), ("height", cf.height)] {
        if !(1..=MAX_SIDE).contains(&v) {
            return Err(ck.fail(
                &format!("{key}.{k}"),
                format!("must be in 1..={MAX_SIDE} px, got {v}"),
            ));
        }
    }
    let fov = ck.positive(&format!("{key}.fov_y"), cf.fov_y)?;
    if fov >= std::f64::consts::PI {
        return Err(ck.fail(
            &format!("{key}.fov_y"),
            format!("must be < pi rad, got {fov}"),
        ));
    }
    let near = ck.positive(&format!("{key}.near"), cf.near)?;
    let far = ck.finite(&format!("{key}.far"), cf.far)?;
    if far <= near {
        return Err(ck.fail(
            &format!("{key}.far"),
            format!("must be > near ({near} m), got {far}"),
        ));
    }
    Intrinsics::new(cf.width, cf.height, fov, near, far).map_err(|e| ck.fail(key, e.to_string()))
}

fn mount(ck: &Check, key: &str, cf: &CameraFile) -> Result<CameraMount, SceneError> {
    if let Some(frame) = &cf.tf_frame {
        if cf.position.is_some() || cf.look_at.is_some() {
            return Err(ck.fail(
                &format!("{key}.tf_frame"),
                "give either tf_frame or position and look_at, not both",
            ));
        }
        if frame.trim().is_empty() {
            return Err(ck.fail(&format!("{key}.tf_frame"), "must not be empty"));
        }
        return Ok(CameraMount::TfFrame(frame.clone()));
    }
    let required = |k: &str, v: Option<[f64; 3]>| {
        v.ok_or_else(|| {
            ck.fail(
                &format!("{key}.{k}"),
                "required (or tf_frame instead of position and look_at)",
            )
        })
    };
    let position = ck.vec3(
        &format!("{key}.position"),
        required("position", cf.position)?,
    )?;
    let target = ck.vec3(&format!("{key}.look_at"), required("look_at", cf.look_at)?)?;
    look_at(position, target)
        .map(CameraMount::Fixed)
        .map_err(|e| ck.fail(&format!("{key}.look_at"), e.to_string()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    fn parse(yaml: &str) -> Result<Vec<SceneCamera>, SceneError> {
        let files: Vec<CameraFile> = serde_yaml::from_str(yaml).expect("yaml");
        build_cameras(
            &Check {
                file: Path::new("s.yaml"),
            },
            &files,
        )
    }

    fn error(yaml: &str) -> (String, String) {
        match parse(yaml) {
            Err(SceneError::Invalid { key, message, .. }) => (key, message),
            other => panic!("expected an error, got {other:?}"),
        }
    }

    #[test]
    fn defaults_and_a_fixed_pose() {
        let c = parse("- {name: camera, position: [0.5, -0.8, 0.6], look_at: [0.5, 0.0, 0.1]}")
            .unwrap();
        let c = &c[0];
        assert_eq!(
            c.camera.intrinsics,
            Intrinsics::new(640, 480, 0.75, 0.1, 4.0).unwrap()
        );
        assert_eq!((c.rate, c.camera.noise, c.index), (15.0, Noise::None, 0));
        assert_eq!(c.optical_frame(), "camera_color_optical_frame");
        let CameraMount::Fixed(pose) = &c.mount else {
            panic!("fixed")
        };
        let expected = look_at([0.5, -0.8, 0.6].into(), [0.5, 0.0, 0.1].into()).unwrap();
        assert_eq!(*pose, expected);
        let c = parse(
            "- {name: wrist, tf_frame: tool0, noise: d435, rate: 30, width: 320, height: 240}",
        )
        .unwrap();
        assert_eq!(c[0].mount, CameraMount::TfFrame("tool0".into()));
        assert_eq!(
            (c[0].camera.noise, c[0].rate, c[0].camera.intrinsics.width),
            (Noise::D435, 30.0, 320)
        );
        assert_eq!(
            c[0].noise_key(9, 4),
            NoiseKey {
                seed: 9,
                camera: 0,
                frame: 4
            }
        );
    }

    #[test]
    fn bad_cameras_name_their_key() {
        let at = "position: [0, -1, 1], look_at: [0, 0, 0]";
        for (yaml, key) in [
            (format!("- {{name: 'a b', {at}}}"), "cameras.0.name"),
            (
                format!("- {{name: c, {at}}}\n- {{name: c, {at}}}"),
                "cameras.1.name",
            ),
            (format!("- {{name: c, width: 0, {at}}}"), "cameras.0.width"),
            (
                format!("- {{name: c, height: 9000, {at}}}"),
                "cameras.0.height",
            ),
            (
                format!("- {{name: c, fov_y: 3.2, {at}}}"),
                "cameras.0.fov_y",
            ),
            (format!("- {{name: c, fov_y: -1, {at}}}"), "cameras.0.fov_y"),
            (format!("- {{name: c, near: 0, {at}}}"), "cameras.0.near"),
            (format!("- {{name: c, far: 0.05, {at}}}"), "cameras.0.far"),
            (format!("- {{name: c, rate: 0, {at}}}"), "cameras.0.rate"),
            (
                format!("- {{name: c, noise: d415, {at}}}"),
                "cameras.0.noise",
            ),
            (
                format!("- {{name: c, tf_frame: tool0, {at}}}"),
                "cameras.0.tf_frame",
            ),
            ("- {name: c, tf_frame: ' '}".into(), "cameras.0.tf_frame"),
            (
                "- {name: c, look_at: [0, 0, 0]}".into(),
                "cameras.0.position",
            ),
            (
                "- {name: c, position: [0, 0, 0]}".into(),
                "cameras.0.look_at",
            ),
            (
                "- {name: c, position: [0, 0, 1], look_at: [0, 0, 1]}".into(),
                "cameras.0.look_at",
            ),
            (
                "- {name: c, position: [0, .nan, 1], look_at: [0, 0, 1]}".into(),
                "cameras.0.position.1",
            ),
        ] {
            assert_eq!(error(&yaml).0, key, "{yaml}");
        }
        // and a good one passes the same checks (the negative of the above)
        assert!(parse(&format!("- {{name: c, {at}}}")).is_ok());
    }

    #[test]
    fn unknown_keys_are_refused() {
        let r: Result<Vec<CameraFile>, _> =
            serde_yaml::from_str("- {name: c, fov: 1.0, tf_frame: a}");
        assert!(r.unwrap_err().to_string().contains("unknown field `fov`"));
    }
}
