//! Parsed samples of a log file, spilled once to a temporary binary file during the
//! first pass so that the second pass (residual diagnostics, plot series, candidate
//! statistics) streams them back instead of tokenising and parsing the text again.
//!
//! Design choice (issue 12, item 1): a spill rather than one-pass sufficient statistics.
//! Everything the second pass computes depends on θ̂, known only after the first pass:
//! residuals, their histogram, normal-probability plot and autocorrelation, plot
//! predictions, and the candidate effects (built from θ̂ and screened on the first pass's
//! thinned sample). Making them one-pass would change what they are (histogram bins fixed
//! before the residual scale is known, candidate columns chosen before θ̂) and so the
//! reports; the spill keeps the second pass exactly as it was: the same 1024-sample chunks
//! in the same order, hence bit-identical results. Its cost is a write and a read of
//! 8 bytes per value (168 B per sample of a quad× log with rotor accelerations, about the
//! size of its CSV text: 1.7 GB of temp space for 10 M rows), memory copies through the
//! page cache instead of tokenising and ~21 float parses per sample.
//!
//! Format: per chunk, two little-endian u32 (rotor-speed and rotor-acceleration series
//! counts), then every vector of the [`SampleChunk`] in field order, each as a
//! little-endian u64 length followed by that many little-endian f64. The file lives in
//! [`std::env::temp_dir`] (`TMPDIR`) and is removed when its [`Spill`] is dropped, also
//! on an error or a panic unwinding through the pipeline.

use std::fs::{File, OpenOptions};
use std::io::{BufReader, BufWriter, Read, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use crate::CHUNK_SAMPLES;
use crate::error::Error;
use crate::sample::SampleChunk;

/// Buffer of the spill writer and reader, bytes.
const BUFFER_BYTES: usize = 1 << 18;

/// Most rotor series a chunk read back may claim (guards against a corrupted file).
const MAX_ROTORS: u32 = 64;

/// A spill file on disk; removes it when dropped.
#[derive(Debug)]
pub(crate) struct Spill {
    path: PathBuf,
}

impl Drop for Spill {
    fn drop(&mut self) {
        // Nothing useful to do if it is already gone.
        let _ = std::fs::remove_file(&self.path);
    }
}

/// The error naming the spill file at `path`.
fn spill_error(path: &Path) -> impl Fn(std::io::Error) -> Error + '_ {
    move |source| Error::Spill {
        path: path.to_path_buf(),
        source,
    }
}

/// A unique new file name in the temp dir (process id and a per-process counter).
fn new_path() -> PathBuf {
    static NEXT: AtomicU64 = AtomicU64::new(0);
    let n = NEXT.fetch_add(1, Ordering::Relaxed);
    std::env::temp_dir().join(format!("mrsysid-spill-{}-{n}.bin", std::process::id()))
}

/// Writes chunks to a new spill file.
pub(crate) struct SpillWriter {
    // Declared first: the file is closed before the guard removes it.
    out: BufWriter<File>,
    spill: Spill,
    bytes: Vec<u8>,
}

impl SpillWriter {
    /// Creates a new spill file in the temp dir.
    pub(crate) fn create() -> Result<Self, Error> {
        let path = new_path();
        let file = OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(&path)
            .map_err(spill_error(&path))?;
        Ok(Self {
            out: BufWriter::with_capacity(BUFFER_BYTES, file),
            spill: Spill { path },
            bytes: Vec::new(),
        })
    }

    /// Appends `chunk`.
    pub(crate) fn write(&mut self, chunk: &SampleChunk) -> Result<(), Error> {
        let b = &mut self.bytes;
        b.clear();
        b.extend_from_slice(&(chunk.omega.len() as u32).to_le_bytes());
        b.extend_from_slice(&(chunk.omega_dot.len() as u32).to_le_bytes());
        for v in vectors(chunk) {
            b.extend_from_slice(&(v.len() as u64).to_le_bytes());
            for x in v {
                b.extend_from_slice(&x.to_le_bytes());
            }
        }
        self.out
            .write_all(&self.bytes)
            .map_err(spill_error(&self.spill.path))
    }

    /// Flushes the file; the spill is then ready to be read back.
    pub(crate) fn finish(mut self) -> Result<Spill, Error> {
        self.out.flush().map_err(spill_error(&self.spill.path))?;
        let Self { out, spill, .. } = self;
        drop(out);
        Ok(spill)
    }
}

/// The vectors of `chunk` in file order.
fn vectors(c: &SampleChunk) -> impl Iterator<Item = &Vec<f64>> {
    std::iter::once(&c.t)
        .chain(&c.velocity)
        .chain(&c.rates)
        .chain(&c.omega)
        .chain(&c.omega_dot)
        .chain(&c.wrench)
        .chain(std::iter::once(&c.height))
        .chain(&c.attitude)
}

/// The vectors of `chunk` in file order, for filling.
fn vectors_mut(c: &mut SampleChunk) -> impl Iterator<Item = &mut Vec<f64>> {
    std::iter::once(&mut c.t)
        .chain(&mut c.velocity)
        .chain(&mut c.rates)
        .chain(&mut c.omega)
        .chain(&mut c.omega_dot)
        .chain(&mut c.wrench)
        .chain(std::iter::once(&mut c.height))
        .chain(&mut c.attitude)
}

