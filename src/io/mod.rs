//! Log ingestion: contract and mapped CSV, MCAP (JSON and ROS 2 CDR), PX4 ULog and
//! ArduPilot DataFlash, turned
//! into the [`SampleChunk`](crate::sample::SampleChunk) stream of the data contract
//! (`docs/data-contract.md`), streaming in bounded memory.
//!
//! Pipeline per sample: a source (CSV row or time-aligned MCAP and ULog messages) fills
//! the slot layout of the mapping → values checked finite, converted to SI and FRD/NED,
//! checked against physical ranges → time checked strictly increasing; a gap longer than
//! [`ReadOptions::max_gap`] closes the segment (never bridged) → in a short look-ahead
//! window: spikes flagged, ω̇ and Ω̇ differentiated when not logged, F = m a and
//! M = I ω̇ + ω × I ω derived when not logged → chunks of at most
//! [`crate::CHUNK_SAMPLES`] samples, each inside one segment.
//!
//! The front: [`open_log`] gives a [`LogReader`] (chunks, then a [`Summary`]), chosen by
//! [`ReadOptions`] and a [`Mapping`] file's contents; every error is an [`IoError`].
//! [`read_definitions`] and the PX4 helpers ([`rotors_from_parameters`],
//! [`vehicle_skeleton`]), [`read_parameters`] and the ArduPilot helpers
//! ([`ardupilot_rotors`], [`ardupilot_skeleton`], [`actuator_lines`]) serve
//! `mrsysid vehicle --from-log`. The submodules are
//! private; [`internals`] holds the two decoders the fuzz tests and benchmarks drive
//! directly, and `fixtures` (cargo feature `fixtures`, tests only) the log writers.

mod align;
mod ardupilot;
mod cdr;
mod contract_csv;
mod csv_input;
mod dataflash;
mod decimal;
mod derive;
mod error;
mod field_path;
#[cfg(feature = "fixtures")]
pub mod fixtures;
mod json_error;
mod layout;
mod mapping;
mod mcap_read;
mod open;
mod options;
mod px4;
mod reader;
mod ros2msg;
mod row_source;
mod scalar;
mod slots;
mod summary;
mod ulog;
mod units;
mod validate;

pub use ardupilot::{
    ArduPilotParameterError, MISSING_ROTOR_SPEEDS, actuator_lines, ardupilot_rotors,
    ardupilot_skeleton,
};
pub use contract_csv::DEFAULT_RANGE_BYTES;
pub use dataflash::{LogParameters, read_parameters};
pub use derive::DeriveOptions;
pub use error::{ErrorKind, IoError, Location, display_name};
pub use layout::LayoutReport;
pub use mapping::{
    ActuatorMap, BodyFrame, Frames, LoadsProcessing, Mapping, McapOptions, SignalMap, Signals,
    TopicTime, WorldFrame,
};
pub use open::{LogFormat, log_format, open_log};
pub use options::{InvalidSamples, ReadOptions};
pub use px4::{
    Px4ParameterError, Px4Rotor, layout_check, rotors_from_parameters, vehicle_skeleton,
};
pub use reader::LogReader;
pub use summary::AirborneSpan;
pub use summary::{Dropout, Gap, Summary};
pub use ulog::{LogDefinitions, read_definitions};

pub(crate) use derive::{JerkScratch, rotor_jerk};
use row_source::RowSource;
pub(crate) use validate::{QUATERNION_NORM_TOLERANCE, time_unit_suspect};

/// Largest rotor count the readers handle.
pub const MAX_ROTORS: usize = 16;

/// The two decoders of the MCAP reader that the crate's fuzz tests and ingest benchmark
/// drive directly, outside a log: a ROS 2 `.msg` schema (`ros2msg` encoding) and a CDR
/// message decoded by it into the JSON value the field paths address. Reading a log
/// needs neither ([`open_log`] does it); they are here for those checks only.
pub mod internals {
    pub use super::cdr::{CdrError, decode as decode_cdr};
    pub use super::ros2msg::{
        Schema as Ros2Schema, SchemaError as Ros2SchemaError, parse_schema as parse_ros2_schema,
    };
}
