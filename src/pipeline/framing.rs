//! The byte frame of every file of statistics as data (`docs/stats-format.md`): a
//! 16-byte magic string naming the kind of file, the format version, the payload's
//! length and CRC-32, then the payload in the postcard 1.0 encoding. One frame for the
//! first-pass parts, the second-pass plan and parts, and the remainder plan and parts.

use serde::Serialize;
use serde::de::DeserializeOwned;

use crate::error::StatsError;

/// Version of the byte format of every kind of file; a file of another version is
/// refused.
pub const STATS_FORMAT_VERSION: u32 = 2;

/// Bytes before the payload: magic, version (u32), payload length (u64), CRC-32 of the
/// payload (u32), all little-endian.
const HEADER_BYTES: usize = 16 + 4 + 8 + 4;

/// `value` framed under `magic`.
pub(super) fn to_bytes<T: Serialize>(magic: &[u8; 16], value: &T) -> Vec<u8> {
    // Serialising plain data into a Vec cannot fail.
    let payload = postcard::to_stdvec(value).unwrap_or_default();
    let mut out = Vec::with_capacity(HEADER_BYTES + payload.len());
    out.extend_from_slice(magic);
    out.extend_from_slice(&STATS_FORMAT_VERSION.to_le_bytes());
    out.extend_from_slice(&(payload.len() as u64).to_le_bytes());
    out.extend_from_slice(&crc32fast::hash(&payload).to_le_bytes());
    out.extend_from_slice(&payload);
    out
}

/// The value framed under `magic` in `bytes` (`what`: the kind of file, for the error
/// on another magic); `file` names it in errors.
pub(super) fn from_bytes<T: DeserializeOwned>(
    magic: &[u8; 16],
    what: &str,
    bytes: &[u8],
    file: &str,
) -> Result<T, StatsError> {
    let bad = |what: String| StatsError::Format {
        file: file.to_string(),
        what,
    };
    if bytes.len() < HEADER_BYTES || &bytes[..16] != magic {
        return Err(bad(format!("not a mrsysid {what} (bad magic bytes)")));
    }
    let word = |at: usize, n: usize| {
        let mut b = [0u8; 8];
        b[..n].copy_from_slice(&bytes[at..at + n]);
        u64::from_le_bytes(b)
    };
    let version = word(16, 4);
    if version != u64::from(STATS_FORMAT_VERSION) {
        return Err(bad(format!(
            "format version {version}, this mrsysid reads version {STATS_FORMAT_VERSION}"
        )));
    }
    let (length, crc) = (word(20, 8), word(28, 4));
    let payload = &bytes[HEADER_BYTES..];
    if payload.len() as u64 != length {
        return Err(bad(format!(
            "truncated or padded: the header gives {length} payload bytes, the file has {}",
            payload.len()
        )));
    }
    if u64::from(crc32fast::hash(payload)) != crc {
        return Err(bad("checksum mismatch: the file is corrupted".into()));
    }
    postcard::from_bytes(payload).map_err(|e| bad(format!("payload: {e}")))
}

/// 64-bit FNV-1a of `bytes`: a stable hash (std's is not stable across releases).
pub(super) fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
        (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3)
    })
}

/// Writes `bytes` to `path` (whole or not at all).
pub(super) fn save(path: &std::path::Path, bytes: &[u8]) -> Result<(), StatsError> {
    crate::util::write_atomically(path, bytes).map_err(|e| StatsError::Io {
        file: path.display().to_string(),
        what: e.to_string(),
    })
}

/// The bytes of the file at `path`.
pub(super) fn load(path: &std::path::Path) -> Result<Vec<u8>, StatsError> {
    std::fs::read(path).map_err(|e| StatsError::Io {
        file: path.display().to_string(),
        what: e.to_string(),
    })
}
