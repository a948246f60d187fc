//! Binary STL via `stl_io`. STL stores positions per triangle and its header holds the
//! triangle count, so triangles are spooled as position triples while meshing and handed to
//! `stl_io::write_stl` as an exact-size iterator at the end.

use super::{Spool, commit, create_output, io_err};
use crate::{IsoMeshError, MeshSink, Vertex, Window};
use fathom_core::atomic_file::AtomicFile;
use std::fs::File;
use std::io::{BufReader, Read};
use std::path::{Path, PathBuf};

pub struct StlSink {
    path: PathBuf,
    out: Option<AtomicFile>,
    tris: Spool,
    count: u64,
}

impl StlSink {
    pub fn create(path: &Path) -> Result<Self, IsoMeshError> {
        let out = create_output(path)?;
        Ok(StlSink {
            path: path.into(),
            out: Some(out),
            tris: Spool::create(path, "triangles")?,
            count: 0,
        })
    }
}

impl MeshSink for StlSink {
    fn vertices(&mut self, _: &[Vertex]) -> Result<(), IsoMeshError> {
        Ok(())
    }

    fn triangles(&mut self, t: &[[u32; 3]], window: &Window) -> Result<(), IsoMeshError> {
        let mut b = Vec::with_capacity(t.len() * 36);
        for tri in t {
            for &i in tri {
                for c in window.get(i).p {
                    b.extend_from_slice(&c.to_le_bytes());
                }
            }
        }
        self.count += t.len() as u64;
        self.tris.write(&b)
    }

    fn finish(&mut self) -> Result<(), IsoMeshError> {
        if self.count > u32::MAX as u64 {
            return Err(IsoMeshError::Format {
                path: self.path.display().to_string(),
                msg: format!(
                    "{} triangles; binary STL holds at most {}",
                    self.count,
                    u32::MAX
                ),
            });
        }
        let out = self.out.take().expect("finish called once");
        let mut w = std::io::BufWriter::with_capacity(1 << 20, out);
        let mut it = Triangles {
            r: self.tris.reader()?,
            left: self.count as usize,
            error: None,
        };
        stl_io::write_stl(&mut w, &mut it).map_err(io_err(&self.path))?;
        if let Some(e) = it.error {
            return Err(e);
        }
        commit(w, &self.path)
    }
}

/// Reads spooled triangles back, computing each facet normal.
struct Triangles {
    r: BufReader<File>,
    left: usize,
    error: Option<IsoMeshError>,
}

impl Iterator for Triangles {
    type Item = stl_io::Triangle;
    fn next(&mut self) -> Option<stl_io::Triangle> {
        if self.left == 0 {
            return None;
        }
        self.left -= 1;
        let mut b = [0u8; 36];
        if let Err(source) = self.r.read_exact(&mut b) {
            self.error.get_or_insert(IsoMeshError::Io {
                path: "triangle spool".into(),
                source,
            });
        }
        let f = |i: usize| f32::from_le_bytes(b[4 * i..4 * i + 4].try_into().unwrap());
        let v = [0, 1, 2].map(|k| glam::Vec3::new(f(3 * k), f(3 * k + 1), f(3 * k + 2)));
        let n = (v[1] - v[0]).cross(v[2] - v[0]).normalize_or_zero();
        Some(stl_io::Triangle {
            normal: stl_io::Normal::new(n.to_array()),
            vertices: v.map(|p| stl_io::Vertex::new(p.to_array())),
        })
    }
    fn size_hint(&self) -> (usize, Option<usize>) {
        (self.left, Some(self.left))
    }
}

impl ExactSizeIterator for Triangles {}
