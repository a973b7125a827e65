//! Streaming CSV source: one `csv::ByteRecord` reused for every row, only the mapped
//! columns parsed, so memory is bounded whatever the file size.

use std::fs::File;
use std::io::BufReader;
use std::path::Path;

use super::RowSource;
use super::error::{ErrorKind, IoError, Location, column};
use super::mapping::{Mapping, contract_mapping};
use super::slots::SlotLayout;

/// A CSV file read row by row into the slot layout of its mapping.
pub struct CsvSource {
    file: String,
    reader: csv::Reader<BufReader<File>>,
    record: csv::ByteRecord,
    /// Header column index of each slot.
    column_of_slot: Vec<usize>,
    /// Header names, for error labels.
    header: Vec<String>,
}

impl CsvSource {
    /// Opens `path`, reads the header and resolves the mapping (the contract mapping
    /// when `mapping` is `None`) for a vehicle with `rotors` rotors.
    pub fn open(
        path: &Path,
        file: &str,
        mapping: Option<&Mapping>,
        rotors: usize,
    ) -> Result<(Self, Mapping, SlotLayout), IoError> {
        let handle = File::open(path).map_err(|e| {
            IoError::new(file, Location::File, None, ErrorKind::Read(e.to_string()))
        })?;
        let mut reader = csv::ReaderBuilder::new()
            .flexible(true)
            .buffer_capacity(1 << 16)
            .from_reader(BufReader::with_capacity(1 << 16, handle));
        let header_record = reader
            .byte_headers()
            .map_err(|e| csv_error(file, &e))?
            .clone();
        if header_record.is_empty() || header_record.iter().all(|f| f.is_empty()) {
            return Err(IoError::new(
                file,
                Location::Line(1),
                None,
                ErrorKind::Empty,
            ));
        }
        let mut header = Vec::with_capacity(header_record.len());
        for (i, field) in header_record.iter().enumerate() {
            let name = std::str::from_utf8(field).map_err(|_| {
                IoError::new(
                    file,
                    Location::Line(1),
                    None,
                    ErrorKind::Format(format!("header field {} is not valid UTF-8", i + 1)),
                )
            })?;
            // A UTF-8 byte-order mark (spreadsheet exports) is not part of the first name.
            header.push(name.trim_start_matches('\u{feff}').trim().to_string());
        }
        let names: Vec<&str> = header.iter().map(String::as_str).collect();
        let mapping = match mapping {
            Some(m) => m.clone(),
            None => contract_mapping(&names, rotors, file)?,
        };
        let layout = SlotLayout::resolve(&mapping, rotors, file, false)?;
        let mut column_of_slot = Vec::with_capacity(layout.len());
        for slot in 0..layout.len() {
            let name = layout.source_name(slot);
            let idx = names.iter().position(|h| *h == name).ok_or_else(|| {
                IoError::new(
                    file,
                    Location::Line(1),
                    column(name),
                    ErrorKind::MissingSignal(format!(
                        "column of {} not in the header",
                        layout.signal_of_slot(slot).key()
                    )),
                )
            })?;
            column_of_slot.push(idx);
        }
        let source = Self {
            file: file.to_string(),
            reader,
            record: csv::ByteRecord::new(),
            column_of_slot,
            header,
        };
        Ok((source, mapping, layout))
    }
}

fn csv_error(file: &str, e: &csv::Error) -> IoError {
    let line = e
        .position()
        .map_or(Location::File, |p| Location::Line(p.line()));
    let kind = match e.kind() {
        csv::ErrorKind::Io(io) => ErrorKind::Read(io.to_string()),
        csv::ErrorKind::Utf8 { .. } => ErrorKind::Format("not valid UTF-8".into()),
        _ => ErrorKind::Format(e.to_string()),
    };
    IoError::new(file, line, None, kind)
}

impl RowSource for CsvSource {
    fn file(&self) -> &str {
        &self.file
    }

    fn next_row(&mut self, raw: &mut [f64]) -> Result<Option<(Location, Option<f64>)>, IoError> {
        loop {
            let more = self
                .reader
                .read_byte_record(&mut self.record)
                .map_err(|e| csv_error(&self.file, &e))?;
            if !more {
                return Ok(None);
            }
            let line = self.record.position().map_or(0, |p| p.line());
            let loc = Location::Line(line);
            // A blank line (single empty field) is skipped like the csv crate does.
            if self.record.len() == 1 && self.record[0].is_empty() {
                continue;
            }
            if self.record.len() != self.header.len() {
                return Err(IoError::new(
                    &self.file,
                    loc,
                    None,
                    ErrorKind::Format(format!(
                        "row has {} fields, header has {}",
                        self.record.len(),
                        self.header.len()
                    )),
                ));
            }
            for (slot, &col) in self.column_of_slot.iter().enumerate() {
                raw[slot] = parse_field(&self.record[col]).map_err(|text| {
                    IoError::new(
                        &self.file,
                        loc,
                        column(&self.header[col]),
                        ErrorKind::NotANumber(text),
                    )
                })?;
            }
            return Ok(Some((loc, None)));
        }
    }
}

/// Parses one CSV field as f64 (surrounding spaces allowed); the error carries the text.
fn parse_field(bytes: &[u8]) -> Result<f64, String> {
    let text =
        std::str::from_utf8(bytes).map_err(|_| String::from_utf8_lossy(bytes).into_owned())?;
    let padded = bytes.first().is_some_and(u8::is_ascii_whitespace)
        || bytes.last().is_some_and(u8::is_ascii_whitespace);
    let number = if padded { text.trim() } else { text };
    number.parse::<f64>().map_err(|_| text.to_string())
}

/// Writes samples as a DESIGN.md contract CSV (header `t,u,v,w,p,q,r,omega_1..N,
/// [omega_dot_1..N,]fx,fy,fz,mx,my,mz[,height][,qw,qx,qy,qz]`), shortest round-trip
/// float formatting so reading back gives identical values.
pub fn write_contract_csv<'a>(
    path: &Path,
    chunks: impl IntoIterator<Item = &'a crate::sample::SampleChunk>,
) -> std::io::Result<()> {
    use std::io::Write;
    let mut out = std::io::BufWriter::new(File::create(path)?);
    let mut header_written = false;
    let mut line = String::new();
    for c in chunks {
        if !header_written {
            let mut h = String::from("t,u,v,w,p,q,r");
            for i in 1..=c.rotor_count() {
                h += &format!(",omega_{i}");
            }
            for i in 1..=c.omega_dot.len() {
                h += &format!(",omega_dot_{i}");
            }
            h += ",fx,fy,fz,mx,my,mz";
            if !c.height.is_empty() {
                h += ",height";
            }
            if !c.attitude[0].is_empty() {
                h += ",qw,qx,qy,qz";
            }
            writeln!(out, "{h}")?;
            header_written = true;
        }
        for k in 0..c.len() {
            line.clear();
            let mut put = |v: f64| {
                if !line.is_empty() {
                    line.push(',');
                }
                line.push_str(&format!("{v:?}"));
            };
            put(c.t[k]);
            c.velocity.iter().for_each(|v| put(v[k]));
            c.rates.iter().for_each(|v| put(v[k]));
            c.omega.iter().for_each(|v| put(v[k]));
            c.omega_dot.iter().for_each(|v| put(v[k]));
            c.wrench.iter().for_each(|v| put(v[k]));
            if !c.height.is_empty() {
                put(c.height[k]);
            }
            if !c.attitude[0].is_empty() {
                c.attitude.iter().for_each(|v| put(v[k]));
            }
            writeln!(out, "{line}")?;
        }
    }
    out.flush()
}
