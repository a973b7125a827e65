//! ULog message formats (`F` messages): their text parsed, and a mapped field path
//! located in a format as a byte offset and scalar type, so a data message is decoded by
//! reading only the mapped fields.

use std::collections::HashMap;

use super::super::field_path::{self, FieldPathError, Step, Style};
use super::super::scalar::Scalar;
use super::MAX_NESTING;

/// The scalar of a ULog type name, if it is one (`char` is a byte).
pub(super) fn scalar_named(name: &str) -> Option<Scalar> {
    Some(match name {
        "int8_t" => Scalar::I8,
        "uint8_t" | "char" => Scalar::U8,
        "int16_t" => Scalar::I16,
        "uint16_t" => Scalar::U16,
        "int32_t" => Scalar::I32,
        "uint32_t" => Scalar::U32,
        "int64_t" => Scalar::I64,
        "uint64_t" => Scalar::U64,
        "float" => Scalar::F32,
        "double" => Scalar::F64,
        "bool" => Scalar::Bool,
        _ => return None,
    })
}

/// One field of a format: `type[array] name`.
#[derive(Debug, Clone, PartialEq)]
pub struct FieldDef {
    /// Type name: a scalar type or another format's name.
    pub ty: String,
    /// Array length, when the field is an array.
    pub array: Option<usize>,
    /// Field name.
    pub name: String,
}

/// Parses the text of an `F` message, `name:type field;type[n] field;…`.
pub fn parse_format(text: &str) -> Result<(String, Vec<FieldDef>), String> {
    let (name, body) = text
        .split_once(':')
        .ok_or_else(|| format!("format {text:?} has no ':' after the message name"))?;
    if name.is_empty() {
        return Err("format with an empty message name".into());
    }
    let mut fields = Vec::new();
    for item in body.split(';').filter(|s| !s.is_empty()) {
        let (ty, fname) = item
            .split_once(' ')
            .ok_or_else(|| format!("field {item:?} of format {name:?} is not `type name`"))?;
        let (ty, array) = match ty.split_once('[') {
            Some((t, rest)) => {
                let n = rest
                    .strip_suffix(']')
                    .and_then(|n| n.parse::<usize>().ok())
                    .ok_or_else(|| {
                        format!("field {fname:?} of format {name:?}: bad array type {ty:?}")
                    })?;
                (t, Some(n))
            }
            None => (ty, None),
        };
        if ty.is_empty() || fname.is_empty() || fname.contains(' ') {
            return Err(format!(
                "field {item:?} of format {name:?} is not `type name`"
            ));
        }
        fields.push(FieldDef {
            ty: ty.to_string(),
            array,
            name: fname.to_string(),
        });
    }
    Ok((name.to_string(), fields))
}

/// Parses a ULog field path `a.b[2].c`.
pub(super) fn parse_path(path: &str) -> Result<Vec<Step>, FieldPathError> {
    field_path::parse(path, Style::Ulog)
}

/// Splits a mapped topic `name[k]` into name and multi-instance id (0 when absent).
pub fn split_instance(topic: &str) -> Result<(&str, u8), String> {
    match topic.strip_suffix(']').and_then(|t| t.rsplit_once('[')) {
        Some((name, k)) => k
            .parse::<u8>()
            .map(|k| (name, k))
            .map_err(|_| format!("topic {topic:?}: instance {k:?} is not a number 0..=255")),
        None => Ok((topic, 0)),
    }
}

/// The formats of a file, by message name.
#[derive(Debug, Clone, Default)]
pub struct Formats {
    by_name: HashMap<String, Vec<FieldDef>>,
}

impl Formats {
    /// Adds the format of an `F` message.
    pub fn insert(&mut self, name: String, fields: Vec<FieldDef>) {
        self.by_name.insert(name, fields);
    }

    /// The fields of format `name`.
    pub fn get(&self, name: &str) -> Option<&[FieldDef]> {
        self.by_name.get(name).map(Vec::as_slice)
    }

    /// Size of one value of type `ty`, bytes.
    fn size_of(&self, ty: &str, depth: usize) -> Result<usize, String> {
        if let Some(s) = scalar_named(ty) {
            return Ok(s.size());
        }
        if depth > MAX_NESTING {
            return Err(format!(
                "format {ty:?} nests deeper than {MAX_NESTING} levels (a cycle?)"
            ));
        }
        let fields = self
            .get(ty)
            .ok_or_else(|| format!("unknown type {ty:?} (neither a scalar nor a format)"))?;
        let mut size = 0usize;
        for f in fields {
            size = size
                .checked_add(self.field_size(f, depth + 1)?)
                .ok_or("format too large")?;
        }
        Ok(size)
    }

