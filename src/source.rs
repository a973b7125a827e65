//! Where a fit's samples come from: a log file (read by [`crate::io`]) or samples
//! already in memory, checked once at this boundary so that nothing downstream can
//! meet a malformed sample.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use crate::io::{ErrorKind, IoError, Location, QUATERNION_NORM_TOLERANCE, display_name};
use crate::sample::{CHUNK_SAMPLES, Sample, SampleChunk, Signals};

/// One log of a fit: a file, or samples in memory.
#[derive(Debug, Clone)]
pub enum LogSource {
    /// A log file (CSV contract or mapped CSV, MCAP, ULog), read by [`crate::io`].
    File(PathBuf),
    /// Samples in memory, already checked by [`MemoryLog`].
    Memory(Arc<MemoryLog>),
}

impl LogSource {
    /// Display name: the file name, or the memory log's name.
    pub fn name(&self) -> String {
        match self {
            Self::File(path) => display_name(path),
            Self::Memory(log) => log.name.clone(),
        }
    }
}

impl From<PathBuf> for LogSource {
    fn from(path: PathBuf) -> Self {
        Self::File(path)
    }
}

impl From<&Path> for LogSource {
    fn from(path: &Path) -> Self {
        Self::File(path.to_path_buf())
    }
}

impl From<&str> for LogSource {
    fn from(path: &str) -> Self {
        Self::File(path.into())
    }
}

impl From<MemoryLog> for LogSource {
    fn from(log: MemoryLog) -> Self {
        Self::Memory(Arc::new(log))
    }
}

/// A log held in memory: consecutive samples in chunks, every one checked against the
/// data contract (`docs/data-contract.md`): all signals of a sample present, finite
/// values, time strictly increasing, rotor speeds ≥ 0 rad/s, attitude quaternions of
/// unit norm, the same rotor count and optional signals in every sample.
#[derive(Debug, Clone, PartialEq)]
pub struct MemoryLog {
    name: String,
    chunks: Vec<SampleChunk>,
    samples: u64,
}

impl MemoryLog {
    /// A log named `name` (the name errors and reports use) from `samples` in time order.
    /// The first sample fixes the rotor count and which optional signals (Ω̇, height,
    /// attitude) every sample must carry.
    pub fn from_samples(
        name: &str,
        samples: impl IntoIterator<Item = Sample>,
    ) -> Result<Self, IoError> {
        let mut log = Self::empty(name);
        let mut shape: Option<Signals> = None;
        let mut chunk: Option<SampleChunk> = None;
        for (k, s) in samples.into_iter().enumerate() {
            let expected = *shape.get_or_insert_with(|| s.signals());
            expected.check(name, k as u64, &s)?;
            let c = chunk.get_or_insert_with(|| expected.chunk());
            c.push(&s);
            if c.len() == CHUNK_SAMPLES {
                log.append(chunk.take().expect("chunk in progress"))?;
            }
        }
        if let Some(c) = chunk {
            log.append(c)?;
        }
        Ok(log)
    }

    /// A log named `name` from consecutive `chunks` (each in the layout of
    /// [`SampleChunk`]: every signal vector of one length), every one carrying the same
    /// rotor count and optional signals.
    pub fn from_chunks(
        name: &str,
        chunks: impl IntoIterator<Item = SampleChunk>,
    ) -> Result<Self, IoError> {
        let mut log = Self::empty(name);
        for c in chunks {
            log.append(c)?;
        }
        Ok(log)
    }

    fn empty(name: &str) -> Self {
        Self {
            name: name.to_string(),
            chunks: Vec::new(),
            samples: 0,
        }
    }

    /// The log's name.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Number of samples.
    pub fn len(&self) -> u64 {
        self.samples
    }

    /// True when the log holds no sample.
    pub fn is_empty(&self) -> bool {
        self.samples == 0
    }

    /// The checked chunks, in time order.
    pub fn chunks(&self) -> &[SampleChunk] {
        &self.chunks
    }

