//! Node parameters: the standard ROS 2 params file (`node_name:` or `/**:` then
//! `ros__parameters:`), `--ros-args` (`--params-file`, `-p name:=value`, `-r from:=to`,
//! `-r __ns:=/x`, `-r __node:=name`), validated like scene keys: every error names the
//! file (or the command line) and the key.
//!
//! Every parameter is declared once in [`DECLARED`], with its type, unit, default and
//! meaning; `config/params/developable_sim.yaml` documents the same list.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// A parameter value, typed as ROS 2 types them (`1` is an integer, `1.0` a double).
#[derive(Clone, Debug, PartialEq)]
pub enum ParamValue {
    Bool(bool),
    Integer(i64),
    Double(f64),
    String(String),
    StringArray(Vec<String>),
}

/// The type a parameter is declared with.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ParamType {
    Bool,
    Integer,
    /// A double; an integer value is accepted and converted (`2` means 2.0).
    Double,
    String,
    StringArray,
}

impl ParamType {
    fn name(self) -> &'static str {
        match self {
            ParamType::Bool => "a bool",
            ParamType::Integer => "an integer",
            ParamType::Double => "a double",
            ParamType::String => "a string",
            ParamType::StringArray => "a string array",
        }
    }
}

/// One declared parameter.
pub struct Declared {
    pub name: &'static str,
    pub ty: ParamType,
    /// Default, as YAML text.
    pub default: &'static str,
    pub doc: &'static str,
}

/// Every parameter the node reads.
pub const DECLARED: &[Declared] = &[
    Declared {
        name: "scene",
        ty: ParamType::String,
        default: "\"\"",
        doc: "Scene file (YAML); the SCENE argument of `developable_sim node` wins over it.",
    },
    Declared {
        name: "scene_overrides",
        ty: ParamType::StringArray,
        default: "[]",
        doc: "Scene keys to override, as `key.path=value` (like `run --set`).",
    },
    Declared {
        name: "record",
        ty: ParamType::String,
        default: "\"\"",
        doc: "Bag folder to record into (must not exist yet); empty: no recording.",
    },
    Declared {
        name: "record_compression",
        ty: ParamType::String,
        default: "none",
        doc: "MCAP chunk compression: none or lz4.",
    },
    Declared {
        name: "record_cameras",
        ty: ParamType::Bool,
        default: "false",
        doc: "Record the cameras' images and clouds too (big: 6.4 MB a 640 x 480 frame); \
              their camera_info is recorded regardless.",
    },
    Declared {
        name: "record_flush_period",
        ty: ParamType::Double,
        default: "1.0",
        doc: "s; the bag's open chunk is closed and flushed at least this often, so a killed \
              node loses at most this much.",
    },
    Declared {
        name: "duration",
        ty: ParamType::Double,
        default: "0.0",
        doc: "s of simulation time after which the node exits; 0: run until stopped.",
    },
    Declared {
        name: "as_fast_as_possible",
        ty: ParamType::Bool,
        default: "false",
        doc: "Step as fast as possible instead of at the scene's dt in real time.",
    },
    Declared {
        name: "real_time_factor",
        ty: ParamType::Double,
        default: "1.0",
        doc: "Simulated seconds per wall-clock second in real-time mode (> 0).",
    },
    Declared {
        name: "lockstep",
        ty: ParamType::String,
        default: "\"\"",
        doc: "Empty: free-running ticks. A handle name: one step per pose accepted on that \
              handle's topic. `service`: one step per ~/step call.",
    },
    Declared {
        name: "start_paused",
        ty: ParamType::Bool,
        default: "false",
        doc: "Start paused (resume with ~/set_paused false, step with ~/step).",
    },
    Declared {
        name: "accept_empty_frame_id",
        ty: ParamType::Bool,
        default: "false",
        doc: "Take poses with an empty header.frame_id as expressed in the scene frame \
              (otherwise they are rejected as an unknown frame).",
    },
    Declared {
        name: "max_stamp_lead",
        ty: ParamType::Double,
        default: "10.0",
        doc: "s, poses stamped further ahead of the node's wall clock at arrival are \
              rejected (one accepted far-future stamp would make every later pose stale); \
              > 0.",
    },
    Declared {
        name: "marker.line_width",
        ty: ParamType::Double,
        default: "0.002",
        doc: "m, width of the ruling lines (LINE_LIST scale.x).",
    },
    Declared {
        name: "marker.sphere_diameter",
        ty: ParamType::Double,
        default: "0.012",
        doc: "m, diameter of the singular-point spheres (SPHERE_LIST scale).",
    },
    Declared {
        name: "use_sim_time",
        ty: ParamType::Bool,
        default: "false",
        doc: "Standard ROS parameter. false: the node owns time and publishes /clock (sim \
              time from 0). true: it follows an external /clock (ClockQoS) and publishes \
              none: simulated time starts at the first sample, the node steps as the \
              clock advances, a jump backwards resets the simulation (counted in \
              SimStatus.clock_resets), a jump forward beyond max_clock_jump moves the \
              time origin instead of simulating the gap.",
    },
    Declared {
        name: "max_clock_jump",
        ty: ParamType::Double,
        default: "1.0",
        doc: "s, > 0, run-time, under use_sim_time: a /clock sample that advances more \
              than this beyond the wall time since the previous sample is a jump: the \
              time origin moves by it (said on stderr) instead of the gap being \
              simulated.",
    },
    Declared {
        name: "paused",
        ty: ParamType::Bool,
        default: "false",
        doc: "Run-time: true pauses the simulation, false resumes it (as ~/set_paused); \
              starts as start_paused.",
    },
    Declared {
        name: "markers_rate",
        ty: ParamType::Double,
        default: "0.0",
        doc: "Hz, >= 0, run-time: at most this many markers messages per second of \
              simulated time per object; 0: every tick. Set: overrides the scene's \
              outputs.markers_rate.",
    },
    Declared {
        name: "foxglove_port",
        ty: ParamType::Integer,
        default: "0",
        doc: "TCP port of the live Foxglove WebSocket server (as --foxglove PORT; \
              subprotocol foxglove.sdk.v1, ros2msg schemas, cdr); 0: none.",
    },
    Declared {
        name: "foxglove_bind",
        ty: ParamType::String,
        default: "127.0.0.1",
        doc: "IP address the Foxglove WebSocket server binds (as --foxglove-bind): \
              127.0.0.1 this machine only, 0.0.0.0 every interface (no authentication).",
    },
    Declared {
        name: "tf_max_lag",
        ty: ParamType::Double,
        default: "0.25",
        doc: "s, >= 0: a TF lookup (a tf_frame handle at a tick, a pose in another frame) \
              at most this long after the newest transform of its chain takes that newest \
              transform; later, or older than the 10 s TF buffer, it is a counted \
              rejection (rejected_tf_lookup) and the handle keeps its last target.",
    },
];

