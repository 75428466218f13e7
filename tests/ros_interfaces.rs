//! The Rust message structs match the `.msg` definitions field for field: same names,
//! same order, same types, for every message and service the node uses. (The Python
//! suite checks the bytes: tests/python/test_interfaces.py.)

use std::collections::BTreeSet;

use developable_sim::wire::introspect::{to_value, Value};
use developable_sim::wire::msgs::*;
use developable_sim::wire::schema::{is_primitive, parse_msg, FieldDef, DEFINITIONS, SERVICES};

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
    (
        parse_msg(package, req).unwrap(),
        parse_msg(package, resp).unwrap(),
    )
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
