//! What the CSV reader needs of a file beyond its text: its bytes, decompressed on the
//! fly when it is gzip-compressed (with the compressed position reached, for errors),
//! and its dialect.
//!
//! Dialect: a spreadsheet set to a European locale exports `;` between fields and a
//! decimal comma (`0,057897`); tab-separated exports exist too. A header read with the
//! comma as one field holding `;` or a tab is read again with that delimiter, and every
//! field of such a file may have a decimal comma (a field with a comma that does not
//! parse otherwise is read with the comma as the decimal point). Values are the same
//! bits as the comma file's; error messages quote fields as written.

use std::fs::File;
use std::io::{BufRead, BufReader, Read, Seek, SeekFrom};
use std::path::Path;
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};

use flate2::bufread::MultiGzDecoder;

use super::decimal::fast_path_in;

/// The text of the file at `path`: decompressed on the fly when it is gzip-compressed,
/// with its [`GzipPosition`] then.
pub fn open_text(path: &Path) -> std::io::Result<(Box<dyn Read + Send>, Option<GzipPosition>)> {
    let mut handle = File::open(path)?;
    if !is_gzip(&mut handle)? {
        return Ok((Box::new(handle), None));
    }
    let position = GzipPosition {
        consumed: Arc::default(),
        size: handle.metadata()?.len(),
    };
    let counted = Counted::new(
        BufReader::with_capacity(1 << 16, handle),
        Arc::clone(&position.consumed),
    );
    Ok((Box::new(MultiGzDecoder::new(counted)), Some(position)))
}

/// True when the file starts with the gzip magic bytes (RFC 1952): the CSV text is then
/// decompressed on the fly. Leaves the file at its start.
fn is_gzip(file: &mut File) -> std::io::Result<bool> {
    let mut magic = [0u8; 2];
    let mut n = 0;
    while n < magic.len() {
        let k = file.read(&mut magic[n..])?;
        if k == 0 {
            break;
        }
        n += k;
    }
    file.seek(SeekFrom::Start(0))?;
    Ok(n == 2 && magic == [0x1f, 0x8b])
}

/// The delimiter of a file whose header, read with commas, is `header`: `;` or tab
/// when the header is one field holding it (the more frequent of the two), else `,`.
pub fn delimiter(header: &csv::ByteRecord) -> u8 {
    if header.len() != 1 {
        return b',';
    }
    let count = |d: u8| header[0].iter().filter(|&&b| b == d).count();
    match (count(b';'), count(b'\t')) {
        (0, 0) => b',',
        (semicolons, tabs) if semicolons >= tabs => b';',
        _ => b'\t',
    }
}

/// Longest field read with a decimal comma without a heap allocation, bytes.
const SHORT_FIELD: usize = 64;

/// The value of `field` read with its commas as decimal points, when it has one and
/// then parses (as a comma-free field does: surrounding spaces allowed); `None` otherwise.
pub fn decimal_comma_value(field: &[u8]) -> Option<f64> {
    memchr::memchr(b',', field)?;
    let mut short = [0u8; SHORT_FIELD];
    let mut long = Vec::new();
    let text: &mut [u8] = if field.len() <= SHORT_FIELD {
        &mut short[..field.len()]
    } else {
        long.extend_from_slice(field);
        &mut long
    };
    text.copy_from_slice(field);
    for b in text.iter_mut() {
        if *b == b',' {
            *b = b'.';
        }
    }
    if let Some(x) = fast_path_in(text, 0..text.len()) {
        return Some(x);
    }
    let text = std::str::from_utf8(text).ok()?.trim();
    super::decimal::parse_f64(text).ok()
}

/// A buffered reader that counts the bytes consumed from it: under a gzip decoder, the
/// compressed bytes the decoder has taken, so an error can say where the stream broke.
pub struct Counted<R> {
    inner: R,
    consumed: Arc<AtomicU64>,
}

impl<R> Counted<R> {
    /// `inner`, counting into `consumed`.
    pub fn new(inner: R, consumed: Arc<AtomicU64>) -> Self {
        Self { inner, consumed }
    }
}

impl<R: BufRead> Read for Counted<R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = self.inner.read(buf)?;
        self.consumed.fetch_add(n as u64, Ordering::Relaxed);
        Ok(n)
    }
}

impl<R: BufRead> BufRead for Counted<R> {
    fn fill_buf(&mut self) -> std::io::Result<&[u8]> {
        self.inner.fill_buf()
    }

    fn consume(&mut self, amt: usize) {
        self.inner.consume(amt);
        self.consumed.fetch_add(amt as u64, Ordering::Relaxed);
    }
}

/// How far a gzip-compressed file was read: the compressed bytes its decoder consumed,
/// of the file's size.
#[derive(Debug, Clone)]
pub struct GzipPosition {
    /// Compressed bytes consumed so far (shared with the [`Counted`] reader).
    pub consumed: Arc<AtomicU64>,
    /// Size of the file, bytes.
    pub size: u64,
}

impl GzipPosition {
    /// The read error `e` of the decompressed text, `text` bytes of which were read,
    /// with the compressed position reached.
    pub fn describe(&self, e: &std::io::Error, text: u64) -> String {
        format!(
            "{e} (the gzip stream broke at compressed byte {} of {}, after {text} bytes of \
             text: the file is truncated or corrupt)",
            self.consumed.load(Ordering::Relaxed),
            self.size
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Decimal commas give the bits of decimal points; fields without a comma, and ones
    /// that do not parse with it, are left to the caller.
    #[test]
    fn decimal_commas_read_as_points() {
        for (comma, point) in [
            ("0,057897", "0.057897"),
            ("-11,768", "-11.768"),
            (" 2,5e-3 ", "2.5e-3"),
            ("12345678901234567890,5", "12345678901234567890.5"),
        ] {
            let want: f64 = point.parse().unwrap();
            assert_eq!(
                decimal_comma_value(comma.as_bytes()).map(f64::to_bits),
                Some(want.to_bits()),
                "{comma}"
            );
        }
        let long = format!("{},5", "1".repeat(80));
        assert_eq!(
            decimal_comma_value(long.as_bytes()),
            format!("{}.5", "1".repeat(80)).parse().ok()
        );
        assert_eq!(decimal_comma_value(b"1.5"), None);
        assert_eq!(decimal_comma_value(b"1.234,5"), None);
        assert_eq!(decimal_comma_value(b"1,2,3"), None);
    }

    /// One header field holding `;` or tabs names its delimiter; a comma header stays.
    #[test]
    fn delimiter_from_the_header() {
        let record = |fields: &[&str]| csv::ByteRecord::from(fields.to_vec());
        assert_eq!(delimiter(&record(&["t;u;v"])), b';');
        assert_eq!(delimiter(&record(&["t\tu\tv"])), b'\t');
        assert_eq!(delimiter(&record(&["t", "u;v"])), b',');
        assert_eq!(delimiter(&record(&["t"])), b',');
    }
}
