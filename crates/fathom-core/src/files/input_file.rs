//! Reading input files safely: only regular files are opened (a FIFO would block the open
//! forever, a device such as `/dev/zero` never ends), symlinks are followed to what they name
//! and judged by that, and every read is capped at a documented size before it starts (and
//! again while reading, in case the file grows meanwhile).

use std::fs::File;
use std::io::Read;
use std::path::{Path, PathBuf};

/// Why an input file was not read; every variant names the path.
#[derive(Debug, thiserror::Error)]
pub enum ReadError {
    /// The file could not be opened or read.
    #[error("cannot read {}: {source}", path.display())]
    Io {
        /// The file that was to be read.
        path: PathBuf,
        /// The error from the operating system.
        #[source]
        source: std::io::Error,
    },
    /// Not a regular file (a directory, FIFO, socket or device): refused before opening.
    #[error("cannot read {}: it is a {kind}, not a regular file", path.display())]
    NotAFile {
        /// The path given.
        path: PathBuf,
        /// What it is instead (`directory`, `FIFO`, ...).
        kind: &'static str,
    },
    /// Larger than the limit for its kind of file; not read.
    #[error("cannot read {}: it is {size} bytes; the limit is {max} bytes", path.display())]
    TooLarge {
        /// The file that was to be read.
        path: PathBuf,
        /// Its size, bytes.
        size: u64,
        /// The limit for its kind of file, bytes.
        max: u64,
    },
}

impl ReadError {
    /// What is wrong, without the path (for messages that name the file themselves).
    pub fn reason(&self) -> String {
        match self {
            ReadError::Io { source, .. } => source.to_string(),
            ReadError::NotAFile { kind, .. } => format!("it is a {kind}, not a regular file"),
            ReadError::TooLarge { size, max, .. } => {
                format!("it is {size} bytes; the limit is {max} bytes")
            }
        }
    }
}

/// What kind of non-regular file `m` describes, for messages.
fn kind(m: &std::fs::Metadata) -> &'static str {
    let t = m.file_type();
    if t.is_dir() {
        return "directory";
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if t.is_fifo() {
            return "FIFO (named pipe)";
        }
        if t.is_socket() {
            return "socket";
        }
        if t.is_char_device() || t.is_block_device() {
            return "device";
        }
    }
    "special file"
}

/// Opens `path` if it is a regular file (after following symlinks) of at most `max` bytes;
/// returns the file and its size.
pub fn open(path: &Path, max: u64) -> Result<(File, u64), ReadError> {
    let io = |source| ReadError::Io {
        path: path.into(),
        source,
    };
    let m = std::fs::metadata(path).map_err(io)?;
    if !m.is_file() {
        return Err(ReadError::NotAFile {
            path: path.into(),
            kind: kind(&m),
        });
    }
    if m.len() > max {
        return Err(ReadError::TooLarge {
            path: path.into(),
            size: m.len(),
            max,
        });
    }
    let f = File::open(path).map_err(io)?;
    Ok((f, m.len()))
}

/// Reads the whole of `path`, a regular file of at most `max` bytes.
pub fn read(path: &Path, max: u64) -> Result<Vec<u8>, ReadError> {
    let (f, len) = open(path, max)?;
    let mut bytes = Vec::with_capacity(len as usize);
    f.take(max.saturating_add(1))
        .read_to_end(&mut bytes)
        .map_err(|source| ReadError::Io {
            path: path.into(),
            source,
        })?;
    if bytes.len() as u64 > max {
        return Err(ReadError::TooLarge {
            path: path.into(),
            size: bytes.len() as u64,
            max,
        });
    }
    Ok(bytes)
}

/// [`read`] as UTF-8 text (a leading byte-order mark is kept; see the callers).
pub fn read_to_string(path: &Path, max: u64) -> Result<String, ReadError> {
    let bytes = read(path, max)?;
    String::from_utf8(bytes).map_err(|e| ReadError::Io {
        path: path.into(),
        source: std::io::Error::new(std::io::ErrorKind::InvalidData, e),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_regular_files_under_the_limit_are_read() {
        let dir = std::env::temp_dir().join(format!("fathom-input-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("a.txt");
        std::fs::write(&p, "hello").unwrap();
        assert_eq!(read(&p, 5).unwrap(), b"hello");
        let e = read(&p, 4).unwrap_err().to_string();
        assert!(e.contains("5 bytes") && e.contains("limit is 4"), "{e}");
        let e = read(&dir, 100).unwrap_err().to_string();
        assert!(e.contains("directory"), "{e}");
        #[cfg(unix)]
        {
            // A device behind a symlink: refused without reading a byte.
            let link = dir.join("zero.bin");
            let _ = std::fs::remove_file(&link);
            std::os::unix::fs::symlink("/dev/zero", &link).unwrap();
            let e = read(&link, 1 << 30).unwrap_err().to_string();
            assert!(e.contains("device"), "{e}");
            // A FIFO: refused at once instead of blocking in open.
            let fifo = dir.join("pipe");
            let _ = std::fs::remove_file(&fifo);
            let made = std::process::Command::new("mkfifo").arg(&fifo).status();
            if made.is_ok_and(|s| s.success()) {
                let e = read(&fifo, 100).unwrap_err().to_string();
                assert!(e.contains("FIFO"), "{e}");
            }
        }
        std::fs::remove_dir_all(&dir).ok();
    }
}
