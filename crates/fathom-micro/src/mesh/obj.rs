//! Wavefront OBJ through `tobj`. `tobj` reports what went wrong but not where, and trusts face
//! indices it has not checked, so a first pass over the text ([`scan`]) checks every line
//! `tobj` reads (`v`, `vt`, `vn`, `f`, `l`) and names the file, line and column of the first
//! bad one; it also counts vertices and triangles, so oversized meshes are refused before
//! anything is allocated for them. Only text that passed reaches `tobj`.

use super::{RawMesh, check_counts};
use crate::error::MeshLoadError;
use crate::limits;
use glam::{DVec2, DVec3};
use std::path::Path;

/// Reads an OBJ file, refusing oversized files before reading them.
pub fn load(path: &Path) -> Result<RawMesh, MeshLoadError> {
    let text = super::read_limited(path)?;
    let origin = path.display().to_string();
    let text = String::from_utf8(text).map_err(|e| {
        let valid = &e.as_bytes()[..e.utf8_error().valid_up_to()];
        let line = valid.iter().filter(|&&b| b == b'\n').count() + 1;
        let col = valid.iter().rev().take_while(|&&b| b != b'\n').count() + 1;
        MeshLoadError::Syntax {
            origin: origin.clone(),
            line,
            col,
            msg: "the file is not valid UTF-8 text".into(),
        }
    })?;
    parse(&text, &origin)
}

/// What the first pass counted.
#[derive(Debug, Default, PartialEq)]
pub struct Counts {
    /// `v` lines.
    pub positions: u64,
    /// `vt` lines.
    pub texcoords: u64,
    /// `vn` lines.
    pub normals: u64,
    /// Triangles the faces make (a polygon of n corners makes n - 2).
    pub triangles: u64,
}

/// Checks every line `tobj` will read; counts vertices and triangles.
pub fn scan(text: &str, origin: &str) -> Result<Counts, MeshLoadError> {
    let mut c = Counts::default();
    for (n, line) in text.lines().enumerate() {
        let at = |col_byte: usize, msg: String| MeshLoadError::Syntax {
            origin: origin.into(),
            line: n + 1,
            col: line[..col_byte.min(line.len())].chars().count() + 1,
            msg,
        };
        // Words with their byte offsets.
        let words: Vec<(usize, &str)> = line
            .split_whitespace()
            .map(|w| (w.as_ptr() as usize - line.as_ptr() as usize, w))
            .collect();
        let Some(&(_, kw)) = words.first() else {
            continue;
        };
        let floats = |from: usize, need: usize, what: &str| -> Result<Vec<f64>, MeshLoadError> {
            let mut out = Vec::new();
            for i in from..from + need {
                let Some(&(off, w)) = words.get(i) else {
                    return Err(at(
                        line.len(),
                        format!("`{kw}` needs {need} numbers ({what}), found {}", i - from),
                    ));
                };
                // tobj reads f32: a value beyond its range would become infinite.
                match w.parse::<f32>() {
                    Ok(x) => out.push(x as f64),
                    Err(_) => {
                        return Err(at(off, format!("expected a number ({what}), found `{w}`")));
                    }
                }
            }
            Ok(out)
        };
        match kw {
            "v" => {
                floats(1, 3, "x y z")?;
                match words.len() {
                    4 => {}
                    5 => {
                        let w = floats(4, 1, "the weight w")?[0];
                        if w == 0.0 || !w.is_finite() {
                            return Err(at(
                                words[4].0,
                                "the weight w of a vertex must be a finite number other than 0"
                                    .into(),
                            ));
                        }
                    }
                    7 => {
                        floats(4, 3, "the colour r g b")?;
                    }
                    _ => {
                        return Err(at(
                            words[4].0,
                            "a vertex is `v x y z`, `v x y z w` or `v x y z r g b`".into(),
                        ));
                    }
                }
                c.positions += 1;
            }
            "vt" => {
                floats(1, 2, "u v")?;
                c.texcoords += 1;
            }
            "vn" => {
                floats(1, 3, "x y z")?;
                c.normals += 1;
            }
            "f" | "l" => {
                for &(off, w) in &words[1..] {
                    check_face_vertex(w, &c).map_err(|m| at(off, m))?;
                }
                let n = words.len() as u64 - 1;
                if kw == "f" && n >= 3 {
                    c.triangles += n - 2;
                }
            }
            _ => {}
        }
        if c.positions > limits::MAX_VERTICES || c.triangles > limits::MAX_TRIANGLES {
            check_counts(origin, c.positions, c.triangles)?;
        }
    }
    Ok(c)
}

