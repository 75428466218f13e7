//! The `robot_colliders:` section of a scene file: a robot's links, described by the
//! URDF `robot_state_publisher` latches on `/robot_description` and moved by TF, as
//! kinematic colliders of the contact stage. The description itself arrives at run
//! time (see [`super::urdf`]); the scene says where to find it and what to take.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::check::Check;
use super::SceneError;

fn d_topic() -> String {
    "/robot_description".into()
}
fn d_friction() -> f64 {
    0.5
}

/// Where a robot description comes from and which of its links collide.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct RobotCollidersFile {
    /// The description topic (`std_msgs/msg/String`, a URDF; subscribed reliable and
    /// transient local, as `robot_state_publisher` latches it). Relative names resolve
    /// in the node's namespace. Default `/robot_description`.
    #[serde(default = "d_topic")]
    pub topic: String,
    /// The links whose `<collision>` shapes push the ribbons. Default: every link that
    /// has a `<collision>`.
    #[serde(default)]
    pub links: Option<Vec<String>>,
    /// Every collision shape grown outwards by this much, m (>= 0): a margin around the
    /// real surface. Default 0.
    #[serde(default)]
    pub thickness: f64,
    /// Coulomb friction coefficient μ ribbon-link (>= 0). Default 0.5.
    #[serde(default = "d_friction")]
    pub friction: f64,
    /// Prefix of the links' TF frames (robot_state_publisher's `frame_prefix`): link
    /// `forearm` follows TF frame `<frame_prefix>forearm`. Default "".
    #[serde(default)]
    pub frame_prefix: String,
    /// Folders of the packages named by `package://NAME/...` mesh URIs, relative to the
    /// scene file. A package not listed here is looked up as `share/NAME` under each
    /// entry of `AMENT_PREFIX_PATH` (a sourced ROS 2 workspace). Default none.
    #[serde(default)]
    pub packages: BTreeMap<String, String>,
}

/// The `robot_colliders:` section, validated.
#[derive(Clone, Debug, PartialEq)]
pub struct RobotColliders {
    /// The description topic before name resolution.
    pub topic: String,
    /// The links to take (None: every link with a `<collision>`).
    pub links: Option<Vec<String>>,
    /// m, >= 0.
    pub thickness: f64,
    /// Coulomb μ, >= 0.
    pub friction: f64,
    pub frame_prefix: String,
    /// Package name -> folder (absolute, or relative to the working directory).
    pub packages: BTreeMap<String, PathBuf>,
    /// The scene file's folder: relative mesh file names are relative to it.
    pub base_dir: PathBuf,
}

impl RobotCollidersFile {
    /// Validate against the scene `file`.
    pub(super) fn check(&self, ck: &Check, file: &Path) -> Result<RobotColliders, SceneError> {
        let key = "robot_colliders";
        if self.topic.trim().is_empty() {
            return Err(ck.fail(&format!("{key}.topic"), "must not be empty"));
        }
        if let Some(links) = &self.links {
            if links.is_empty() {
                return Err(ck.fail(
                    &format!("{key}.links"),
                    "an empty list takes no link: leave the key out to take every link with a <collision>",
                ));
            }
            if let Some(bad) = links.iter().find(|l| l.trim().is_empty()) {
                return Err(ck.fail(&format!("{key}.links"), format!("bad link name `{bad}`")));
            }
        }
        let base_dir = file.parent().unwrap_or(Path::new(".")).to_path_buf();
        Ok(RobotColliders {
            topic: self.topic.clone(),
            links: self.links.clone(),
            thickness: ck.non_negative(&format!("{key}.thickness"), self.thickness)?,
            friction: ck.non_negative(&format!("{key}.friction"), self.friction)?,
            frame_prefix: self.frame_prefix.clone(),
            packages: self
                .packages
                .iter()
                .map(|(name, dir)| (name.clone(), base_dir.join(dir)))
                .collect(),
            base_dir,
        })
    }
}
