//! Writing a file so that readers never see it half-written: a temporary name beside it,
//! flushed to disk, then renamed into place.

use std::io::Write;
use std::path::{Path, PathBuf};

/// Writes `bytes` to `<path>.partial` and renames it into place.
pub fn write_atomically(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let tmp = PathBuf::from(format!("{}.partial", path.display()));
    let result = std::fs::File::create(&tmp).and_then(|mut f| {
        f.write_all(bytes)?;
        f.sync_all()
    });
    match result {
        Ok(()) => std::fs::rename(&tmp, path),
        Err(e) => {
            let _ = std::fs::remove_file(&tmp);
            Err(e)
        }
    }
}
