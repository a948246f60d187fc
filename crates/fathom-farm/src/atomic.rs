//! Files that never lie: every output is written to a temporary name in the same directory
//! and renamed over its final name only once complete, so a killed task, a full disk or a
//! failed encoder leaves no partial file under a final name (the temporary one is removed
//! when the failure is seen; a killed task's is ignored and overwritten by a rerun).

use crate::error::FarmError;
use fathom_core::atomic_file::{AtomicFile, WriteError};
pub use fathom_core::atomic_file::{is_temp_name, temp_path};
use std::io::Write;
use std::path::Path;

/// The farm's error for a failed atomic write.
fn farm_err(e: WriteError) -> FarmError {
    match e {
        WriteError::Io { path, source } => FarmError::Write { path, source },
        WriteError::MissingDirectory { ref path, .. } | WriteError::NotAFileName { ref path } => {
            FarmError::Write {
                path: path.clone(),
                source: std::io::Error::other(e.to_string()),
            }
        }
    }
}

/// Writes `bytes` to `path` through a temporary file, synced, then renamed
/// ([`fathom_core::atomic_file`], which also removes the temporary file on Ctrl-C).
pub fn write(path: &Path, bytes: &[u8]) -> Result<(), FarmError> {
    write_with(path, |f| f.write_all(bytes))
}

/// [`write`] with the temporary file filled by `fill`: on an error the temporary file is
/// removed and nothing appears under `path`.
pub fn write_with(
    path: &Path,
    fill: impl FnOnce(&mut AtomicFile) -> std::io::Result<()>,
) -> Result<(), FarmError> {
    let mut f = AtomicFile::create(path).map_err(farm_err)?;
    fill(&mut f).map_err(|source| FarmError::Write {
        path: path.into(),
        source,
    })?;
    f.commit().map_err(farm_err)
}

/// Writes `bytes` to `path` only if nothing is there: through a temporary file and a hard
/// link, which fails if the name exists (one creator wins a race, and the name never shows
/// a partial file). Returns whether this call created it.
pub fn create_exclusive(path: &Path, bytes: &[u8]) -> Result<bool, FarmError> {
    let tmp = temp_path(path);
    let werr = |source| FarmError::Write {
        path: path.into(),
        source,
    };
    let (tmp, mut f) = fathom_core::cleanup::Pending::create(tmp, |p| std::fs::File::create_new(p))
        .map_err(werr)?;
    f.write_all(bytes)
        .and_then(|()| f.sync_all())
        .map_err(werr)?;
    drop(f);
    let linked = std::fs::hard_link(tmp.path(), path);
    drop(tmp);
    match linked {
        Ok(()) => Ok(true),
        Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => Ok(false),
        Err(e) => Err(werr(e)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use fathom_core::testing::scratch_dir;

    /// A writer onto a "disk" that fills up after `room` bytes.
    struct SmallDisk<'a> {
        file: &'a mut AtomicFile,
        room: usize,
    }

    impl Write for SmallDisk<'_> {
        fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
            if self.room == 0 {
                return Err(std::io::Error::new(
                    std::io::ErrorKind::StorageFull,
                    "No space left on device",
                ));
            }
            let n = buf.len().min(self.room);
            self.room -= n;
            self.file.write(&buf[..n])
        }
        fn flush(&mut self) -> std::io::Result<()> {
            self.file.flush()
        }
    }

    #[test]
    fn a_full_disk_leaves_no_file_under_the_final_name_nor_a_temporary_one() {
        let dir = scratch_dir("farm-atomic");
        let path = dir.join("tile-00000.png");
        let bytes = vec![7u8; 10_000];
        let e = write_with(&path, |f| {
            let mut w = SmallDisk {
                file: f,
                room: 4096,
            };
            w.write_all(&bytes)
        })
        .unwrap_err();
        assert!(matches!(e, FarmError::Write { .. }), "{e}");
        assert!(e.to_string().contains("No space left"), "{e}");
        assert!(!path.exists());
        assert_eq!(
            std::fs::read_dir(&dir).unwrap().count(),
            0,
            "temporary left"
        );
        // A good write lands whole, and replaces an older file.
        write(&path, b"old").unwrap();
        write(&path, &bytes).unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), bytes);
        assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 1);
        // Exclusive creation: the first wins, the second changes nothing.
        let m = dir.join("farm.json");
        assert!(create_exclusive(&m, b"job A").unwrap());
        assert!(!create_exclusive(&m, b"job B").unwrap());
        assert_eq!(std::fs::read(&m).unwrap(), b"job A");
        assert_eq!(
            std::fs::read_dir(&dir).unwrap().count(),
            2,
            "temporary left"
        );
        std::fs::remove_dir_all(&dir).ok();
    }
}
