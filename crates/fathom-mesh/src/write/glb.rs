//! Binary glTF 2.0 (GLB): one mesh with `POSITION`, `COLOR_0` (linear, normalised bytes) and
//! `u32` indices. The JSON is built with `gltf-json`; the binary chunk is assembled from the
//! spooled vertex, colour and index streams, since its length and the position bounds go in
//! the JSON, which comes first.

use super::{Spool, commit, create_output, io_err};
use crate::{IsoMeshError, MeshSink, Vertex, Window};
use fathom_core::atomic_file::AtomicFile;
use gltf_json as json;
use json::validation::Checked::Valid;
use json::validation::USize64;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

pub struct GlbSink {
    path: PathBuf,
    out: Option<AtomicFile>,
    positions: Spool,
    colours: Spool,
    indices: Spool,
    nv: u64,
    ni: u64,
    lo: [f32; 3],
    hi: [f32; 3],
}

impl GlbSink {
    pub fn create(path: &Path) -> Result<Self, IsoMeshError> {
        let out = create_output(path)?;
        Ok(GlbSink {
            path: path.into(),
            out: Some(out),
            positions: Spool::create(path, "positions")?,
            colours: Spool::create(path, "colours")?,
            indices: Spool::create(path, "indices")?,
            nv: 0,
            ni: 0,
            lo: [f32::MAX; 3],
            hi: [f32::MIN; 3],
        })
    }
}

/// 8-bit sRGB to 8-bit linear.
fn linear8(s: u8) -> u8 {
    let s = s as f64 / 255.0;
    let l = if s <= 0.04045 {
        s / 12.92
    } else {
        ((s + 0.055) / 1.055).powf(2.4)
    };
    (l * 255.0 + 0.5) as u8
}

impl MeshSink for GlbSink {
    fn vertices(&mut self, v: &[Vertex]) -> Result<(), IsoMeshError> {
        let mut p = Vec::with_capacity(v.len() * 12);
        let mut c = Vec::with_capacity(v.len() * 4);
        for x in v {
            for a in 0..3 {
                p.extend_from_slice(&x.p[a].to_le_bytes());
                self.lo[a] = self.lo[a].min(x.p[a]);
                self.hi[a] = self.hi[a].max(x.p[a]);
            }
            c.extend(x.colour.map(linear8));
            c.push(255);
        }
        self.nv += v.len() as u64;
        self.positions.write(&p)?;
        self.colours.write(&c)
    }

    fn triangles(&mut self, t: &[[u32; 3]], _: &Window) -> Result<(), IsoMeshError> {
        let mut b = Vec::with_capacity(t.len() * 12);
        for tri in t {
            for i in tri {
                b.extend_from_slice(&i.to_le_bytes());
            }
        }
        self.ni += 3 * t.len() as u64;
        self.indices.write(&b)
    }

    fn finish(&mut self) -> Result<(), IsoMeshError> {
        let (pos_len, col_len, idx_len) = (self.nv * 12, self.nv * 4, self.ni * 4);
        let bin_len = pos_len + col_len + idx_len;
        let root = self.json(pos_len, col_len, idx_len);
        let mut text = json::serialize::to_string(&root).map_err(|e| IsoMeshError::Format {
            path: self.path.display().to_string(),
            msg: e.to_string(),
        })?;
        while text.len() % 4 != 0 {
            text.push(' ');
        }
        let total = 12 + 8 + text.len() as u64 + 8 + bin_len;
        if total > u32::MAX as u64 {
            return Err(IsoMeshError::Format {
                path: self.path.display().to_string(),
                msg: format!(
                    "the GLB would be {total} bytes; GLB files hold at most 4 GiB (use .ply)"
                ),
            });
        }
        let out = self.out.take().expect("finish called once");
        let mut w = BufWriter::with_capacity(1 << 20, out);
        let e = io_err(&self.path);
        let mut head = Vec::with_capacity(28);
        head.extend_from_slice(b"glTF");
        head.extend_from_slice(&2u32.to_le_bytes());
        head.extend_from_slice(&(total as u32).to_le_bytes());
        head.extend_from_slice(&(text.len() as u32).to_le_bytes());
        head.extend_from_slice(b"JSON");
        w.write_all(&head).map_err(&e)?;
        w.write_all(text.as_bytes()).map_err(&e)?;
        w.write_all(&(bin_len as u32).to_le_bytes()).map_err(&e)?;
        w.write_all(b"BIN\0").map_err(&e)?;
        self.positions.copy_to(&mut w, &self.path)?;
        self.colours.copy_to(&mut w, &self.path)?;
        self.indices.copy_to(&mut w, &self.path)?;
        commit(w, &self.path)
    }
}

