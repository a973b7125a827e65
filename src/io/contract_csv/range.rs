//! One byte range of whole records parsed into slot values: split at the delimiter
//! directly when the text holds no quote and no lone CR, else through the csv
//! tokeniser; both give the same rows, values, line numbers and faults.

use super::super::csv_input::decimal_comma_value;
use super::super::decimal::{fast_path_in, parse_f64};

/// Why a row could not be read; turned into an [`IoError`] with its true line when the
/// row is consumed.
#[derive(Debug, Clone)]
pub(super) enum Fault {
    /// The row has this many fields, not the header's count.
    Width(usize),
    /// The value of this slot is not a number (its text).
    NotANumber(usize, String),
    /// The tokeniser failed (the message).
    Tokenise(String),
}

/// One byte range of the file and, once parsed, its rows.
#[derive(Debug, Default)]
pub(super) struct Range {
    /// The text: whole records.
    pub(super) bytes: Vec<u8>,
    /// Slot values, row after row (a faulty row's values are unspecified).
    pub(super) values: Vec<f64>,
    /// Line of each row counted from the range start (the range's first line is 0).
    pub(super) lines: Vec<u64>,
    /// Faulty rows (row index, fault), in row order.
    pub(super) faults: Vec<(usize, Fault)>,
    /// Line feeds in `bytes`.
    pub(super) newlines: u64,
}

/// What parsing a range needs to know of the file.
#[derive(Debug)]
pub(super) struct Columns {
    /// Header column of each slot.
    pub(super) of_slot: Vec<usize>,
    /// Header width.
    pub(super) header_len: usize,
    /// Field delimiter: `,`, `;` or tab.
    pub(super) delimiter: u8,
}

/// A csv reader over whole records in memory, fields split at `delimiter`, with the
/// settings of every read here.
pub(super) fn tokeniser(bytes: &[u8], delimiter: u8) -> csv::Reader<&[u8]> {
    csv::ReaderBuilder::new()
        .has_headers(false)
        .flexible(true)
        .delimiter(delimiter)
        .from_reader(bytes)
}

/// The line (0-based, from the start of `bytes`) and byte offset of the first byte of
/// `record`: the tokeniser places a record after the previous one's terminator, so the
/// record terminators it skipped (blank lines, the LF of a CRLF) are counted here.
fn record_start(bytes: &[u8], record: &csv::ByteRecord) -> u64 {
    let (mut byte, mut line) = record
        .position()
        .map_or((0, 1), |p| (p.byte() as usize, p.line()));
    while let Some(&b) = bytes.get(byte) {
        match b {
            b'\n' => line += 1,
            b'\r' => {}
            _ => break,
        }
        byte += 1;
    }
    line - 1
}

impl Range {
    /// Tokenises and parses `bytes` into rows (blank lines skipped, as the csv
    /// tokeniser does); each row's first failure in slot order is kept as its fault.
    /// Text without quotes whose lines end in LF or CRLF (every contract log we write,
    /// and Windows exports) is split on its commas and line ends directly, which is what
    /// the csv tokeniser would do with it; any other text (quoted fields, a lone CR)
    /// goes through the tokeniser.
    pub(super) fn parse(&mut self, columns: &Columns) {
        self.values.clear();
        self.lines.clear();
        self.faults.clear();
        let bytes = &self.bytes;
        self.newlines = memchr::memchr_iter(b'\n', bytes).count() as u64;
        let quoted = memchr::memchr(b'"', bytes).is_some();
        let lone_cr = memchr::memchr_iter(b'\r', bytes).any(|i| bytes.get(i + 1) != Some(&b'\n'));
        if quoted || lone_cr {
            self.parse_tokenised(columns);
        } else {
            self.parse_plain(columns);
        }
    }

