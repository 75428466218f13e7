//! Python overrides (`{"ribbon.segments": 200}`) as the scene loader's `--set` specs
//! (`ribbon.segments=200`): the value written as YAML, so a Python run and
//! `developable_sim run --set` of the same overrides load the same scene.

use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};

/// `KEY=VALUE` specs from a mapping of key paths to values, in the mapping's order (a
/// dict keeps insertion order, so later keys win as later `--set`s do).
pub fn specs(overrides: Option<&Bound<'_, PyAny>>) -> PyResult<Vec<String>> {
    let Some(overrides) = overrides else {
        return Ok(Vec::new());
    };
    if overrides.is_none() {
        return Ok(Vec::new());
    }
    let dict = overrides.cast::<PyDict>().map_err(|_| {
        PyTypeError::new_err(
            "overrides must be a dict of key paths to values, e.g. {\"ribbon.segments\": 200}",
        )
    })?;
    let mut out = Vec::with_capacity(dict.len());
    for (key, value) in dict.iter() {
        let key: String = key
            .extract()
            .map_err(|_| PyTypeError::new_err("override keys must be strings (key paths)"))?;
        out.push(format!("{key}={}", yaml(&value, true)?));
    }
    Ok(out)
}

/// `value` as YAML text. A top-level string is written as it is (parsed as YAML, like
/// `--set`: `"full"` is the string full, `"[1, 2]"` a list); strings inside lists and
/// dicts are quoted. Floats in Rust's shortest round-trip form (bit-exact through the
/// YAML parser).
fn yaml(value: &Bound<'_, PyAny>, top: bool) -> PyResult<String> {
    if value.is_none() {
        return Ok("null".into());
    }
    if let Ok(b) = value.cast::<PyBool>() {
        return Ok(if b.is_true() { "true" } else { "false" }.into());
    }
    if value.is_instance_of::<PyInt>() {
        return Ok(value.str()?.to_string());
    }
    if value.is_instance_of::<PyFloat>() {
        return Ok(float(value.extract()?));
    }
    // NumPy scalars: booleans (`numpy.bool`, which also has `__index__`), integers
    // (`__index__`), floats (`__float__` only)
    let type_name = value.get_type().name()?.to_string();
    if !is_sequence(value) && (type_name == "bool" || type_name == "bool_") {
        return Ok(if value.is_truthy()? { "true" } else { "false" }.into());
    }
    if !is_sequence(value) && value.hasattr("__index__")? {
        return Ok(value.call_method0("__index__")?.str()?.to_string());
    }
    if !is_sequence(value) && value.hasattr("__float__")? {
        return Ok(float(value.extract()?));
    }
    if let Ok(s) = value.cast::<PyString>() {
        let s: String = s.extract()?;
        return Ok(if top { s } else { quoted(&s) });
    }
    if let Ok(d) = value.cast::<PyDict>() {
        let mut parts = Vec::with_capacity(d.len());
        for (k, v) in d.iter() {
            let k: String = k.extract()?;
            parts.push(format!("{}: {}", quoted(&k), yaml(&v, false)?));
        }
        return Ok(format!("{{{}}}", parts.join(", ")));
    }
    if is_sequence(value) {
        let mut parts = Vec::new();
        for item in value.try_iter()? {
            parts.push(yaml(&item?, false)?);
        }
        return Ok(format!("[{}]", parts.join(", ")));
    }
    Err(PyTypeError::new_err(format!(
        "override value {} of type {} cannot be written as YAML (use bool, int, float, str, list, tuple, dict or a NumPy array)",
        value.repr()?,
        value.get_type().name()?
    )))
}

/// Lists, tuples and anything else iterable that is not a string or a mapping (NumPy
/// arrays).
fn is_sequence(value: &Bound<'_, PyAny>) -> bool {
    value.is_instance_of::<PyList>()
        || value.is_instance_of::<PyTuple>()
        || (!value.is_instance_of::<PyString>()
            && !value.is_instance_of::<PyDict>()
            && value.hasattr("__len__").unwrap_or(false)
            && value.hasattr("__iter__").unwrap_or(false))
}

/// A float as YAML: shortest round-trip digits, `.inf`, `-.inf`, `.nan`.
pub fn float(x: f64) -> String {
    if x.is_nan() {
        ".nan".into()
    } else if x.is_infinite() {
        if x > 0.0 { ".inf" } else { "-.inf" }.into()
    } else {
        // `{:?}` keeps a decimal point or exponent (1.0, 1e-6): always a float in YAML
        format!("{x:?}")
    }
}

/// A double-quoted YAML string (JSON escaping is valid YAML).
fn quoted(s: &str) -> String {
    let mut out = String::with_capacity(s.len() + 2);
    out.push('"');
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            '\t' => out.push_str("\\t"),
            c if (c as u32) < 0x20 => out.push_str(&format!("\\u{:04x}", c as u32)),
            c => out.push(c),
        }
    }
    out.push('"');
    out
}
