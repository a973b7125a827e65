//! Scratch directories of a test binary: `mrsysid-<tag>-<pid>` in the temp dir, removed
//! when the binary exits (its tests run in parallel and share a directory, so no single
//! test can remove it; the exit handler runs after all of them, passed or failed).

use std::path::PathBuf;
use std::sync::{Mutex, Once};

static DIRS: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

extern "C" fn remove_all() {
    let dirs = DIRS.lock().unwrap_or_else(|e| e.into_inner());
    for dir in dirs.iter() {
        let _ = std::fs::remove_dir_all(dir);
    }
}

/// The binary's scratch directory for `tag`, created on first use.
pub fn dir(tag: &str) -> PathBuf {
    static REGISTER: Once = Once::new();
    // SAFETY: `remove_all` is an `extern "C" fn()` that touches only a static.
    REGISTER.call_once(|| unsafe {
        libc::atexit(remove_all);
    });
    let dir = std::env::temp_dir().join(format!("mrsysid-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("scratch dir");
    let mut dirs = DIRS.lock().unwrap_or_else(|e| e.into_inner());
    if !dirs.contains(&dir) {
        dirs.push(dir.clone());
    }
    dir
}
