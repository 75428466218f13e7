//! Topic and service names of the node, resolved as ROS 2 resolves them: relative names
//! live in the node's namespace, `~/x` under the node, absolute names stay; then
//! `-r from:=to` remaps apply.
//!
//! Defaults: handle inputs `handles/<handle>` (relative, so `-r __ns:=/robot1` moves
//! them to `/robot1/handles/<handle>`; a `topic:` given in the scene is absolute and
//! stays), outputs `<object>/markers`, `<object>/singular_points`, `<object>/status`
//! (relative), `colliders` (relative; only for a scene with colliders), `/clock`
//! (absolute), services `~/reset`, `~/set_paused`, `~/step` and the
//! simulation_interfaces ones (`~/get_simulator_features`, ...).

use crate::scene::Scene;

/// Why a name is not acceptable.
#[derive(Debug, thiserror::Error)]
#[error("invalid ROS name `{name}`: {reason}")]
pub struct NameError {
    pub name: String,
    pub reason: String,
}

/// Every resolved name of a node.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct NodeNames {
    /// Node base name, e.g. `developable_sim`.
    pub node: String,
    /// Namespace, `/` or `/a/b`.
    pub namespace: String,
    /// `-r from:=to` remaps, applied to every name resolved.
    pub remaps: Vec<(String, String)>,
    /// Input topic of each handle (scene order).
    pub handles: Vec<String>,
    pub clock: String,
    /// `/tf` and `/tf_static` (TF in; the outputs table resolves TF out itself).
    pub tf: String,
    pub tf_static: String,
    pub reset: String,
    pub set_paused: String,
    pub step: String,
    /// `~/grasp` (developable_sim/srv/Grasp) and `~/release` (developable_sim/srv/Release).
    pub grasp: String,
    pub release: String,
    /// Per handle: `handles/<handle>/grasp` (std_srvs/srv/SetBool: true closes the
    /// gripper on the nearest point, false opens it).
    pub handle_grasp: Vec<String>,
    /// Where a recording keeps the commands the node applied
    /// (developable_sim/msg/SimCommand; bags only, nothing is published there).
    pub commands: String,
    /// The robot description topic (`robot_colliders.topic`; empty without
    /// `robot_colliders:`).
    pub robot_description: String,
    /// Where a recording keeps the robot links' TF lookups (tf2_msgs/msg/TFMessage; bags
    /// only).
    pub robot_link_poses: String,
    /// The rcl_interfaces parameter services.
    pub parameters: ParameterServices,
    /// The simulation_interfaces services.
    pub simulation: SimulationServices,
}

/// `~/get_simulator_features`, `~/reset_simulation`, `~/step_simulation`,
/// `~/get_simulation_state`, `~/set_simulation_state` (simulation_interfaces), and the
/// SimulateSteps action `~/simulate_steps`.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct SimulationServices {
    pub get_features: String,
    pub reset: String,
    pub step: String,
    pub get_state: String,
    pub set_state: String,
    pub simulate_steps: String,
}

/// `~/list_parameters`, `~/get_parameters`, `~/set_parameters`, `~/describe_parameters`,
/// `~/get_parameter_types`.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct ParameterServices {
    pub list: String,
    pub get: String,
    pub set: String,
    pub describe: String,
    pub get_types: String,
}

impl NodeNames {
    /// Fully qualified node name, e.g. `/robot1/developable_sim`.
    pub fn fqn(&self) -> String {
        join(&self.namespace, &self.node)
    }

    /// `name` (relative, private `~/` or absolute) as the node resolves it: expanded
    /// in its namespace, then the remaps applied.
    pub fn resolve_name(&self, name: &str) -> Result<String, NameError> {
        let fqn = self.fqn();
        let full = expand(name, &self.namespace, &fqn)?;
        let mut out = full.clone();
        for (from, to) in &self.remaps {
            if expand(from, &self.namespace, &fqn)? == full {
                out = expand(to, &self.namespace, &fqn)?;
            }
        }
        Ok(out)
    }

    /// Resolve the names of `scene` for node `node` in `namespace`, then apply `remaps`
    /// (`from`, `to`), each resolved the same way.
    pub fn resolve(
        scene: &Scene,
        node: &str,
        namespace: &str,
        remaps: &[(String, String)],
    ) -> Result<NodeNames, NameError> {
        check_token(node, node)?;
        let names = NodeNames {
            node: node.to_string(),
            namespace: normalize_namespace(namespace)?,
            remaps: remaps.to_vec(),
            ..NodeNames::default()
        };
        let resolve = |name: &str| names.resolve_name(name);
        let handles = scene
            .handle_topics
            .iter()
            .map(|t| resolve(t))
            .collect::<Result<Vec<_>, _>>()?;
        Ok(NodeNames {
            clock: resolve("/clock")?,
            tf: resolve("/tf")?,
            tf_static: resolve("/tf_static")?,
            reset: resolve("~/reset")?,
            set_paused: resolve("~/set_paused")?,
            step: resolve("~/step")?,
            commands: resolve("~/commands")?,
            robot_description: match &scene.robot {
                Some(r) => resolve(&r.topic)?,
                None => String::new(),
            },
            robot_link_poses: resolve("~/robot_link_poses")?,
            grasp: resolve("~/grasp")?,
            release: resolve("~/release")?,
            handle_grasp: scene
                .world
                .handles()
                .iter()
                .map(|h| resolve(&format!("handles/{}/grasp", h.name)))
                .collect::<Result<Vec<_>, _>>()?,
            parameters: ParameterServices {
                list: resolve("~/list_parameters")?,
                get: resolve("~/get_parameters")?,
                set: resolve("~/set_parameters")?,
                describe: resolve("~/describe_parameters")?,
                get_types: resolve("~/get_parameter_types")?,
            },
            simulation: SimulationServices {
                get_features: resolve("~/get_simulator_features")?,
                reset: resolve("~/reset_simulation")?,
                step: resolve("~/step_simulation")?,
                get_state: resolve("~/get_simulation_state")?,
                set_state: resolve("~/set_simulation_state")?,
                simulate_steps: resolve("~/simulate_steps")?,
            },
            handles,
            ..names.clone()
        })
    }
}

