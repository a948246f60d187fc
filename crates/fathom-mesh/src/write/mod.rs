//! Mesh files: PLY (binary, with vertex colours), STL (binary, via `stl_io`), OBJ (text, with
//! vertex colours as the common `v x y z r g b` extension) and GLB (binary glTF 2.0, JSON via
//! `gltf-json`).
//!
//! Every sink creates its output's temporary file when it is made, so an unwritable path fails
//! before any work, and renames it into place only in [`MeshSink::finish`]: an existing file
//! survives a refused, failed or interrupted run.
//! Formats whose header holds counts (PLY, STL, GLB) spool the streamed vertices and triangles
//! to files beside the output and assemble it in [`MeshSink::finish`], so memory stays
//! bounded; OBJ streams straight through. Why our own PLY and OBJ writers: `ply-rs` builds
//! the whole file as maps of properties in memory (dozens of bytes per vertex, and it cannot
//! stream), and OBJ is a few `write!` lines; both are read back with `ply-rs` and `tobj` in the
//! tests.

mod glb;
mod obj;
mod ply;
mod stl;

use crate::{IsoMeshError, MeshSink};
use fathom_core::atomic_file::AtomicFile;
use fathom_core::cleanup::Pending;
use std::fs::File;
use std::io::{BufReader, BufWriter, Read, Write};
use std::path::{Path, PathBuf};

/// An output format, chosen by file extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    Ply,
    Stl,
    Obj,
    Glb,
}

impl Format {
    pub const ALL: [(Format, &'static str); 4] = [
        (Format::Ply, "ply"),
        (Format::Stl, "stl"),
        (Format::Obj, "obj"),
        (Format::Glb, "glb"),
    ];

    /// The format of `path` by its extension.
    pub fn of(path: &Path) -> Result<Format, IsoMeshError> {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .unwrap_or("")
            .to_ascii_lowercase();
        Format::ALL
            .iter()
            .find(|(_, e)| *e == ext)
            .map(|(f, _)| *f)
            .ok_or_else(|| IsoMeshError::Format {
                path: path.display().to_string(),
                msg: format!(
                    "unknown mesh format `.{ext}`; valid choices: {}",
                    Format::ALL.map(|(_, e)| format!(".{e}")).join(", ")
                ),
            })
    }
}

/// Opens a sink writing `path` in the format its extension names (the file is created now).
pub fn create(path: &Path) -> Result<Box<dyn MeshSink>, IsoMeshError> {
    Ok(match Format::of(path)? {
        Format::Ply => Box::new(ply::PlySink::create(path)?),
        Format::Stl => Box::new(stl::StlSink::create(path)?),
        Format::Obj => Box::new(obj::ObjSink::create(path)?),
        Format::Glb => Box::new(glb::GlbSink::create(path)?),
    })
}

fn io_err(path: &Path) -> impl Fn(std::io::Error) -> IsoMeshError + '_ {
    move |source| IsoMeshError::Io {
        path: path.display().to_string(),
        source,
    }
}

/// A temporary file beside the output holding one stream of records: registered with
/// [`fathom_core::cleanup`], so it is removed when dropped (an error, the end of the run) and
/// by the command's Ctrl-C handler.
struct Spool {
    temp: Pending,
    path: PathBuf,
    w: Option<BufWriter<File>>,
    pub bytes: u64,
}

impl Spool {
    fn create(out: &Path, tag: &str) -> Result<Spool, IsoMeshError> {
        let mut name = out.file_name().unwrap_or_default().to_os_string();
        name.push(format!(".{tag}.part"));
        let path = out.with_file_name(name);
        let (temp, f) =
            Pending::create(path.clone(), |p| File::create(p)).map_err(io_err(&path))?;
        Ok(Spool {
            temp,
            path,
            w: Some(BufWriter::with_capacity(1 << 20, f)),
            bytes: 0,
        })
    }

    fn write(&mut self, b: &[u8]) -> Result<(), IsoMeshError> {
        self.bytes += b.len() as u64;
        let path = self.path.clone();
        self.w
            .as_mut()
            .expect("spool written after it was read")
            .write_all(b)
            .map_err(io_err(&path))
    }

    /// Flushes and reopens the spool for reading.
    fn reader(&mut self) -> Result<BufReader<File>, IsoMeshError> {
        if let Some(mut w) = self.w.take() {
            w.flush().map_err(io_err(&self.path))?;
        }
        let f = File::open(&self.path).map_err(io_err(&self.path))?;
        Ok(BufReader::with_capacity(1 << 20, f))
    }

    /// Appends the whole spool to `out`.
    fn copy_to(&mut self, out: &mut impl Write, out_path: &Path) -> Result<(), IsoMeshError> {
        let mut r = self.reader()?;
        let mut buf = vec![0u8; 1 << 20];
        loop {
            let n = r.read(&mut buf).map_err(io_err(&self.path))?;
            if n == 0 {
                return Ok(());
            }
            out.write_all(&buf[..n]).map_err(io_err(out_path))?;
        }
    }
}

impl Drop for Spool {
    fn drop(&mut self) {
        // Closed before `temp` removes the file.
        self.w = None;
        debug_assert_eq!(self.temp.path(), self.path);
    }
}

/// Creates the output's temporary file (see [`fathom_core::atomic_file`]): the sink fills
/// it and commits it in `finish`, so a refused, failed or interrupted run leaves an existing
/// file as it was.
fn create_output(path: &Path) -> Result<AtomicFile, IsoMeshError> {
    Ok(AtomicFile::create(path)?)
}

/// Flushes `w` and renames its file into place.
fn commit(w: BufWriter<AtomicFile>, path: &Path) -> Result<(), IsoMeshError> {
    let f = w.into_inner().map_err(|e| io_err(path)(e.into_error()))?;
    Ok(f.commit()?)
}

#[cfg(test)]
mod tests;
