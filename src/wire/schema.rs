//! Message definitions as text: the `.msg` files embedded in the binary, a small `.msg`
//! parser, and the `ros2msg` schema rosbag2 writes into MCAP files (the root definition,
//! then every dependency once, depth first, each after a line of 80 `=` and
//! `MSG: pkg/Type`).

/// `(package/msg/Type, definition)` of every message the node uses. Ours are the
/// repository's `msg/*.msg` verbatim; the standard ones are in `src/wire/interfaces/`.
pub const DEFINITIONS: &[(&str, &str)] = &[
    (
        "developable_sim/msg/SimStatus",
        include_str!("../../msg/SimStatus.msg"),
    ),
    (
        "developable_sim/msg/SimCommand",
        include_str!("../../msg/SimCommand.msg"),
    ),
    (
        "developable_sim/msg/GraspState",
        include_str!("../../msg/GraspState.msg"),
    ),
    (
        "geometry_msgs/msg/Wrench",
        include_str!("interfaces/geometry_msgs/Wrench.msg"),
    ),
    (
        "geometry_msgs/msg/WrenchStamped",
        include_str!("interfaces/geometry_msgs/WrenchStamped.msg"),
    ),
    (
        "developable_sim/msg/HandleStatus",
        include_str!("../../msg/HandleStatus.msg"),
    ),
    (
        "developable_sim/msg/SingularPoints",
        include_str!("../../msg/SingularPoints.msg"),
    ),
    (
        "developable_sim/msg/SingularPoint",
        include_str!("../../msg/SingularPoint.msg"),
    ),
    (
        "builtin_interfaces/msg/Time",
        include_str!("interfaces/builtin_interfaces/Time.msg"),
    ),
    (
        "builtin_interfaces/msg/Duration",
        include_str!("interfaces/builtin_interfaces/Duration.msg"),
    ),
    (
        "std_msgs/msg/Header",
        include_str!("interfaces/std_msgs/Header.msg"),
    ),
    (
        "std_msgs/msg/ColorRGBA",
        include_str!("interfaces/std_msgs/ColorRGBA.msg"),
    ),
    (
        "std_msgs/msg/String",
        include_str!("interfaces/std_msgs/String.msg"),
    ),
    (
        "geometry_msgs/msg/Point",
        include_str!("interfaces/geometry_msgs/Point.msg"),
    ),
    (
        "geometry_msgs/msg/Vector3",
        include_str!("interfaces/geometry_msgs/Vector3.msg"),
    ),
    (
        "geometry_msgs/msg/Quaternion",
        include_str!("interfaces/geometry_msgs/Quaternion.msg"),
    ),
    (
        "geometry_msgs/msg/Pose",
        include_str!("interfaces/geometry_msgs/Pose.msg"),
    ),
    (
        "geometry_msgs/msg/PoseStamped",
        include_str!("interfaces/geometry_msgs/PoseStamped.msg"),
    ),
    (
        "sensor_msgs/msg/CompressedImage",
        include_str!("interfaces/sensor_msgs/CompressedImage.msg"),
    ),
    (
        "sensor_msgs/msg/Image",
        include_str!("interfaces/sensor_msgs/Image.msg"),
    ),
    (
        "sensor_msgs/msg/CameraInfo",
        include_str!("interfaces/sensor_msgs/CameraInfo.msg"),
    ),
    (
        "sensor_msgs/msg/RegionOfInterest",
        include_str!("interfaces/sensor_msgs/RegionOfInterest.msg"),
    ),
    (
        "sensor_msgs/msg/PointCloud2",
        include_str!("interfaces/sensor_msgs/PointCloud2.msg"),
    ),
    (
        "sensor_msgs/msg/PointField",
        include_str!("interfaces/sensor_msgs/PointField.msg"),
    ),
    (
        "visualization_msgs/msg/UVCoordinate",
        include_str!("interfaces/visualization_msgs/UVCoordinate.msg"),
    ),
    (
        "visualization_msgs/msg/MeshFile",
        include_str!("interfaces/visualization_msgs/MeshFile.msg"),
    ),
    (
        "visualization_msgs/msg/Marker",
        include_str!("interfaces/visualization_msgs/Marker.msg"),
    ),
    (
        "visualization_msgs/msg/MarkerArray",
        include_str!("interfaces/visualization_msgs/MarkerArray.msg"),
    ),
    (
        "geometry_msgs/msg/Transform",
        include_str!("interfaces/geometry_msgs/Transform.msg"),
    ),
    (
        "geometry_msgs/msg/TransformStamped",
        include_str!("interfaces/geometry_msgs/TransformStamped.msg"),
    ),
    (
        "tf2_msgs/msg/TFMessage",
        include_str!("interfaces/tf2_msgs/TFMessage.msg"),
    ),
    (
        "rosgraph_msgs/msg/Clock",
        include_str!("interfaces/rosgraph_msgs/Clock.msg"),
    ),
    (
        "simulation_interfaces/msg/Result",
        include_str!("interfaces/simulation_interfaces/Result.msg"),
    ),
    (
        "simulation_interfaces/msg/SimulationState",
        include_str!("interfaces/simulation_interfaces/SimulationState.msg"),
    ),
    (
        "simulation_interfaces/msg/SimulatorFeatures",
        include_str!("interfaces/simulation_interfaces/SimulatorFeatures.msg"),
    ),
];

