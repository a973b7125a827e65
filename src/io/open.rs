//! [`open_log`]: the format chosen by the file's magic bytes, the options checked, the
//! source opened and the [`LogReader`] built over it.

use std::io::Read;
use std::path::Path;

use super::MAX_ROTORS;
use super::contract_csv::CsvSource;
use super::dataflash::{self, DataflashSource};
use super::error::{self, ErrorKind, IoError, Location};
use super::mapping::Mapping;
use super::mcap_read::McapSource;
use super::options::ReadOptions;
use super::reader::LogReader;
use super::row_source::RowSource;
use super::ulog::{self, UlogSource};
use crate::vehicle::Vehicle;

/// Opens a CSV (contract or mapped), MCAP, ULog or DataFlash log for streaming; the
/// format is chosen by the MCAP or ULog magic bytes or the DataFlash head bytes of a
/// leading `FMT` message. `mapping` is required for MCAP, ULog and DataFlash and for CSV
/// files that do not follow the contract.
pub fn open_log(
    path: &Path,
    vehicle: &Vehicle,
    mapping: Option<&Mapping>,
    options: &ReadOptions,
) -> Result<LogReader, IoError> {
    let file = error::display_name(path);
    let rotors = vehicle.rotor_count();
    if rotors > MAX_ROTORS {
        return Err(IoError::new(
            &file,
            Location::File,
            None,
            ErrorKind::Mapping(format!(
                "vehicle has {rotors} rotors, at most {MAX_ROTORS} supported"
            )),
        ));
    }
    let mut opts = *options;
    if let Some(d) = mapping.and_then(|m| m.derive) {
        opts.derive = d;
    }
    opts.derive.check().map_err(|e| {
        IoError::new(
            &file,
            Location::File,
            error::key("derive"),
            ErrorKind::Mapping(e.to_string()),
        )
    })?;
    if opts.max_gap.is_nan() || opts.max_gap <= 0.0 {
        return Err(IoError::new(
            &file,
            Location::File,
            None,
            ErrorKind::Mapping(format!("max_gap = {} s must be positive", opts.max_gap)),
        ));
    }
    let magic = log_format(path)
        .map_err(|e| IoError::new(&file, Location::File, None, ErrorKind::Read(e.to_string())))?;
    if magic != LogFormat::Csv {
        let what = match magic {
            LogFormat::Mcap => "an MCAP",
            LogFormat::Ulog => "a ULog",
            _ => "an ArduPilot DataFlash",
        };
        let mapping = mapping.ok_or_else(|| {
            IoError::new(
                &file,
                Location::File,
                None,
                ErrorKind::Mapping(format!(
                    "{what} log needs a mapping file naming topics and fields"
                )),
            )
        })?;
        let align_gap = mapping.mcap.align_gap.unwrap_or(opts.max_gap);
        if align_gap.is_nan() || align_gap <= 0.0 {
            return Err(IoError::new(
                &file,
                Location::File,
                error::key("mcap.align_gap"),
                ErrorKind::Mapping(format!("align_gap = {align_gap} s must be positive")),
            ));
        }
        let (source, layout): (Box<dyn RowSource>, _) = match magic {
            LogFormat::Mcap => {
                let (s, l) = McapSource::open(path, &file, mapping, rotors, align_gap)?;
                (Box::new(s), l)
            }
            LogFormat::Ulog => {
                let (s, l) = UlogSource::open(path, &file, mapping, rotors, align_gap)?;
                (Box::new(s), l)
            }
            _ => {
                let (s, l) = DataflashSource::open(path, &file, mapping, rotors, align_gap)?;
                (Box::new(s), l)
            }
        };
        return Ok(LogReader::new(
            source, layout, mapping, vehicle, opts, &file, true,
        ));
    }
    let (source, resolved, layout) = CsvSource::open(
        path,
        &file,
        mapping,
        rotors,
        opts.parse_threads,
        opts.range_bytes,
    )?;
    Ok(LogReader::new(
        Box::new(source),
        layout,
        &resolved,
        vehicle,
        opts,
        &file,
        false,
    ))
}

