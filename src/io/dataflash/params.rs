//! What a DataFlash log says about the vehicle: its parameters (`PARM`) and the first
//! text message (`MSG`, the firmware name), read without a mapping (`mrsysid vehicle
//! --from-log`).

use std::collections::BTreeMap;
use std::path::Path;

use super::super::error::{IoError, display_name};
use super::format::{Kind, text};
use super::messages::MessageReader;

/// The parameters and firmware text of a DataFlash log.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct LogParameters {
    /// Each parameter's first value in the log (ArduPilot logs them all at the start;
    /// later `PARM` messages are changes in flight).
    pub parameters: BTreeMap<String, f64>,
    /// The first `MSG` text (ArduPilot writes its firmware name and version there, e.g.
    /// `ArduCopter V4.5.7 (…)`).
    pub firmware: Option<String>,
}

/// Reads the `PARM` and `MSG` messages of a whole DataFlash log. Errors name the byte
/// offset and message.
pub fn read_parameters(path: &Path) -> Result<LogParameters, IoError> {
    let file = display_name(path);
    let mut r = MessageReader::open(path, &file)?;
    let mut out = LogParameters::default();
    while let Some(offset) = r.next_message()? {
        let Some(f) = r.formats[r.kind as usize].as_ref() else {
            continue;
        };
        match f.name.as_str() {
            "PARM" => {
                let (Some((_, name)), Some((_, value))) = (f.field("Name"), f.field("Value"))
                else {
                    return Err(r.err(offset, "PARM message has no Name or Value field".into()));
                };
                let Kind::Number(s, _) = value.kind else {
                    return Err(r.err(offset, "PARM message: Value is not a number".into()));
                };
                let name = text(&r.body[name.offset..name.offset + name.kind.size()]);
                let v = s.read_le(&r.body[value.offset..]);
                out.parameters.entry(name).or_insert(v);
            }
            "MSG" if out.firmware.is_none() => {
                if let Some((_, m)) = f.field("Message") {
                    out.firmware = Some(text(&r.body[m.offset..m.offset + m.kind.size()]));
                }
            }
            _ => {}
        }
    }
    Ok(out)
}
