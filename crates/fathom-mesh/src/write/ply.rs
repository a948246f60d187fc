//! Binary little-endian PLY with per-vertex sRGB colours (`red green blue` as uchar), faces as
//! `uchar` counts of `uint` indices: the layout MeshLab, Blender and most slicers read.

use super::{Spool, commit, create_output, io_err};
use crate::{IsoMeshError, MeshSink, Vertex, Window};
use fathom_core::atomic_file::AtomicFile;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

pub struct PlySink {
    path: PathBuf,
    out: Option<AtomicFile>,
    verts: Spool,
    faces: Spool,
    nv: u64,
    nf: u64,
}

impl PlySink {
    pub fn create(path: &Path) -> Result<Self, IsoMeshError> {
        let out = create_output(path)?;
        Ok(PlySink {
            path: path.into(),
            out: Some(out),
            verts: Spool::create(path, "vertices")?,
            faces: Spool::create(path, "faces")?,
            nv: 0,
            nf: 0,
        })
    }
}

impl MeshSink for PlySink {
    fn vertices(&mut self, v: &[Vertex]) -> Result<(), IsoMeshError> {
        let mut b = Vec::with_capacity(v.len() * 15);
        for x in v {
            for c in x.p {
                b.extend_from_slice(&c.to_le_bytes());
            }
            b.extend_from_slice(&x.colour);
        }
        self.nv += v.len() as u64;
        self.verts.write(&b)
    }

    fn triangles(&mut self, t: &[[u32; 3]], _: &Window) -> Result<(), IsoMeshError> {
        let mut b = Vec::with_capacity(t.len() * 13);
        for tri in t {
            b.push(3);
            for i in tri {
                b.extend_from_slice(&i.to_le_bytes());
            }
        }
        self.nf += t.len() as u64;
        self.faces.write(&b)
    }

    fn finish(&mut self) -> Result<(), IsoMeshError> {
        let out = self.out.take().expect("finish called once");
        let mut w = BufWriter::with_capacity(1 << 20, out);
        let header = format!(
            "ply\nformat binary_little_endian 1.0\ncomment made by fathom\n\
             element vertex {}\nproperty float x\nproperty float y\nproperty float z\n\
             property uchar red\nproperty uchar green\nproperty uchar blue\n\
             element face {}\nproperty list uchar uint vertex_indices\nend_header\n",
            self.nv, self.nf
        );
        w.write_all(header.as_bytes()).map_err(io_err(&self.path))?;
        self.verts.copy_to(&mut w, &self.path)?;
        self.faces.copy_to(&mut w, &self.path)?;
        commit(w, &self.path)
    }
}