    /// [`Range::parse`] of text without quotes in which every CR starts a CRLF: records
    /// are its non-empty lines (without their CR), fields the text between commas.
    fn parse_plain(&mut self, columns: &Columns) {
        let bytes = std::mem::take(&mut self.bytes);
        let mut ends = Vec::with_capacity(columns.header_len + 1);
        let mut start = 0;
        let mut line = 0;
        while start < bytes.len() {
            let end = memchr::memchr(b'\n', &bytes[start..]).map_or(bytes.len(), |i| start + i);
            let line_text = &bytes[start..end];
            let record = line_text.strip_suffix(b"\r").unwrap_or(line_text);
            if !record.is_empty() {
                field_ends(record, columns.delimiter, &mut ends);
                let field = |c: usize| (if c == 0 { 0 } else { ends[c - 1] + 1 })..ends[c];
                self.push_row(line, ends.len(), columns, record, field);
            }
            start = end + 1;
            line += 1;
        }
        self.bytes = bytes;
    }

    /// [`Range::parse`] through the csv tokeniser (quoted fields, lone CR line ends).
    fn parse_tokenised(&mut self, columns: &Columns) {
        let bytes = std::mem::take(&mut self.bytes);
        let mut reader = tokeniser(&bytes, columns.delimiter);
        let mut record = csv::ByteRecord::new();
        loop {
            match reader.read_byte_record(&mut record) {
                Ok(true) => {}
                Ok(false) => break,
                Err(e) => {
                    let line = e.position().map_or(1, |p| p.line());
                    self.lines.push(line - 1);
                    let k = columns.of_slot.len();
                    self.values.resize(self.values.len() + k, 0.0);
                    self.faults
                        .push((self.lines.len() - 1, Fault::Tokenise(e.to_string())));
                    break;
                }
            }
            if record.len() == 1 && record[0].is_empty() {
                continue;
            }
            let line = record_start(&bytes, &record);
            let field = |c: usize| record.range(c).unwrap_or_default();
            self.push_row(line, record.len(), columns, record.as_slice(), field);
        }
        self.bytes = bytes;
    }

    /// Adds the record on `line` with `width` fields, field c being `text[field(c)]`:
    /// its slot values, or its fault (the width, else the first slot that is not a
    /// number).
    fn push_row(
        &mut self,
        line: u64,
        width: usize,
        columns: &Columns,
        text: &[u8],
        field: impl Fn(usize) -> std::ops::Range<usize>,
    ) {
        let row = self.lines.len();
        self.lines.push(line);
        let start = self.values.len();
        self.values.resize(start + columns.of_slot.len(), 0.0);
        if width != columns.header_len {
            self.faults.push((row, Fault::Width(width)));
            return;
        }
        // A field the fast path reads is ASCII. For the others, one UTF-8 check of the
        // whole row (when the first comes) instead of one per field; a row that fails it
        // is checked field by field so the error names the offending field.
        let mut utf8 = None;
        let values = &mut self.values[start..];
        for (slot, (&col, v)) in columns.of_slot.iter().zip(values).enumerate() {
            let range = field(col);
            if let Some(x) = fast_path_in(text, range.clone()) {
                *v = x;
                continue;
            }
            if columns.delimiter != b','
                && let Some(x) = decimal_comma_value(&text[range.clone()])
            {
                *v = x;
                continue;
            }
            let checked = *utf8.get_or_insert_with(|| std::str::from_utf8(text).ok());
            let parsed = match checked.and_then(|t| t.get(range.clone())) {
                Some(f) => parse_text(f),
                None => parse_field(&text[range]),
            };
            match parsed {
                Ok(x) => *v = x,
                Err(t) => {
                    self.faults.push((row, Fault::NotANumber(slot, t)));
                    break;
                }
            }
        }
    }
}

/// Sets `ends` to the offset of every `delimiter` in `record`, then its length: field c
/// ends at `ends[c]`. Eight bytes at a time.
fn field_ends(record: &[u8], delimiter: u8, ends: &mut Vec<usize>) {
    ends.clear();
    let pattern = u64::from(delimiter) * 0x0101_0101_0101_0101;
    let words = record.chunks_exact(8);
    let tail = words.remainder();
    for (w, word) in words.enumerate() {
        let word = u64::from_le_bytes(word.try_into().unwrap_or_default());
        let mut found = delimiter_bytes(word, pattern);
        while found != 0 {
            ends.push(8 * w + found.trailing_zeros() as usize / 8);
            found &= found - 1;
        }
    }
    let base = record.len() - tail.len();
    ends.extend(memchr::memchr_iter(delimiter, tail).map(|i| base + i));
    ends.push(record.len());
}

