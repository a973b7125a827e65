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
//! reports; the spill keeps the second pass as it was: the same 1024-sample chunks in the
//! same order (passed in segments, see below). Its cost is a write and a read of
//! 8 bytes per value (200 B per sample of a quad× log with rotor accelerations, a little
//! more than its CSV text: 2 GB of temp space for 10 M rows), memory copies through the
//! page cache instead of tokenising and ~21 float parses per sample. The rates of rotor
//! acceleration Ω̈ derived in the first pass are spilled too: reading 32 B per sample
//! back costs less than differentiating again; so are the slow rotor thrusts of a
//! diagnosis (96 B per sample of a quad×), which need seconds of samples around each.
//!
//! Format: per chunk, six little-endian u32 (the series counts of rotor speed, rotor
//! acceleration, its rate, slow thrust, height and attitude; [`ABSENT`] for an optional
//! signal the chunk does not carry), then every vector of the [`SampleChunk`] it
//! carries in field order, each as a little-endian u64 length followed by that many
//! little-endian f64. The file
//! lives in [`std::env::temp_dir`] (`TMPDIR`). On Unix its name is removed as soon as it
//! is open (the space is freed when the process ends, however it ends: Ctrl-C or a kill
//! leave nothing behind); elsewhere it is removed when its [`Spill`] is dropped, also on
//! an error or a panic unwinding through the pipeline.
//!
//! The spill keeps where each chunk starts and the caller's tally of the samples before
//! it, so that any run of chunks can be read back on its own (segments of the second
//! pass, on several threads) and its results placed in order.

use std::fs::{File, OpenOptions};
use std::io::{BufReader, BufWriter, Read, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use crate::error::Error;
use crate::sample::{CHUNK_SAMPLES, SampleChunk};

/// Buffer of the spill writer and reader, bytes.
const BUFFER_BYTES: usize = 1 << 18;

/// Most rotor series a chunk read back may claim, 64 rotors in every band (guards
/// against a corrupted file).
const MAX_ROTORS: u32 = 64 * crate::sample::TRIM_BANDS_HZ.len() as u32;

/// The series count of an optional signal a chunk does not carry.
const ABSENT: u32 = u32::MAX;

/// The series counts opening a chunk: rotor speeds Ω, then the optional signals Ω̇, Ω̈,
/// slow Ω² (1 series per rotor, per rotor and band), height (1) and attitude (4), `None`
/// when absent.
#[derive(Debug, Clone, Copy)]
struct Counts {
    omega: usize,
    optional: [Option<usize>; 5],
}

impl Counts {
    /// The counts of `c`.
    fn of(c: &SampleChunk) -> Self {
        let rotors = |s: &Option<Vec<Vec<f64>>>| s.as_ref().map(Vec::len);
        Self {
            omega: c.omega.len(),
            optional: [
                rotors(&c.omega_dot),
                rotors(&c.omega_ddot),
                rotors(&c.omega_squared_slow),
                c.height.as_ref().map(|_| 1),
                c.attitude.as_ref().map(|q| q.len()),
            ],
        }
    }

    /// The counts as written, [`ABSENT`] for a signal not carried.
    fn to_le_bytes(self) -> impl Iterator<Item = [u8; 4]> {
        let optional = self.optional.map(|n| n.map_or(ABSENT, |n| n as u32));
        std::iter::once(self.omega as u32)
            .chain(optional)
            .map(u32::to_le_bytes)
    }
}

/// A spill file; removes it when dropped.
#[derive(Debug)]
pub(crate) struct Spill {
    /// Read handle (positional reads: segments are read on several threads at once);
    /// `None` only while the spill is dropped.
    file: Option<File>,
    /// Its name in the temp dir (for messages; already removed on Unix).
    path: PathBuf,
    /// Whether the name still has to be removed.
    named: bool,
    chunks: Vec<Mark>,
}

/// Where a chunk of the spill starts, and what came before it.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Mark {
    /// Byte offset of the chunk.
    offset: u64,
    /// The writer's caller's tally (e.g. samples of two kinds) over the chunks before it.
    before: [u64; 2],
}

impl Drop for Spill {
    fn drop(&mut self) {
        // Closed first: a file still open cannot be removed everywhere (Windows).
        drop(self.file.take());
        if self.named {
            // Nothing useful to do if it is already gone.
            let _ = std::fs::remove_file(&self.path);
        }
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
    /// Bytes written so far.
    written: u64,
    /// The caller's running tally.
    tally: [u64; 2],
}

impl SpillWriter {
    /// Creates a new spill file in the temp dir.
    pub(crate) fn create() -> Result<Self, Error> {
        let path = new_path();
        let fail = spill_error(&path);
        let file = OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(&path)
            .map_err(&fail)?;
        let mut spill = Spill {
            file: Some(File::open(&path).map_err(&fail)?),
            path: path.clone(),
            named: true,
            chunks: Vec::new(),
        };
        // Both handles are open: on Unix the name can go now, so that no exit, however
        // abrupt, leaves the file behind.
        spill.named = !(cfg!(unix) && std::fs::remove_file(&path).is_ok());
        Ok(Self {
            out: BufWriter::with_capacity(BUFFER_BYTES, file),
            spill,
            bytes: Vec::new(),
            written: 0,
            tally: [0; 2],
        })
    }