    /// Checks `c` (whose first sample is number `self.samples`) and appends it.
    fn append(&mut self, c: SampleChunk) -> Result<(), IoError> {
        if c.is_empty() {
            return Ok(());
        }
        let first = self.samples;
        let err = |k: usize, field: &str, kind: ErrorKind| {
            IoError::new(
                &self.name,
                Location::Sample(first + k as u64),
                Some(format!("signal {field:?}")),
                kind,
            )
        };
        c.check_lengths().map_err(|e| {
            IoError::new(
                &self.name,
                Location::Sample(first),
                Some(format!("signal {:?}", e.signal)),
                ErrorKind::Format(e.problem),
            )
        })?;
        if let Some(prev) = self.chunks.last() {
            check_same_signals(prev, &c).map_err(|kind| err(0, "chunk", kind))?;
        }
        check_values(&c, self.last_time()).map_err(|(k, field, kind)| err(k, &field, kind))?;
        self.samples += c.len() as u64;
        self.chunks.push(c);
        Ok(())
    }

    fn last_time(&self) -> Option<f64> {
        self.chunks.last().and_then(|c| c.t.last().copied())
    }
}

/// What a log of `signals` needs per sample.
trait Expected {
    /// An empty chunk with these signals.
    fn chunk(self) -> SampleChunk;
    /// Sample `k` of log `name` carries these signals.
    fn check(self, name: &str, k: u64, s: &Sample) -> Result<(), IoError>;
}

impl Expected for Signals {
    fn chunk(self) -> SampleChunk {
        SampleChunk::with_capacity(self.rotors, CHUNK_SAMPLES, self.omega_dot)
    }

    fn check(self, name: &str, k: u64, s: &Sample) -> Result<(), IoError> {
        let err = |field: &str, m: String| {
            IoError::new(
                name,
                Location::Sample(k),
                Some(format!("signal {field:?}")),
                ErrorKind::Format(m),
            )
        };
        if s.omega.len() != self.rotors {
            return Err(err(
                "omega",
                format!(
                    "{} rotor speeds where the log's first sample has {}",
                    s.omega.len(),
                    self.rotors
                ),
            ));
        }
        let want = if self.omega_dot { self.rotors } else { 0 };
        if s.omega_dot.len() != want {
            return Err(err(
                "omega_dot",
                format!(
                    "{} rotor accelerations where the log has {want}",
                    s.omega_dot.len()
                ),
            ));
        }
        let presence = |has: bool, in_log: bool, field: &str| {
            if has == in_log {
                return Ok(());
            }
            let word = |b: bool| if b { "present" } else { "absent" };
            Err(err(
                field,
                format!(
                    "{} here but {} in the log's first sample (an optional signal is in every sample or in none)",
                    word(has),
                    word(in_log)
                ),
            ))
        };
        presence(s.height.is_some(), self.height, "height")?;
        presence(s.attitude.is_some(), self.attitude, "attitude")
    }
}

/// `c` carries the same rotor count and optional signals as `prev`.
fn check_same_signals(prev: &SampleChunk, c: &SampleChunk) -> Result<(), ErrorKind> {
    let (was, is) = (prev.signals(), c.signals());
    if was == is {
        Ok(())
    } else {
        Err(ErrorKind::Format(format!(
            "this chunk carries {is:?}, the previous chunk {was:?}"
        )))
    }
}