/// A parameter problem: where (file or command line), which key, why.
#[derive(Debug, thiserror::Error)]
pub enum ParamsError {
    #[error("{file}: cannot read: {source}")]
    Io {
        file: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{file}: not a ROS 2 params file: {message}")]
    Format { file: String, message: String },
    #[error("{file}: `{key}`: {message}")]
    Invalid {
        file: String,
        key: String,
        message: String,
    },
    #[error("--ros-args: {0}")]
    RosArgs(String),
}

/// Parameters after reading every source, with where each came from.
#[derive(Clone, Debug, Default)]
pub struct Params {
    values: BTreeMap<String, (ParamValue, String)>,
    /// Messages about ignored keys (unknown keys in wildcard sections).
    pub warnings: Vec<String>,
}

impl Params {
    /// A parameter's value (None: not set anywhere; use the default).
    pub fn get(&self, name: &str) -> Option<&ParamValue> {
        self.values.get(name).map(|(v, _)| v)
    }

    /// Where a set parameter came from (file and key, or the command line).
    pub fn source(&self, name: &str) -> Option<&str> {
        self.values.get(name).map(|(_, s)| s.as_str())
    }

    pub fn bool(&self, name: &str) -> Option<bool> {
        match self.get(name) {
            Some(ParamValue::Bool(b)) => Some(*b),
            _ => None,
        }
    }
    pub fn integer(&self, name: &str) -> Option<i64> {
        match self.get(name) {
            Some(ParamValue::Integer(i)) => Some(*i),
            _ => None,
        }
    }
    pub fn double(&self, name: &str) -> Option<f64> {
        match self.get(name) {
            Some(ParamValue::Double(d)) => Some(*d),
            _ => None,
        }
    }
    pub fn string(&self, name: &str) -> Option<&str> {
        match self.get(name) {
            Some(ParamValue::String(s)) => Some(s),
            _ => None,
        }
    }
    pub fn strings(&self, name: &str) -> Option<&[String]> {
        match self.get(name) {
            Some(ParamValue::StringArray(s)) => Some(s),
            _ => None,
        }
    }

