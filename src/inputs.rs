//! Checks of a request's files before any is read: whether two paths are one file
//! (the same device and inode, however the paths are spelled: links, `..`), whether
//! two logs hold the same bytes, and the fit request's refusal of a log given twice or
//! of a validation log that is also fitted. The binary uses [`same_file`] to refuse an
//! output path that would overwrite an input.

use std::fs::File;
use std::io::Read;
use std::path::Path;

use crate::error::RequestError;
use crate::source::LogSource;

/// True when `a` and `b` both exist and are the same file: the same device and inode
/// on Unix (hard and symbolic links, `..` and relative spellings included), the same
/// canonical path elsewhere. A path that does not exist is no file, so never the same.
pub fn same_file(a: &Path, b: &Path) -> bool {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        match (std::fs::metadata(a), std::fs::metadata(b)) {
            (Ok(x), Ok(y)) => x.dev() == y.dev() && x.ino() == y.ino(),
            _ => false,
        }
    }
    #[cfg(not(unix))]
    {
        match (a.canonicalize(), b.canonicalize()) {
            (Ok(x), Ok(y)) => x == y,
            _ => false,
        }
    }
}

/// Bytes compared at a time by [`same_content`].
const BLOCK: usize = 1 << 16;

/// True when the files `a` and `b` hold the same bytes (compressed files compare by
/// their compressed bytes): the same file, or files of one size whose bytes are equal.
/// Files of different sizes are told apart from their metadata alone, and differing
/// files of one size at their first differing block, so only identical files are read
/// whole. A file that cannot be read is not the same as any other (reading it reports
/// why).
pub fn same_content(a: &Path, b: &Path) -> bool {
    if same_file(a, b) {
        return true;
    }
    let size = |p: &Path| {
        std::fs::metadata(p)
            .ok()
            .filter(|m| m.is_file())
            .map(|m| m.len())
    };
    match (size(a), size(b)) {
        (Some(x), Some(y)) if x == y => {}
        _ => return false,
    }
    let (Ok(mut fa), Ok(mut fb)) = (File::open(a), File::open(b)) else {
        return false;
    };
    let (mut ba, mut bb) = (vec![0u8; BLOCK], vec![0u8; BLOCK]);
    loop {
        match (fill(&mut fa, &mut ba), fill(&mut fb, &mut bb)) {
            (Ok(n), Ok(m)) if n == m && ba[..n] == bb[..m] => {
                if n < BLOCK {
                    return true;
                }
            }
            _ => return false,
        }
    }
}

/// Reads into `buf` until it is full or the file ends; the bytes read.
fn fill(file: &mut File, buf: &mut [u8]) -> std::io::Result<usize> {
    let mut n = 0;
    while n < buf.len() {
        match file.read(&mut buf[n..])? {
            0 => break,
            k => n += k,
        }
    }
    Ok(n)
}

/// True when the two logs are the same data: files of the same bytes
/// ([`same_content`]), or logs in memory holding the same samples. A file and a log in
/// memory are not compared.
fn same_log(a: &LogSource, b: &LogSource) -> bool {
    match (a, b) {
        (LogSource::File(x), LogSource::File(y)) => same_content(x, y),
        (LogSource::Memory(x), LogSource::Memory(y)) => {
            std::sync::Arc::ptr_eq(x, y) || (x.len() == y.len() && x.chunks() == y.chunks())
        }
        _ => false,
    }
}

/// The name of a log in messages: a file's path as given, a memory log's name.
fn label(log: &LogSource) -> String {
    match log {
        LogSource::File(path) => path.display().to_string(),
        LogSource::Memory(log) => log.name().to_string(),
    }
}

/// Refuses fit logs among which one is given twice (the same file, a copy of it, or the
/// same samples in memory: leave one log out would predict it from its own copy), and
/// validation logs that are also fit logs (their figures would come from fitted data).
pub fn check_logs(logs: &[LogSource], validate: &[LogSource]) -> Result<(), RequestError> {
    for (i, a) in logs.iter().enumerate() {
        for b in &logs[i + 1..] {
            if same_log(a, b) {
                return Err(RequestError::DuplicateLog {
                    first: label(a),
                    second: label(b),
                });
            }
        }
    }
    for v in validate {
        if let Some(fit) = logs.iter().find(|f| same_log(f, v)) {
            return Err(RequestError::ValidationIsFitLog {
                validation: label(v),
                fit: label(fit),
            });
        }
    }
    for (i, a) in validate.iter().enumerate() {
        for b in &validate[i + 1..] {
            if same_log(a, b) {
                return Err(RequestError::DuplicateLog {
                    first: label(a),
                    second: label(b),
                });
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A scratch directory of this test module.
    fn dir(tag: &str) -> std::path::PathBuf {
        let d = std::env::temp_dir().join(format!("mrsysid-inputs-{tag}-{}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    /// Files of one size told apart in the last block, equal ones found equal, links
    /// and `..` spellings found to be the same file, a missing file never the same.
    #[test]
    fn same_file_and_same_content() {
        let d = dir("content");
        let bytes: Vec<u8> = (0..3 * BLOCK + 17).map(|i| (i % 251) as u8).collect();
        let a = d.join("a");
        let b = d.join("b");
        let c = d.join("c");
        std::fs::write(&a, &bytes).unwrap();
        std::fs::write(&b, &bytes).unwrap();
        let mut other = bytes.clone();
        *other.last_mut().unwrap() ^= 1;
        std::fs::write(&c, &other).unwrap();
        assert!(same_content(&a, &b));
        assert!(!same_content(&a, &c));
        assert!(!same_file(&a, &b));
        std::fs::create_dir_all(d.join("sub")).unwrap();
        assert!(same_file(&a, &d.join("sub/../a")));
        let missing = d.join("missing");
        assert!(!same_file(&missing, &missing));
        assert!(!same_content(&a, &missing));
        std::fs::remove_dir_all(&d).unwrap();
    }
}
