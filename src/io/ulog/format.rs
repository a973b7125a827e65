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

/// Why the text of an `F` message does not parse.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FormatTextError {
    /// No `name:` before the fields.
    #[error("format {text:?} has no ':' after the message name")]
    NoName {
        /// The format text.
        text: String,
    },
    /// An empty name before the `:`.
    #[error("format with an empty message name")]
    EmptyName,
    /// A field that is not `type name`.
    #[error("field {item:?} of format {format:?} is not `type name`")]
    NotTypeName {
        /// The field as written.
        item: String,
        /// The format's message name.
        format: String,
    },
    /// An array type whose length is not `[n]`.
    #[error("field {field:?} of format {format:?}: bad array type {ty:?}")]
    BadArrayType {
        /// The field's name.
        field: String,
        /// The format's message name.
        format: String,
        /// The type as written.
        ty: String,
    },
}

/// Parses the text of an `F` message, `name:type field;type[n] field;…`.
pub fn parse_format(text: &str) -> Result<(String, Vec<FieldDef>), FormatTextError> {
    let (name, body) = text
        .split_once(':')
        .ok_or_else(|| FormatTextError::NoName {
            text: text.to_string(),
        })?;
    if name.is_empty() {
        return Err(FormatTextError::EmptyName);
    }
    let not_type_name = |item: &str| FormatTextError::NotTypeName {
        item: item.to_string(),
        format: name.to_string(),
    };
    let mut fields = Vec::new();
    for item in body.split(';').filter(|s| !s.is_empty()) {
        let (ty, fname) = item.split_once(' ').ok_or_else(|| not_type_name(item))?;
        let (ty, array) = match ty.split_once('[') {
            Some((t, rest)) => {
                let n = rest
                    .strip_suffix(']')
                    .and_then(|n| n.parse::<usize>().ok())
                    .ok_or_else(|| FormatTextError::BadArrayType {
                        field: fname.to_string(),
                        format: name.to_string(),
                        ty: ty.to_string(),
                    })?;
                (t, Some(n))
            }
            None => (ty, None),
        };
        if ty.is_empty() || fname.is_empty() || fname.contains(' ') {
            return Err(not_type_name(item));
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
    fn size_of(&self, ty: &str, depth: usize) -> Result<usize, LocateError> {
        if let Some(s) = scalar_named(ty) {
            return Ok(s.size());
        }
        if depth > MAX_NESTING {
            return Err(LocateError::TooDeep { ty: ty.to_string() });
        }
        let fields = self
            .get(ty)
            .ok_or_else(|| LocateError::UnknownType { ty: ty.to_string() })?;
        let mut size = 0usize;
        for f in fields {
            size = size
                .checked_add(self.field_size(f, depth + 1)?)
                .ok_or(LocateError::TooLarge)?;
        }
        Ok(size)
    }

    /// Size of field `f` (all its array elements), bytes.
    fn field_size(&self, f: &FieldDef, depth: usize) -> Result<usize, LocateError> {
        self.size_of(&f.ty, depth)?
            .checked_mul(f.array.unwrap_or(1))
            .ok_or_else(|| LocateError::FieldTooLarge {
                field: f.name.clone(),
            })
    }

    /// Byte offset and scalar type of `path` inside a message of format `format`.
    pub fn locate(&self, format: &str, path: &str) -> Result<(usize, Scalar), LocateError> {
        let steps = parse_path(path)?;
        let mut ty = format.to_string();
        let mut offset = 0usize;
        let mut i = 0;
        while i < steps.len() {
            let Step::Key(name) = &steps[i] else {
                return Err(LocateError::IndexWithoutName { path: path.into() });
            };
            let fields = self.get(&ty).ok_or_else(|| LocateError::NoFields {
                path: path.into(),
                ty: ty.clone(),
            })?;
            let mut found = None;
            for f in fields {
                if f.name == *name {
                    found = Some(f);
                    break;
                }
                offset = offset
                    .checked_add(self.field_size(f, 0)?)
                    .ok_or(LocateError::TooLarge)?;
            }
            let f = found.ok_or_else(|| LocateError::NoSuchField {
                format: ty.clone(),
                field: name.clone(),
                fields: fields
                    .iter()
                    .filter(|f| !f.name.starts_with("_padding"))
                    .map(|f| f.name.clone())
                    .collect(),
            })?;
            i += 1;
            if let Some(n) = f.array {
                let Some(Step::Index(k)) = steps.get(i) else {
                    return Err(LocateError::NeedsIndex {
                        field: name.clone(),
                        format: ty,
                        length: n,
                    });
                };
                if *k >= n {
                    return Err(LocateError::IndexOutOfRange {
                        index: *k,
                        field: name.clone(),
                        format: ty,
                        length: n,
                    });
                }
                // k < n and the n elements' size fits (checked): k * size cannot overflow.
                let element = self.size_of(&f.ty, 0)?;
                self.field_size(f, 0)?;
                offset = offset
                    .checked_add(k * element)
                    .ok_or(LocateError::TooLarge)?;
                i += 1;
            }
            match scalar_named(&f.ty) {
                Some(s) if i == steps.len() => return Ok((offset, s)),
                Some(_) => {
                    return Err(LocateError::NoSubFields {
                        path: path.into(),
                        field: name.clone(),
                        ty: f.ty.clone(),
                    });
                }
                None => {
                    if i == steps.len() {
                        return Err(LocateError::EndsAtNested {
                            path: path.into(),
                            field: name.clone(),
                            ty: f.ty.clone(),
                        });
                    }
                    self.size_of(&f.ty, 0)?;
                    ty = f.ty.clone();
                }
            }
        }
        Err(FieldPathError::Empty { path: path.into() }.into())
    }
}

/// Why a mapped field path cannot be located in a format.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LocateError {
    /// The path does not parse.
    #[error(transparent)]
    Path(#[from] FieldPathError),
    /// Formats nested deeper than [`MAX_NESTING`] (a format holding itself).
    #[error("format {ty:?} nests deeper than {} levels (a cycle?)", MAX_NESTING)]
    TooDeep {
        /// The format.
        ty: String,
    },
    /// A type that is neither a scalar nor a format of the file.
    #[error("unknown type {ty:?} (neither a scalar nor a format)")]
    UnknownType {
        /// The type.
        ty: String,
    },
    /// A format whose size overflows.
    #[error("format too large")]
    TooLarge,
    /// A field whose size overflows.
    #[error("field {field:?} is too large")]
    FieldTooLarge {
        /// The field.
        field: String,
    },
    /// A path step that is an index with no field before it.
    #[error("field path {path:?}: index without a field name")]
    IndexWithoutName {
        /// The path.
        path: String,
    },
    /// A step into a type that has no format.
    #[error("field path {path:?}: {ty:?} has no fields")]
    NoFields {
        /// The path.
        path: String,
        /// The type stepped into.
        ty: String,
    },
    /// A field the format lacks.
    #[error("format {format:?} has no field {field:?} (fields: {})", fields.join(", "))]
    NoSuchField {
        /// The format.
        format: String,
        /// The field named.
        field: String,
        /// The format's fields (padding left out).
        fields: Vec<String>,
    },
    /// An array field named without an index.
    #[error(
        "field {field:?} of {format:?} is an array of {length}: give an index, e.g. {field}[0]"
    )]
    NeedsIndex {
        /// The field.
        field: String,
        /// The format holding it.
        format: String,
        /// Its elements.
        length: usize,
    },
    /// An index beyond the array.
    #[error("index {index} out of range: field {field:?} of {format:?} has {length} elements")]
    IndexOutOfRange {
        /// The index given.
        index: usize,
        /// The field.
        field: String,
        /// The format holding it.
        format: String,
        /// Its elements.
        length: usize,
    },
    /// A path going on past a scalar.
    #[error("field path {path:?}: {field:?} is a {ty} and has no sub-fields")]
    NoSubFields {
        /// The path.
        path: String,
        /// The scalar field.
        field: String,
        /// Its type.
        ty: String,
    },
    /// A path ending at a nested format.
    #[error("field path {path:?} ends at {field:?}, a nested {ty:?}: name one of its fields")]
    EndsAtNested {
        /// The path.
        path: String,
        /// The field.
        field: String,
        /// Its format.
        ty: String,
    },
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
            let e = f.locate(format, path).unwrap_err().to_string();
            assert!(e.contains(words), "{format}.{path}: {e}");
        }
        assert_eq!(
            f.locate("esc_status", "esc[8].v"),
            Err(LocateError::IndexOutOfRange {
                index: 8,
                field: "esc".into(),
                format: "esc_status".into(),
                length: 8
            })
        );
    }
}
