//! DataFlash message formats: the format characters of an `FMT` message, the layout of
//! the message it defines (each field's byte offset, type and implied scale), and the
//! units and multipliers that `FMTU`, `UNIT` and `MULT` messages attach to the fields.

use std::collections::HashMap;

use super::super::scalar::Scalar;
use super::{FMT_BODY_BYTES, HEADER_BYTES};

/// What one format character stores.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Kind {
    /// A number of this type, times the scale the character implies (`c`: int16 × 100
    /// stored, so 0.01; `L`: latitude/longitude in 1e-7 degrees).
    Number(Scalar, f64),
    /// Text or an array of this many bytes (`n`, `N`, `Z`, `a`): not a number.
    Bytes(usize),
}

impl Kind {
    /// Bytes the field takes.
    pub fn size(self) -> usize {
        match self {
            Self::Number(s, _) => s.size(),
            Self::Bytes(n) => n,
        }
    }
}

/// The field kind of format character `c`, `None` when unknown.
pub fn kind_of(c: u8) -> Option<Kind> {
    use Scalar::*;
    let n = |s, k| Some(Kind::Number(s, k));
    match c {
        b'b' => n(I8, 1.0),
        b'B' | b'M' => n(U8, 1.0),
        b'h' => n(I16, 1.0),
        b'H' => n(U16, 1.0),
        b'i' => n(I32, 1.0),
        b'I' => n(U32, 1.0),
        b'f' => n(F32, 1.0),
        b'd' => n(F64, 1.0),
        b'q' => n(I64, 1.0),
        b'Q' => n(U64, 1.0),
        b'c' => n(I16, 0.01),
        b'C' => n(U16, 0.01),
        b'e' => n(I32, 0.01),
        b'E' => n(U32, 0.01),
        b'L' => n(I32, 1e-7),
        b'n' => Some(Kind::Bytes(4)),
        b'N' => Some(Kind::Bytes(16)),
        b'Z' | b'a' => Some(Kind::Bytes(64)),
        _ => None,
    }
}

/// One field of a message format.
#[derive(Debug, Clone, PartialEq)]
pub struct Field {
    /// Column label (`TimeUS`, `GyrX`).
    pub label: String,
    /// Byte offset in the message body (after the 3 header bytes).
    pub offset: usize,
    /// Type and implied scale.
    pub kind: Kind,
    /// Format character.
    pub code: u8,
}

/// A message format defined by an `FMT` message.
#[derive(Debug, Clone, PartialEq)]
pub struct Format {
    /// Message name (`IMU`, `ESC`).
    pub name: String,
    /// Whole message length, header included, bytes.
    pub length: usize,
    pub fields: Vec<Field>,
    /// Unit and multiplier characters per field, from the type's `FMTU` message.
    pub units: Option<(Vec<u8>, Vec<u8>)>,
}

/// NUL-padded text of a fixed-size string field.
pub fn text(b: &[u8]) -> String {
    let end = b.iter().position(|&c| c == 0).unwrap_or(b.len());
    String::from_utf8_lossy(&b[..end]).into_owned()
}

/// Why the body of an `FMT` message does not define a format.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FmtError {
    /// A body shorter than an `FMT` body.
    #[error("FMT body has {bytes} bytes, {} expected", FMT_BODY_BYTES)]
    Short {
        /// Bytes in the body.
        bytes: usize,
    },
    /// A message name that is empty or not printable ASCII.
    #[error("FMT of type {ty}: name {name:?} is not printable ASCII")]
    Name {
        /// The type defined.
        ty: u8,
        /// The name.
        name: String,
    },
    /// Not one label per format character.
    #[error("FMT of {name} (type {ty}): {codes} format characters but {labels} labels")]
    LabelCount {
        /// The message name.
        name: String,
        /// The type defined.
        ty: u8,
        /// Format characters.
        codes: usize,
        /// Labels.
        labels: usize,
    },
    /// A format character the reader does not know.
    #[error("FMT of {name} (type {ty}): unknown format character {code:?} of field {label:?}")]
    UnknownCode {
        /// The message name.
        name: String,
        /// The type defined.
        ty: u8,
        /// The character.
        code: char,
        /// The field's label.
        label: String,
    },
    /// A length that is not the fields' bytes plus the header.
    #[error(
        "FMT of {name} (type {ty}): length {length} bytes, but its fields take {fields} + {} header bytes",
        HEADER_BYTES
    )]
    Length {
        /// The message name.
        name: String,
        /// The type defined.
        ty: u8,
        /// The length declared, header included, bytes.
        length: usize,
        /// The fields' bytes.
        fields: usize,
    },
}

