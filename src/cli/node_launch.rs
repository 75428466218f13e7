//! The node's settings from every source, in one order of precedence:
//! command-line flag > `--ros-args -p` > params files (in order) > the scene > default.
//!
//! `resolve` turns the `node` command's options and ROS arguments into a
//! [`NodeConfig`]; it reads the params files and the scene but starts nothing.

use std::path::PathBuf;
use std::time::Duration;

use crate::foxglove::{FoxgloveConfig, DEFAULT_BIND};
use crate::record::bag::{BagOptions, Compression};
use crate::ros::node::{Lockstep, NodeConfig, Pacing};
use crate::ros::tf::DEFAULT_MAX_LAG;
use crate::scene::{self, Scene, SceneError};
use crate::session::input::{InputPolicy, DEFAULT_MAX_STAMP_LEAD};
use crate::session::names::{normalize_namespace, NameError, NodeNames};
use crate::session::params::{self, ParamValue, Params, ParamsError, RosArgs};
use crate::session::MarkerStyle;

use super::args::NodeArgs;
use super::bag_name::bag_folder;

/// Why the node's settings cannot be resolved.
#[derive(Debug, thiserror::Error)]
pub enum LaunchError {
    #[error(transparent)]
    Params(#[from] ParamsError),
    #[error(transparent)]
    Scene(#[from] SceneError),
    #[error(transparent)]
    Name(#[from] NameError),
    /// A command-line flag out of its range (the message names the flag).
    #[error("{0}")]
    Flag(String),
    #[error(
        "no scene: give SCENE.yaml (e.g. `developable_sim node config/scenes/ribbon_extreme_torsion.yaml`) or the `scene` parameter"
    )]
    NoScene,
    #[error("ROS_DOMAIN_ID={value:?} is not a domain id (an integer 0..=232)")]
    DomainEnv {
        value: String,
        #[source]
        source: std::num::ParseIntError,
    },
    #[error("domain id {0} is out of range: DDS allows 0..=232 (ROS recommends 0..=101)")]
    DomainRange(u16),
}

/// The node's name, its normalized namespace and its fully qualified name
/// (`--node-name` > `-r __node:=` > developable_sim; `--namespace` > `-r __ns:=` > /).
pub fn identity(args: &NodeArgs, ros: &RosArgs) -> Result<(String, String, String), NameError> {
    let node_name = args
        .node_name
        .clone()
        .or(ros.node_name.clone())
        .unwrap_or_else(|| "developable_sim".into());
    let namespace = args
        .namespace
        .clone()
        .or(ros.namespace.clone())
        .unwrap_or_else(|| "/".into());
    let namespace = normalize_namespace(&namespace)?;
    let fqn = if namespace == "/" {
        format!("/{node_name}")
    } else {
        format!("{namespace}/{node_name}")
    };
    Ok((node_name, namespace, fqn))
}

/// The parameters: `--params` files, then `--ros-args --params-file` files, in order,
/// then `-p` (a later source replaces an earlier one).
fn read_params(args: &NodeArgs, ros: &RosArgs, fqn: &str) -> Result<Params, ParamsError> {
    let mut p = Params::default();
    for f in args.params.iter().chain(&ros.params_files) {
        params::read_params_file(f, fqn, &mut p)?;
    }
    for spec in &ros.params {
        params::set_from_command_line(&mut p, spec)?;
    }
    Ok(p)
}

/// The DDS domain: `--domain-id` > $ROS_DOMAIN_ID (`env`) > 0, at most 232.
pub fn domain_id(cli: Option<u16>, env: Option<&str>) -> Result<u16, LaunchError> {
    let id = match (cli, env) {
        (Some(id), _) => id,
        (None, Some(v)) if !v.trim().is_empty() => {
            v.trim()
                .parse::<u16>()
                .map_err(|source| LaunchError::DomainEnv {
                    value: v.to_string(),
                    source,
                })?
        }
        _ => 0,
    };
    if id > 232 {
        return Err(LaunchError::DomainRange(id));
    }
    Ok(id)
}

fn positive(p: &Params, name: &str, default: f64) -> Result<f64, ParamsError> {
    let v = p.double(name).unwrap_or(default);
    if v > 0.0 && v.is_finite() {
        Ok(v)
    } else {
        Err(p.invalid(name, format!("must be > 0, got {v}")))
    }
}

fn non_negative(p: &Params, name: &str, default: f64) -> Result<f64, ParamsError> {
    let v = p.double(name).unwrap_or(default);
    if v >= 0.0 && v.is_finite() {
        Ok(v)
    } else {
        Err(p.invalid(name, format!("must be >= 0, got {v}")))
    }
}

/// The scene file (the SCENE argument > the `scene` parameter) and its overrides (the
/// `scene_overrides` parameter, then `--set`: a later override wins).
fn scene_source(args: &NodeArgs, p: &Params) -> Result<(PathBuf, Vec<String>), LaunchError> {
    let path = match (&args.scene, p.string("scene").filter(|s| !s.is_empty())) {
        (Some(s), _) => s.clone(),
        (None, Some(s)) => PathBuf::from(s),
        (None, None) => return Err(LaunchError::NoScene),
    };
    let mut overrides: Vec<String> = p
        .strings("scene_overrides")
        .map(|s| s.to_vec())
        .unwrap_or_default();
    overrides.extend(args.overrides.sets.iter().cloned());
    Ok((path, overrides))
}

/// Simulated time to run, s (0: until stopped): `--duration` > `duration` > 0.
pub fn duration(args: &NodeArgs, p: &Params) -> Result<f64, LaunchError> {
    match args.duration {
        Some(d) if d.is_finite() && d >= 0.0 => Ok(d),
        Some(d) => Err(LaunchError::Flag(format!(
            "--duration must be >= 0 s, got {d}"
        ))),
        None => {
            let d = p.double("duration").unwrap_or(0.0);
            if d < 0.0 {
                return Err(p
                    .invalid("duration", format!("must be >= 0, got {d}"))
                    .into());
            }
            Ok(d)
        }
    }
}

/// Real time x `--real-time-factor` > `real_time_factor` > 1, unless
/// `--as-fast-as-possible` or the `as_fast_as_possible` parameter.
pub fn pacing(args: &NodeArgs, p: &Params) -> Result<Pacing, LaunchError> {
    let factor = match args.real_time_factor {
        Some(f) if f > 0.0 && f.is_finite() => f,
        Some(f) => {
            return Err(LaunchError::Flag(format!(
                "--real-time-factor must be > 0, got {f}"
            )))
        }
        None => positive(p, "real_time_factor", 1.0)?,
    };
    Ok(
        if args.as_fast_as_possible || p.bool("as_fast_as_possible") == Some(true) {
            Pacing::AsFastAsPossible
        } else {
            Pacing::RealTime { factor }
        },
    )
}

/// What drives steps (`--lockstep` > `lockstep` > off) and the spec as given.
pub fn lockstep(
    args: &NodeArgs,
    p: &Params,
    scene: &Scene,
) -> Result<(Lockstep, String), LaunchError> {
    let spec = args
        .lockstep
        .clone()
        .or_else(|| p.string("lockstep").map(String::from))
        .unwrap_or_default();
    let handles: Vec<&str> = scene
        .world
        .handles()
        .iter()
        .map(|h| h.name.as_str())
        .collect();
    let lockstep = match spec.as_str() {
        "" => Lockstep::Off,
        "service" => Lockstep::Service,
        h => match handles.iter().position(|n| *n == h) {
            Some(i) => Lockstep::Handle(i),
            None => {
                let msg = format!(
                    "`{h}` is neither `service` nor a handle of scene {} (handles: {})",
                    scene.name,
                    if handles.is_empty() {
                        "none".to_string()
                    } else {
                        handles.join(", ")
                    }
                );
                if args.lockstep.is_some() {
                    return Err(LaunchError::Flag(format!("--lockstep {msg}")));
                }
                return Err(p.invalid("lockstep", msg).into());
            }
        },
    };
    Ok((lockstep, spec))
}

/// The bag folder (`--record [DIR]` > `record` > none) with its options
/// (`record_compression`, `record_flush_period` in s, `--record-cameras` or
/// `record_cameras`).
pub fn record(args: &NodeArgs, p: &Params) -> Result<Option<(PathBuf, BagOptions)>, ParamsError> {
    let compression: Compression = p
        .string("record_compression")
        .unwrap_or("none")
        .parse()
        .map_err(|e: String| p.invalid("record_compression", e))?;
    let flush = positive(p, "record_flush_period", 1.0)?;
    let dir = args.record.clone().map(bag_folder).or_else(|| {
        p.string("record")
            .filter(|s| !s.is_empty())
            .map(PathBuf::from)
    });
    Ok(dir.map(|dir| {
        let options = BagOptions {
            compression,
            flush_period: Duration::from_secs_f64(flush),
            record_cameras: args.record_cameras || p.bool("record_cameras").unwrap_or(false),
            ..BagOptions::default()
        };
        (dir, options)
    }))
}

/// Marker sizes (`marker.line_width`, `marker.sphere_diameter`, m).
fn marker_style(p: &Params) -> Result<MarkerStyle, ParamsError> {
    Ok(MarkerStyle {
        line_width: positive(p, "marker.line_width", 0.002)?,
        sphere_diameter: positive(p, "marker.sphere_diameter", 0.012)?,
        ..MarkerStyle::default()
    })
}

/// Which handle poses are accepted: the scene's frame id, `accept_empty_frame_id`,
/// `max_stamp_lead` (s).
fn input_policy(p: &Params, scene: &Scene) -> Result<InputPolicy, ParamsError> {
    Ok(InputPolicy {
        frame_id: scene.frame_id.clone(),
        accept_empty_frame_id: p.bool("accept_empty_frame_id").unwrap_or(false),
        max_stamp_lead: positive(p, "max_stamp_lead", DEFAULT_MAX_STAMP_LEAD)?,
    })
}

/// The Foxglove server's address: `--foxglove` > `foxglove_port` > 0 (off), and
/// `--foxglove-bind` > `foxglove_bind` > 127.0.0.1; the values in effect go into `p`.
pub fn foxglove(args: &NodeArgs, p: &mut Params) -> Result<Option<FoxgloveConfig>, LaunchError> {
    let port = match (args.foxglove, p.integer("foxglove_port")) {
        (Some(port), _) => port,
        (None, Some(i)) => u16::try_from(i).map_err(|_| {
            p.invalid(
                "foxglove_port",
                format!("must be a TCP port 0..=65535, got {i}"),
            )
        })?,
        (None, None) => 0,
    };
    let bind = match (&args.foxglove_bind, p.string("foxglove_bind")) {
        (Some(b), _) => b.clone(),
        (None, Some(b)) => b.to_string(),
        (None, None) => DEFAULT_BIND.to_string(),
    };
    if bind.parse::<std::net::IpAddr>().is_err() {
        let msg = format!("`{bind}` is not an IP address (e.g. 127.0.0.1, 0.0.0.0)");
        if args.foxglove_bind.is_some() {
            return Err(LaunchError::Flag(format!("--foxglove-bind {msg}")));
        }
        return Err(p.invalid("foxglove_bind", msg).into());
    }
    p.set_effective("foxglove_port", ParamValue::Integer(port.into()));
    p.set_effective("foxglove_bind", ParamValue::String(bind.clone()));
    Ok((port > 0).then_some(FoxgloveConfig { bind, port }))
}

/// Every setting of the node. `env_domain_id` is $ROS_DOMAIN_ID; `log` receives the
/// warnings about the params files and the notes about ignored ROS arguments, as soon
/// as they are known (before the scene is loaded).
pub fn resolve(
    args: &NodeArgs,
    ros: &RosArgs,
    env_domain_id: Option<&str>,
    log: &mut dyn FnMut(String),
) -> Result<NodeConfig, LaunchError> {
    let (node_name, namespace, fqn) = identity(args, ros)?;
    let mut p = read_params(args, ros, &fqn)?;
    for w in &p.warnings {
        log(format!("[developable_sim] warning: {w}"));
    }
    for i in &ros.ignored {
        log(format!(
            "[developable_sim] note: ROS argument `{i}` is accepted and ignored"
        ));
    }
    let (scene_path, overrides) = scene_source(args, &p)?;
    let scene = scene::load(&scene_path, &overrides)?;
    let duration = duration(args, &p)?;
    let pacing = pacing(args, &p)?;
    let (lockstep, lockstep_spec) = lockstep(args, &p, &scene)?;
    let record = record(args, &p)?;
    let style = marker_style(&p)?;
    let names = NodeNames::resolve(&scene, &node_name, &namespace, &ros.remaps)?;
    let domain_id = domain_id(args.domain_id, env_domain_id)?;
    let policy = input_policy(&p, &scene)?;
    let start_paused = args.paused || p.bool("start_paused").unwrap_or(false);
    let use_sim_time = p.bool("use_sim_time").unwrap_or(false);
    let tf_max_lag = non_negative(&p, "tf_max_lag", DEFAULT_MAX_LAG)?;
    let max_clock_jump = positive(&p, "max_clock_jump", 1.0)?;
    if p.double("markers_rate").is_some() {
        non_negative(&p, "markers_rate", 0.0)?;
    }
    let foxglove = foxglove(args, &mut p)?;
    p.set_effective(
        "scene",
        ParamValue::String(scene_path.display().to_string()),
    );
    p.set_effective("duration", ParamValue::Double(duration));
    p.set_effective("lockstep", ParamValue::String(lockstep_spec));
    if let Some((r, _)) = &record {
        p.set_effective("record", ParamValue::String(r.display().to_string()));
    }
    Ok(NodeConfig {
        scene,
        names,
        domain_id,
        record,
        duration: (duration > 0.0).then_some(duration),
        pacing,
        lockstep,
        start_paused,
        policy,
        style,
        use_sim_time,
        tf_max_lag,
        max_clock_jump,
        params: p,
        foxglove,
    })
}

#[cfg(test)]
#[path = "node_launch_tests.rs"]
mod tests;
