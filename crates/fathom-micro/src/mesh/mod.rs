//! Triangle meshes as the shell builder needs them: welded positions with one unit normal each
//! (so offset vertices are shared and the shell has no cracks), and texture coordinates per
//! triangle corner (so UV seams stay seams without splitting positions).
//!
//! Loaders ([`obj`], [`gltf`]) and generators ([`teapot`], [`bush`]) produce a [`RawMesh`];
//! [`TriangleMesh::build`] cleans it: triangles with non-finite vertices, degenerate triangles and
//! triangles whose UVs have zero area are skipped and counted in the [`MeshReport`]; edges
//! shared by more than two triangles (non-manifold) are counted; missing normals are computed
//! (angle-weighted); missing UVs come from a chosen [`UvProjection`] or give a clear error.

pub mod bush;
pub mod gltf;
pub mod normals;
pub mod obj;
pub mod teapot;
pub mod uv;

use crate::error::MeshLoadError;
use crate::limits;
use glam::{DVec2, DVec3};
use std::collections::HashMap;
use std::path::Path;
pub use uv::UvProjection;

/// A mesh as read: positions (possibly duplicated along seams), triangles indexing them, and
/// optional per-corner normals and UVs.
#[derive(Clone, Debug, Default)]
pub struct RawMesh {
    /// Vertex positions.
    pub positions: Vec<DVec3>,
    /// Vertex indices of each triangle.
    pub triangles: Vec<[u32; 3]>,
    /// Normals per triangle corner, when the file has them.
    pub corner_normals: Option<Vec<[DVec3; 3]>>,
    /// UVs per triangle corner, when the file has them.
    pub corner_uvs: Option<Vec<[DVec2; 3]>>,
}

/// A cleaned mesh: welded positions, one unit normal per position, UVs per triangle corner.
#[derive(Clone, Debug)]
pub struct TriangleMesh {
    /// Welded vertex positions.
    pub positions: Vec<DVec3>,
    /// Unit normal per position.
    pub normals: Vec<DVec3>,
    /// Position indices of each triangle.
    pub triangles: Vec<[u32; 3]>,
    /// UVs per triangle corner.
    pub uvs: Vec<[DVec2; 3]>,
}

/// What cleaning a mesh found and did.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MeshReport {
    /// Triangles in the file.
    pub input_triangles: usize,
    /// Triangles kept.
    pub triangles: usize,
    /// Vertices after welding.
    pub vertices: usize,
    /// Triangles skipped for a NaN or infinite coordinate.
    pub skipped_non_finite: usize,
    /// Triangles skipped for a repeated vertex or a (near-)zero area.
    pub skipped_degenerate: usize,
    /// Triangles skipped for a (near-)zero or non-finite area in UV space.
    pub skipped_zero_uv_area: usize,
    /// Edges shared by more than two triangles.
    pub non_manifold_edges: usize,
    /// Whether the normals were computed (the file had none).
    pub normals_computed: bool,
    /// "file" or the projection's name.
    pub uv_source: String,
}

impl std::fmt::Display for MeshReport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} of {} triangles kept, {} vertices; skipped: {} with non-finite vertices, {} degenerate, {} with zero UV area; {} non-manifold edges; normals {}; UVs from {}",
            self.triangles,
            self.input_triangles,
            self.vertices,
            self.skipped_non_finite,
            self.skipped_degenerate,
            self.skipped_zero_uv_area,
            self.non_manifold_edges,
            if self.normals_computed {
                "computed"
            } else {
                "from the file"
            },
            self.uv_source
        )
    }
}

/// The built-in meshes, by the name `fathom micro` accepts in place of a file.
pub const BUILTINS: &[(&str, &str)] = &[
    (
        "teapot",
        "the Utah teapot, Newell's 32 Bezier patches tessellated",
    ),
    ("bush", "a lobed cube-sphere bush"),
    ("triangle", "one flat triangle in the xz plane"),
];

