//! ROS 2 CDR (XCDR1, little or big endian) decoding into a JSON value, driven by a
//! [`Schema`], so the same field paths address JSON and CDR messages.

use serde_json::{Map, Value};

use super::ros2msg::{Field, FieldType, Schema, Shape};
use super::scalar::Scalar;

/// Largest sequence length accepted (guards against corrupt length prefixes).
const MAX_SEQUENCE: usize = 1 << 24;
/// Deepest nesting accepted.
const MAX_DEPTH: usize = 32;

/// Why a CDR message does not decode.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CdrError {
    /// Fewer than the 4 bytes of the encapsulation header.
    #[error("CDR message shorter than its 4-byte header")]
    NoHeader,
    /// An encapsulation that is not plain CDR (big or little endian).
    #[error("unknown CDR representation identifier {0}")]
    Representation(u8),
    /// The message ends before a value it must hold.
    #[error("CDR message ends at byte {len} but {need} more bytes are needed at byte {at}")]
    Truncated {
        /// Bytes in the message.
        len: usize,
        /// Bytes the value needs.
        need: usize,
        /// Where the value starts.
        at: usize,
    },
    /// Nesting deeper than the decoder follows.
    #[error("message nesting too deep")]
    TooDeep,
    /// A nested type the schema does not define.
    #[error("type {0:?} not in schema")]
    UnknownType(String),
    /// A sequence length prefix longer than the message could hold.
    #[error("field {field:?}: sequence length {length} exceeds the message")]
    SequenceTooLong {
        /// The field.
        field: String,
        /// The length prefix read.
        length: usize,
    },
}

struct Cursor<'a> {
    data: &'a [u8],
    pos: usize,
    little: bool,
}

impl Cursor<'_> {
    fn align(&mut self, n: usize) {
        // Alignment is relative to the end of the 4-byte encapsulation header.
        let rel = self.pos - 4;
        self.pos += (n - rel % n) % n;
    }

    fn take(&mut self, n: usize) -> Result<&[u8], CdrError> {
        let end = self
            .pos
            .checked_add(n)
            .filter(|&e| e <= self.data.len())
            .ok_or(CdrError::Truncated {
                len: self.data.len(),
                need: n,
                at: self.pos,
            })?;
        let s = &self.data[self.pos..end];
        self.pos = end;
        Ok(s)
    }

    fn u32(&mut self) -> Result<u32, CdrError> {
        self.align(4);
        // `take` returns the 4 bytes asked for: the conversion cannot fail.
        let b: [u8; 4] = self.take(4)?.try_into().unwrap_or_default();
        Ok(if self.little {
            u32::from_le_bytes(b)
        } else {
            u32::from_be_bytes(b)
        })
    }

    fn primitive(&mut self, p: Scalar) -> Result<Value, CdrError> {
        let n = p.size();
        self.align(n);
        let little = self.little;
        let b = self.take(n)?;
        // `take` returns the `p.size()` bytes of the scalar: the conversions cannot fail.
        macro_rules! num {
            ($t:ty) => {{
                let arr: [u8; std::mem::size_of::<$t>()] = b.try_into().unwrap_or_default();
                if little {
                    <$t>::from_le_bytes(arr)
                } else {
                    <$t>::from_be_bytes(arr)
                }
            }};
        }
        Ok(match p {
            Scalar::Bool => Value::Bool(b[0] != 0),
            Scalar::I8 => Value::from(b[0] as i8),
            Scalar::U8 => Value::from(b[0]),
            Scalar::I16 => Value::from(num!(i16)),
            Scalar::U16 => Value::from(num!(u16)),
            Scalar::I32 => Value::from(num!(i32)),
            Scalar::U32 => Value::from(num!(u32)),
            Scalar::I64 => Value::from(num!(i64)),
            Scalar::U64 => Value::from(num!(u64)),
            Scalar::F32 => number(num!(f32) as f64),
            Scalar::F64 => number(num!(f64)),
        })
    }
}

/// JSON cannot hold NaN/inf; they become strings the reader reports as not finite.
fn number(x: f64) -> Value {
    serde_json::Number::from_f64(x).map_or_else(|| Value::String(format!("{x}")), Value::Number)
}

