//! The shell: each triangle's vertices offset along their normals by the shell height make a
//! prism, split into three tetrahedra (Porumbescu et al. 2005, "Shell maps").
//!
//! No cracks: a prism's side quads are split along a diagonal chosen by the global indices of
//! the edge's two vertices only (from the lower-indexed vertex's base to the higher-indexed
//! vertex's top), so the two prisms on either side of an edge split their shared quad the same
//! way and every interior face is shared by exactly two tetrahedra. With a < b < c the
//! triangle's vertex indices: (a b c c'), (a b b' c'), (a a' b' c').
//!
//! Tetrahedra that the offset turns inside out (the shell folds where it is thicker than the
//! surface's concave radius) or flattens are skipped and counted.

use crate::error::MicroError;
use crate::limits;
use crate::mesh::TriangleMesh;
use crate::tet::{NONE, Tet, jacobian, spectral_norm};
use crate::texture::Tiling;
use glam::DVec3;
use std::collections::HashMap;

/// The vertices of the three tetrahedra as (sorted corner rank, on top).
const SPLIT: [[(usize, bool); 4]; 3] = [
    [(0, false), (1, false), (2, false), (2, true)],
    [(0, false), (1, false), (1, true), (2, true)],
    [(0, false), (0, true), (1, true), (2, true)],
];

/// What building a shell found.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ShellReport {
    /// Triangles of the base mesh.
    pub triangles: usize,
    /// Tetrahedra built (three per prism, less those skipped).
    pub tetrahedra: usize,
    /// Tetrahedra skipped because the offset turned them inside out or flat.
    pub skipped_inverted: usize,
    /// Faces with one tetrahedron (the shell's surface).
    pub boundary_faces: usize,
    /// Faces shared by exactly two tetrahedra.
    pub interior_faces: usize,
    /// Faces claimed by more than two tetrahedra (non-manifold input).
    pub overfull_faces: usize,
    /// Largest per-prism Lipschitz factor.
    pub lipschitz_max: f64,
    /// Median per-prism Lipschitz factor.
    pub lipschitz_median: f64,
}

/// A shell of tetrahedra over a mesh.
#[derive(Clone, Debug)]
pub struct Shell {
    /// The tetrahedra, three per prism.
    pub tets: Vec<Tet>,
    /// `neighbours[t][k]`: the tetrahedron across face `k` of `t` (opposite vertex `k`), or
    /// [`NONE`].
    pub neighbours: Vec<[u32; 4]>,
    /// Shell height, mesh units.
    pub height: f64,
    /// How the texture tiles the mesh's UVs.
    pub tiling: Tiling,
    /// What building the shell found.
    pub report: ShellReport,
    /// Bounding box of every shell vertex.
    pub bounds: (DVec3, DVec3),
}

