//! Outputs that are whole or absent: every file fathom writes goes to a hidden temporary
//! name in the same directory (`.NAME.tmp-PID-N`), is synced, and is renamed over its final
//! name only once complete. A failed encoder, a full disk, a refused run or an interruption
//! leaves the previous file under the final name byte for byte; the temporary file is
//! removed on every exit path (dropped unfinished, or by [`crate::cleanup::interrupted`] on
//! Ctrl-C / SIGTERM), and only SIGKILL can leave one behind under its hidden name.
//!
//! [`AtomicFile::create`] creates the temporary file at once, so a missing directory or an
//! unwritable one is reported before any work, as opening the final file used to be.

use crate::cleanup::Pending;
use std::fs::File;
use std::io::{Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

/// Why an output could not be written; every variant names the final path.
#[derive(Debug, thiserror::Error)]
pub enum WriteError {
    /// The directory the file would go in does not exist.
    #[error("cannot write {}: the directory {} does not exist", path.display(), dir.display())]
    MissingDirectory {
        /// The file that was to be written.
        path: PathBuf,
        /// The directory that does not exist.
        dir: PathBuf,
    },
    /// The path names a directory (or has no file name).
    #[error("cannot write {}: it is a directory, not a file name", path.display())]
    NotAFileName {
        /// The path given.
        path: PathBuf,
    },
    /// Creating, writing, syncing or renaming the file failed (no permission, disk full, ...).
    #[error("cannot write {}: {source}", path.display())]
    Io {
        /// The file that was to be written.
        path: PathBuf,
        /// The error from the operating system.
        #[source]
        source: std::io::Error,
    },
}

impl WriteError {
    fn io(path: &Path) -> impl Fn(std::io::Error) -> WriteError + '_ {
        move |source| WriteError::Io {
            path: path.into(),
            source,
        }
    }
}

static COUNTER: AtomicU64 = AtomicU64::new(0);

/// The hidden temporary name `path` is written under: unique per process and call.
pub fn temp_path(path: &Path) -> PathBuf {
    let n = COUNTER.fetch_add(1, Ordering::Relaxed);
    let name = path.file_name().unwrap_or_default().to_string_lossy();
    path.with_file_name(format!(".{name}.tmp-{}-{n}", std::process::id()))
}

/// Whether a file name is one of [`temp_path`]'s.
pub fn is_temp_name(name: &str) -> bool {
    name.starts_with('.') && name.contains(".tmp-")
}

/// Checks that `path` can name an output: it has a file name, is not a directory, and its
/// directory exists. (Whether the directory is writable is learnt by creating a file in it.)
pub fn check_output_path(path: &Path) -> Result<(), WriteError> {
    if path.file_name().is_none() || path.is_dir() {
        return Err(WriteError::NotAFileName { path: path.into() });
    }
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    if !dir.is_dir() {
        return Err(WriteError::MissingDirectory {
            path: path.into(),
            dir: dir.into(),
        });
    }
    Ok(())
}

/// Makes sure `dir`, an output directory, exists: creates it when missing, but only it,
/// never its missing parents (a typo in a parent should fail, not build a tree somewhere).
pub fn create_output_dir(dir: &Path) -> Result<(), WriteError> {
    if dir.is_dir() {
        return Ok(());
    }
    let parent = match dir.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    if !parent.is_dir() {
        return Err(WriteError::MissingDirectory {
            path: dir.into(),
            dir: parent.into(),
        });
    }
    std::fs::create_dir(dir).map_err(WriteError::io(dir))
}

/// An output being written under its temporary name; [`AtomicFile::commit`] puts it in
/// place, dropping it unfinished removes it.
#[derive(Debug)]
pub struct AtomicFile {
    path: PathBuf,
    file: File,
    temp: Pending,
}

impl AtomicFile {
    /// Creates the temporary file for `path` now (so a bad path fails before any work).
    pub fn create(path: &Path) -> Result<AtomicFile, WriteError> {
        check_output_path(path)?;
        let (temp, file) = Pending::create(temp_path(path), |p| File::create_new(p))
            .map_err(WriteError::io(path))?;
        Ok(AtomicFile {
            path: path.into(),
            file,
            temp,
        })
    }

    /// The final path.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The temporary path being written.
    pub fn temp_path(&self) -> &Path {
        self.temp.path()
    }

    /// Syncs the file and renames it over the final path.
    pub fn commit(self) -> Result<(), WriteError> {
        let AtomicFile { path, file, temp } = self;
        file.sync_all().map_err(WriteError::io(&path))?;
        drop(file);
        temp.rename_to(&path)
            .map_err(|(_temp, e)| WriteError::io(&path)(e))
    }
}

impl Write for AtomicFile {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.file.write(buf)
    }
    fn flush(&mut self) -> std::io::Result<()> {
        self.file.flush()
    }
}

