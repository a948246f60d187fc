//! What the two grid file formats share: a fixed-size header read first, the body's size
//! checked against the header and the memory limit before it is read, and little-endian voxel
//! arrays in both directions.

use crate::error::VolumeError;
use fathom_core::atomic_file::AtomicFile;
use std::io::{Read, Write};
use std::path::{Path, PathBuf};

/// A format error at byte `offset` of `path`.
pub fn format_err(path: &Path, offset: u64, msg: impl Into<String>) -> VolumeError {
    VolumeError::Format {
        path: path.to_path_buf(),
        offset,
        msg: msg.into(),
    }
}

/// An I/O error on `path`.
pub fn io_err(path: &Path) -> impl Fn(std::io::Error) -> VolumeError + '_ {
    move |source| VolumeError::Io {
        path: PathBuf::from(path),
        source,
    }
}

/// Reads `path` whose first `header_len` bytes say how long the whole file must be:
/// `parse_header(header, file_len)` checks the header (and the memory limit) and returns the
/// expected total length, which is compared with the file's before the body is read. A file
/// shorter than the header is handed to `parse_header` as it is, so it can say which field is
/// missing. Returns the whole file.
pub fn read_checked(
    path: &Path,
    header_len: usize,
    parse_header: impl FnOnce(&[u8], u64) -> Result<u64, VolumeError>,
) -> Result<Vec<u8>, VolumeError> {
    // Only a regular file: a FIFO would block the open, a device never ends. Its size is
    // checked against the header (and the memory limit) before the body is read.
    let (mut f, len) = fathom_core::input_file::open(path, u64::MAX).map_err(|e| match e {
        fathom_core::input_file::ReadError::Io { source, .. } => io_err(path)(source),
        other => VolumeError::Invalid(other.to_string()),
    })?;
    let mut header = vec![0u8; header_len.min(len as usize)];
    f.read_exact(&mut header).map_err(io_err(path))?;
    let total = parse_header(&header, len)?;
    check_length(path, len, total)?;
    let mut bytes = header;
    bytes.resize(total as usize, 0);
    f.read_exact(&mut bytes[header_len..])
        .map_err(io_err(path))?;
    Ok(bytes)
}

/// Compares a file's length with what its header promises.
pub fn check_length(path: &Path, len: u64, total: u64) -> Result<(), VolumeError> {
    if len < total {
        return Err(format_err(
            path,
            len,
            format!(
                "the file is truncated: it ends after {len} bytes, its header promises {total}"
            ),
        ));
    }
    if len > total {
        return Err(format_err(
            path,
            total,
            format!(
                "{} unexpected bytes after the last voxel (the header promises {total} bytes)",
                len - total
            ),
        ));
    }
    Ok(())
}

/// Little-endian reader over a header, whose errors name the field and its byte offset.
pub struct Fields<'a> {
    pub path: &'a Path,
    pub bytes: &'a [u8],
    pub at: usize,
}

impl Fields<'_> {
    /// The next `n` bytes, or an error naming the missing `field`.
    pub fn take(&mut self, n: usize, field: &str) -> Result<&[u8], VolumeError> {
        let end = self.at + n;
        if end > self.bytes.len() {
            return Err(format_err(
                self.path,
                self.bytes.len() as u64,
                format!("the file is truncated inside its header (expected {field})"),
            ));
        }
        let s = &self.bytes[self.at..end];
        self.at = end;
        Ok(s)
    }

    pub fn u32(&mut self, field: &str) -> Result<u32, VolumeError> {
        Ok(u32::from_le_bytes(self.take(4, field)?.try_into().unwrap()))
    }

    pub fn i32(&mut self, field: &str) -> Result<i32, VolumeError> {
        Ok(i32::from_le_bytes(self.take(4, field)?.try_into().unwrap()))
    }

    pub fn f32s<const N: usize>(&mut self, field: &str) -> Result<[f32; N], VolumeError> {
        let b = self.take(4 * N, field)?;
        Ok(std::array::from_fn(|i| {
            f32::from_le_bytes(b[4 * i..4 * i + 4].try_into().unwrap())
        }))
    }
}

/// Appends a box as six little-endian f32 (min xyz, max xyz), as both formats store it.
pub fn push_box(h: &mut Vec<u8>, b: &crate::grid::WorldBox) {
    for v in b.min.to_array().into_iter().chain(b.max.to_array()) {
        h.extend_from_slice(&v.to_le_bytes());
    }
}

/// Voxels from little-endian 4-byte words.
pub fn words<T>(bytes: &[u8], from: fn([u8; 4]) -> T) -> Vec<T> {
    bytes
        .chunks_exact(4)
        .map(|c| from(c.try_into().unwrap()))
        .collect()
}

/// Writes `header` then the voxels as little-endian 4-byte words, atomically (the old file
/// stays until the new one is whole).
pub fn write_file<T: Copy>(
    path: &Path,
    header: &[u8],
    data: &[T],
    to: fn(T) -> [u8; 4],
) -> Result<(), VolumeError> {
    let f = AtomicFile::create(path)?;
    let mut w = std::io::BufWriter::new(f);
    w.write_all(header).map_err(io_err(path))?;
    for chunk in data.chunks(1 << 16) {
        let bytes: Vec<u8> = chunk.iter().flat_map(|&v| to(v)).collect();
        w.write_all(&bytes).map_err(io_err(path))?;
    }
    let f = w.into_inner().map_err(|e| io_err(path)(e.into_error()))?;
    Ok(f.commit()?)
}