fn join(namespace: &str, name: &str) -> String {
    if namespace == "/" {
        format!("/{name}")
    } else {
        format!("{namespace}/{name}")
    }
}

fn check_token(token: &str, whole: &str) -> Result<(), NameError> {
    let bad = |reason: &str| NameError {
        name: whole.to_string(),
        reason: reason.to_string(),
    };
    if token.is_empty() {
        return Err(bad("empty name component (`//` or a trailing `/`)"));
    }
    if !token.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') {
        return Err(bad("only [A-Za-z0-9_] may appear between slashes"));
    }
    if token.starts_with(|c: char| c.is_ascii_digit()) {
        return Err(bad("a name component must not start with a digit"));
    }
    if token.contains("__") {
        return Err(bad("`__` is not allowed in ROS names"));
    }
    Ok(())
}

/// `""`, `/`, `robot1`, `/robot1/` -> `/` or `/robot1`.
pub fn normalize_namespace(ns: &str) -> Result<String, NameError> {
    let trimmed = ns.trim_matches('/');
    if trimmed.is_empty() {
        return Ok("/".into());
    }
    for t in trimmed.split('/') {
        check_token(t, ns)?;
    }
    Ok(format!("/{trimmed}"))
}

/// Expand a topic or service name to an absolute one.
pub fn expand(name: &str, namespace: &str, fqn: &str) -> Result<String, NameError> {
    let full = if let Some(rest) = name.strip_prefix("~/") {
        format!("{fqn}/{rest}")
    } else if name == "~" {
        fqn.to_string()
    } else if name.starts_with('/') {
        name.to_string()
    } else {
        join(namespace, name)
    };
    if full.ends_with('/') || full.len() < 2 {
        return Err(NameError {
            name: name.into(),
            reason: "must not be empty or end with `/`".into(),
        });
    }
    for t in full[1..].split('/') {
        check_token(t, name)?;
    }
    Ok(full)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn expands_relative_private_and_absolute_names() {
        assert_eq!(expand("a/b", "/", "/n").unwrap(), "/a/b");
        assert_eq!(expand("a/b", "/r1", "/r1/n").unwrap(), "/r1/a/b");
        assert_eq!(expand("/clock", "/r1", "/r1/n").unwrap(), "/clock");
        assert_eq!(expand("~/reset", "/r1", "/r1/n").unwrap(), "/r1/n/reset");
        assert!(expand("a//b", "/", "/n").is_err());
        assert!(expand("a/1b", "/", "/n").is_err());
        assert!(expand("a/b/", "/", "/n").is_err());
        assert_eq!(normalize_namespace("robot1/").unwrap(), "/robot1");
        assert_eq!(normalize_namespace("").unwrap(), "/");
        assert!(normalize_namespace("/a b").is_err());
    }

    #[test]
    fn resolves_scene_names_with_namespace_and_remaps() {
        let scene = crate::scene::load(
            std::path::Path::new(concat!(
                env!("CARGO_MANIFEST_DIR"),
                "/config/scenes/ribbon_extreme_torsion.yaml"
            )),
            &[],
        )
        .unwrap();
        let n = NodeNames::resolve(&scene, "developable_sim", "/", &[]).unwrap();
        assert_eq!(n.handles, ["/handles/twist_end"]);
        assert_eq!(n.resolve_name("ribbon/markers").unwrap(), "/ribbon/markers");
        assert_eq!(n.reset, "/developable_sim/reset");
        let n = NodeNames::resolve(
            &scene,
            "sim",
            "/robot1",
            &[("handles/twist_end".into(), "/gripper/pose".into())],
        )
        .unwrap();
        assert_eq!(n.handles, ["/gripper/pose"]);
        assert_eq!(
            n.resolve_name("ribbon/status").unwrap(),
            "/robot1/ribbon/status"
        );
        assert_eq!(n.clock, "/clock");
        assert_eq!(n.step, "/robot1/sim/step");
        assert_eq!(n.fqn(), "/robot1/sim");
        assert!(NodeNames::resolve(&scene, "bad name", "/", &[]).is_err());
    }
}
