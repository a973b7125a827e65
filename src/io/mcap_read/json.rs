//! Field paths into a decoded message (a JSON value; CDR is decoded to one): the value
//! at a path, what the message has where a path leaves it, and a time as a number.

use serde_json::Value;

use super::super::field_path::{self, FieldPathError, Step, Style};

/// Parses a JSON field path `a.b[2].c`.
pub(super) fn parse_path(path: &str) -> Result<Vec<Step>, FieldPathError> {
    field_path::parse(path, Style::Json)
}

pub(super) fn lookup<'v>(value: &'v Value, steps: &[Step]) -> Option<&'v Value> {
    steps.iter().try_fold(value, |v, s| match s {
        Step::Key(k) => v.get(k),
        Step::Index(i) => v.get(*i),
    })
}

/// What `value` has where the path `steps` leaves it, e.g. `gyro has 3 elements`, `the
/// message has fields f, gyro, vel`; empty when the path is in it.
pub(super) fn what_is_there(value: &Value, steps: &[Step]) -> String {
    let mut v = value;
    let mut path = String::new();
    for step in steps {
        let next = match step {
            Step::Key(k) => v.get(k),
            Step::Index(i) => v.get(*i),
        };
        let Some(next) = next else {
            let here = if path.is_empty() {
                "the message".to_string()
            } else {
                path
            };
            return match v {
                Value::Object(map) => {
                    let keys: Vec<&str> = map.keys().map(String::as_str).collect();
                    format!("{here} has fields {}", keys.join(", "))
                }
                Value::Array(items) => format!("{here} has {} elements", items.len()),
                other => format!("{here} is {other}, not an object or array"),
            };
        };
        match step {
            Step::Key(k) if path.is_empty() => path = k.clone(),
            Step::Key(k) => path = format!("{path}.{k}"),
            Step::Index(i) => path = format!("{path}[{i}]"),
        }
        v = next;
    }
    String::new()
}

/// A number, or a ROS time `{sec, nanosec}` / `{secs, nsecs}` in seconds.
pub(super) fn as_number(v: &Value) -> Option<f64> {
    if let Some(x) = v.as_f64() {
        return Some(x);
    }
    let sec = v.get("sec").or_else(|| v.get("secs"))?.as_f64()?;
    let ns = v.get("nanosec").or_else(|| v.get("nsecs"))?.as_f64()?;
    Some(sec + ns * 1e-9)
}