/// Parses the body of an `FMT` message (type, length, name, format, labels): the type
/// it defines and its format, or what is wrong.
pub fn parse_fmt(body: &[u8]) -> Result<(u8, Format), FmtError> {
    if body.len() < FMT_BODY_BYTES {
        return Err(FmtError::Short { bytes: body.len() });
    }
    let (ty, length) = (body[0], body[1] as usize);
    let name = text(&body[2..6]);
    let codes: Vec<u8> = body[6..22]
        .iter()
        .copied()
        .take_while(|&c| c != 0)
        .collect();
    let labels = text(&body[22..86]);
    if name.is_empty() || !name.bytes().all(|c| c.is_ascii_graphic()) {
        return Err(FmtError::Name { ty, name });
    }
    let labels: Vec<&str> = if labels.is_empty() {
        Vec::new()
    } else {
        labels.split(',').collect()
    };
    if labels.len() != codes.len() {
        return Err(FmtError::LabelCount {
            name,
            ty,
            codes: codes.len(),
            labels: labels.len(),
        });
    }
    let mut offset = 0;
    let mut fields = Vec::with_capacity(codes.len());
    for (&code, label) in codes.iter().zip(labels) {
        let kind = kind_of(code).ok_or_else(|| FmtError::UnknownCode {
            name: name.clone(),
            ty,
            code: code as char,
            label: label.to_string(),
        })?;
        fields.push(Field {
            label: label.to_string(),
            offset,
            kind,
            code,
        });
        offset += kind.size();
    }
    if offset + HEADER_BYTES != length {
        return Err(FmtError::Length {
            name,
            ty,
            length,
            fields: offset,
        });
    }
    Ok((
        ty,
        Format {
            name,
            length,
            fields,
            units: None,
        },
    ))
}

/// The unit names (`UNIT`) and multipliers (`MULT`) of a log, by character; ArduPilot's
/// standard multipliers when the log has no `MULT` message for a character.
#[derive(Debug, Clone, Default)]
pub struct UnitTables {
    pub units: HashMap<u8, String>,
    pub mults: HashMap<u8, f64>,
}

impl UnitTables {
    /// The multiplier of character `c`: `None` for `-` (none) and `?` (unknown), when the
    /// format's implied scale applies.
    pub fn multiplier(&self, c: u8) -> Option<f64> {
        if c == b'-' || c == b'?' {
            return None;
        }
        if let Some(&m) = self.mults.get(&c) {
            return (m != 0.0).then_some(m);
        }
        Some(match c {
            b'2' => 1e2,
            b'1' => 1e1,
            b'0' => 1.0,
            b'A' => 1e-1,
            b'B' => 1e-2,
            b'C' => 1e-3,
            b'D' => 1e-4,
            b'E' => 1e-5,
            b'F' => 1e-6,
            b'G' => 1e-7,
            b'I' => 1e-9,
            b'!' => 3.6,
            b'/' => 3600.0,
            _ => return None,
        })
    }
}

impl Format {
    /// The field labelled `label`.
    pub fn field(&self, label: &str) -> Option<(usize, &Field)> {
        self.fields
            .iter()
            .enumerate()
            .find(|(_, f)| f.label == label)
    }