    /// Record the value in effect for `name` when a command-line flag or argument set it
    /// (`--duration`, the SCENE argument), so the parameter services report it.
    pub fn set_effective(&mut self, name: &str, value: ParamValue) {
        self.values
            .insert(name.to_string(), (value, "command line".to_string()));
    }

    /// An error about parameter `name`, naming where it was set.
    pub fn invalid(&self, name: &str, message: impl Into<String>) -> ParamsError {
        let (file, key) = match self.source(name) {
            Some(s) => match s.split_once('\u{1}') {
                Some((f, k)) => (f.to_string(), k.to_string()),
                None => (s.to_string(), name.to_string()),
            },
            None => ("parameters".to_string(), name.to_string()),
        };
        ParamsError::Invalid {
            file,
            key,
            message: message.into(),
        }
    }

    /// Set `name` from a YAML value (type-checked against [`DECLARED`]). `file` and
    /// `key` locate it in error messages; `strict`: unknown names are errors (else
    /// warnings).
    fn set(
        &mut self,
        name: &str,
        value: &serde_yaml::Value,
        file: &str,
        key: &str,
        strict: bool,
    ) -> Result<(), ParamsError> {
        let invalid = |message: String| ParamsError::Invalid {
            file: file.to_string(),
            key: key.to_string(),
            message,
        };
        let Some(decl) = DECLARED.iter().find(|d| d.name == name) else {
            let known: Vec<&str> = DECLARED.iter().map(|d| d.name).collect();
            let message = format!("unknown parameter `{name}` (known: {})", known.join(", "));
            if strict {
                return Err(invalid(message));
            }
            self.warnings
                .push(format!("{file}: `{key}`: {message}; ignored"));
            return Ok(());
        };
        let got = describe(value);
        let typed = match (decl.ty, value) {
            (ParamType::Bool, serde_yaml::Value::Bool(b)) => ParamValue::Bool(*b),
            (ParamType::Integer, serde_yaml::Value::Number(n)) if n.is_i64() => {
                ParamValue::Integer(n.as_i64().unwrap_or_default())
            }
            (ParamType::Double, serde_yaml::Value::Number(n)) => {
                let v = n.as_f64().unwrap_or(f64::NAN);
                if !v.is_finite() {
                    return Err(invalid(format!("must be a finite number, got {v}")));
                }
                ParamValue::Double(v)
            }
            (ParamType::String, serde_yaml::Value::String(s)) => ParamValue::String(s.clone()),
            (ParamType::StringArray, serde_yaml::Value::Sequence(items)) => {
                let mut out = Vec::new();
                for (i, item) in items.iter().enumerate() {
                    match item {
                        serde_yaml::Value::String(s) => out.push(s.clone()),
                        other => {
                            return Err(invalid(format!(
                                "element {i} must be a string, got {}",
                                describe(other)
                            )))
                        }
                    }
                }
                ParamValue::StringArray(out)
            }
            (ty, _) => return Err(invalid(format!("expected {}, got {got}", ty.name()))),
        };
        self.values
            .insert(name.to_string(), (typed, format!("{file}\u{1}{key}")));
        Ok(())
    }
}

fn describe(v: &serde_yaml::Value) -> String {
    match v {
        serde_yaml::Value::Null => "an empty value".into(),
        serde_yaml::Value::Bool(b) => format!("the bool {b}"),
        serde_yaml::Value::Number(n) if n.is_f64() => format!("the double {n}"),
        serde_yaml::Value::Number(n) => format!("the integer {n}"),
        serde_yaml::Value::String(s) => format!("the string {s:?}"),
        serde_yaml::Value::Sequence(_) => "a list".into(),
        serde_yaml::Value::Mapping(_) => "a map".into(),
        serde_yaml::Value::Tagged(_) => "a tagged value".into(),
    }
}

/// Does a params-file section key (`/**`, `node`, `/ns/node`, `/**/node`, `/ns/*`)
/// apply to the node with fully qualified name `fqn` (`/ns/node`)?
pub fn section_matches(pattern: &str, fqn: &str) -> bool {
    let pattern = if pattern.starts_with('/') {
        pattern.to_string()
    } else {
        format!("/{pattern}")
    };
    let p: Vec<&str> = pattern.split('/').filter(|s| !s.is_empty()).collect();
    let n: Vec<&str> = fqn.split('/').filter(|s| !s.is_empty()).collect();
    fn m(p: &[&str], n: &[&str]) -> bool {
        match p.first() {
            None => n.is_empty(),
            Some(&"**") => (0..=n.len()).any(|k| m(&p[1..], &n[k..])),
            Some(&"*") => !n.is_empty() && m(&p[1..], &n[1..]),
            Some(tok) => !n.is_empty() && n[0] == *tok && m(&p[1..], &n[1..]),
        }
    }
    m(&p, &n)
}

/// Read a params file into `params`, for the node `fqn`. Sections for other nodes are
/// skipped. Unknown keys are errors in sections naming this node, warnings in
/// wildcard sections (`/**`), which other nodes share.
pub fn read_params_file(path: &Path, fqn: &str, params: &mut Params) -> Result<(), ParamsError> {
    let text = std::fs::read_to_string(path).map_err(|source| ParamsError::Io {
        file: path.to_path_buf(),
        source,
    })?;
    read_params_str(&text, &path.display().to_string(), fqn, params)
}

/// Like [`read_params_file`] from text; `file` names it in messages.
pub fn read_params_str(
    text: &str,
    file: &str,
    fqn: &str,
    params: &mut Params,
) -> Result<(), ParamsError> {
    let format = |message: String| ParamsError::Format {
        file: file.to_string(),
        message,
    };
    let root: serde_yaml::Value = serde_yaml::from_str(text).map_err(|e| format(e.to_string()))?;
    let serde_yaml::Value::Mapping(sections) = root else {
        return Err(format(
            "expected a map of node names (e.g. `developable_sim:` or `/**:`), each holding \
             `ros__parameters:`"
                .into(),
        ));
    };
    for (section, body) in &sections {
        let Some(section) = section.as_str() else {
            return Err(format(format!(
                "section key {section:?} is not a node name"
            )));
        };
        let serde_yaml::Value::Mapping(body) = body else {
            return Err(ParamsError::Invalid {
                file: file.into(),
                key: section.into(),
                message: "expected a map holding `ros__parameters:`".into(),
            });
        };
        for key in body.keys() {
            if key.as_str() != Some("ros__parameters") {
                return Err(ParamsError::Invalid {
                    file: file.into(),
                    key: format!("{section}.{}", key.as_str().unwrap_or("?")),
                    message: "only `ros__parameters` may appear under a node name".into(),
                });
            }
        }
        if !section_matches(section, fqn) {
            let base = fqn.rsplit('/').next().unwrap_or(fqn);
            if section.trim_start_matches('/') == base || section.ends_with(&format!("/{base}")) {
                params.warnings.push(format!(
                    "{file}: section `{section}` does not apply to node {fqn} (ROS matches the \
                     fully qualified name; write `{fqn}:` or `/**/{base}:`)"
                ));
            }
            continue;
        }
        // `/**/name` names this node; `/**` or `/ns/*` are shared with other nodes
        let wildcard = section
            .rsplit('/')
            .next()
            .is_some_and(|last| last.contains('*'));
        let prefix = format!("{section}.ros__parameters");
        let Some(values) = body.get("ros__parameters") else {
            continue;
        };
        let mut flat = Vec::new();
        match values {
            serde_yaml::Value::Mapping(m) => {
                flatten("", m, &mut flat).map_err(|k| ParamsError::Invalid {
                    file: file.into(),
                    key: format!("{prefix}.{k}"),
                    message: "parameter names must be strings".into(),
                })?
            }
            serde_yaml::Value::Null => {}
            _ => {
                return Err(ParamsError::Invalid {
                    file: file.into(),
                    key: prefix,
                    message: "expected a map of parameters".into(),
                })
            }
        }
        for (name, value) in flat {
            params.set(&name, &value, file, &format!("{prefix}.{name}"), !wildcard)?;
        }
    }
    Ok(())
}

fn flatten(
    prefix: &str,
    map: &serde_yaml::Mapping,
    out: &mut Vec<(String, serde_yaml::Value)>,
) -> Result<(), String> {
    for (k, v) in map {
        let Some(k) = k.as_str() else {
            return Err(format!("{prefix}{k:?}"));
        };
        let name = if prefix.is_empty() {
            k.to_string()
        } else {
            format!("{prefix}.{k}")
        };
        match v {
            serde_yaml::Value::Mapping(m) => flatten(&name, m, out)?,
            _ => out.push((name, v.clone())),
        }
    }
    Ok(())
}

/// Set `name:=value` from the command line (`-p`); the value is YAML.
pub fn set_from_command_line(params: &mut Params, spec: &str) -> Result<(), ParamsError> {
    let (name, raw) = spec
        .split_once(":=")
        .ok_or_else(|| ParamsError::RosArgs(format!("-p {spec}: expected NAME:=VALUE")))?;
    let value: serde_yaml::Value = serde_yaml::from_str(raw)
        .map_err(|e| ParamsError::RosArgs(format!("-p {spec}: value is not valid YAML: {e}")))?;
    // `node_name:param:=value` applies to that node only: handled by the caller
    params.set(name, &value, "command line (-p)", name, true)
}

/// The ROS arguments (`--ros-args ... [--]`) found on the command line.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RosArgs {
    pub params_files: Vec<PathBuf>,
    /// `-p name:=value`, in order.
    pub params: Vec<String>,
    /// `-r from:=to` (besides `__ns` and `__node`), in order.
    pub remaps: Vec<(String, String)>,
    /// `-r __ns:=/x`.
    pub namespace: Option<String>,
    /// `-r __node:=name` (or `__name`).
    pub node_name: Option<String>,
    /// Accepted and ignored (logging, enclaves), for a notice.
    pub ignored: Vec<String>,
}

