//! The order of precedence of the node's settings: flag > `-p` > params files > scene >
//! default, each source tried alone and against the next.

use std::path::PathBuf;

use super::*;

const SCENE: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/config/scenes/ribbon_extreme_torsion.yaml"
);

fn args() -> NodeArgs {
    NodeArgs {
        scene: Some(PathBuf::from(SCENE)),
        ..NodeArgs::default()
    }
}

/// A params file for every node (`/**`) with these `ros__parameters` lines.
fn params_file(name: &str, lines: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("node_launch_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(format!("{name}.yaml"));
    let body: String = lines.lines().map(|l| format!("    {l}\n")).collect();
    std::fs::write(&path, format!("/**:\n  ros__parameters:\n{body}")).unwrap();
    path
}

fn resolve_quiet(a: &NodeArgs, ros: &RosArgs) -> Result<NodeConfig, LaunchError> {
    resolve(a, ros, None, &mut |_| {})
}

/// The error of a resolution that must fail (NodeConfig has no Debug for unwrap_err).
fn error(r: Result<NodeConfig, LaunchError>) -> LaunchError {
    match r {
        Ok(_) => panic!("resolved, expected an error"),
        Err(e) => e,
    }
}

fn factor(c: &NodeConfig) -> f64 {
    match c.pacing {
        Pacing::RealTime { factor } => factor,
        Pacing::AsFastAsPossible => panic!("not real time"),
    }
}

#[test]
fn flag_beats_dash_p_beats_params_files_beats_default() {
    let first = params_file("first", "real_time_factor: 2.0");
    let second = params_file("second", "real_time_factor: 2.5");
    let mut a = args();
    let mut ros = RosArgs::default();
    assert_eq!(factor(&resolve_quiet(&a, &ros).unwrap()), 1.0, "default");
    a.params = vec![first.clone()];
    assert_eq!(
        factor(&resolve_quiet(&a, &ros).unwrap()),
        2.0,
        "params file"
    );
    // --params files first, then --ros-args --params-file: the later one wins
    ros.params_files = vec![second];
    assert_eq!(factor(&resolve_quiet(&a, &ros).unwrap()), 2.5, "later file");
    ros.params = vec!["real_time_factor:=3.0".into()];
    assert_eq!(factor(&resolve_quiet(&a, &ros).unwrap()), 3.0, "-p");
    a.real_time_factor = Some(4.0);
    assert_eq!(factor(&resolve_quiet(&a, &ros).unwrap()), 4.0, "flag");
}

#[test]
fn the_scene_supplies_what_no_source_sets() {
    let c = resolve_quiet(&args(), &RosArgs::default()).unwrap();
    // the frame id of accepted poses is the scene's
    assert_eq!(c.policy.frame_id, "world");
    assert_eq!(c.policy.max_stamp_lead, DEFAULT_MAX_STAMP_LEAD);
    assert_eq!(c.tf_max_lag, DEFAULT_MAX_LAG);
    assert_eq!(c.duration, None);
    assert_eq!(c.lockstep, Lockstep::Off);
    assert!(c.record.is_none());
    // scene_overrides first, then --set: the flag wins
    let mut a = args();
    a.overrides.sets = vec!["dt=0.004".into()];
    let ros = RosArgs {
        params: vec!["scene_overrides:=['dt=0.002']".into()],
        ..RosArgs::default()
    };
    let c = resolve_quiet(&a, &ros).unwrap();
    assert_eq!(c.scene.world.dt(), 0.004);
    a.overrides.sets.clear();
    let c = resolve_quiet(&a, &ros).unwrap();
    assert_eq!(c.scene.world.dt(), 0.002);
}

#[test]
fn scene_argument_beats_the_scene_parameter() {
    let ros = RosArgs {
        params: vec!["scene:=/nonexistent/scene.yaml".into()],
        ..RosArgs::default()
    };
    assert!(resolve_quiet(&args(), &ros).is_ok());
    let none = NodeArgs::default();
    let e = error(resolve_quiet(&none, &ros)).to_string();
    assert!(e.contains("/nonexistent/scene.yaml"), "{e}");
    let e = error(resolve_quiet(&none, &RosArgs::default()));
    assert!(matches!(e, LaunchError::NoScene), "{e}");
}

#[test]
fn names_flags_beat_remaps_beat_defaults() {
    let mut a = args();
    let mut ros = RosArgs::default();
    assert_eq!(identity(&a, &ros).unwrap().2, "/developable_sim");
    ros.namespace = Some("robot1".into());
    ros.node_name = Some("sim".into());
    assert_eq!(identity(&a, &ros).unwrap().2, "/robot1/sim");
    a.namespace = Some("/robot2".into());
    a.node_name = Some("other".into());
    assert_eq!(
        identity(&a, &ros).unwrap(),
        ("other".into(), "/robot2".into(), "/robot2/other".into())
    );
    a.namespace = Some("/bad ns".into());
    assert!(identity(&a, &ros).is_err());
}

#[test]
fn domain_flag_beats_the_environment_beats_zero() {
    assert_eq!(domain_id(None, None).unwrap(), 0);
    assert_eq!(domain_id(None, Some(" ")).unwrap(), 0);
    assert_eq!(domain_id(None, Some("7")).unwrap(), 7);
    assert_eq!(domain_id(Some(3), Some("7")).unwrap(), 3);
    assert_eq!(domain_id(Some(3), Some("x")).unwrap(), 3);
    let e = domain_id(None, Some("x")).unwrap_err();
    assert_eq!(
        e.to_string(),
        "ROS_DOMAIN_ID=\"x\" is not a domain id (an integer 0..=232)"
    );
    // the parse error stays in the chain (main prints it after a colon)
    assert!(std::error::Error::source(&e).is_some());
    assert!(matches!(
        domain_id(Some(233), None),
        Err(LaunchError::DomainRange(233))
    ));
}

#[test]
fn bad_values_name_their_source() {
    let mut a = args();
    a.duration = Some(-1.0);
    let e = error(resolve_quiet(&a, &RosArgs::default())).to_string();
    assert_eq!(e, "--duration must be >= 0 s, got -1");
    let file = params_file("bad", "max_stamp_lead: -2.0");
    let a = NodeArgs {
        params: vec![file.clone()],
        ..args()
    };
    let e = error(resolve_quiet(&a, &RosArgs::default())).to_string();
    assert!(
        e.contains("max_stamp_lead") && e.contains("must be > 0, got -2"),
        "{e}"
    );
    assert!(e.contains(&file.display().to_string()), "{e}");
    let mut a = args();
    a.lockstep = Some("nope".into());
    let e = error(resolve_quiet(&a, &RosArgs::default())).to_string();
    assert!(
        e.starts_with("--lockstep `nope` is neither `service` nor a handle of scene"),
        "{e}"
    );
    assert!(e.contains("(handles: twist_end"), "{e}");
}

#[test]
fn lockstep_on_a_handle_and_pacing_flags() {
    let mut a = args();
    let ros = RosArgs {
        params: vec![
            "lockstep:=twist_end".into(),
            "as_fast_as_possible:=true".into(),
        ],
        ..RosArgs::default()
    };
    let c = resolve_quiet(&a, &ros).unwrap();
    assert_eq!(c.lockstep, Lockstep::Handle(0));
    assert_eq!(c.pacing, Pacing::AsFastAsPossible);
    a.lockstep = Some("service".into());
    let c = resolve_quiet(&a, &ros).unwrap();
    assert_eq!(c.lockstep, Lockstep::Service);
    assert_eq!(c.params.string("lockstep"), Some("service"));
}

#[test]
fn warnings_and_ignored_arguments_are_logged() {
    let file = params_file("unknown", "no_such_parameter: 1");
    let a = NodeArgs {
        params: vec![file],
        ..args()
    };
    let ros = RosArgs {
        ignored: vec!["--log-level".into()],
        ..RosArgs::default()
    };
    let mut log = Vec::new();
    resolve(&a, &ros, None, &mut |l| log.push(l)).unwrap();
    assert!(
        log.iter().any(
            |l| l.starts_with("[developable_sim] warning: ") && l.contains("no_such_parameter")
        ),
        "{log:?}"
    );
    assert!(
        log.contains(
            &"[developable_sim] note: ROS argument `--log-level` is accepted and ignored"
                .to_string()
        ),
        "{log:?}"
    );
}
