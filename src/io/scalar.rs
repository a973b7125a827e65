//! The fixed-width scalar types of the binary formats: a ULog field type (`uint16_t`,
//! `float`, …) and a ROS 2 primitive (`uint16`, `float32`, …) are the same kind of value,
//! named differently. Each format keeps its own names; the size and the little-endian
//! value are read here once.

/// A fixed-width scalar: an integer, a float or a one-byte bool.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Scalar {
    /// One byte, 0 false (ULog `bool`, ROS 2 `bool`).
    Bool,
    /// `int8_t`, `int8`.
    I8,
    /// `uint8_t`, `uint8`; also ULog `char` and ROS 2 `byte` and `char`.
    U8,
    /// `int16_t`, `int16`.
    I16,
    /// `uint16_t`, `uint16`.
    U16,
    /// `int32_t`, `int32`.
    I32,
    /// `uint32_t`, `uint32`.
    U32,
    /// `int64_t`, `int64`.
    I64,
    /// `uint64_t`, `uint64`.
    U64,
    /// `float`, `float32`.
    F32,
    /// `double`, `float64`.
    F64,
}

impl Scalar {
    /// Size, bytes (also the CDR alignment).
    pub fn size(self) -> usize {
        match self {
            Self::Bool | Self::I8 | Self::U8 => 1,
            Self::I16 | Self::U16 => 2,
            Self::I32 | Self::U32 | Self::F32 => 4,
            Self::I64 | Self::U64 | Self::F64 => 8,
        }
    }

    /// The little-endian value at the start of `b` (at least [`Scalar::size`] bytes) as a
    /// number; a bool is its byte.
    pub fn read_le(self, b: &[u8]) -> f64 {
        let a = |n: usize| -> [u8; 8] {
            let mut out = [0u8; 8];
            out[..n].copy_from_slice(&b[..n]);
            out
        };
        match self {
            Self::I8 => b[0] as i8 as f64,
            Self::U8 | Self::Bool => b[0] as f64,
            Self::I16 => i16::from_le_bytes([b[0], b[1]]) as f64,
            Self::U16 => u16::from_le_bytes([b[0], b[1]]) as f64,
            Self::I32 => i32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
            Self::U32 => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
            Self::F32 => f32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
            Self::I64 => i64::from_le_bytes(a(8)) as f64,
            Self::U64 => u64::from_le_bytes(a(8)) as f64,
            Self::F64 => f64::from_le_bytes(a(8)),
        }
    }
}