/// Split `args` (without the program name) into the arguments for our own parser and
/// the ROS arguments. Several `--ros-args` blocks are allowed; `--` ends one.
pub fn split_ros_args(args: &[String]) -> Result<(Vec<String>, RosArgs), ParamsError> {
    let mut own = Vec::new();
    let mut ros = RosArgs::default();
    let mut i = 0;
    let mut in_ros = false;
    let value = |i: usize, flag: &str| -> Result<String, ParamsError> {
        args.get(i + 1)
            .cloned()
            .ok_or_else(|| ParamsError::RosArgs(format!("{flag} needs a value")))
    };
    while i < args.len() {
        let a = args[i].as_str();
        if !in_ros {
            if a == "--ros-args" {
                in_ros = true;
            } else {
                own.push(args[i].clone());
            }
            i += 1;
            continue;
        }
        match a {
            "--" => in_ros = false,
            "--ros-args" => {}
            "--params-file" => {
                ros.params_files.push(PathBuf::from(value(i, a)?));
                i += 1;
            }
            "-p" | "--param" => {
                ros.params.push(value(i, a)?);
                i += 1;
            }
            "-r" | "--remap" => {
                let spec = value(i, a)?;
                i += 1;
                let (from, to) = spec.rsplit_once(":=").ok_or_else(|| {
                    ParamsError::RosArgs(format!("{a} {spec}: expected FROM:=TO"))
                })?;
                // `node:from:=to` applies to a node by name; we are the only node
                let from = from.rsplit(':').next().unwrap_or(from);
                match from {
                    "__ns" => ros.namespace = Some(to.to_string()),
                    "__node" | "__name" => ros.node_name = Some(to.to_string()),
                    _ => ros.remaps.push((from.to_string(), to.to_string())),
                }
            }
            "--log-level" | "--log-config-file" | "-e" | "--enclave" => {
                ros.ignored.push(format!("{a} {}", value(i, a)?));
                i += 1;
            }
            "--enable-rosout-logs"
            | "--disable-rosout-logs"
            | "--enable-stdout-logs"
            | "--disable-stdout-logs"
            | "--enable-external-lib-logs"
            | "--disable-external-lib-logs" => ros.ignored.push(a.to_string()),
            other => {
                return Err(ParamsError::RosArgs(format!(
                "unknown ROS argument `{other}` (supported: --params-file FILE, -p NAME:=VALUE, \
                     -r FROM:=TO, -r __ns:=/NS, -r __node:=NAME, --log-level LEVEL)"
            )))
            }
        }
        i += 1;
    }
    Ok((own, ros))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn args(s: &str) -> Vec<String> {
        s.split_whitespace().map(String::from).collect()
    }

    #[test]
    fn splits_ros_args_blocks() {
        let (own, ros) = split_ros_args(&args(
            "node s.yaml --ros-args --params-file p.yaml -r __ns:=/robot -r __node:=sim \
             -p duration:=2.0 -r /a:=/b --log-level info -- --record bag",
        ))
        .unwrap();
        assert_eq!(own, args("node s.yaml --record bag"));
        assert_eq!(ros.params_files, [PathBuf::from("p.yaml")]);
        assert_eq!(ros.namespace.as_deref(), Some("/robot"));
        assert_eq!(ros.node_name.as_deref(), Some("sim"));
        assert_eq!(ros.params, ["duration:=2.0"]);
        assert_eq!(ros.remaps, [("/a".to_string(), "/b".to_string())]);
        assert!(split_ros_args(&args("x --ros-args --bogus")).is_err());
        assert!(split_ros_args(&args("x --ros-args --params-file")).is_err());
    }

    #[test]
    fn section_patterns_follow_ros() {
        assert!(section_matches("/**", "/developable_sim"));
        assert!(section_matches("/**", "/a/b/developable_sim"));
        assert!(section_matches("developable_sim", "/developable_sim"));
        assert!(!section_matches("developable_sim", "/ns/developable_sim"));
        assert!(section_matches(
            "/ns/developable_sim",
            "/ns/developable_sim"
        ));
        assert!(section_matches(
            "/**/developable_sim",
            "/ns/developable_sim"
        ));
        assert!(section_matches("/ns/*", "/ns/developable_sim"));
        assert!(!section_matches("other_node", "/developable_sim"));
    }

    #[test]
    fn reads_sections_types_and_names_file_and_key_in_errors() {
        let fqn = "/developable_sim";
        let mut p = Params::default();
        read_params_str(
            "developable_sim:\n  ros__parameters:\n    real_time_factor: 2\n    marker:\n      line_width: 0.004\n    scene_overrides: [\"dt=0.02\"]\nother:\n  ros__parameters:\n    whatever: 1\n/**:\n  ros__parameters:\n    use_sim_time: false\n    some_other_nodes_param: 3\n",
            "p.yaml",
            fqn,
            &mut p,
        )
        .unwrap();
        assert_eq!(p.double("real_time_factor"), Some(2.0));
        assert_eq!(p.double("marker.line_width"), Some(0.004));
        assert_eq!(p.strings("scene_overrides").unwrap(), ["dt=0.02"]);
        assert_eq!(p.warnings.len(), 1);

        let err = |text: &str| {
            read_params_str(text, "p.yaml", fqn, &mut Params::default())
                .unwrap_err()
                .to_string()
        };
        let e = err("developable_sim:\n  ros__parameters:\n    real_time_factr: 2.0\n");
        assert!(
            e.contains("p.yaml") && e.contains("developable_sim.ros__parameters.real_time_factr"),
            "{e}"
        );
        let e = err("developable_sim:\n  ros__parameters:\n    as_fast_as_possible: 1\n");
        assert!(e.contains("expected a bool, got the integer 1"), "{e}");
        let e = err("developable_sim:\n  parameters:\n    duration: 1.0\n");
        assert!(e.contains("ros__parameters"), "{e}");
        let e = err("- a\n- b\n");
        assert!(e.contains("not a ROS 2 params file"), "{e}");
        let e = err("developable_sim:\n  ros__parameters:\n    duration: .nan\n");
        assert!(e.contains("finite"), "{e}");

        // `/**/name` names this node: strict; a section for the same name in another
        // namespace is reported
        let e = read_params_str(
            "/**/developable_sim:\n  ros__parameters:\n    bogus: 1\n",
            "p.yaml",
            "/robot1/developable_sim",
            &mut Params::default(),
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.contains("/**/developable_sim.ros__parameters.bogus"),
            "{e}"
        );
        let mut p = Params::default();
        read_params_str(
            "developable_sim:\n  ros__parameters:\n    duration: 1.0\n",
            "p.yaml",
            "/robot1/developable_sim",
            &mut p,
        )
        .unwrap();
        assert_eq!(p.double("duration"), None);
        assert!(p.warnings[0].contains("does not apply"), "{:?}", p.warnings);

        let mut p = Params::default();
        set_from_command_line(&mut p, "lockstep:=service").unwrap();
        assert_eq!(p.string("lockstep"), Some("service"));
        assert!(set_from_command_line(&mut p, "duration:=abc").is_err());
        assert!(set_from_command_line(&mut p, "duration").is_err());
        let e = p.invalid("lockstep", "bad").to_string();
        assert!(
            e.contains("command line (-p)") && e.contains("lockstep"),
            "{e}"
        );
    }
}
