//! The CSV data contract (`docs/data-contract.md`), written compactly and atomically.
//!
//! Column order: `t,u,v,w,p,q,r,omega_1..omega_N`, then `fx,fy,fz,mx,my,mz` (unless the
//! log is IMU-only), `omega_dot_1..omega_dot_N`, `ax,ay,az`, `height`, `qw,qx,qy,qz` when
//! present. Numbers are rounded to [`SIGNIFICANT_DIGITS`] significant digits, time to
//! [`TIME_RESOLUTION`] (six significant digits would merge the samples of a 500 Hz log
//! from t = 1000 s on), and printed in Rust's shortest round-trip form, so output is
//! byte-for-byte reproducible.

use std::io::Write;
use std::path::{Path, PathBuf};

use crate::sample::SampleChunk;

/// Significant digits of every number written.
pub const SIGNIFICANT_DIGITS: usize = 6;

/// Resolution of the time column written, s: 1 µs (a ULog's clock).
pub const TIME_RESOLUTION: f64 = 1e-6;

/// A table of named columns of equal length.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct LogTable {
    /// (header name, values) in output order.
    pub columns: Vec<(String, Vec<f64>)>,
}

impl LogTable {
    /// The contract columns of `chunk`; the wrench columns only with `with_wrench`.
    pub fn from_chunk(chunk: &SampleChunk, with_wrench: bool) -> Self {
        let mut columns = vec![("t".to_string(), chunk.t.clone())];
        for (name, v) in ["u", "v", "w"].iter().zip(&chunk.velocity) {
            columns.push((name.to_string(), v.clone()));
        }
        for (name, v) in ["p", "q", "r"].iter().zip(&chunk.rates) {
            columns.push((name.to_string(), v.clone()));
        }
        for (i, v) in chunk.omega.iter().enumerate() {
            columns.push((format!("omega_{}", i + 1), v.clone()));
        }
        if with_wrench {
            for (name, v) in ["fx", "fy", "fz", "mx", "my", "mz"]
                .iter()
                .zip(&chunk.wrench)
            {
                columns.push((name.to_string(), v.clone()));
            }
        }
        for (i, v) in chunk.omega_dot.iter().flatten().enumerate() {
            columns.push((format!("omega_dot_{}", i + 1), v.clone()));
        }
        let mut table = Self { columns };
        if let Some(height) = &chunk.height {
            table.push("height", height.clone());
        }
        if let Some(attitude) = &chunk.attitude {
            for (name, v) in ["qw", "qx", "qy", "qz"].iter().zip(attitude) {
                table.push(name, v.clone());
            }
        }
        table
    }

    /// Appends a column.
    pub fn push(&mut self, name: &str, values: Vec<f64>) {
        self.columns.push((name.to_string(), values));
    }

    /// Inserts a column before the column called `before` (at the end if absent).
    pub fn insert_before(&mut self, before: &str, name: &str, values: Vec<f64>) {
        let at = self
            .columns
            .iter()
            .position(|(n, _)| n == before)
            .unwrap_or(self.columns.len());
        self.columns.insert(at, (name.to_string(), values));
    }

    /// Rows.
    pub fn len(&self) -> usize {
        self.columns.first().map_or(0, |c| c.1.len())
    }

    /// True without rows.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The CSV text.
    pub fn to_csv_bytes(&self) -> Vec<u8> {
        let mut out = Vec::with_capacity(self.len() * self.columns.len() * 11);
        let header: Vec<&str> = self.columns.iter().map(|(n, _)| n.as_str()).collect();
        out.extend_from_slice(header.join(",").as_bytes());
        out.push(b'\n');
        for k in 0..self.len() {
            for (j, (name, v)) in self.columns.iter().enumerate() {
                if j > 0 {
                    out.push(b',');
                }
                let x = if name == "t" {
                    round_time(v[k])
                } else {
                    round_significant(v[k])
                };
                // Writing into a Vec cannot fail.
                let _ = write!(out, "{x}");
            }
            out.push(b'\n');
        }
        out
    }

    /// Writes the CSV to `path` atomically: a temporary file in the same directory,
    /// flushed and renamed over `path`, so a failed run leaves no partial file.
    pub fn write_csv(&self, path: &Path) -> Result<(), CsvWriteError> {
        crate::util::write_atomically(path, &self.to_csv_bytes()).map_err(|source| CsvWriteError {
            path: path.to_path_buf(),
            source,
        })
    }
}

/// Time `t` (s) rounded to [`TIME_RESOLUTION`]: the nearest double to the decimal with
/// six decimals, as parsing the written text gives (−0 becomes 0).
pub fn round_time(t: f64) -> f64 {
    let micro = (t / TIME_RESOLUTION).round();
    if micro == 0.0 || !micro.is_finite() {
        return if micro == 0.0 { 0.0 } else { t };
    }
    // An integer count of µs over 10⁶, both exact: one correctly rounded division.
    micro / 1e6
}

/// A log CSV that could not be written.
#[derive(Debug, thiserror::Error)]
#[error("{}: cannot write: {source}", path.display())]
pub struct CsvWriteError {
    /// The file.
    pub path: PathBuf,
    /// The operating system's error.
    pub source: std::io::Error,
}

/// `x` rounded to [`SIGNIFICANT_DIGITS`] significant digits (−0 becomes 0).
pub fn round_significant(x: f64) -> f64 {
    if x == 0.0 || !x.is_finite() {
        return if x == 0.0 { 0.0 } else { x };
    }
    let s = format!("{:.*e}", SIGNIFICANT_DIGITS - 1, x);
    s.parse().unwrap_or(x)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Six significant digits wrote t = 1000, 1000.002 and 1000.004 s of a 500 Hz log
    /// all as `1000` (a duplicate timestamp the reader refuses); times are written to the
    /// µs, and a time with six or fewer significant digits is written as before.
    #[test]
    fn times_are_written_to_the_microsecond() {
        let t: Vec<f64> = (499_999..500_003).map(|k| k as f64 * 0.002).collect();
        let table = LogTable {
            columns: vec![("t".into(), t), ("u".into(), vec![1.234_567_89; 4])],
        };
        let text = String::from_utf8(table.to_csv_bytes()).expect("utf-8");
        assert_eq!(
            text,
            "t,u\n999.998,1.23457\n1000,1.23457\n1000.002,1.23457\n1000.004,1.23457\n"
        );
        for t in [0.0, 0.01, 0.07, 29.99, 59.998, 123.456, 1999.0] {
            assert_eq!(round_time(t), round_significant(t), "{t}");
        }
    }
}
