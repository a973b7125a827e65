//! PX4 ULog reader (PX4 docs, "ULog File Format"): a streaming parser of the header,
//! definitions and data sections, and the [`RowSource`] that maps topics and fields onto
//! the sample slots the same way as MCAP (one mapping format for both).
//!
//! - Header: 7 magic bytes `ULog 01 12 35`, a version byte (0 or 1), the start time (µs).
//! - Messages: `uint16 size`, `uint8 type`, `size` payload bytes. Known types: `B` flag
//!   bits (first message only; unknown incompatible bits refuse the file, the data-appended
//!   bit is honoured), `F` formats, `I`/`M` info, `P`/`Q` parameters, `A`/`R` subscriptions,
//!   `D` data, `O` dropouts, `L`/`C` strings, `S` sync. Other types are skipped, as the
//!   spec asks.
//! - A mapped topic is `name` (instance 0) or `name[k]` (multi-instance id k); fields are
//!   paths into its format (`xyz[1]`, `esc[2].esc_rpm`), located once per subscription as
//!   a byte offset and scalar type, so a data message is decoded by reading only the
//!   mapped fields. Time is the topic's `timestamp` field (µs) unless the mapping names
//!   another (`[time]` or `[mcap.topic_time]`).
//! - Asynchronous topics are aligned on the time-base topic by linear interpolation
//!   between messages at most `align_gap` apart. A logger dropout (`O`) is never bridged:
//!   messages on either side are not interpolated between, and the time-base sample after
//!   it starts a new segment.
//! - Memory is bounded: one message buffer (≤ 64 KiB) and the alignment queues.
//!
//! Errors name the file, the byte offset of the message, its type and the field.

mod definitions;
mod format;
mod messages;
mod source;
mod topics;

pub use definitions::{LogDefinitions, read_definitions};
pub use source::UlogSource;

/// The seven magic bytes a ULog file starts with.
pub const MAGIC: [u8; 7] = [0x55, 0x4c, 0x6f, 0x67, 0x01, 0x12, 0x35];
/// Size of the file header, bytes.
pub const HEADER_BYTES: u64 = 16;
/// Size of a message header (`uint16 size`, `uint8 type`), bytes.
pub const MESSAGE_HEADER_BYTES: u64 = 3;
/// Smallest payload of a flag-bits (`B`) message, bytes.
pub const FLAG_BITS_BYTES: usize = 40;
/// Deepest nesting of formats accepted (a cycle is an error, not a stack overflow).
pub const MAX_NESTING: usize = 16;