    /// Size of field `f` (all its array elements), bytes.
    fn field_size(&self, f: &FieldDef, depth: usize) -> Result<usize, String> {
        self.size_of(&f.ty, depth)?
            .checked_mul(f.array.unwrap_or(1))
            .ok_or_else(|| format!("field {:?} is too large", f.name))
    }

    /// Byte offset and scalar type of `path` inside a message of format `format`.
    pub fn locate(&self, format: &str, path: &str) -> Result<(usize, Scalar), String> {
        let steps = parse_path(path).map_err(|e| e.to_string())?;
        let mut ty = format.to_string();
        let mut offset = 0usize;
        let mut i = 0;
        while i < steps.len() {
            let Step::Key(name) = &steps[i] else {
                return Err(format!("field path {path:?}: index without a field name"));
            };
            let fields = self
                .get(&ty)
                .ok_or_else(|| format!("field path {path:?}: {ty:?} has no fields"))?;
            let mut found = None;
            for f in fields {
                if f.name == *name {
                    found = Some(f);
                    break;
                }
                offset = offset
                    .checked_add(self.field_size(f, 0)?)
                    .ok_or("format too large")?;
            }
            let f = found.ok_or_else(|| {
                let names: Vec<&str> = fields
                    .iter()
                    .filter(|f| !f.name.starts_with("_padding"))
                    .map(|f| f.name.as_str())
                    .collect();
                format!(
                    "format {ty:?} has no field {name:?} (fields: {})",
                    names.join(", ")
                )
            })?;
            i += 1;
            if let Some(n) = f.array {
                let Some(Step::Index(k)) = steps.get(i) else {
                    return Err(format!(
                        "field {name:?} of {ty:?} is an array of {n}: give an index, e.g. {name}[0]"
                    ));
                };
                if *k >= n {
                    return Err(format!(
                        "index {k} out of range: field {name:?} of {ty:?} has {n} elements"
                    ));
                }
                // k < n and the n elements' size fits (checked): k * size cannot overflow.
                let element = self.size_of(&f.ty, 0)?;
                self.field_size(f, 0)?;
                offset = offset.checked_add(k * element).ok_or("format too large")?;
                i += 1;
            }
            match scalar_named(&f.ty) {
                Some(s) if i == steps.len() => return Ok((offset, s)),
                Some(_) => {
                    return Err(format!(
                        "field path {path:?}: {name:?} is a {} and has no sub-fields",
                        f.ty
                    ));
                }
                None => {
                    if i == steps.len() {
                        return Err(format!(
                            "field path {path:?} ends at {name:?}, a nested {:?}: name one of its fields",
                            f.ty
                        ));
                    }
                    self.size_of(&f.ty, 0)?;
                    ty = f.ty.clone();
                }
            }
        }
        Err(format!("empty field path {path:?}"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn format_and_paths() {
        let mut f = Formats::default();
        for text in [
            "esc_report:int32_t esc_rpm;float v;uint8_t[4] _padding0;",
            "esc_status:uint64_t timestamp;uint8_t esc_count;uint8_t[7] _padding0;esc_report[8] esc",
            "loop:uint64_t timestamp;loop[1] me",
            "big:uint64_t timestamp;double[4611686018427387904] b;double x",
        ] {
            let (n, fields) = parse_format(text).unwrap();
            f.insert(n, fields);
        }
        // esc_report is 12 bytes; esc starts at byte 16 of esc_status.
        for (path, at) in [
            ("timestamp", (0, Scalar::U64)),
            ("esc[2].esc_rpm", (16 + 2 * 12, Scalar::I32)),
            ("esc[0].v", (20, Scalar::F32)),
        ] {
            assert_eq!(f.locate("esc_status", path), Ok(at), "{path}");
        }
        for (format, path, words) in [
            ("esc_status", "esc[8].v", "out of range"),
            ("esc_status", "esc", "give an index"),
            ("esc_status", "esc[1]", "nested"),
            ("esc_status", "rpm", "fields: timestamp, esc_count, esc"),
            ("loop", "me[0].timestamp", "nests deeper"),
            ("big", "x", "too large"),
            ("big", "b[3]", "too large"),
        ] {
            let e = f.locate(format, path).unwrap_err();
            assert!(e.contains(words), "{format}.{path}: {e}");
        }
        assert_eq!(
            split_instance("actuator_outputs[1]").unwrap(),
            ("actuator_outputs", 1)
        );
        assert_eq!(split_instance("a").unwrap(), ("a", 0));
        assert!(split_instance("a[x]").is_err());
    }
}