/// Finite values, time strictly increasing (from `previous`), Ω ≥ 0 and unit
/// quaternions; the first violation as (sample, field, what).
fn check_values(c: &SampleChunk, previous: Option<f64>) -> Result<(), (usize, String, ErrorKind)> {
    let mut series: Vec<(String, &[f64])> = vec![("t".into(), &c.t)];
    let names = ["u", "v", "w", "p", "q", "r"];
    for (k, v) in c.velocity.iter().chain(&c.rates).enumerate() {
        series.push((names[k].into(), v));
    }
    for (i, w) in c.omega.iter().enumerate() {
        series.push((format!("omega{}", i + 1), w));
    }
    for (i, w) in c.omega_dot.iter().flatten().enumerate() {
        series.push((format!("omega_dot{}", i + 1), w));
    }
    for (k, name) in ["fx", "fy", "fz", "mx", "my", "mz"].iter().enumerate() {
        series.push((name.to_string(), &c.wrench[k]));
    }
    if let Some(height) = &c.height {
        series.push(("height".into(), height));
    }
    if let Some(q) = &c.attitude {
        for (k, name) in ["qw", "qx", "qy", "qz"].iter().enumerate() {
            series.push((name.to_string(), &q[k]));
        }
    }
    for (name, v) in &series {
        if let Some(k) = v.iter().position(|x| !x.is_finite()) {
            return Err((k, name.clone(), ErrorKind::NotFinite(v[k])));
        }
    }
    let mut before = previous;
    for (k, &t) in c.t.iter().enumerate() {
        if let Some(p) = before.filter(|&p| t <= p) {
            return Err((k, "t".into(), ErrorKind::Time { t, previous: p }));
        }
        before = Some(t);
    }
    for (i, w) in c.omega.iter().enumerate() {
        if let Some(k) = w.iter().position(|&x| x < 0.0) {
            return Err((
                k,
                format!("omega{}", i + 1),
                ErrorKind::OutOfRange {
                    value: w[k],
                    range: "[0, ∞) rad/s (rotor speed magnitudes)".into(),
                },
            ));
        }
    }
    if let Some(attitude) = &c.attitude {
        for k in 0..c.len() {
            let norm = attitude.iter().map(|q| q[k] * q[k]).sum::<f64>().sqrt();
            if (norm - 1.0).abs() > QUATERNION_NORM_TOLERANCE {
                return Err((
                    k,
                    "attitude".into(),
                    ErrorKind::OutOfRange {
                        value: norm,
                        range: format!("quaternion norm 1 ± {QUATERNION_NORM_TOLERANCE}"),
                    },
                ));
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample(t: f64, rotors: usize) -> Sample {
        Sample {
            t,
            omega: vec![500.0; rotors],
            ..Sample::default()
        }
    }

    #[test]
    fn samples_are_chunked_and_checked_at_the_boundary() {
        let n = CHUNK_SAMPLES + 5;
        let log = MemoryLog::from_samples("mem", (0..n).map(|k| sample(k as f64 * 0.01, 4)))
            .expect("valid samples");
        assert_eq!(log.len(), n as u64);
        assert_eq!(
            log.chunks()
                .iter()
                .map(SampleChunk::len)
                .collect::<Vec<_>>(),
            [CHUNK_SAMPLES, 5]
        );
        // Three rotor speeds in a four-rotor log, named by sample index.
        let bad = (0..10).map(|k| sample(k as f64, if k == 7 { 3 } else { 4 }));
        let e = MemoryLog::from_samples("mem", bad).unwrap_err();
        assert_eq!(e.location, Location::Sample(7));
        assert!(e.to_string().contains("3 rotor speeds"), "{e}");
        // Time going back across a chunk boundary.
        let t = |k: usize| if k == n - 1 { 0.0 } else { k as f64 };
        let e = MemoryLog::from_samples("mem", (0..n).map(|k| sample(t(k), 4))).unwrap_err();
        assert_eq!(e.location, Location::Sample(n as u64 - 1));
        // NaN, and a chunk with a short series.
        let mut s = sample(0.0, 4);
        s.rates[1] = f64::NAN;
        let e = MemoryLog::from_samples("mem", [s]).unwrap_err();
        assert_eq!(
            e.to_string(),
            "mem: sample 0, signal \"q\": not a finite number (NaN)"
        );
        let mut c = SampleChunk::with_capacity(4, 2, false);
        c.push(&sample(0.0, 4));
        c.push(&sample(1.0, 4));
        c.wrench[3].pop();
        let e = MemoryLog::from_chunks("mem", [c]).unwrap_err();
        assert!(e.to_string().contains("\"mx\": 1 values for 2"), "{e}");
    }
}