    /// Appends `chunk`; `tally` is the caller's count of it (e.g. its samples of two
    /// kinds), summed into each later chunk's [`Spill::before`].
    pub(crate) fn write(&mut self, chunk: &SampleChunk, tally: [u64; 2]) -> Result<(), Error> {
        self.spill.chunks.push(Mark {
            offset: self.written,
            before: self.tally,
        });
        self.tally = [self.tally[0] + tally[0], self.tally[1] + tally[1]];
        let b = &mut self.bytes;
        b.clear();
        for n in Counts::of(chunk).to_le_bytes() {
            b.extend_from_slice(&n);
        }
        for v in vectors(chunk) {
            b.extend_from_slice(&(v.len() as u64).to_le_bytes());
            // Sized once, then filled: one copy loop, no capacity check per value.
            let at = b.len();
            b.resize(at + 8 * v.len(), 0);
            for (d, x) in b[at..].chunks_exact_mut(8).zip(v) {
                d.copy_from_slice(&x.to_le_bytes());
            }
        }
        self.written += self.bytes.len() as u64;
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

/// The vectors of `chunk` in file order (the optional signals it carries).
fn vectors(c: &SampleChunk) -> impl Iterator<Item = &Vec<f64>> {
    std::iter::once(&c.t)
        .chain(&c.velocity)
        .chain(&c.rates)
        .chain(&c.omega)
        .chain(c.omega_dot.iter().flatten())
        .chain(c.omega_ddot.iter().flatten())
        .chain(c.omega_squared_slow.iter().flatten())
        .chain(&c.wrench)
        .chain(&c.height)
        .chain(c.attitude.iter().flatten())
}

/// The vectors of `chunk` in file order, for filling.
fn vectors_mut(c: &mut SampleChunk) -> impl Iterator<Item = &mut Vec<f64>> {
    std::iter::once(&mut c.t)
        .chain(&mut c.velocity)
        .chain(&mut c.rates)
        .chain(&mut c.omega)
        .chain(c.omega_dot.iter_mut().flatten())
        .chain(c.omega_ddot.iter_mut().flatten())
        .chain(c.omega_squared_slow.iter_mut().flatten())
        .chain(&mut c.wrench)
        .chain(&mut c.height)
        .chain(c.attitude.iter_mut().flatten())
}

impl Spill {
    /// Number of chunks written.
    pub(crate) fn chunks(&self) -> usize {
        self.chunks.len()
    }

    /// The writer's caller's tally over the chunks before chunk `c` (`c` < [`Self::chunks`]).
    pub(crate) fn before(&self, c: usize) -> [u64; 2] {
        self.chunks[c].before
    }

    /// Reads the chunks `range` back in the order written, handing each to `consume`
    /// (one chunk in memory at a time; positional reads, so ranges can be read on several
    /// threads at once).
    pub(crate) fn stream_chunks(
        &self,
        range: std::ops::Range<usize>,
        mut consume: impl FnMut(&mut SampleChunk) -> Result<(), Error>,
    ) -> Result<(), Error> {
        let fail = spill_error(&self.path);
        let (Some(first), Some(file)) = (self.chunks.get(range.start), self.file.as_ref()) else {
            return Ok(());
        };
        let at = Positioned {
            file,
            offset: first.offset,
        };
        let mut input = BufReader::with_capacity(BUFFER_BYTES, at);
        let mut chunk = SampleChunk::default();
        let mut bytes = Vec::new();
        for _ in range.start..range.end.min(self.chunks()) {
            let counts = read_counts(&mut input)
                .map_err(&fail)?
                .ok_or_else(|| fail(corrupt("segment ends early")))?;
            read_chunk(&mut input, counts, &mut chunk, &mut bytes).map_err(&fail)?;
            consume(&mut chunk)?;
        }
        Ok(())
    }
}

/// Reads `file` from `offset` on by positional reads, which leave the handle's own
/// position alone (several threads read one handle).
struct Positioned<'f> {
    file: &'f File,
    offset: u64,
}

impl Read for Positioned<'_> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        #[cfg(unix)]
        let n = std::os::unix::fs::FileExt::read_at(self.file, buf, self.offset)?;
        #[cfg(windows)]
        let n = std::os::windows::fs::FileExt::seek_read(self.file, buf, self.offset)?;
        self.offset += n as u64;
        Ok(n)
    }
}