/// Checks one `v`, `v/vt`, `v//vn` or `v/vt/vn` against the elements defined so far.
fn check_face_vertex(w: &str, c: &Counts) -> Result<(), String> {
    let parts: Vec<&str> = w.split('/').collect();
    if parts.len() > 3 || parts[0].is_empty() {
        return Err(format!(
            "expected a face vertex `v`, `v/vt`, `v//vn` or `v/vt/vn`, found `{w}`"
        ));
    }
    let names = ["vertex", "texture coordinate", "normal"];
    let have = [c.positions, c.texcoords, c.normals];
    for (k, p) in parts.iter().enumerate() {
        if p.is_empty() {
            continue;
        }
        let i: i64 = p
            .parse()
            .map_err(|_| format!("expected a whole number ({} index), found `{p}`", names[k]))?;
        let n = have[k] as i64;
        let ok = if i > 0 { i <= n } else { i < 0 && -i <= n };
        if !ok {
            return Err(format!(
                "{} index {i} is out of range: {n} defined so far (indices run 1..={n}, or -1..=-{n} counting back)",
                names[k]
            ));
        }
    }
    Ok(())
}

/// Parses OBJ text; `origin` names it in errors.
pub fn parse(text: &str, origin: &str) -> Result<RawMesh, MeshLoadError> {
    let counts = scan(text, origin)?;
    check_counts(origin, counts.positions, counts.triangles)?;
    let opts = tobj::LoadOptions {
        triangulate: true,
        single_index: false,
        ignore_points: true,
        ignore_lines: true,
    };
    let (models, _materials) = tobj::load_obj_buf(&mut text.as_bytes(), &opts, |_| {
        Err(tobj::LoadError::OpenFileFailed)
    })
    .map_err(|e| MeshLoadError::Invalid {
        origin: origin.into(),
        msg: format!("the OBJ reader refused the file: {e}"),
    })?;
    let mut raw = RawMesh::default();
    let mut normals = Vec::new();
    let mut uvs = Vec::new();
    let (mut all_normals, mut all_uvs) = (true, true);
    for m in &models {
        let mesh = &m.mesh;
        let base = raw.positions.len() as u32;
        raw.positions.extend(
            mesh.positions
                .chunks_exact(3)
                .map(|p| DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64)),
        );
        let has_n = mesh.normal_indices.len() == mesh.indices.len() && !mesh.normals.is_empty();
        let has_t = mesh.texcoord_indices.len() == mesh.indices.len() && !mesh.texcoords.is_empty();
        all_normals &= has_n;
        all_uvs &= has_t;
        for (k, t) in mesh.indices.chunks_exact(3).enumerate() {
            raw.triangles.push([t[0] + base, t[1] + base, t[2] + base]);
            if has_n {
                normals.push([0, 1, 2].map(|j| {
                    let i = mesh.normal_indices[3 * k + j] as usize * 3;
                    mesh.normals.get(i..i + 3).map_or(DVec3::ZERO, |n| {
                        DVec3::new(n[0] as f64, n[1] as f64, n[2] as f64)
                    })
                }));
            }
            if has_t {
                uvs.push([0, 1, 2].map(|j| {
                    let i = mesh.texcoord_indices[3 * k + j] as usize * 2;
                    mesh.texcoords
                        .get(i..i + 2)
                        .map_or(DVec2::NAN, |t| DVec2::new(t[0] as f64, t[1] as f64))
                }));
            }
        }
    }
    // Normals or UVs on only some faces count as none (the mesh builder computes normals; UVs
    // then need a projection).
    raw.corner_normals = all_normals.then_some(normals);
    raw.corner_uvs = (all_uvs && !raw.triangles.is_empty()).then_some(uvs);
    Ok(raw)
}