/// `(package/srv/Type, definition)` of the services the node serves.
pub const SERVICES: &[(&str, &str)] = &[
    (
        "developable_sim/srv/Grasp",
        include_str!("../../srv/Grasp.srv"),
    ),
    (
        "developable_sim/srv/Release",
        include_str!("../../srv/Release.srv"),
    ),
    (
        "std_srvs/srv/Trigger",
        include_str!("interfaces/std_srvs/Trigger.srv"),
    ),
    (
        "std_srvs/srv/SetBool",
        include_str!("interfaces/std_srvs/SetBool.srv"),
    ),
    (
        "std_srvs/srv/Empty",
        include_str!("interfaces/std_srvs/Empty.srv"),
    ),
    (
        "simulation_interfaces/srv/GetSimulatorFeatures",
        include_str!("interfaces/simulation_interfaces/GetSimulatorFeatures.srv"),
    ),
    (
        "simulation_interfaces/srv/ResetSimulation",
        include_str!("interfaces/simulation_interfaces/ResetSimulation.srv"),
    ),
    (
        "simulation_interfaces/srv/StepSimulation",
        include_str!("interfaces/simulation_interfaces/StepSimulation.srv"),
    ),
    (
        "simulation_interfaces/srv/GetSimulationState",
        include_str!("interfaces/simulation_interfaces/GetSimulationState.srv"),
    ),
    (
        "simulation_interfaces/srv/SetSimulationState",
        include_str!("interfaces/simulation_interfaces/SetSimulationState.srv"),
    ),
];

/// `(package/action/Type, definition)` of the actions the node serves.
pub const ACTIONS: &[(&str, &str)] = &[(
    "simulation_interfaces/action/SimulateSteps",
    include_str!("interfaces/simulation_interfaces/SimulateSteps.action"),
)];

/// The definition text of `package/msg/Type`.
pub fn definition(type_name: &str) -> Option<&'static str> {
    DEFINITIONS
        .iter()
        .find(|(n, _)| *n == type_name)
        .map(|(_, d)| *d)
}

/// One field (or constant) of a `.msg` definition.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct FieldDef {
    /// Element type: a primitive (`float64`, `string`, ...) or `package/msg/Type`.
    pub base: String,
    /// `None`: a single value; `Some(None)`: unbounded sequence `T[]`; `Some(Some(n))`:
    /// fixed array `T[n]` (bounded sequences `T[<=n]` are reported as `T[]`).
    pub array: Option<Option<usize>>,
    pub name: String,
    /// Constants (`TYPE NAME=VALUE`) have `constant: true`; they carry no data.
    pub constant: bool,
}

const PRIMITIVES: &[&str] = &[
    "bool", "byte", "char", "float32", "float64", "int8", "uint8", "int16", "uint16", "int32",
    "uint32", "int64", "uint64", "string", "wstring",
];

/// True for a primitive `.msg` type (`string<=N` included).
pub fn is_primitive(base: &str) -> bool {
    let b = base.split("<=").next().unwrap_or(base);
    PRIMITIVES.contains(&b)
}

/// Parse a `.msg` text of package `package`: fields and constants in order. Comments
/// and blank lines are skipped; type names are normalized to `package/msg/Type`.
pub fn parse_msg(package: &str, text: &str) -> Result<Vec<FieldDef>, String> {
    let mut out = Vec::new();
    for (i, raw) in text.lines().enumerate() {
        let line = match raw.find('#') {
            // a string constant may contain '#'; no definition here has one
            Some(p) => &raw[..p],
            None => raw,
        }
        .trim();
        if line.is_empty() {
            continue;
        }
        if line == "---" {
            return Err(format!("line {}: `---` in a message definition", i + 1));
        }
        let (ty, rest) = line
            .split_once(char::is_whitespace)
            .ok_or_else(|| format!("line {}: expected `TYPE NAME`: {raw}", i + 1))?;
        let rest = rest.trim();
        let (name, constant) = match rest.split_once('=') {
            Some((n, _)) => (n.trim(), true),
            None => (rest.split_whitespace().next().unwrap_or(""), false),
        };
        if name.is_empty() {
            return Err(format!("line {}: missing field name: {raw}", i + 1));
        }
        let (base, array) = match ty.find('[') {
            Some(p) => {
                let inner = ty[p + 1..]
                    .strip_suffix(']')
                    .ok_or_else(|| format!("line {}: bad array type `{ty}`", i + 1))?;
                let array = if inner.is_empty() || inner.starts_with("<=") {
                    None
                } else {
                    Some(
                        inner
                            .parse::<usize>()
                            .map_err(|_| format!("line {}: bad array size `{ty}`", i + 1))?,
                    )
                };
                (&ty[..p], Some(array))
            }
            None => (ty, None),
        };
        let base = if is_primitive(base) {
            base.to_string()
        } else {
            normalize_type(package, base)
        };
        out.push(FieldDef {
            base,
            array,
            name: name.to_string(),
            constant,
        });
    }
    Ok(out)
}

