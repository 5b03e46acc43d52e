//! Scratch folders for tests that write files: fresh and empty when made, removed when the test is done with
//! them, kept when the test fails so that what it wrote can be looked at.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

/// `mislab-<prefix>-<pid>-<name>` under the system's temp folder, emptied on creation, removed on drop unless
/// the thread is panicking (a failing test's files stay).
pub struct Scratch(PathBuf);

impl Scratch {
    pub fn new(prefix: &str, name: &str) -> Scratch {
        let dir = std::env::temp_dir().join(format!("mislab-{prefix}-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap_or_else(|e| panic!("cannot create {}: {e}", dir.display()));
        Scratch(dir)
    }
}

/// A scratch folder of its own for each call (numbered), for a helper that tests running at the same time call
/// with the same arguments.
pub fn unique(prefix: &str) -> Scratch {
    static NEXT: AtomicUsize = AtomicUsize::new(0);
    Scratch::new(prefix, &NEXT.fetch_add(1, Ordering::Relaxed).to_string())
}

impl std::ops::Deref for Scratch {
    type Target = Path;
    fn deref(&self) -> &Path {
        &self.0
    }
}

impl AsRef<Path> for Scratch {
    fn as_ref(&self) -> &Path {
        &self.0
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        if !std::thread::panicking() {
            let _ = std::fs::remove_dir_all(&self.0);
        }
    }
}
