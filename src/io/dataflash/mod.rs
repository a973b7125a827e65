//! ArduPilot DataFlash reader (`.bin` logs; ArduPilot's "Logger" library): a streaming
//! parser of the self-described message stream, and the [`RowSource`] that maps messages
//! and fields onto the sample slots with the same mapping format as MCAP and ULog.
//!
//! - Every message starts with the head bytes `0xA3 0x95` and a type byte; its length
//!   and fields come from the `FMT` message (type 128: type, length, name `char[4]`,
//!   format `char[16]`, labels `char[64]`) that defined the type before it. Format
//!   characters: `b B h H i I f d q Q M` integers and floats, `c C e E` 16/32-bit
//!   integers stored × 100, `L` latitude/longitude in 1e-7°, `n N Z a` text and arrays
//!   (not numbers).
//! - `FMTU` messages give each field a unit and a multiplier character, `UNIT` and
//!   `MULT` messages their meaning. A field's value is the raw value times its `FMTU`
//!   multiplier (ArduPilot's rule), else times the scale its format character implies.
//!   When the mapping gives a signal no `unit`, the field's `FMTU` unit is used (`rpm`,
//!   `deg/s`, `m/s/s`…).
//! - A mapped message is `NAME` or `NAME[k]`: instance k of a multi-instance message,
//!   told by its instance field (`FMTU` unit `#`, else a field `I`, `Instance` or `C`);
//!   `NAME` is instance 0. A field is a label of the signal's `topic` (`GyrX`) or names
//!   its own message (`ESC[2].RPM`), so one signal can gather one field per instance.
//!   Time is the message's `TimeUS` (µs) unless the mapping names another field.
//! - Messages of other rates are aligned on the time-base message by linear
//!   interpolation between messages at most `align_gap` apart ([`super::align`]).
//! - Memory is bounded: one message body (≤ 252 bytes), the 256 formats and the
//!   alignment queues.
//!
//! Errors name the file, the byte offset of the message, its name and the field: a
//! truncated message, corrupted head bytes, a type no `FMT` defined, a bad `FMT`.

pub(super) mod format;
mod messages;
mod params;
mod source;
mod topics;

pub use params::{LogParameters, read_parameters};
pub use source::DataflashSource;

#[cfg(doc)]
use super::row_source::RowSource;

/// The two head bytes every message starts with.
pub const HEAD: [u8; 2] = [0xA3, 0x95];
/// Message type of `FMT`.
pub const FMT_TYPE: u8 = 128;
/// Bytes of a message header (two head bytes and the type).
pub const HEADER_BYTES: usize = 3;
/// Bytes of an `FMT` message body: type, length, name[4], format[16], labels[64].
pub const FMT_BODY_BYTES: usize = 86;