/// A log's format, from its first bytes (or its `.ulg`/`.bin` extension).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LogFormat {
    /// CSV text (contract or mapped), possibly gzip-compressed.
    Csv,
    /// MCAP.
    Mcap,
    /// PX4 ULog.
    Ulog,
    /// ArduPilot DataFlash (`.bin`).
    Dataflash,
}

/// The format of the file by its magic bytes (MCAP, ULog, DataFlash `FMT` head), whatever
/// its name (a ULog named `.bin` is a ULog); bytes of no format are CSV, except in a
/// `.ulg`, `.bin` or `.mcap` file, which is that format (so a corrupt one is told so). A
/// gzip-compressed `.ulg.gz`, `.bin.gz` or `.mcap.gz` is an error saying to decompress it
/// (only CSV is read compressed).
pub fn log_format(path: &Path) -> std::io::Result<LogFormat> {
    let mut magic = [0u8; 8];
    let mut f = std::fs::File::open(path)?;
    let mut n = 0;
    while n < 8 {
        let k = f.read(&mut magic[n..])?;
        if k == 0 {
            break;
        }
        n += k;
    }
    let named = |e: &str| path.extension().is_some_and(|x| x.eq_ignore_ascii_case(e));
    let inner = |e: &str| {
        named("gz")
            && Path::new(path.file_stem().unwrap_or_default())
                .extension()
                .is_some_and(|x| x.eq_ignore_ascii_case(e))
    };
    Ok(if n >= 5 && &magic[..5] == b"\x89MCAP" {
        LogFormat::Mcap
    } else if n >= 7 && magic[..7] == ulog::MAGIC {
        LogFormat::Ulog
    } else if n >= 3 && magic[..2] == dataflash::HEAD && magic[2] == dataflash::FMT_TYPE {
        LogFormat::Dataflash
    } else if n >= 2
        && magic[..2] == [0x1f, 0x8b]
        && ["ulg", "bin", "mcap"].iter().any(|e| inner(e))
    {
        return Err(std::io::Error::other(
            "a gzip-compressed ULog, DataFlash or MCAP log: decompress it first (gunzip); \
             only CSV logs are read compressed",
        ));
    } else if named("ulg") {
        LogFormat::Ulog
    } else if named("bin") {
        LogFormat::Dataflash
    } else if named("mcap") {
        LogFormat::Mcap
    } else {
        LogFormat::Csv
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A log is told by its first bytes whatever its name; a name decides only for bytes
    /// of no format; a compressed binary log is refused with what to do.
    #[test]
    fn a_log_s_format_is_its_content_then_its_name() {
        let dir = std::env::temp_dir().join(format!("mrsysid-log-format-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let format = |name: &str, bytes: &[u8]| {
            let path = dir.join(name);
            std::fs::write(&path, bytes).unwrap();
            log_format(&path)
        };
        let ulog = [&ulog::MAGIC[..], &[0; 9]].concat();
        let dataflash = [0xA3, 0x95, 0x80, 0x80, 0x59];
        assert_eq!(format("ulog.bin", &ulog).unwrap(), LogFormat::Ulog);
        assert_eq!(format("df.csv", &dataflash).unwrap(), LogFormat::Dataflash);
        assert_eq!(
            format("mcap.ulg", b"\x89MCAP0\r\n").unwrap(),
            LogFormat::Mcap
        );
        assert_eq!(format("text.bin", b"t,u\n").unwrap(), LogFormat::Dataflash);
        assert_eq!(format("text.csv", b"t,u\n").unwrap(), LogFormat::Csv);
        assert_eq!(
            format("log.csv.gz", &[0x1f, 0x8b, 8, 0]).unwrap(),
            LogFormat::Csv
        );
        let e = format("log.ulg.gz", &[0x1f, 0x8b, 8, 0]).unwrap_err();
        assert!(e.to_string().contains("decompress it first"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