/// `Type` -> `package/msg/Type`, `pkg/Type` -> `pkg/msg/Type`, `pkg/msg/Type` unchanged.
fn normalize_type(package: &str, name: &str) -> String {
    let parts: Vec<&str> = name.split('/').collect();
    match parts.as_slice() {
        [t] => format!("{package}/msg/{t}"),
        [p, t] => format!("{p}/msg/{t}"),
        _ => name.to_string(),
    }
}

/// `package/msg/Type` -> `package/Type` (the form after `MSG:` in a schema).
fn short_name(type_name: &str) -> String {
    type_name.replacen("/msg/", "/", 1)
}

fn package_of(type_name: &str) -> &str {
    type_name.split('/').next().unwrap_or("")
}

/// The `ros2msg` schema of `type_name`: its definition, then each dependency once,
/// depth first in field order, each preceded by 80 `=` and `MSG: pkg/Type`.
///
/// Panics if a definition is missing from [`DEFINITIONS`] (a build-time table; the
/// unit tests cover every type).
pub fn ros2msg_schema(type_name: &str) -> String {
    let mut out = with_newline(definition(type_name).unwrap_or_else(|| {
        panic!("no embedded definition for {type_name}");
    }));
    let mut seen = vec![type_name.to_string()];
    append_dependencies(type_name, &mut seen, &mut out);
    out
}

fn with_newline(text: &str) -> String {
    let mut s = text.to_string();
    if !s.ends_with('\n') {
        s.push('\n');
    }
    s
}

fn append_dependencies(type_name: &str, seen: &mut Vec<String>, out: &mut String) {
    let text = definition(type_name).unwrap_or("");
    let fields = parse_msg(package_of(type_name), text).unwrap_or_default();
    for f in fields {
        if f.constant || is_primitive(&f.base) || seen.contains(&f.base) {
            continue;
        }
        seen.push(f.base.clone());
        out.push_str(&"=".repeat(80));
        out.push('\n');
        out.push_str("MSG: ");
        out.push_str(&short_name(&f.base));
        out.push('\n');
        out.push_str(&with_newline(definition(&f.base).unwrap_or_else(|| {
            panic!("no embedded definition for {}", f.base);
        })));
        append_dependencies(&f.base.clone(), seen, out);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_definition_parses_and_its_dependencies_are_embedded() {
        for (name, text) in DEFINITIONS {
            let fields = parse_msg(package_of(name), text).unwrap();
            assert!(!fields.is_empty(), "{name}");
            for f in fields {
                assert!(
                    f.constant || is_primitive(&f.base) || definition(&f.base).is_some(),
                    "{name}: {} has no embedded definition",
                    f.base
                );
            }
            let schema = ros2msg_schema(name);
            assert!(schema.starts_with(&with_newline(text)));
        }
    }

    #[test]
    fn schema_lists_each_dependency_once_depth_first() {
        let s = ros2msg_schema("geometry_msgs/msg/PoseStamped");
        let msg_lines: Vec<&str> = s.lines().filter(|l| l.starts_with("MSG: ")).collect();
        assert_eq!(
            msg_lines,
            [
                "MSG: std_msgs/Header",
                "MSG: builtin_interfaces/Time",
                "MSG: geometry_msgs/Pose",
                "MSG: geometry_msgs/Point",
                "MSG: geometry_msgs/Quaternion"
            ]
        );
        let sep = "=".repeat(80);
        assert_eq!(s.lines().filter(|l| *l == sep).count(), 5);
        let m = ros2msg_schema("visualization_msgs/msg/MarkerArray");
        assert_eq!(m.matches("MSG: std_msgs/Header\n").count(), 1);
        assert!(m.contains("MSG: visualization_msgs/MeshFile\n"));
    }

    #[test]
    fn parser_reads_arrays_constants_and_comments() {
        let f = parse_msg(
            "p",
            "# c\nint32 A=1 # x\nfloat64[2] m\nFoo[] foos\nq/Bar b\nstring<=5 s\nuint8[<=3] u\n",
        )
        .unwrap();
        assert_eq!(f.len(), 6);
        assert!(f[0].constant && f[0].name == "A");
        assert_eq!(f[1].array, Some(Some(2)));
        assert_eq!((f[2].base.as_str(), f[2].array), ("p/msg/Foo", Some(None)));
        assert_eq!(f[3].base, "q/msg/Bar");
        assert_eq!(f[4].base, "string<=5");
        assert_eq!(f[5].array, Some(None));
        assert!(parse_msg("p", "float64\n").is_err());
    }
}
