//! Wavefront OBJ, streamed: `v x y z r g b` lines (colours in [0, 1], the extension MeshLab,
//! Blender and tobj read) as vertices arrive, `f a b c` lines (1-based) as triangles do.

use super::{commit, create_output, io_err};
use crate::{IsoMeshError, MeshSink, Vertex, Window};
use fathom_core::atomic_file::AtomicFile;
use std::fmt::Write as _;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

pub struct ObjSink {
    path: PathBuf,
    w: Option<BufWriter<AtomicFile>>,
}

impl ObjSink {
    pub fn create(path: &Path) -> Result<Self, IsoMeshError> {
        let f = create_output(path)?;
        let mut w = BufWriter::with_capacity(1 << 20, f);
        w.write_all(b"# made by fathom\n").map_err(io_err(path))?;
        Ok(ObjSink {
            path: path.into(),
            w: Some(w),
        })
    }
}

impl MeshSink for ObjSink {
    fn vertices(&mut self, v: &[Vertex]) -> Result<(), IsoMeshError> {
        let mut s = String::with_capacity(v.len() * 48);
        for x in v {
            let c = x.colour.map(|c| c as f32 / 255.0);
            let _ = writeln!(
                s,
                "v {} {} {} {:.4} {:.4} {:.4}",
                x.p[0], x.p[1], x.p[2], c[0], c[1], c[2]
            );
        }
        self.w
            .as_mut()
            .expect("written before finish")
            .write_all(s.as_bytes())
            .map_err(io_err(&self.path))
    }

    fn triangles(&mut self, t: &[[u32; 3]], _: &Window) -> Result<(), IsoMeshError> {
        let mut s = String::with_capacity(t.len() * 32);
        for tri in t {
            let _ = writeln!(
                s,
                "f {} {} {}",
                tri[0] as u64 + 1,
                tri[1] as u64 + 1,
                tri[2] as u64 + 1
            );
        }
        self.w
            .as_mut()
            .expect("written before finish")
            .write_all(s.as_bytes())
            .map_err(io_err(&self.path))
    }

    fn finish(&mut self) -> Result<(), IsoMeshError> {
        let w = self.w.take().expect("finish called once");
        commit(w, &self.path)
    }
}
