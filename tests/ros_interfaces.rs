//! The Rust message structs match the `.msg` definitions field for field: same names,
//! same order, same types, for every message and service the node uses. (The Python
//! suite checks the bytes: tests/python/test_interfaces.py.)

use std::collections::BTreeSet;

use developable_sim::wire::introspect::{to_value, Value};
use developable_sim::wire::msgs::*;
use developable_sim::wire::schema::{
    is_primitive, parse_msg, FieldDef, ACTIONS, DEFINITIONS, SERVICES,
};
use developable_sim::wire::sim_interfaces::*;

/// `package/msg/Type` of a Rust struct name (each name is unique among the definitions).
fn ros_type_of(rust_name: &str) -> String {
    let matches: Vec<&str> = DEFINITIONS
        .iter()
        .map(|(n, _)| *n)
        .filter(|n| n.rsplit('/').next() == Some(rust_name))
        .collect();
    assert_eq!(matches.len(), 1, "struct {rust_name}: {matches:?}");
    matches[0].to_string()
}

fn definition_fields(ros_type: &str) -> Vec<FieldDef> {
    let text = DEFINITIONS
        .iter()
        .find(|(n, _)| *n == ros_type)
        .map(|(_, t)| *t)
        .unwrap();
    let pkg = ros_type.split('/').next().unwrap();
    parse_msg(pkg, text)
        .unwrap()
        .into_iter()
        .filter(|f| !f.constant)
        .collect()
}

