//! Log ingestion: contract and mapped CSV, MCAP (JSON and ROS 2 CDR) and PX4 ULog, turned
//! into the [`SampleChunk`] stream of the data contract (`docs/data-contract.md`),
//! streaming in
//! bounded memory.
//!
//! Pipeline per sample: a source (CSV row or time-aligned MCAP messages) fills the slot
//! layout of the mapping → values checked finite, converted to SI and FRD/NED, checked
//! against physical ranges → time checked strictly increasing; a gap longer than
//! [`ReadOptions::max_gap`] closes the segment (never bridged) → in a short look-ahead
//! window: spikes flagged, ω̇ and Ω̇ differentiated when not logged, F = m a and
//! M = I ω̇ + ω × I ω derived when not logged → chunks of at most
//! [`crate::CHUNK_SAMPLES`] samples, each inside one segment.

pub mod cdr;
pub mod contract_csv;
pub mod csv_input;
pub mod decimal;
pub mod derive;
pub mod error;
pub mod json_error;
pub mod layout;
pub mod mapping;
pub mod mcap_read;
pub mod px4;
pub mod ros2msg;
pub mod slots;
pub mod ulog;
pub mod units;
pub mod validate;

mod align;
mod field_path;
#[cfg(feature = "fixtures")]
pub mod fixtures;
mod open;
mod options;
mod reader;
mod row_source;
mod scalar;
mod summary;

pub use derive::DeriveOptions;
pub use error::{ErrorKind, IoError, Location};
pub use layout::LayoutReport;
pub use mapping::Mapping;
pub use open::open_log;
pub use options::{InvalidSamples, ReadOptions};
pub use reader::LogReader;
pub(crate) use row_source::RowSource;
pub use summary::{Dropout, Gap, Summary};

/// Largest rotor count the readers handle.
pub const MAX_ROTORS: usize = 16;
