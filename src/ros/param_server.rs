//! The node's parameters at run time, as the rcl_interfaces parameter services see them:
//! every parameter of [`DECLARED`] with its current value; the ones in [`RUNTIME`] can
//! be set while the node runs (the node applies them), the others are refused with a
//! reason (they shape what the node built at start-up).

use crate::session::params::{
    set_from_command_line, Declared, ParamType, ParamValue, Params, DECLARED,
};
use crate::wire::param_msgs::{parameter_type as pt, *};

/// Parameters that can change at run time, with the bound their value must keep
/// (lower bound, whether the bound itself is allowed).
const RUNTIME: &[(&str, Option<(f64, bool)>)] = &[
    ("paused", None),
    ("markers_rate", Some((0.0, true))),
    ("accept_empty_frame_id", None),
    ("max_stamp_lead", Some((0.0, false))),
    ("tf_max_lag", Some((0.0, true))),
    ("real_time_factor", Some((0.0, false))),
    ("marker.line_width", Some((0.0, false))),
    ("marker.sphere_diameter", Some((0.0, false))),
];

fn runtime(name: &str) -> Option<Option<(f64, bool)>> {
    RUNTIME.iter().find(|(n, _)| *n == name).map(|(_, b)| *b)
}

/// Every declared parameter and its current value.
pub struct ParamTable {
    entries: Vec<(&'static Declared, ParamValue)>,
}

fn type_code(ty: ParamType) -> u8 {
    match ty {
        ParamType::Bool => pt::BOOL,
        ParamType::Integer => pt::INTEGER,
        ParamType::Double => pt::DOUBLE,
        ParamType::String => pt::STRING,
        ParamType::StringArray => pt::STRING_ARRAY,
    }
}

/// A value as `rcl_interfaces/msg/ParameterValue`.
fn to_msg(v: &ParamValue) -> ParameterValue {
    let mut m = ParameterValue::default();
    match v {
        ParamValue::Bool(b) => (m.type_, m.bool_value) = (pt::BOOL, *b),
        ParamValue::Integer(i) => (m.type_, m.integer_value) = (pt::INTEGER, *i),
        ParamValue::Double(d) => (m.type_, m.double_value) = (pt::DOUBLE, *d),
        ParamValue::String(s) => (m.type_, m.string_value) = (pt::STRING, s.clone()),
        ParamValue::StringArray(s) => {
            (m.type_, m.string_array_value) = (pt::STRING_ARRAY, s.clone())
        }
    }
    m
}

impl ParamTable {
    /// The values set in `params`, the declared defaults for the rest.
    pub fn new(params: &Params) -> ParamTable {
        let entries = DECLARED
            .iter()
            .map(|d| {
                let value = params.get(d.name).cloned().unwrap_or_else(|| {
                    let mut p = Params::default();
                    // the defaults are valid YAML of their type (tested)
                    let _ = set_from_command_line(&mut p, &format!("{}:={}", d.name, d.default));
                    p.get(d.name)
                        .cloned()
                        .unwrap_or(ParamValue::String(String::new()))
                });
                (d, value)
            })
            .collect();
        ParamTable { entries }
    }

    pub fn get(&self, name: &str) -> Option<&ParamValue> {
        self.entries
            .iter()
            .find(|(d, _)| d.name == name)
            .map(|(_, v)| v)
    }

    /// Record the value in effect (the node's own changes, e.g. `~/set_paused`).
    pub fn store(&mut self, name: &str, value: ParamValue) {
        if let Some(e) = self.entries.iter_mut().find(|(d, _)| d.name == name) {
            e.1 = value;
        }
    }