/// 0x80 in each byte of `word` equal to the delimiter whose byte `pattern` repeats eight
/// times, 0 in the others (exact: no carries between bytes).
fn delimiter_bytes(word: u64, pattern: u64) -> u64 {
    const LOW7: u64 = 0x7f7f_7f7f_7f7f_7f7f;
    let x = word ^ pattern;
    !(((x & LOW7) + LOW7) | x | LOW7)
}

/// Offset just past the last whole record of `bytes` (which start at a record start),
/// if a record ends before the last one begins; see the module notes.
pub(super) fn range_end(bytes: &[u8], delimiter: u8) -> Option<usize> {
    if memchr::memchr(b'"', bytes).is_none()
        && let Some(i) = memchr::memrchr(b'\n', bytes)
    {
        return Some(i + 1);
    }
    let mut reader = tokeniser(bytes, delimiter);
    let mut record = csv::ByteRecord::new();
    let mut last = 0;
    while let Ok(true) = reader.read_byte_record(&mut record) {
        last = record.position().map_or(0, |p| p.byte() as usize);
    }
    (last > 0).then_some(last)
}

/// Parses one CSV field as f64 (surrounding spaces allowed), a field whose untrimmed text
/// the fast path ([`fast_path_in`]) has already left to std; the error carries the text.
fn parse_field(bytes: &[u8]) -> Result<f64, String> {
    let text =
        std::str::from_utf8(bytes).map_err(|_| String::from_utf8_lossy(bytes).into_owned())?;
    parse_text(text)
}