/// Loads a mesh file (`.obj`, `.gltf`, `.glb`) or a built-in mesh by name. `uv` overrides the
/// file's UVs (and is required when the file has none).
pub fn load(
    spec: &str,
    uv: Option<UvProjection>,
) -> Result<(TriangleMesh, MeshReport), MeshLoadError> {
    let path = Path::new(spec);
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase());
    let raw = match ext.as_deref() {
        Some("obj") => obj::load(path)?,
        Some("gltf") | Some("glb") => gltf::load(path)?,
        _ => match spec {
            "teapot" => teapot::raw(teapot::DEFAULT_DIVISIONS, teapot::DEFAULT_TILE),
            "bush" => bush::raw(bush::DEFAULT_DIVISIONS),
            "triangle" => triangle(),
            _ => {
                return Err(MeshLoadError::UnknownFormat {
                    origin: spec.into(),
                    ext: ext.unwrap_or_default(),
                    builtins: BUILTINS.iter().map(|b| b.0).collect::<Vec<_>>().join(", "),
                });
            }
        },
    };
    TriangleMesh::build(raw, uv, spec)
}

/// One triangle in the xz plane, facing +y, with planar UVs equal to (x, z).
pub fn triangle() -> RawMesh {
    let p = vec![
        DVec3::new(-1.0, 0.0, -1.0),
        DVec3::new(-1.0, 0.0, 1.0),
        DVec3::new(1.0, 0.0, -1.0),
    ];
    let uv = [p[0], p[1], p[2]].map(|q| DVec2::new(q.x, q.z));
    RawMesh {
        positions: p,
        triangles: vec![[0, 1, 2]],
        corner_normals: Some(vec![[DVec3::Y; 3]]),
        corner_uvs: Some(vec![uv]),
    }
}

/// Checks counts against the limits before anything is allocated for them.
pub fn check_counts(origin: &str, vertices: u64, triangles: u64) -> Result<(), MeshLoadError> {
    for (what, count, max) in [
        ("vertices", vertices, limits::MAX_VERTICES),
        ("triangles", triangles, limits::MAX_TRIANGLES),
    ] {
        if count > max {
            return Err(MeshLoadError::TooLarge {
                origin: origin.into(),
                what,
                count,
                max,
            });
        }
    }
    Ok(())
}

/// A position key that welds bit-identical positions (with -0 and +0 equal).
fn weld_key(p: DVec3) -> [u64; 3] {
    [p.x, p.y, p.z].map(|c| (c + 0.0).to_bits())
}