    /// `list_parameters`: names under any of `prefixes` (all with none), at most
    /// `depth` levels below the prefix (0: any depth), and the prefixes of the names.
    pub fn list(&self, req: &ListParametersRequest) -> ListParametersResult {
        let mut out = ListParametersResult::default();
        for (d, _) in &self.entries {
            let under = |prefix: &String| {
                d.name
                    .strip_prefix(&format!("{prefix}."))
                    .map(|rest| rest.split('.').count() as u64)
            };
            let levels = if req.prefixes.is_empty() {
                Some(d.name.split('.').count() as u64)
            } else {
                req.prefixes
                    .iter()
                    .filter_map(under)
                    .min()
                    .or_else(|| req.prefixes.iter().any(|p| p == d.name).then_some(0))
            };
            let Some(levels) = levels else { continue };
            if req.depth != 0 && levels > req.depth {
                continue;
            }
            out.names.push(d.name.to_string());
            if let Some((prefix, _)) = d.name.rsplit_once('.') {
                if !out.prefixes.iter().any(|p| p == prefix) {
                    out.prefixes.push(prefix.to_string());
                }
            }
        }
        out
    }

    /// `get_parameters`: an unknown name gets a value of type NOT_SET.
    pub fn values(&self, names: &[String]) -> Vec<ParameterValue> {
        names
            .iter()
            .map(|n| self.get(n).map(to_msg).unwrap_or_default())
            .collect()
    }

    /// `describe_parameters`: an unknown name gets an empty descriptor of type NOT_SET.
    pub fn describe(&self, names: &[String]) -> Vec<ParameterDescriptor> {
        names
            .iter()
            .map(|n| {
                let Some((d, _)) = self.entries.iter().find(|(d, _)| d.name == n) else {
                    return ParameterDescriptor {
                        name: n.clone(),
                        ..ParameterDescriptor::default()
                    };
                };
                let bound = runtime(d.name).flatten();
                ParameterDescriptor {
                    name: d.name.to_string(),
                    type_: type_code(d.ty),
                    description: d.doc.to_string(),
                    additional_constraints: match bound {
                        Some((lo, true)) => format!(">= {lo}"),
                        Some((lo, false)) => format!("> {lo}"),
                        None => String::new(),
                    },
                    read_only: runtime(d.name).is_none(),
                    floating_point_range: bound
                        .map(|(lo, _)| FloatingPointRange {
                            from_value: lo,
                            to_value: f64::MAX,
                            step: 0.0,
                        })
                        .into_iter()
                        .collect(),
                    ..ParameterDescriptor::default()
                }
            })
            .collect()
    }

    /// `get_parameter_types`.
    pub fn types(&self, names: &[String]) -> Vec<u8> {
        names
            .iter()
            .map(|n| {
                self.entries
                    .iter()
                    .find(|(d, _)| d.name == n)
                    .map_or(pt::NOT_SET, |(d, _)| type_code(d.ty))
            })
            .collect()
    }