    /// The instance field: the one whose `FMTU` unit is `#`, else one labelled `I`,
    /// `Instance` or `C` (EKF core).
    pub fn instance_field(&self) -> Option<&Field> {
        if let Some((units, _)) = &self.units {
            let k = units.iter().position(|&u| u == b'#')?;
            return self.fields.get(k);
        }
        ["I", "Instance", "C"]
            .iter()
            .find_map(|l| self.field(l).map(|(_, f)| f))
    }

    /// The value factor of field `k`: its `FMTU` multiplier applied to the raw value
    /// (ArduPilot's rule), else the scale its format character implies.
    pub fn factor(&self, k: usize, tables: &UnitTables) -> f64 {
        let implied = match self.fields[k].kind {
            Kind::Number(_, s) => s,
            Kind::Bytes(_) => 1.0,
        };
        self.units
            .as_ref()
            .and_then(|(_, m)| m.get(k))
            .and_then(|&c| tables.multiplier(c))
            .unwrap_or(implied)
    }

    /// The unit name of field `k` from `FMTU` and `UNIT`, when the log gives one.
    pub fn unit<'a>(&self, k: usize, tables: &'a UnitTables) -> Option<&'a str> {
        let c = *self.units.as_ref()?.0.get(k)?;
        tables.units.get(&c).map(String::as_str)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fmt_body(ty: u8, len: u8, name: &str, format: &str, labels: &str) -> Vec<u8> {
        let mut b = vec![ty, len];
        let pad = |s: &str, n: usize| {
            let mut v = s.as_bytes().to_vec();
            v.resize(n, 0);
            v
        };
        b.extend(pad(name, 4));
        b.extend(pad(format, 16));
        b.extend(pad(labels, 64));
        b
    }

    #[test]
    fn parses_offsets_scales_and_refuses_inconsistent_formats() {
        // Q 8 + B 1 + e 4 + f 4 = 17 bytes + 3 header bytes.
        let body = fmt_body(60, 20, "ESC", "QBef", "TimeUS,Instance,RPM,Volt");
        let (ty, f) = parse_fmt(&body).unwrap();
        assert_eq!((ty, f.name.as_str(), f.length), (60, "ESC", 20));
        let offsets: Vec<usize> = f.fields.iter().map(|x| x.offset).collect();
        assert_eq!(offsets, [0, 8, 9, 13]);
        assert_eq!(f.fields[2].kind, Kind::Number(Scalar::I32, 0.01));
        assert_eq!(f.instance_field().unwrap().label, "Instance");
        let tables = UnitTables::default();
        assert_eq!(f.factor(2, &tables), 0.01);
        let with_units = Format {
            units: Some((b"s#qv".to_vec(), b"F-B0".to_vec())),
            ..f.clone()
        };
        assert_eq!(with_units.factor(0, &tables), 1e-6);
        assert_eq!(with_units.factor(2, &tables), 1e-2);
        assert_eq!(with_units.factor(1, &tables), 1.0);
        for (body, words) in [
            (
                fmt_body(60, 21, "ESC", "QBef", "TimeUS,Instance,RPM,Volt"),
                "length 21",
            ),
            (
                fmt_body(60, 20, "ESC", "QBef", "TimeUS,Instance,RPM"),
                "4 format characters but 3 labels",
            ),
            (
                fmt_body(60, 20, "ESC", "QBxf", "TimeUS,Instance,RPM,Volt"),
                "unknown format character 'x'",
            ),
            (
                fmt_body(60, 20, "", "QBef", "TimeUS,Instance,RPM,Volt"),
                "not printable",
            ),
        ] {
            let e = parse_fmt(&body).unwrap_err().to_string();
            assert!(e.contains(words), "{e}");
        }
        assert_eq!(parse_fmt(&body[..50]), Err(FmtError::Short { bytes: 50 }));
    }
}