impl Seek for AtomicFile {
    fn seek(&mut self, pos: SeekFrom) -> std::io::Result<u64> {
        self.file.seek(pos)
    }
}

/// Writes `bytes` to `path` atomically.
pub fn write(path: &Path, bytes: impl AsRef<[u8]>) -> Result<(), WriteError> {
    let mut f = AtomicFile::create(path)?;
    f.write_all(bytes.as_ref()).map_err(WriteError::io(path))?;
    f.commit()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::{file_names, scratch_dir};
    use std::time::{Duration, Instant};

    #[test]
    fn a_file_appears_whole_or_not_at_all() {
        let dir = scratch_dir("atomic-whole");
        let path = dir.join("out.png");
        write(&path, b"old").unwrap();
        // Unfinished: dropped (an error on the way) leaves the old file and no temporary.
        let mut f = AtomicFile::create(&path).unwrap();
        f.write_all(b"half of the new").unwrap();
        assert!(is_temp_name(
            &f.temp_path().file_name().unwrap().to_string_lossy()
        ));
        drop(f);
        assert_eq!(std::fs::read(&path).unwrap(), b"old");
        assert_eq!(file_names(&dir), ["out.png"]);
        // Finished: replaces it.
        let mut f = AtomicFile::create(&path).unwrap();
        f.write_all(b"new").unwrap();
        f.commit().unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), b"new");
        assert_eq!(file_names(&dir), ["out.png"]);
        // Bad paths fail at creation, naming what is wrong.
        let e = AtomicFile::create(&dir.join("no/such/dir/x.png")).unwrap_err();
        assert!(e.to_string().contains("does not exist"), "{e}");
        let e = AtomicFile::create(&dir).unwrap_err();
        assert!(e.to_string().contains("is a directory"), "{e}");
        // Output directories: the last level is made, missing parents are an error.
        create_output_dir(&dir.join("frames")).unwrap();
        assert!(dir.join("frames").is_dir());
        create_output_dir(&dir.join("frames")).unwrap();
        let e = create_output_dir(&dir.join("typo/frames")).unwrap_err();
        assert!(e.to_string().contains("does not exist"), "{e}");
        assert!(!dir.join("typo").exists());
        std::fs::remove_dir(dir.join("frames")).unwrap();
        std::fs::remove_dir_all(&dir).ok();
    }

    /// The child half of the next test: writes its output slowly, forever, until killed.
    #[test]
    #[ignore = "run by a_killed_writer_leaves_the_old_file_intact as its child process"]
    fn slow_writer_child() {
        let Some(path) = std::env::var_os("FATHOM_SLOW_WRITER") else {
            return;
        };
        let mut f = AtomicFile::create(Path::new(&path)).unwrap();
        loop {
            f.write_all(&[b'n'; 4096]).unwrap();
            f.flush().unwrap();
            std::thread::sleep(Duration::from_millis(5));
        }
    }

    #[test]
    fn a_killed_writer_leaves_the_old_file_intact() {
        let dir = scratch_dir("atomic-killed");
        let path = dir.join("out.bin");
        let old: Vec<u8> = (0..100_000u32).map(|i| (i * 7 % 251) as u8).collect();
        write(&path, &old).unwrap();
        let mut child = std::process::Command::new(std::env::current_exe().unwrap())
            .args([
                "--exact",
                "files::atomic_file::tests::slow_writer_child",
                "--ignored",
                "--nocapture",
            ])
            .env("FATHOM_SLOW_WRITER", &path)
            .stdout(std::process::Stdio::null())
            .spawn()
            .unwrap();
        // Wait until the child has written a good part of its temporary file.
        let start = Instant::now();
        let written = || {
            std::fs::read_dir(&dir)
                .unwrap()
                .filter_map(|e| e.ok())
                .filter(|e| is_temp_name(&e.file_name().to_string_lossy()))
                .map(|e| e.metadata().map_or(0, |m| m.len()))
                .max()
                .unwrap_or(0)
        };
        while written() < 64 * 1024 {
            assert!(
                start.elapsed() < Duration::from_secs(60),
                "the child never wrote"
            );
            assert!(child.try_wait().unwrap().is_none(), "the child ended");
            std::thread::sleep(Duration::from_millis(10));
        }
        child.kill().unwrap();
        child.wait().unwrap();
        assert_eq!(
            std::fs::read(&path).unwrap(),
            old,
            "the old file is byte-identical"
        );
        // SIGKILL leaves the hidden temporary (nothing can remove it); never the final name.
        let left = file_names(&dir);
        assert!(
            left.iter().all(|n| n == "out.bin" || is_temp_name(n)),
            "{left:?}"
        );
        std::fs::remove_dir_all(&dir).ok();
    }
}