/// The series counts opening a chunk; `None` at the end of the file.
fn read_counts(input: &mut impl Read) -> std::io::Result<Option<Counts>> {
    let mut head = [0u8; 24];
    let got = input.read(&mut head[..1])?;
    if got == 0 {
        return Ok(None);
    }
    input.read_exact(&mut head[1..])?;
    let mut raw = head
        .chunks_exact(4)
        .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]));
    // The next count, one that `valid` accepts or [`ABSENT`].
    let mut next = |valid: &dyn Fn(u32) -> bool| match raw.next() {
        Some(ABSENT) => Ok(None),
        Some(n) if valid(n) => Ok(Some(n as usize)),
        _ => Err(corrupt("series count out of range")),
    };
    let rotors = |n| n <= MAX_ROTORS;
    let omega = next(&rotors)?.ok_or_else(|| corrupt("no rotor speed series"))?;
    let optional = [
        next(&rotors)?,
        next(&rotors)?,
        next(&rotors)?,
        next(&|n| n == 1)?,
        next(&|n| n == 4)?,
    ];
    Ok(Some(Counts { omega, optional }))
}

/// Reads one chunk's vectors into `chunk` (its allocations reused); `bytes` is scratch.
fn read_chunk(
    input: &mut impl Read,
    counts: Counts,
    chunk: &mut SampleChunk,
    bytes: &mut Vec<u8>,
) -> std::io::Result<()> {
    let [omega_dot, omega_ddot, slow, height, attitude] = counts.optional;
    let rotors = |series: &mut Option<Vec<Vec<f64>>>, count: Option<usize>| match count {
        Some(n) => series.get_or_insert_with(Vec::new).resize_with(n, Vec::new),
        None => *series = None,
    };
    chunk.omega.resize_with(counts.omega, Vec::new);
    rotors(&mut chunk.omega_dot, omega_dot);
    rotors(&mut chunk.omega_ddot, omega_ddot);
    rotors(&mut chunk.omega_squared_slow, slow);
    // One height and four attitude series when present (`read_counts`).
    if height.is_none() {
        chunk.height = None;
    } else {
        chunk.height.get_or_insert_with(Vec::new);
    }
    if attitude.is_none() {
        chunk.attitude = None;
    } else {
        chunk.attitude.get_or_insert_with(Default::default);
    }
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
            if rotors == 6 {
                // Derived rates of rotor acceleration and slow thrusts travel with the
                // chunk.
                c.omega_ddot = Some(
                    c.omega
                        .iter()
                        .map(|w| w.iter().map(|x| -x).collect())
                        .collect(),
                );
                c.omega_squared_slow = Some(
                    (0..crate::sample::TRIM_BANDS_HZ.len() * rotors)
                        .map(|i| {
                            c.omega[i % rotors]
                                .iter()
                                .map(|x| x * x + i as f64)
                                .collect()
                        })
                        .collect(),
                );
            }
            chunks.push(c);
        }
        let mut writer = SpillWriter::create().expect("create");
        for (k, c) in chunks.iter().enumerate() {
            writer.write(c, [c.len() as u64, k as u64]).expect("write");
        }
        let spill = writer.finish().expect("finish");
        let path = spill.path.clone();
        // Each chunk with the tally of the chunks before it; two runs (chunks 0–1 and 2)
        // read in reverse order to show they stand alone.
        assert_eq!(spill.chunks(), 3);
        let before: Vec<[u64; 2]> = (0..3).map(|c| spill.before(c)).collect();
        let after_first = CHUNK_SAMPLES as u64;
        assert_eq!(before, vec![[0, 0], [after_first, 0], [after_first + 3, 1]]);
        let mut back = vec![Vec::new(); 2];
        for (s, range) in [(1, 2..3), (0, 0..2)] {
            spill
                .stream_chunks(range, |c| {
                    back[s].push(c.clone());
                    Ok(())
                })
                .expect("read back");
        }
        let back: Vec<SampleChunk> = back.concat();
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
        writer.write(&c, [0; 2]).expect("write");
        writer.out.flush().expect("flush");
        writer
            .out
            .get_ref()
            .set_len(writer.written - 5)
            .expect("truncate");
        let spill = writer.finish().expect("finish");
        let err = spill
            .stream_chunks(0..1, |_| Ok(()))
            .expect_err("truncated");
        let text = err.to_string();
        assert!(text.contains("mrsysid-spill-"), "{text}");
    }

    /// On Unix the file has no name once open, so nothing is left behind even by a
    /// killed process; elsewhere dropping an unfinished spill removes it.
    #[test]
    fn no_spill_file_is_left_behind() {
        let writer = SpillWriter::create().expect("create");
        let path = writer.spill.path.clone();
        assert_eq!(path.exists(), !cfg!(unix));
        drop(writer);
        assert!(!path.exists());
    }
}