impl TriangleMesh {
    /// Cleans a raw mesh (see the module doc). `origin` names the source in errors.
    pub fn build(
        raw: RawMesh,
        uv: Option<UvProjection>,
        origin: &str,
    ) -> Result<(TriangleMesh, MeshReport), MeshLoadError> {
        check_counts(
            origin,
            raw.positions.len() as u64,
            raw.triangles.len() as u64,
        )?;
        let mut report = MeshReport {
            input_triangles: raw.triangles.len(),
            ..Default::default()
        };
        let bad_index = raw
            .triangles
            .iter()
            .flatten()
            .find(|&&i| i as usize >= raw.positions.len());
        if let Some(i) = bad_index {
            return Err(MeshLoadError::Invalid {
                origin: origin.into(),
                msg: format!(
                    "a triangle refers to vertex {i}, but the mesh has {} vertices",
                    raw.positions.len()
                ),
            });
        }
        if uv.is_none() && raw.corner_uvs.is_none() {
            return Err(MeshLoadError::NoUvs {
                origin: origin.into(),
            });
        }
        // Weld bit-identical positions.
        let mut remap = Vec::with_capacity(raw.positions.len());
        let mut positions = Vec::new();
        let mut seen: HashMap<[u64; 3], u32> = HashMap::new();
        for &p in &raw.positions {
            let id = *seen.entry(weld_key(p)).or_insert_with(|| {
                positions.push(p);
                positions.len() as u32 - 1
            });
            remap.push(id);
        }
        let (lo, hi) = positions
            .iter()
            .filter(|p| p.is_finite())
            .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), &p| {
                (lo.min(p), hi.max(p))
            });
        let diag = (hi - lo).length();
        let area_floor = 1e-12 * diag * diag;
        let mut tris = Vec::with_capacity(raw.triangles.len());
        let mut keep = Vec::with_capacity(raw.triangles.len());
        for (k, t) in raw.triangles.iter().enumerate() {
            let w = t.map(|i| remap[i as usize]);
            let p = w.map(|i| positions[i as usize]);
            if p.iter().any(|q| !q.is_finite()) {
                report.skipped_non_finite += 1;
                continue;
            }
            let area2 = (p[1] - p[0]).cross(p[2] - p[0]).length();
            if w[0] == w[1]
                || w[1] == w[2]
                || w[0] == w[2]
                || area2.partial_cmp(&area_floor) != Some(std::cmp::Ordering::Greater)
            {
                report.skipped_degenerate += 1;
                continue;
            }
            tris.push(w);
            keep.push(k);
        }
        // UVs: the projection when one is chosen, else the file's.
        let uvs: Vec<[DVec2; 3]> = match (uv, &raw.corner_uvs) {
            (Some(proj), _) => {
                report.uv_source = proj.name().into();
                uv::project(proj, &positions, &tris, lo, hi)
            }
            (None, Some(c)) => {
                report.uv_source = "file".into();
                keep.iter().map(|&k| c[k]).collect()
            }
            (None, None) => unreachable!("checked above"),
        };
        let mut kept = Vec::with_capacity(tris.len());
        let mut kept_uvs = Vec::with_capacity(tris.len());
        let mut kept_src = Vec::with_capacity(tris.len());
        for ((t, u), k) in tris.into_iter().zip(uvs).zip(keep) {
            let a = (u[1] - u[0]).perp_dot(u[2] - u[0]);
            if a.abs().partial_cmp(&1e-14) != Some(std::cmp::Ordering::Greater)
                || u.iter().any(|x| !x.is_finite())
            {
                report.skipped_zero_uv_area += 1;
                continue;
            }
            kept.push(t);
            kept_uvs.push(u);
            kept_src.push(k);
        }
        if kept.is_empty() {
            report.triangles = 0;
            return Err(MeshLoadError::Empty {
                origin: origin.into(),
                report: report.to_string(),
            });
        }
        // Drop positions no kept triangle uses.
        let mut used = vec![u32::MAX; positions.len()];
        let mut compact = Vec::new();
        for t in &mut kept {
            for i in t.iter_mut() {
                if used[*i as usize] == u32::MAX {
                    used[*i as usize] = compact.len() as u32;
                    compact.push(positions[*i as usize]);
                }
                *i = used[*i as usize];
            }
        }
        let corner_normals = raw
            .corner_normals
            .as_ref()
            .map(|c| kept_src.iter().map(|&k| c[k]).collect::<Vec<_>>());
        let (normals, computed) =
            normals::vertex_normals(&compact, &kept, corner_normals.as_deref());
        report.normals_computed = computed;
        report.non_manifold_edges = non_manifold_edges(&kept);
        report.triangles = kept.len();
        report.vertices = compact.len();
        Ok((
            TriangleMesh {
                positions: compact,
                normals,
                triangles: kept,
                uvs: kept_uvs,
            },
            report,
        ))
    }

    /// The axis-aligned bounding box (min, max).
    pub fn bounds(&self) -> (DVec3, DVec3) {
        self.positions
            .iter()
            .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), &p| {
                (lo.min(p), hi.max(p))
            })
    }

    /// The unit normal of triangle `t` from its winding, flipped to agree with its vertex
    /// normals (the shell's outside).
    pub fn face_normal(&self, t: usize) -> DVec3 {
        let [a, b, c] = self.triangles[t].map(|i| self.positions[i as usize]);
        let n = (b - a).cross(c - a).normalize_or_zero();
        let avg: DVec3 = self.triangles[t]
            .iter()
            .map(|&i| self.normals[i as usize])
            .sum();
        if n.dot(avg) < 0.0 { -n } else { n }
    }
}

/// Edges shared by more than two triangles.
pub fn non_manifold_edges(tris: &[[u32; 3]]) -> usize {
    let mut count: HashMap<(u32, u32), u32> = HashMap::new();
    for t in tris {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            *count.entry((a.min(b), a.max(b))).or_default() += 1;
        }
    }
    count.values().filter(|&&c| c > 2).count()
}

#[cfg(test)]
mod tests;

/// Reads a file, refusing it before reading when it exceeds [`limits::MAX_MESH_FILE_BYTES`]
/// or is not a regular file (a FIFO would block, a device such as `/dev/zero` never ends).
pub fn read_limited(path: &Path) -> Result<Vec<u8>, MeshLoadError> {
    use fathom_core::input_file::{self, ReadError};
    let origin = path.display().to_string();
    input_file::read(path, limits::MAX_MESH_FILE_BYTES).map_err(|e| match e {
        ReadError::TooLarge { size, .. } => MeshLoadError::FileTooLarge { origin, size },
        ReadError::Io { source, .. } => MeshLoadError::Io { origin, source },
        ReadError::NotAFile { kind, .. } => MeshLoadError::Invalid {
            origin,
            msg: format!("it is a {kind}, not a regular file; it was not read"),
        },
    })
}