impl Shell {
    /// Builds the shell of `mesh` with height `height` (world units) for a texture tiled as
    /// `tiling` says.
    pub fn build(mesh: &TriangleMesh, height: f64, tiling: &Tiling) -> Result<Shell, MicroError> {
        let (lo, hi) = mesh.bounds();
        let diag = (hi - lo).length();
        let rel = height / diag.max(1e-300);
        if !(rel.is_finite() && rel > 1e-6 && rel <= limits::MAX_SHELL_RELATIVE) {
            return Err(MicroError::ShellHeight { height, diag });
        }
        tiling.validate()?;
        let scale = tiling.cell.size();
        let mut tets = Vec::with_capacity(3 * mesh.triangles.len());
        let mut report = ShellReport {
            triangles: mesh.triangles.len(),
            ..Default::default()
        };
        let top_of = |i: u32| mesh.positions[i as usize] + mesh.normals[i as usize] * height;
        let mut prism_l = Vec::with_capacity(mesh.triangles.len());
        for (ti, tri) in mesh.triangles.iter().enumerate() {
            let mut order = [0usize, 1, 2];
            order.sort_by_key(|&c| tri[c]);
            let face_n = mesh.face_normal(ti);
            let first = tets.len();
            let mut l_max: f64 = 0.0;
            for split in SPLIT {
                let corner = split.map(|(rank, _)| order[rank] as u8);
                let top = split.map(|(_, t)| t);
                let verts: [DVec3; 4] = std::array::from_fn(|k| {
                    let i = tri[corner[k] as usize];
                    if top[k] {
                        top_of(i)
                    } else {
                        mesh.positions[i as usize]
                    }
                });
                // The same tetrahedron in the ideal right prism fixes its orientation.
                let ideal: [DVec3; 4] = std::array::from_fn(|k| {
                    let p = mesh.positions[tri[corner[k] as usize] as usize];
                    if top[k] { p + face_n * height } else { p }
                });
                let vol = |v: &[DVec3; 4]| (v[1] - v[0]).dot((v[2] - v[0]).cross(v[3] - v[0]));
                let planes = Tet::planes_of(&verts);
                let (Some(planes), true) = (planes, vol(&verts) * vol(&ideal) > 0.0) else {
                    report.skipped_inverted += 1;
                    continue;
                };
                let tex: [DVec3; 4] = std::array::from_fn(|k| {
                    let uv = mesh.uvs[ti][corner[k] as usize] * tiling.tiles;
                    DVec3::new(uv.x, if top[k] { 1.0 } else { 0.0 }, uv.y)
                });
                let scene = tex.map(|t| t * scale);
                let jac = jacobian(&planes, &scene);
                l_max = l_max.max(spectral_norm(&jac));
                let normals = corner.map(|c| mesh.normals[tri[c as usize] as usize]);
                let bottom_face = (0..4)
                    .find(|&k| top[k] && (0..4).filter(|&j| j != k).all(|j| !top[j]))
                    .unwrap_or(4) as u8;
                tets.push(Tet {
                    verts,
                    tex,
                    normals,
                    planes,
                    corner,
                    top,
                    tri: ti as u32,
                    bottom_face,
                    jac,
                    lipschitz: 0.0,
                });
            }
            for t in &mut tets[first..] {
                t.lipschitz = l_max;
            }
            if tets.len() > first {
                prism_l.push(l_max);
            }
        }
        let neighbours = adjacency(mesh, &tets, &mut report);
        report.tetrahedra = tets.len();
        prism_l.sort_by(f64::total_cmp);
        report.lipschitz_max = prism_l.last().copied().unwrap_or(0.0);
        report.lipschitz_median = prism_l.get(prism_l.len() / 2).copied().unwrap_or(0.0);
        let bounds = tets
            .iter()
            .flat_map(|t| t.verts)
            .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(a, b), p| {
                (a.min(p), b.max(p))
            });
        Ok(Shell {
            tets,
            neighbours,
            height,
            tiling: tiling.clone(),
            report,
            bounds,
        })
    }
}

/// Shell vertex id: base vertex `i` is `2 i`, its offset copy `2 i + 1`.
fn shell_vertex(mesh: &TriangleMesh, t: &Tet, k: usize) -> u64 {
    2 * mesh.triangles[t.tri as usize][t.corner[k] as usize] as u64 + t.top[k] as u64
}

/// Pairs tetrahedra across shared faces; counts boundary, interior and overfull faces.
fn adjacency(mesh: &TriangleMesh, tets: &[Tet], report: &mut ShellReport) -> Vec<[u32; 4]> {
    let mut faces: HashMap<[u64; 3], Vec<(u32, u8)>> = HashMap::with_capacity(tets.len() * 2);
    for (ti, t) in tets.iter().enumerate() {
        for k in 0..4 {
            let mut key = [0u64; 3];
            for (n, j) in (0..4).filter(|&j| j != k).enumerate() {
                key[n] = shell_vertex(mesh, t, j);
            }
            key.sort_unstable();
            faces.entry(key).or_default().push((ti as u32, k as u8));
        }
    }
    let mut nb = vec![[NONE; 4]; tets.len()];
    for owners in faces.values() {
        match owners[..] {
            [_] => report.boundary_faces += 1,
            [(a, fa), (b, fb)] => {
                report.interior_faces += 1;
                nb[a as usize][fa as usize] = b;
                nb[b as usize][fb as usize] = a;
            }
            _ => report.overfull_faces += 1,
        }
    }
    nb
}

#[cfg(test)]
mod tests;