    /// Check one `set_parameters` entry: known, changeable at run time, of its type
    /// (an integer is taken for a double), within its bound. Ok: the value to apply
    /// (not stored yet: the caller applies it, then [`ParamTable::store`]s it).
    pub fn check(&self, p: &Parameter) -> Result<ParamValue, String> {
        let Some((d, _)) = self.entries.iter().find(|(d, _)| d.name == p.name) else {
            return Err(format!(
                "parameter `{}` is not declared by this node",
                p.name
            ));
        };
        let Some(bound) = runtime(d.name) else {
            return Err(format!(
                "parameter `{}` is read-only: it shapes what the node built at start-up \
                 (set it in the params file or with -p and restart)",
                d.name
            ));
        };
        let v = &p.value;
        let value = match (d.ty, v.type_) {
            (ParamType::Bool, pt::BOOL) => ParamValue::Bool(v.bool_value),
            (ParamType::Integer, pt::INTEGER) => ParamValue::Integer(v.integer_value),
            (ParamType::Double, pt::DOUBLE) => ParamValue::Double(v.double_value),
            (ParamType::Double, pt::INTEGER) => ParamValue::Double(v.integer_value as f64),
            (ParamType::String, pt::STRING) => ParamValue::String(v.string_value.clone()),
            _ => {
                return Err(format!(
                    "parameter `{}` is of type {} (type code {}), got type code {}",
                    d.name,
                    type_name(d.ty),
                    type_code(d.ty),
                    v.type_
                ))
            }
        };
        if let (ParamValue::Double(x), Some((lo, inclusive))) = (&value, bound) {
            let ok = x.is_finite() && (*x > lo || (inclusive && *x == lo));
            if !ok {
                let op = if inclusive { ">=" } else { ">" };
                return Err(format!("parameter `{}` must be {op} {lo}, got {x}", d.name));
            }
        }
        Ok(value)
    }
}

fn type_name(t: ParamType) -> &'static str {
    match t {
        ParamType::Bool => "bool",
        ParamType::Integer => "integer",
        ParamType::Double => "double",
        ParamType::String => "string",
        ParamType::StringArray => "string array",
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn param(name: &str, value: ParameterValue) -> Parameter {
        Parameter {
            name: name.into(),
            value,
        }
    }
    fn double(x: f64) -> ParameterValue {
        to_msg(&ParamValue::Double(x))
    }

    #[test]
    fn every_default_parses_to_its_declared_type() {
        let t = ParamTable::new(&Params::default());
        for d in DECLARED {
            let v = t.get(d.name).unwrap();
            assert_eq!(to_msg(v).type_, type_code(d.ty), "{}", d.name);
        }
        assert_eq!(t.get("real_time_factor"), Some(&ParamValue::Double(1.0)));
        assert_eq!(t.get("use_sim_time"), Some(&ParamValue::Bool(false)));
        for (name, _) in RUNTIME {
            assert!(DECLARED.iter().any(|d| d.name == *name), "{name}");
        }
    }

    #[test]
    fn lists_describes_and_checks_like_rclcpp() {
        let t = ParamTable::new(&Params::default());
        let all = t.list(&ListParametersRequest::default());
        assert_eq!(all.names.len(), DECLARED.len());
        assert_eq!(all.prefixes, ["marker"]);
        let marker = t.list(&ListParametersRequest {
            prefixes: vec!["marker".into()],
            depth: 1,
        });
        assert_eq!(
            marker.names,
            ["marker.line_width", "marker.sphere_diameter"]
        );
        assert_eq!(t.values(&["nope".into()])[0].type_, pt::NOT_SET);
        assert_eq!(
            t.types(&["paused".into(), "x".into()]),
            [pt::BOOL, pt::NOT_SET]
        );
        let d = &t.describe(&["scene".into(), "markers_rate".into()]);
        assert!(d[0].read_only && !d[1].read_only);
        assert_eq!(d[1].floating_point_range[0].from_value, 0.0);

        // run-time parameters are checked; read-only ones refused with a reason
        assert_eq!(
            t.check(&param("markers_rate", double(5.0))),
            Ok(ParamValue::Double(5.0))
        );
        let int = ParameterValue {
            type_: pt::INTEGER,
            integer_value: 2,
            ..Default::default()
        };
        assert_eq!(
            t.check(&param("markers_rate", int)),
            Ok(ParamValue::Double(2.0))
        );
        let e = t
            .check(&param("scene", to_msg(&ParamValue::String("x".into()))))
            .unwrap_err();
        assert!(e.contains("read-only"), "{e}");
        let e = t.check(&param("max_stamp_lead", double(0.0))).unwrap_err();
        assert!(e.contains("must be > 0"), "{e}");
        let e = t.check(&param("paused", double(1.0))).unwrap_err();
        assert!(e.contains("type bool"), "{e}");
        assert!(t.check(&param("markers_rate", double(f64::NAN))).is_err());
        assert!(t
            .check(&param("bogus", double(1.0)))
            .unwrap_err()
            .contains("not declared"));
    }
}
