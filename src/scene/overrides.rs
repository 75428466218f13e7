//! `--set dotted.key=value`: override any scene key by its path; the value is YAML.

use super::SceneError;

/// Apply `spec` (`a.b.c=value`) to a YAML tree. Missing maps on the path are created;
/// list elements are addressed by index (`handles.0.point=[1, 0]`).
pub fn apply_override(root: &mut serde_yaml::Value, spec: &str) -> Result<(), SceneError> {
    let err = |message: String| SceneError::Override {
        spec: spec.to_string(),
        message,
    };
    let (path, raw) = spec
        .split_once('=')
        .ok_or_else(|| err("expected KEY=VALUE, e.g. ribbon.segments=200".into()))?;
    let path = path.trim();
    if path.is_empty() || path.split('.').any(str::is_empty) {
        return Err(err("empty key".into()));
    }
    let value: serde_yaml::Value =
        serde_yaml::from_str(raw).map_err(|e| err(format!("value is not valid YAML: {e}")))?;
    let mut node = root;
    let parts: Vec<&str> = path.split('.').collect();
    for (i, part) in parts.iter().enumerate() {
        let last = i + 1 == parts.len();
        node = match node {
            serde_yaml::Value::Mapping(map) => {
                let key = serde_yaml::Value::String((*part).to_string());
                if last {
                    map.insert(key, value);
                    return Ok(());
                }
                map.entry(key)
                    .or_insert_with(|| serde_yaml::Value::Mapping(Default::default()))
            }
            serde_yaml::Value::Sequence(seq) => {
                let index: usize = part
                    .parse()
                    .map_err(|_| err(format!("`{part}` must be a list index here")))?;
                let len = seq.len();
                let slot = seq.get_mut(index).ok_or_else(|| {
                    err(format!(
                        "index {index} is out of range (list has {len} entries)"
                    ))
                })?;
                if last {
                    *slot = value;
                    return Ok(());
                }
                slot
            }
            _ => {
                let prefix = parts[..i].join(".");
                return Err(err(format!("`{prefix}` is not a map or list")));
            }
        };
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn overrides_nested_keys_lists_and_creates_maps() {
        let mut v: serde_yaml::Value =
            serde_yaml::from_str("ribbon: {segments: 50}\nhandles: [{name: a}]").unwrap();
        apply_override(&mut v, "ribbon.segments=200").unwrap();
        apply_override(&mut v, "solver.kind=lbfgsb").unwrap();
        apply_override(&mut v, "handles.0.name=b").unwrap();
        assert_eq!(v["ribbon"]["segments"], serde_yaml::Value::from(200));
        assert_eq!(v["solver"]["kind"], serde_yaml::Value::from("lbfgsb"));
        assert_eq!(v["handles"][0]["name"], serde_yaml::Value::from("b"));
        assert!(apply_override(&mut v, "ribbon.segments").is_err());
        assert!(apply_override(&mut v, "handles.3.name=x").is_err());
        assert!(apply_override(&mut v, "ribbon.segments.x=1").is_err());
    }
}