impl GlbSink {
    fn json(&self, pos_len: u64, col_len: u64, idx_len: u64) -> json::Root {
        let mut root = json::Root::default();
        let buffer = root.push(json::Buffer {
            byte_length: USize64(pos_len + col_len + idx_len),
            extensions: Default::default(),
            extras: Default::default(),
            name: None,
            uri: None,
        });
        let view = |offset: u64, len: u64, target| json::buffer::View {
            buffer,
            byte_length: USize64(len),
            byte_offset: Some(USize64(offset)),
            byte_stride: None,
            extensions: Default::default(),
            extras: Default::default(),
            name: None,
            target: Some(Valid(target)),
        };
        use json::buffer::Target::{ArrayBuffer, ElementArrayBuffer};
        let (vp, vc, vi) = (
            view(0, pos_len, ArrayBuffer),
            view(pos_len, col_len, ArrayBuffer),
            view(pos_len + col_len, idx_len, ElementArrayBuffer),
        );
        let (vp, vc, vi) = (root.push(vp), root.push(vc), root.push(vi));
        use json::accessor::{ComponentType, GenericComponentType, Type};
        let accessor =
            |view, count: u64, ct, ty, normalized, bounds: Option<([f32; 3], [f32; 3])>| {
                json::Accessor {
                    buffer_view: Some(view),
                    byte_offset: Some(USize64(0)),
                    count: USize64(count),
                    component_type: Valid(GenericComponentType(ct)),
                    extensions: Default::default(),
                    extras: Default::default(),
                    name: None,
                    type_: Valid(ty),
                    min: bounds.map(|b| json::Value::from(b.0.to_vec())),
                    max: bounds.map(|b| json::Value::from(b.1.to_vec())),
                    normalized,
                    sparse: None,
                }
            };
        let bounds = (self.nv > 0).then_some((self.lo, self.hi));
        let positions = root.push(accessor(
            vp,
            self.nv,
            ComponentType::F32,
            Type::Vec3,
            false,
            bounds,
        ));
        let colours = root.push(accessor(
            vc,
            self.nv,
            ComponentType::U8,
            Type::Vec4,
            true,
            None,
        ));
        let indices = root.push(accessor(
            vi,
            self.ni,
            ComponentType::U32,
            Type::Scalar,
            false,
            None,
        ));
        let primitive = json::mesh::Primitive {
            attributes: [
                (Valid(json::mesh::Semantic::Positions), positions),
                (Valid(json::mesh::Semantic::Colors(0)), colours),
            ]
            .into_iter()
            .collect(),
            extensions: Default::default(),
            extras: Default::default(),
            indices: Some(indices),
            material: None,
            mode: Valid(json::mesh::Mode::Triangles),
            targets: None,
        };
        let mesh = root.push(json::Mesh {
            extensions: Default::default(),
            extras: Default::default(),
            name: None,
            primitives: vec![primitive],
            weights: None,
        });
        let node = root.push(json::Node {
            mesh: Some(mesh),
            ..Default::default()
        });
        let scene = root.push(json::Scene {
            extensions: Default::default(),
            extras: Default::default(),
            name: None,
            nodes: vec![node],
        });
        root.scene = Some(scene);
        root
    }
}
