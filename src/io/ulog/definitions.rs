//! What a ULog file says about itself before its data: the parameters (`P`) and string
//! info (`I`) of the definitions section, read without a mapping (`mrsysid vehicle
//! --from-ulog`).

use std::collections::BTreeMap;
use std::path::Path;

use super::super::error::{IoError, display_name};
use super::messages::MessageReader;

/// The key/value of an `I`, `P` or `M` message: `(type, name, value bytes)`.
fn key_value(payload: &[u8], skip: usize) -> Option<(&str, &str, &[u8])> {
    let len = *payload.get(skip)? as usize;
    let key = payload.get(skip + 1..skip + 1 + len)?;
    let key = std::str::from_utf8(key).ok()?;
    let (ty, name) = key.split_once(' ')?;
    Some((ty, name, &payload[skip + 1 + len..]))
}

/// A parameter value of a `P` message (`int32_t` or `float`) as a number.
fn param_value(ty: &str, v: &[u8]) -> Option<f64> {
    let b: [u8; 4] = v.get(..4)?.try_into().ok()?;
    match ty {
        "int32_t" => Some(i32::from_le_bytes(b) as f64),
        "float" => Some(f32::from_le_bytes(b) as f64),
        _ => None,
    }
}

/// What a ULog file says about itself: the definitions section's parameters and info.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct LogDefinitions {
    /// Logging start time from the header, µs.
    pub start_us: u64,
    /// Initial parameter values by name (`int32_t` and `float` parameters).
    pub parameters: BTreeMap<String, f64>,
    /// String-valued info messages (`I`, `char[n]` values) by key name, e.g. `sys_name`.
    pub info: BTreeMap<String, String>,
}

/// Reads the header and definitions section of a ULog file (stops at the first
/// subscription or data message): parameters and string info. Errors name the byte
/// offset and message.
pub fn read_definitions(path: &Path) -> Result<LogDefinitions, IoError> {
    let file = display_name(path);
    let (mut r, start_us) = MessageReader::open(path, &file)?;
    let mut defs = LogDefinitions {
        start_us,
        ..LogDefinitions::default()
    };
    let mut first = true;
    while let Some(offset) = r.next_message()? {
        let kind = r.kind;
        if std::mem::take(&mut first) && kind == b'B' {
            r.flag_bits(offset)?;
            continue;
        }
        match kind {
            b'A' | b'D' => break,
            b'P' => {
                let (ty, name, v) = key_value(&r.buf, 0)
                    .ok_or_else(|| r.err(offset, "malformed 'P' parameter message".into()))?;
                if let Some(x) = param_value(ty, v) {
                    defs.parameters.insert(name.to_string(), x);
                }
            }
            b'I' => {
                let (ty, name, v) = key_value(&r.buf, 0)
                    .ok_or_else(|| r.err(offset, "malformed 'I' info message".into()))?;
                if ty.starts_with("char[") {
                    defs.info
                        .insert(name.to_string(), String::from_utf8_lossy(v).into_owned());
                }
            }
            _ => {}
        }
    }
    Ok(defs)
}
