//! ROS 2 `.msg` schema text as stored in MCAP (`ros2msg` schema encoding): the main
//! definition followed by its dependencies, each after a `====` line and `MSG: pkg/Type`.
//! Parsed into field lists the CDR decoder walks.

use std::collections::HashMap;

use super::scalar::Scalar;

/// A primitive or nested field type.
#[derive(Debug, Clone, PartialEq)]
pub enum FieldType {
    /// bool, byte, char, int8…uint64, float32, float64.
    Primitive(Scalar),
    /// string / wstring (bounded or not).
    String,
    /// A nested message type, fully qualified `pkg/msg/Type`.
    Message(String),
}

/// Array shape of a field.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Shape {
    /// A single value.
    Scalar,
    /// `T[N]`: exactly N values, no length prefix.
    Fixed(usize),
    /// `T[]` or `T[<=N]`: a uint32 length prefix.
    Sequence,
}

/// One field of a message definition.
#[derive(Debug, Clone, PartialEq)]
pub struct Field {
    /// Field name.
    pub name: String,
    /// Element type.
    pub ty: FieldType,
    /// Array shape.
    pub shape: Shape,
}

/// All message definitions of one schema, by fully qualified name; `root` is the main one.
#[derive(Debug, Clone, PartialEq)]
pub struct Schema {
    /// Fully qualified name of the main type.
    pub root: String,
    /// Definitions by fully qualified name.
    pub types: HashMap<String, Vec<Field>>,
}

/// Why schema text was refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SchemaError {
    /// A line that is not `type name` (nor a comment or constant).
    #[error("schema line {line}: expected \"type name\", got {text:?}")]
    NotTypeName {
        /// 1-based line within its definition.
        line: usize,
        /// The line, comment and surrounding space removed.
        text: String,
    },
    /// An array type without its closing `]`.
    #[error("schema line {line}: bad array {ty:?}")]
    BadArray {
        /// 1-based line within its definition.
        line: usize,
        /// The type as written.
        ty: String,
    },
    /// An array size that is not a whole number.
    #[error("schema line {line}: bad array size {size:?}")]
    BadArraySize {
        /// 1-based line within its definition.
        line: usize,
        /// The text between the brackets.
        size: String,
    },
    /// A field whose message type the schema does not define.
    #[error("type {ty:?} of field {owner}.{field} is not defined in the schema")]
    Undefined {
        /// The missing type, fully qualified.
        ty: String,
        /// The type holding the field.
        owner: String,
        /// The field.
        field: String,
    },
    /// The main type is not defined.
    #[error("main type {root:?} is not defined")]
    NoMainType {
        /// The main type, fully qualified.
        root: String,
    },
}

/// `pkg/Type` → `pkg/msg/Type`; names without a package resolve in `pkg` of the
/// enclosing definition; `Header` means `std_msgs/msg/Header`.
fn qualify(name: &str, pkg: &str) -> String {
    match name.split('/').collect::<Vec<_>>().as_slice() {
        [p, "msg", t] => format!("{p}/msg/{t}"),
        [p, t] => format!("{p}/msg/{t}"),
        ["Header"] => "std_msgs/msg/Header".into(),
        [t] => format!("{pkg}/msg/{t}"),
        _ => name.to_string(),
    }
}

fn primitive(name: &str) -> Option<FieldType> {
    use Scalar::*;
    let p = match name {
        "bool" => Bool,
        "int8" => I8,
        "uint8" | "byte" | "char" => U8,
        "int16" => I16,
        "uint16" => U16,
        "int32" => I32,
        "uint32" => U32,
        "int64" => I64,
        "uint64" => U64,
        "float32" => F32,
        "float64" => F64,
        _ if name == "string"
            || name == "wstring"
            || name.starts_with("string<=")
            || name.starts_with("wstring<=") =>
        {
            return Some(FieldType::String);
        }
        _ => return None,
    };
    Some(FieldType::Primitive(p))
}