fn check_fields(
    what: &str,
    fields: &[(&'static str, Value)],
    defs: &[FieldDef],
    seen: &mut BTreeSet<String>,
) {
    let names: Vec<&str> = fields.iter().map(|(n, _)| *n).collect();
    let def_names: Vec<&str> = defs.iter().map(|f| f.name.as_str()).collect();
    assert_eq!(names, def_names, "{what}: field names or order differ");
    for ((name, v), def) in fields.iter().zip(defs) {
        let at = format!("{what}.{name}");
        match def.array {
            None => check_single(&at, &def.base, v, seen),
            Some(None) => match v {
                Value::Seq(items) => {
                    assert!(!items.is_empty(), "{at}: give the sample an element");
                    for item in items {
                        check_single(&at, &def.base, item, seen);
                    }
                }
                other => panic!("{at}: expected a sequence {}[], got {other:?}", def.base),
            },
            Some(Some(n)) => match v {
                Value::Array(items) => {
                    assert_eq!(items.len(), n, "{at}: fixed array size");
                    for item in items {
                        check_single(&at, &def.base, item, seen);
                    }
                }
                other => panic!(
                    "{at}: expected a fixed array {}[{n}], got {other:?}",
                    def.base
                ),
            },
        }
    }
}

fn check_single(at: &str, base: &str, v: &Value, seen: &mut BTreeSet<String>) {
    if is_primitive(base) {
        assert_eq!(v.primitive(), Some(base), "{at}: type differs");
    } else {
        check_struct(v, base, seen);
    }
}

fn check_struct(v: &Value, ros_type: &str, seen: &mut BTreeSet<String>) {
    let Value::Struct(name, fields) = v else {
        panic!("{ros_type}: not a struct: {v:?}");
    };
    assert_eq!(
        ros_type_of(name),
        ros_type,
        "struct {name} stands for {ros_type}"
    );
    seen.insert(ros_type.to_string());
    check_fields(ros_type, fields, &definition_fields(ros_type), seen);
}

/// Samples with every sequence non-empty, so every nested type is visited.
fn marker_array() -> MarkerArray {
    MarkerArray {
        markers: vec![Marker {
            points: vec![Point::default()],
            colors: vec![ColorRGBA::default()],
            uv_coordinates: vec![UVCoordinate::default()],
            texture: CompressedImage {
                data: vec![1],
                ..Default::default()
            },
            mesh_file: MeshFile {
                data: vec![1],
                ..Default::default()
            },
            ..Default::default()
        }],
    }
}

#[test]
fn every_message_struct_matches_its_msg_definition() {
    let mut seen = BTreeSet::new();
    let root = |v: Value, t: &str, seen: &mut BTreeSet<String>| check_struct(&v, t, seen);
    root(
        to_value(&marker_array()).unwrap(),
        MarkerArray::TYPE,
        &mut seen,
    );
    root(
        to_value(&SingularPoints {
            points: vec![SingularPoint::default()],
            ..Default::default()
        })
        .unwrap(),
        SingularPoints::TYPE,
        &mut seen,
    );
    root(
        to_value(&SimStatus {
            handles: vec![HandleStatus::default()],
            ..Default::default()
        })
        .unwrap(),
        SimStatus::TYPE,
        &mut seen,
    );
    root(
        to_value(&PoseStamped::default()).unwrap(),
        PoseStamped::TYPE,
        &mut seen,
    );
    root(to_value(&Clock::default()).unwrap(), Clock::TYPE, &mut seen);
    root(
        to_value(&GraspState::default()).unwrap(),
        GraspState::TYPE,
        &mut seen,
    );
    root(
        to_value(&WrenchStamped::default()).unwrap(),
        WrenchStamped::TYPE,
        &mut seen,
    );
    root(
        to_value(&SimCommand {
            string_array_value: vec!["a".into()],
            ..Default::default()
        })
        .unwrap(),
        SimCommand::TYPE,
        &mut seen,
    );
    root(
        to_value(&TFMessage {
            transforms: vec![TransformStamped::default()],
        })
        .unwrap(),
        TFMessage::TYPE,
        &mut seen,
    );
    root(
        to_value(&SimulatorFeatures {
            features: vec![1],
            spawn_formats: vec!["urdf".into()],
            ..Default::default()
        })
        .unwrap(),
        SimulatorFeatures::TYPE,
        &mut seen,
    );
    root(
        to_value(&SimResult::default()).unwrap(),
        SimResult::TYPE,
        &mut seen,
    );
    root(
        to_value(&SimulationState::default()).unwrap(),
        SimulationState::TYPE,
        &mut seen,
    );
    root(
        to_value(&Image {
            data: vec![1],
            ..Default::default()
        })
        .unwrap(),
        Image::TYPE,
        &mut seen,
    );
    root(
        to_value(&CameraInfo {
            d: vec![0.0],
            ..Default::default()
        })
        .unwrap(),
        CameraInfo::TYPE,
        &mut seen,
    );
    root(
        to_value(&PointCloud2 {
            fields: vec![PointField::default()],
            data: vec![1],
            ..Default::default()
        })
        .unwrap(),
        PointCloud2::TYPE,
        &mut seen,
    );
    root(
        to_value(&StringMsg {
            data: "<robot/>".into(),
        })
        .unwrap(),
        StringMsg::TYPE,
        &mut seen,
    );
    let all: BTreeSet<String> = DEFINITIONS.iter().map(|(n, _)| n.to_string()).collect();
    assert_eq!(seen, all, "every embedded definition has a checked struct");
}

fn service_parts(name: &str) -> (Vec<FieldDef>, Vec<FieldDef>) {
    let text = SERVICES.iter().find(|(n, _)| *n == name).unwrap().1;
    let (req, resp) = text.split_once("---").unwrap();
    let package = name.split('/').next().unwrap();
    let fields = |text: &str| -> Vec<FieldDef> {
        let all = parse_msg(package, text).unwrap();
        all.into_iter().filter(|f| !f.constant).collect()
    };
    (fields(req), fields(resp))
}

fn fields_of(v: Value) -> Vec<(&'static str, Value)> {
    match v {
        Value::Struct(_, f) => f,
        other => panic!("not a struct: {other:?}"),
    }
}

/// An empty IDL struct carries `uint8 structure_needs_at_least_one_member`.
fn or_placeholder(defs: Vec<FieldDef>) -> Vec<FieldDef> {
    if defs.is_empty() {
        vec![FieldDef {
            base: "uint8".into(),
            array: None,
            name: "structure_needs_at_least_one_member".into(),
            constant: false,
        }]
    } else {
        defs
    }
}

#[test]
fn service_structs_match_std_srvs() {
    let mut seen = BTreeSet::new();
    let (req, resp) = service_parts("std_srvs/srv/Trigger");
    check_fields(
        "Trigger_Request",
        &fields_of(to_value(&TriggerRequest::default()).unwrap()),
        &or_placeholder(req),
        &mut seen,
    );
    check_fields(
        "Trigger_Response",
        &fields_of(to_value(&TriggerResponse::default()).unwrap()),
        &resp,
        &mut seen,
    );
    let (req, resp) = service_parts("std_srvs/srv/SetBool");
    check_fields(
        "SetBool_Request",
        &fields_of(to_value(&SetBoolRequest::default()).unwrap()),
        &req,
        &mut seen,
    );
    check_fields(
        "SetBool_Response",
        &fields_of(to_value(&SetBoolResponse::default()).unwrap()),
        &resp,
        &mut seen,
    );
    let (req, resp) = service_parts("std_srvs/srv/Empty");
    check_fields(
        "Empty_Request",
        &fields_of(to_value(&EmptyMessage::default()).unwrap()),
        &or_placeholder(req),
        &mut seen,
    );
    check_fields(
        "Empty_Response",
        &fields_of(to_value(&EmptyMessage::default()).unwrap()),
        &or_placeholder(resp),
        &mut seen,
    );
}

/// Our services (srv/) against their definitions, field for field.
#[test]
fn service_structs_match_our_srv_files() {
    let mut seen = BTreeSet::new();
    let (req, resp) = service_parts("developable_sim/srv/Grasp");
    check_fields(
        "Grasp_Request",
        &fields_of(to_value(&GraspRequest::default()).unwrap()),
        &req,
        &mut seen,
    );
    check_fields(
        "Grasp_Response",
        &fields_of(to_value(&GraspResponse::default()).unwrap()),
        &resp,
        &mut seen,
    );
    let (req, resp) = service_parts("developable_sim/srv/Release");
    check_fields(
        "Release_Request",
        &fields_of(to_value(&ReleaseRequest::default()).unwrap()),
        &req,
        &mut seen,
    );
    check_fields(
        "Release_Response",
        &fields_of(to_value(&ReleaseResponse::default()).unwrap()),
        &resp,
        &mut seen,
    );
}

/// The simulation_interfaces services (vendored release 1.5.1) against their
/// definitions, field for field.
#[test]
fn service_structs_match_simulation_interfaces() {
    let mut seen = BTreeSet::new();
    let mut check = |name: &str, req: Value, resp: Value| {
        let (rq, rs) = service_parts(&format!("simulation_interfaces/srv/{name}"));
        check_fields(name, &fields_of(req), &or_placeholder(rq), &mut seen);
        check_fields(name, &fields_of(resp), &rs, &mut seen);
    };
    let features = GetSimulatorFeaturesResponse {
        features: SimulatorFeatures {
            features: vec![20],
            spawn_formats: vec!["sdf".into()],
            ..Default::default()
        },
    };
    check(
        "GetSimulatorFeatures",
        to_value(&TriggerRequest::default()).unwrap(),
        to_value(&features).unwrap(),
    );
    check(
        "ResetSimulation",
        to_value(&ResetSimulationRequest::default()).unwrap(),
        to_value(&ResultResponse::default()).unwrap(),
    );
    check(
        "StepSimulation",
        to_value(&StepSimulationRequest::default()).unwrap(),
        to_value(&ResultResponse::default()).unwrap(),
    );
    check(
        "GetSimulationState",
        to_value(&TriggerRequest::default()).unwrap(),
        to_value(&GetSimulationStateResponse::default()).unwrap(),
    );
    check(
        "SetSimulationState",
        to_value(&SetSimulationStateRequest::default()).unwrap(),
        to_value(&ResultResponse::default()).unwrap(),
    );
    assert!(seen.contains("simulation_interfaces/msg/SimulatorFeatures"));
}

/// The SimulateSteps action's goal, result and feedback (vendored release 1.5.1)
/// against the three parts of its .action, field for field.
#[test]
fn action_structs_match_simulate_steps() {
    let text = ACTIONS
        .iter()
        .find(|(n, _)| *n == "simulation_interfaces/action/SimulateSteps")
        .unwrap()
        .1;
    let parts: Vec<Vec<FieldDef>> = text
        .split("\n---\n")
        .map(|part| {
            let all = parse_msg("simulation_interfaces", part).unwrap();
            all.into_iter().filter(|f| !f.constant).collect()
        })
        .collect();
    assert_eq!(parts.len(), 3, "goal, result, feedback");
    let mut seen = BTreeSet::new();
    let samples = [
        ("Goal", to_value(&SimulateStepsGoal::default()).unwrap()),
        ("Result", to_value(&SimulateStepsResult::default()).unwrap()),
        (
            "Feedback",
            to_value(&SimulateStepsFeedback::default()).unwrap(),
        ),
    ];
    for ((what, v), defs) in samples.into_iter().zip(&parts) {
        check_fields(what, &fields_of(v), defs, &mut seen);
    }
    assert!(seen.contains("simulation_interfaces/msg/Result"));
    // the checker itself: the feedback's two counters swapped are caught
    let mut swapped = parts[2].clone();
    swapped.swap(0, 1);
    let v = to_value(&SimulateStepsFeedback::default()).unwrap();
    let r = std::panic::catch_unwind(|| {
        check_fields("Feedback", &fields_of(v), &swapped, &mut BTreeSet::new())
    });
    assert!(r.is_err());
}

/// The constants the node answers with are the vendored definitions' values.
#[test]
fn simulation_interfaces_constants_are_the_definitions() {
    let value = |ty: &str, file_text: &str, name: &str| -> u64 {
        let line = file_text
            .lines()
            .map(|l| l.split('#').next().unwrap_or("").trim())
            .find(|l| {
                l.split_whitespace()
                    .nth(1)
                    .map(|n| n.split('=').next().unwrap().trim())
                    == Some(name)
            })
            .unwrap_or_else(|| panic!("{ty}: no constant {name}"));
        line.split('=').nth(1).unwrap().trim().parse().unwrap()
    };
    let def = |n: &str| DEFINITIONS.iter().find(|(d, _)| *d == n).unwrap().1;
    let srv = |n: &str| SERVICES.iter().find(|(d, _)| *d == n).unwrap().1;
    let f = def("simulation_interfaces/msg/SimulatorFeatures");
    for (name, v) in [
        ("SIMULATION_RESET", SimulatorFeatures::SIMULATION_RESET),
        (
            "SIMULATION_RESET_TIME",
            SimulatorFeatures::SIMULATION_RESET_TIME,
        ),
        (
            "SIMULATION_RESET_STATE",
            SimulatorFeatures::SIMULATION_RESET_STATE,
        ),
        (
            "SIMULATION_RESET_SPAWNED",
            SimulatorFeatures::SIMULATION_RESET_SPAWNED,
        ),
        (
            "SIMULATION_STATE_GETTING",
            SimulatorFeatures::SIMULATION_STATE_GETTING,
        ),
        (
            "SIMULATION_STATE_SETTING",
            SimulatorFeatures::SIMULATION_STATE_SETTING,
        ),
        (
            "SIMULATION_STATE_PAUSE",
            SimulatorFeatures::SIMULATION_STATE_PAUSE,
        ),
        (
            "STEP_SIMULATION_SINGLE",
            SimulatorFeatures::STEP_SIMULATION_SINGLE,
        ),
        (
            "STEP_SIMULATION_MULTIPLE",
            SimulatorFeatures::STEP_SIMULATION_MULTIPLE,
        ),
        (
            "STEP_SIMULATION_ACTION",
            SimulatorFeatures::STEP_SIMULATION_ACTION,
        ),
    ] {
        assert_eq!(value("SimulatorFeatures", f, name), u64::from(v), "{name}");
    }
    let s = def("simulation_interfaces/msg/SimulationState");
    for (name, v) in [
        ("STATE_STOPPED", SimulationState::STOPPED),
        ("STATE_PLAYING", SimulationState::PLAYING),
        ("STATE_PAUSED", SimulationState::PAUSED),
        ("STATE_QUITTING", SimulationState::QUITTING),
        ("STATE_NO_WORLD", SimulationState::NO_WORLD),
        ("STATE_LOADING_WORLD", SimulationState::LOADING_WORLD),
    ] {
        assert_eq!(value("SimulationState", s, name), u64::from(v), "{name}");
    }
    let r = def("simulation_interfaces/msg/Result");
    for (name, v) in [
        ("RESULT_FEATURE_UNSUPPORTED", SimResult::FEATURE_UNSUPPORTED),
        ("RESULT_OK", SimResult::OK),
        ("RESULT_NOT_FOUND", SimResult::NOT_FOUND),
        ("RESULT_INCORRECT_STATE", SimResult::INCORRECT_STATE),
        ("RESULT_OPERATION_FAILED", SimResult::OPERATION_FAILED),
    ] {
        assert_eq!(value("Result", r, name), u64::from(v), "{name}");
    }
    let reset = srv("simulation_interfaces/srv/ResetSimulation");
    for (name, v) in [
        ("SCOPE_DEFAULT", ResetSimulationRequest::SCOPE_DEFAULT),
        ("SCOPE_TIME", ResetSimulationRequest::SCOPE_TIME),
        ("SCOPE_STATE", ResetSimulationRequest::SCOPE_STATE),
        ("SCOPE_SPAWNED", ResetSimulationRequest::SCOPE_SPAWNED),
        ("SCOPE_ALL", ResetSimulationRequest::SCOPE_ALL),
    ] {
        assert_eq!(
            value("ResetSimulation", reset, name),
            u64::from(v),
            "{name}"
        );
    }
    let set = srv("simulation_interfaces/srv/SetSimulationState");
    for (name, v) in [
        ("ALREADY_IN_TARGET_STATE", ALREADY_IN_TARGET_STATE),
        ("STATE_TRANSITION_ERROR", STATE_TRANSITION_ERROR),
        ("INCORRECT_TRANSITION", INCORRECT_TRANSITION),
    ] {
        assert_eq!(
            value("SetSimulationState", set, name),
            u64::from(v),
            "{name}"
        );
    }
    // the checker itself: a wrong value would be caught
    assert_ne!(value("SimulationState", s, "STATE_PAUSED"), 1);
}

#[test]
fn a_reordered_struct_would_be_caught() {
    // the checker itself: a struct whose fields are swapped fails
    #[derive(serde::Serialize)]
    struct Point {
        y: f64,
        x: f64,
        z: f64,
    }
    let v = to_value(&Point {
        y: 0.0,
        x: 0.0,
        z: 0.0,
    })
    .unwrap();
    let r = std::panic::catch_unwind(|| {
        check_struct(&v, "geometry_msgs/msg/Point", &mut BTreeSet::new())
    });
    assert!(r.is_err());
}