impl Spill {
    /// Reads the chunks back in the order written, handing each to `consume` (one chunk
    /// in memory at a time).
    pub(crate) fn stream(
        &self,
        mut consume: impl FnMut(&SampleChunk) -> Result<(), Error>,
    ) -> Result<(), Error> {
        let fail = spill_error(&self.path);
        let file = File::open(&self.path).map_err(&fail)?;
        let mut input = BufReader::with_capacity(BUFFER_BYTES, file);
        let mut chunk = SampleChunk::default();
        let mut bytes = Vec::new();
        while let Some(counts) = read_counts(&mut input).map_err(&fail)? {
            read_chunk(&mut input, counts, &mut chunk, &mut bytes).map_err(&fail)?;
            consume(&chunk)?;
        }
        Ok(())
    }
}

/// The two rotor-series counts opening a chunk; `None` at the end of the file.
fn read_counts(input: &mut impl Read) -> std::io::Result<Option<[usize; 2]>> {
    let mut head = [0u8; 8];
    let got = input.read(&mut head[..1])?;
    if got == 0 {
        return Ok(None);
    }
    input.read_exact(&mut head[1..])?;
    let count = |b: &[u8]| u32::from_le_bytes([b[0], b[1], b[2], b[3]]);
    let (omega, omega_dot) = (count(&head[..4]), count(&head[4..]));
    if omega > MAX_ROTORS || omega_dot > MAX_ROTORS {
        return Err(corrupt("rotor series count out of range"));
    }
    Ok(Some([omega as usize, omega_dot as usize]))
}

/// Reads one chunk's vectors into `chunk` (its allocations reused); `bytes` is scratch.
fn read_chunk(
    input: &mut impl Read,
    [omega, omega_dot]: [usize; 2],
    chunk: &mut SampleChunk,
    bytes: &mut Vec<u8>,
) -> std::io::Result<()> {
    chunk.omega.resize_with(omega, Vec::new);
    chunk.omega_dot.resize_with(omega_dot, Vec::new);
    for v in vectors_mut(chunk) {
        let mut len = [0u8; 8];
        input.read_exact(&mut len)?;
        let len = u64::from_le_bytes(len);
        if len > CHUNK_SAMPLES as u64 {
            return Err(corrupt("vector longer than a chunk"));
        }
        bytes.resize(len as usize * 8, 0);
        input.read_exact(bytes)?;
        v.clear();
        v.extend(
            bytes
                .chunks_exact(8)
                .map(|b| f64::from_le_bytes(b.try_into().expect("chunks_exact gives 8 bytes"))),
        );
    }
    Ok(())
}

fn corrupt(what: &str) -> std::io::Error {
    std::io::Error::new(std::io::ErrorKind::InvalidData, what)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sample::Sample;

    fn sample(k: usize, rotors: usize) -> Sample {
        let x = k as f64 * 0.1 - 3.0;
        Sample {
            t: x,
            velocity: [x, -x, f64::MIN_POSITIVE * x],
            rates: [x.sin(), -0.0, 1e300 * x],
            omega: (0..rotors).map(|r| 100.0 + r as f64 + x).collect(),
            omega_dot: vec![],
            wrench: [x; 6],
            height: Some(x.abs()),
            attitude: Some([1.0, 0.0, x * 1e-3, -x * 1e-3]),
        }
    }

    /// Bit for bit: the spill stores the f64 bytes themselves (−0, subnormals, 1e300
    /// included), chunk by chunk in order, and the file is gone after the drop.
    #[test]
    fn chunks_come_back_bit_for_bit_and_the_file_is_removed() {
        let mut chunks = Vec::new();
        for (len, rotors) in [(CHUNK_SAMPLES, 4), (3, 6), (1, 4)] {
            let mut c = SampleChunk::with_capacity(rotors, len, false);
            for k in 0..len {
                c.push(&sample(k, rotors));
            }
            chunks.push(c);
        }
        let mut writer = SpillWriter::create().expect("create");
        for c in &chunks {
            writer.write(c).expect("write");
        }
        let spill = writer.finish().expect("finish");
        let path = spill.path.clone();
        let mut back = Vec::new();
        spill
            .stream(|c| {
                back.push(c.clone());
                Ok(())
            })
            .expect("read back");
        assert_eq!(back.len(), chunks.len());
        for (a, b) in chunks.iter().zip(&back) {
            let bits = |c: &SampleChunk| -> Vec<u64> {
                vectors(c).flatten().map(|x| x.to_bits()).collect()
            };
            assert_eq!(bits(a), bits(b));
            assert_eq!(a.signals(), b.signals());
        }
        drop(spill);
        assert!(!path.exists(), "spill file left behind");
    }

    /// A truncated file is an error naming it, not a panic or a short read.
    #[test]
    fn a_truncated_spill_is_an_error_naming_the_file() {
        let mut c = SampleChunk::with_capacity(4, 8, false);
        for k in 0..8 {
            c.push(&sample(k, 4));
        }
        let mut writer = SpillWriter::create().expect("create");
        writer.write(&c).expect("write");
        let spill = writer.finish().expect("finish");
        let len = std::fs::metadata(&spill.path).expect("spill").len();
        let file = OpenOptions::new()
            .write(true)
            .open(&spill.path)
            .expect("open");
        file.set_len(len - 5).expect("truncate");
        let err = spill.stream(|_| Ok(())).expect_err("truncated");
        let text = err.to_string();
        assert!(text.contains("mrsysid-spill-"), "{text}");
    }

    /// A failed write is dropped without leaving the file behind.
    #[test]
    fn an_unfinished_spill_is_removed() {
        let writer = SpillWriter::create().expect("create");
        let path = writer.spill.path.clone();
        assert!(path.exists());
        drop(writer);
        assert!(!path.exists());
    }
}