fn parse_fields(text: &str, pkg: &str) -> Result<Vec<Field>, SchemaError> {
    let mut fields = Vec::new();
    for (n, raw) in text.lines().enumerate() {
        let line = raw.split('#').next().unwrap_or("").trim();
        if line.is_empty() {
            continue;
        }
        let mut parts = line.split_whitespace();
        let (Some(ty), Some(name)) = (parts.next(), parts.next()) else {
            return Err(SchemaError::NotTypeName {
                line: n + 1,
                text: line.to_string(),
            });
        };
        if name.contains('=') || parts.clone().next().is_some_and(|p| p.starts_with('=')) {
            continue; // constant
        }
        let (base, shape) = match ty.split_once('[') {
            None => (ty, Shape::Scalar),
            Some((b, rest)) => {
                let inner = rest
                    .strip_suffix(']')
                    .ok_or_else(|| SchemaError::BadArray {
                        line: n + 1,
                        ty: ty.to_string(),
                    })?;
                let shape = if inner.is_empty() || inner.starts_with("<=") {
                    Shape::Sequence
                } else {
                    Shape::Fixed(inner.parse().map_err(|_| SchemaError::BadArraySize {
                        line: n + 1,
                        size: inner.to_string(),
                    })?)
                };
                (b, shape)
            }
        };
        let ty = primitive(base).unwrap_or_else(|| FieldType::Message(qualify(base, pkg)));
        fields.push(Field {
            name: name.to_string(),
            ty,
            shape,
        });
    }
    Ok(fields)
}

/// Parses schema text whose main type is `name` (`pkg/msg/Type` or `pkg/Type`).
pub fn parse_schema(name: &str, text: &str) -> Result<Schema, SchemaError> {
    let root = qualify(name, "");
    let mut types = HashMap::new();
    let mut current = root.clone();
    let mut body = String::new();
    let pkg_of = |q: &str| q.split('/').next().unwrap_or("").to_string();
    for line in text.lines() {
        if line.starts_with("====") {
            types.insert(current.clone(), parse_fields(&body, &pkg_of(&current))?);
            body.clear();
            continue;
        }
        if let Some(t) = line.strip_prefix("MSG:") {
            current = qualify(t.trim(), "");
            continue;
        }
        body.push_str(line);
        body.push('\n');
    }
    types.insert(current.clone(), parse_fields(&body, &pkg_of(&current))?);
    // builtin_interfaces are often left out of schema text.
    for t in [
        "builtin_interfaces/msg/Time",
        "builtin_interfaces/msg/Duration",
    ] {
        types.entry(t.to_string()).or_insert_with(|| {
            vec![
                Field {
                    name: "sec".into(),
                    ty: FieldType::Primitive(Scalar::I32),
                    shape: Shape::Scalar,
                },
                Field {
                    name: "nanosec".into(),
                    ty: FieldType::Primitive(Scalar::U32),
                    shape: Shape::Scalar,
                },
            ]
        });
    }
    let schema = Schema { root, types };
    schema.check()?;
    Ok(schema)
}

impl Schema {
    /// Every referenced type is defined and the nesting is finite.
    fn check(&self) -> Result<(), SchemaError> {
        for (name, fields) in &self.types {
            for f in fields {
                if let FieldType::Message(m) = &f.ty
                    && !self.types.contains_key(m)
                {
                    return Err(SchemaError::Undefined {
                        ty: m.clone(),
                        owner: name.clone(),
                        field: f.name.clone(),
                    });
                }
            }
        }
        if !self.types.contains_key(&self.root) {
            return Err(SchemaError::NoMainType {
                root: self.root.clone(),
            });
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each refusal names the line or type, in the words the MCAP reader reports.
    #[test]
    fn bad_schemas_are_named() {
        let words = |text: &str| parse_schema("p/msg/T", text).map_err(|e| e.to_string());
        for (text, message) in [
            (
                "float64 x\nlonely\n",
                "schema line 2: expected \"type name\", got \"lonely\"",
            ),
            ("float64[3 x\n", "schema line 1: bad array \"float64[3\""),
            ("float64[n] x\n", "schema line 1: bad array size \"n\""),
            (
                "Inner i\n",
                "type \"p/msg/Inner\" of field p/msg/T.i is not defined in the schema",
            ),
            (
                "MSG: q/Other\nfloat64 y\n",
                "main type \"p/msg/T\" is not defined",
            ),
        ] {
            assert_eq!(words(text), Err(message.to_string()), "{text:?}");
        }
    }
}
