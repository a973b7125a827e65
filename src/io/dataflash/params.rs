//! What a DataFlash log says about the vehicle: its parameters (`PARM`) and its firmware
//! name (the first `MSG` text naming an ArduPilot firmware), read without a mapping
//! (`mrsysid vehicle --from-log`).

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
    /// The first `MSG` text that names the firmware, e.g. `ArduCopter V4.5.7 (…)`
    /// (ArduPilot writes it when the log starts; a log started at arming may open with
    /// other texts, `Arming motors`, and may lack it).
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
                    let message = text(&r.body[m.offset..m.offset + m.kind.size()]);
                    out.firmware = names_firmware(&message).then_some(message);
                }
            }
            _ => {}
        }
    }
    Ok(out)
}

/// True for a `MSG` text naming an ArduPilot firmware and its version (`ArduCopter
/// V4.4.4 (865cffa5)`, `ArduPlane V4.5.0`, `Blimp V4.5.1`), not a status text.
fn names_firmware(message: &str) -> bool {
    let mut words = message.split_whitespace();
    let (Some(name), Some(version)) = (words.next(), words.next()) else {
        return false;
    };
    let firmware = name.starts_with("Ardu") || ["Blimp", "AntennaTracker"].contains(&name);
    let numbered = version
        .strip_prefix('V')
        .is_some_and(|v| v.starts_with(|c: char| c.is_ascii_digit()));
    firmware && numbered
}

#[cfg(test)]
mod tests {
    use super::names_firmware;

    #[test]
    fn a_firmware_text_is_told_from_status_texts() {
        for firmware in [
            "ArduCopter V4.4.4 (865cffa5)",
            "ArduPlane V4.5.0",
            "Blimp V4.5.1",
        ] {
            assert!(names_firmware(firmware), "{firmware}");
        }
        for status in [
            "Arming motors",
            "ArduPilot Ready",
            "EKF3 IMU0 initialised",
            "",
        ] {
            assert!(!names_firmware(status), "{status}");
        }
    }
}