/// [`parse_field`] of a field already known to be UTF-8. Only a padded field gets the
/// fast path again (on its trimmed text); any other goes to std at once.
fn parse_text(text: &str) -> Result<f64, String> {
    let bytes = text.as_bytes();
    let padded = bytes.first().is_some_and(u8::is_ascii_whitespace)
        || bytes.last().is_some_and(u8::is_ascii_whitespace);
    let parsed = if padded {
        parse_f64(text.trim())
    } else {
        text.parse::<f64>()
    };
    parsed.map_err(|_| text.to_string())
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::rngs::StdRng;
    use rand::{RngExt, SeedableRng};

    /// A range of `text` parsed both ways.
    fn both_ways(text: &[u8], columns: &Columns) -> [Range; 2] {
        let mut plain = Range {
            bytes: text.to_vec(),
            ..Range::default()
        };
        let mut tokenised = Range {
            bytes: text.to_vec(),
            ..Range::default()
        };
        plain.parse_plain(columns);
        tokenised.parse_tokenised(columns);
        [plain, tokenised]
    }

    /// The direct split gives the rows, values (bit for bit), line numbers and faults of
    /// the csv tokeniser on random quote-free text with LF and CRLF line ends: numbers,
    /// junk, empty fields, blank lines, rows too short or too long, invalid UTF-8, a last
    /// line with or without its line end.
    #[test]
    fn plain_split_equals_the_tokeniser() {
        let mut rng = StdRng::seed_from_u64(5);
        let columns = Columns {
            of_slot: vec![3, 0, 2, 5],
            header_len: 6,
            delimiter: b',',
        };
        let pieces: [&[u8]; 12] = [
            b"1.5",
            b"-0.25",
            b"7",
            b"1e3",
            b"",
            b" 2 ",
            b"x",
            b"nan",
            b"\xc3",
            b"\xc3\xa9",
            b"123456789012345678901",
            b"-",
        ];
        for case in 0..2000 {
            // Half the texts end some lines in CRLF (Windows exports), mixed with LF.
            let crlf = case % 2 == 1;
            let mut text = Vec::new();
            for _ in 0..rng.random_range(0..30) {
                let line_end: &[u8] = if crlf && rng.random_bool(0.7) {
                    b"\r\n"
                } else {
                    b"\n"
                };
                if rng.random_bool(0.1) {
                    text.extend_from_slice(line_end);
                    continue;
                }
                let width = if rng.random_bool(0.8) {
                    6
                } else {
                    rng.random_range(1..9)
                };
                for f in 0..width {
                    if f > 0 {
                        text.push(b',');
                    }
                    let piece = if rng.random_bool(0.85) {
                        format!("{}", rng.random_range(-1e4..1e4)).into_bytes()
                    } else {
                        pieces[rng.random_range(0..pieces.len())].to_vec()
                    };
                    text.extend_from_slice(&piece);
                }
                text.extend_from_slice(line_end);
            }
            if rng.random_bool(0.5) && text.last() == Some(&b'\n') {
                text.pop();
                if text.last() == Some(&b'\r') {
                    text.pop();
                }
            }
            let [plain, tokenised] = both_ways(&text, &columns);
            let what = String::from_utf8_lossy(&text);
            assert_eq!(plain.lines, tokenised.lines, "{what}");
            let bits = |r: &Range| r.values.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
            let faulty: Vec<usize> = plain.faults.iter().map(|f| f.0).collect();
            let k = columns.of_slot.len();
            let good = |r: &Range| -> Vec<u64> {
                let b = bits(r);
                (0..r.lines.len())
                    .filter(|i| !faulty.contains(i))
                    .flat_map(|i| b[i * k..(i + 1) * k].to_vec())
                    .collect()
            };
            assert_eq!(good(&plain), good(&tokenised), "{what}");
            assert_eq!(
                format!("{:?}", plain.faults),
                format!("{:?}", tokenised.faults),
                "{what}"
            );
        }
    }

    /// Text the direct split cannot read (a lone CR ends a record; a quoted field may
    /// hold a comma or a line end) goes to the tokeniser.
    #[test]
    fn lone_cr_and_quotes_go_to_the_tokeniser() {
        let columns = Columns {
            of_slot: vec![0, 1],
            header_len: 2,
            delimiter: b',',
        };
        for text in [
            &b"1,2\r3,4\n"[..],
            b"1,2\r\n3,4\r",
            b"\"1\",2\n3,4\n",
            b"\"1,5\",2\n",
        ] {
            let mut parsed = Range {
                bytes: text.to_vec(),
                ..Range::default()
            };
            parsed.parse(&columns);
            let [_, tokenised] = both_ways(text, &columns);
            assert_eq!(parsed.lines, tokenised.lines, "{text:?}");
            assert_eq!(parsed.values, tokenised.values, "{text:?}");
            assert_eq!(
                format!("{:?}", parsed.faults),
                format!("{:?}", tokenised.faults),
                "{text:?}"
            );
        }
        // Two records where a lone CR ends the first.
        let [_, tokenised] = both_ways(b"1,2\r3,4\n", &columns);
        assert_eq!(tokenised.values, [1.0, 2.0, 3.0, 4.0]);
    }

    /// Commas are found in every byte position of a word and nowhere else.
    #[test]
    fn field_ends_are_the_commas() {
        let record = b"a,bc,,defghij,k,lmnopqrstu,v,";
        let mut ends = Vec::new();
        field_ends(record, b',', &mut ends);
        let expected: Vec<usize> = record
            .iter()
            .enumerate()
            .filter(|(_, c)| **c == b',')
            .map(|(i, _)| i)
            .chain([record.len()])
            .collect();
        assert_eq!(ends, expected);
        for b in 0..=255u8 {
            let word = u64::from_le_bytes([b, b',', b, 0x2c ^ 0x80, b, b'-', b'.', b]);
            let want = (0..8).filter(|&i| word.to_le_bytes()[i] == b',');
            let got = delimiter_bytes(word, 0x2c2c_2c2c_2c2c_2c2c);
            assert_eq!(got, want.map(|i| 0x80u64 << (8 * i)).sum::<u64>(), "{b:#x}");
        }
    }
}