/// Decodes one CDR message of the schema's main type.
pub fn decode(schema: &Schema, data: &[u8]) -> Result<Value, CdrError> {
    if data.len() < 4 {
        return Err(CdrError::NoHeader);
    }
    let little = match data[1] {
        0 | 2 => false,
        1 | 3 => true,
        k => return Err(CdrError::Representation(k)),
    };
    let mut c = Cursor {
        data,
        pos: 4,
        little,
    };
    decode_message(schema, &schema.root, &mut c, 0)
}

fn decode_message(
    schema: &Schema,
    name: &str,
    c: &mut Cursor,
    depth: usize,
) -> Result<Value, CdrError> {
    if depth > MAX_DEPTH {
        return Err(CdrError::TooDeep);
    }
    let fields = schema
        .types
        .get(name)
        .ok_or_else(|| CdrError::UnknownType(name.to_string()))?;
    let mut map = Map::new();
    for f in fields {
        let v = decode_field(schema, f, c, depth)?;
        map.insert(f.name.clone(), v);
    }
    Ok(Value::Object(map))
}

fn decode_field(
    schema: &Schema,
    f: &Field,
    c: &mut Cursor,
    depth: usize,
) -> Result<Value, CdrError> {
    let count = match f.shape {
        Shape::Scalar => return decode_one(schema, &f.ty, c, depth),
        Shape::Fixed(n) => n,
        Shape::Sequence => c.u32()? as usize,
    };
    if count > MAX_SEQUENCE || count > c.data.len() {
        return Err(CdrError::SequenceTooLong {
            field: f.name.clone(),
            length: count,
        });
    }
    (0..count)
        .map(|_| decode_one(schema, &f.ty, c, depth))
        .collect::<Result<Vec<_>, _>>()
        .map(Value::Array)
}

fn decode_one(
    schema: &Schema,
    ty: &FieldType,
    c: &mut Cursor,
    depth: usize,
) -> Result<Value, CdrError> {
    match ty {
        FieldType::Primitive(p) => c.primitive(*p),
        FieldType::String => {
            let n = c.u32()? as usize;
            let bytes = c.take(n)?;
            let s = bytes.strip_suffix(&[0]).unwrap_or(bytes);
            Ok(Value::String(String::from_utf8_lossy(s).into_owned()))
        }
        FieldType::Message(m) => decode_message(schema, m, c, depth + 1),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::ros2msg::parse_schema;

    #[test]
    fn decodes_nested_arrays_strings_and_alignment() {
        let text = "std_msgs/Header header\nuint8 id\nfloat64[2] pair\nstring label\nint16[] seq\n\
                    ================================================================================\n\
                    MSG: std_msgs/Header\nbuiltin_interfaces/Time stamp\nstring frame_id\n";
        let schema = parse_schema("test/msg/Thing", text).unwrap();
        let mut b: Vec<u8> = vec![0, 1, 0, 0];
        b.extend_from_slice(&7i32.to_le_bytes()); // sec
        b.extend_from_slice(&5u32.to_le_bytes()); // nanosec
        b.extend_from_slice(&4u32.to_le_bytes()); // frame_id length incl. NUL
        b.extend_from_slice(b"map\0");
        b.push(9); // id (offset 16 → 17)
        b.extend_from_slice(&[0; 7]); // align to 8 (relative offset 24)
        b.extend_from_slice(&1.5f64.to_le_bytes());
        b.extend_from_slice(&(-2.0f64).to_le_bytes());
        b.extend_from_slice(&2u32.to_le_bytes());
        b.extend_from_slice(b"a\0");
        b.extend_from_slice(&[0; 2]); // align to 4
        b.extend_from_slice(&2u32.to_le_bytes());
        b.extend_from_slice(&(-3i16).to_le_bytes());
        b.extend_from_slice(&4i16.to_le_bytes());
        let v = decode(&schema, &b).unwrap();
        assert_eq!(v["header"]["stamp"]["sec"], 7);
        assert_eq!(v["header"]["frame_id"], "map");
        assert_eq!(v["id"], 9);
        assert_eq!(v["pair"][1], -2.0);
        assert_eq!(v["label"], "a");
        assert_eq!(v["seq"][0], -3);
        // Truncation is an error, not a panic.
        let e = decode(&schema, &b[..b.len() - 1]).unwrap_err();
        assert_eq!(
            e,
            CdrError::Truncated {
                len: b.len() - 1,
                need: 2,
                at: b.len() - 2
            }
        );
        assert!(e.to_string().contains("more bytes are needed"), "{e}");
    }
}
