//! Simplification to a triangle budget, and the triangle-count estimate made before meshing.
//!
//! [`simplify`] runs meshoptimizer's edge-collapse simplifier (through the `meshopt` crate):
//! quadric error, collapses that would flip a triangle or change the topology refused, so a
//! closed, oriented 2-manifold stays one (the result is checked with [`crate::check::edges`]
//! and a simplification that broke it is an error, never a silent hole). Unused vertices are
//! dropped and colours follow their vertices.
//!
//! [`estimate_triangles`] meshes the scene at two coarse resolutions and extrapolates the
//! growth of the triangle count (r^2 for a smooth surface, up to r^2.73 for a Menger sponge's
//! ever finer holes) to the requested resolution: a few hundred milliseconds before a run that
//! may write gigabytes.

use crate::check::{self, EdgeReport, TriangleIndex};
use crate::stream::{MeshOptions, mesh, plan};
use crate::{IsoMesh, IsoMeshError, Vertex};
use fathom_core::Tape;
use fathom_core::scene::Scene;
use glam::{DVec3, Vec3};

/// What a simplification did.
#[derive(Clone, Debug, PartialEq)]
pub struct Simplified {
    pub mesh: IsoMesh,
    /// Triangles before and after.
    pub triangles_before: u64,
    pub triangles_after: u64,
    /// meshoptimizer's own error bound, world units.
    pub error: f64,
    /// How the edges of the result are shared.
    pub edges: EdgeReport,
}

/// Simplifies `m` to at most `max_triangles` triangles, moving the surface by at most
/// `max_error` (world units; meshoptimizer's quadric bound) so that collapses which would pinch
/// thin parts into sheets (and break the manifold) are not taken. A mesh already within the
/// budget is returned as it is. Fails if `max_triangles` is below 4 (a closed surface needs
/// four), if the budget cannot be met within the error, or if the input was a closed manifold
/// and the result is not.
pub fn simplify(
    m: &IsoMesh,
    max_triangles: u64,
    max_error: f64,
) -> Result<Simplified, IsoMeshError> {
    simplify_checked(m, max_triangles, max_error, true)
}

/// As [`simplify`]; with `keep_closed` false a result that opened the surface is returned
/// (for measuring what the simplifier does; `fathom bench simplify --allow-open`).
pub fn simplify_checked(
    m: &IsoMesh,
    max_triangles: u64,
    max_error: f64,
    keep_closed: bool,
) -> Result<Simplified, IsoMeshError> {
    if max_triangles < MIN_TRIANGLES {
        return Err(IsoMeshError::Simplify(format!(
            "--max-triangles {max_triangles} is out of range [{MIN_TRIANGLES}, {}]",
            u32::MAX / 3
        )));
    }
    let before = m.tris.len() as u64;
    if before <= max_triangles {
        return Ok(Simplified {
            mesh: m.clone(),
            triangles_before: before,
            triangles_after: before,
            error: 0.0,
            edges: check::edges(&m.tris),
        });
    }
    let closed_before = check::edges(&m.tris).is_closed_manifold();
    let positions: Vec<[f32; 3]> = m.verts.iter().map(|v| v.p).collect();
    let indices: Vec<u32> = m.tris.iter().flatten().copied().collect();
    let mut abs_error = 0.0f32;
    let out = meshopt::simplify_decoder(
        &indices,
        &positions,
        (max_triangles * 3) as usize,
        max_error as f32,
        meshopt::SimplifyOptions::ErrorAbsolute,
        Some(&mut abs_error),
    );
    if (out.len() / 3) as u64 > max_triangles {
        return Err(IsoMeshError::Simplify(format!(
            "simplifying within an error of {max_error:.3e} (--max-error) leaves {} \
             triangles, more than --max-triangles {max_triangles}; raise either, or lower \
             --resolution",
            out.len() / 3
        )));
    }
    // Keep the vertices the triangles use, in their order.
    let mut remap = vec![u32::MAX; m.verts.len()];
    let mut verts: Vec<Vertex> = Vec::new();
    let tris: Vec<[u32; 3]> = out
        .chunks_exact(3)
        .map(|t| {
            [0, 1, 2].map(|k| {
                let v = t[k] as usize;
                if remap[v] == u32::MAX {
                    remap[v] = verts.len() as u32;
                    verts.push(m.verts[v]);
                }
                remap[v]
            })
        })
        .collect();
    let tris = drop_back_to_back(tris);
    let edges = check::edges(&tris);
    if keep_closed && closed_before && !edges.is_closed_manifold() {
        return Err(IsoMeshError::Simplify(format!(
            "simplifying to {max_triangles} triangles broke the closed surface ({} boundary, \
             {} non-manifold, {} misoriented edges, {} degenerate triangles); raise \
             --max-triangles",
            edges.boundary, edges.non_manifold, edges.misoriented, edges.degenerate
        )));
    }
    Ok(Simplified {
        triangles_before: before,
        triangles_after: tris.len() as u64,
        error: abs_error as f64,
        mesh: IsoMesh { verts, tris },
        edges,
    })
}

/// Removes pairs of triangles over the same three vertices facing opposite ways: where
/// collapses flatten a thin wall, its two sides end up back to back, and their shared edges
/// then belong to four triangles. Dropping both keeps every edge's count even and its
/// directions balanced, so a closed surface stays closed.
fn drop_back_to_back(tris: Vec<[u32; 3]>) -> Vec<[u32; 3]> {
    use std::collections::HashMap;
    // Canonical rotation (smallest id first) and whether the winding is the reversed one.
    let key = |t: [u32; 3]| {
        let r = (0..3).min_by_key(|&i| t[i]).unwrap_or(0);
        let c = [t[r], t[(r + 1) % 3], t[(r + 2) % 3]];
        if c[1] < c[2] {
            ([c[0], c[1], c[2]], false)
        } else {
            ([c[0], c[2], c[1]], true)
        }
    };
    let mut open: HashMap<[u32; 3], Vec<(usize, bool)>> = HashMap::new();
    let mut keep = vec![true; tris.len()];
    for (i, &t) in tris.iter().enumerate() {
        let (k, rev) = key(t);
        let list = open.entry(k).or_default();
        if let Some(j) = list.iter().position(|&(_, r)| r != rev) {
            let (other, _) = list.swap_remove(j);
            keep[other] = false;
            keep[i] = false;
        } else {
            list.push((i, rev));
        }
    }
    tris.into_iter()
        .zip(keep)
        .filter_map(|(t, k)| k.then_some(t))
        .collect()
}

/// Fewest triangles `--max-triangles` accepts: a closed surface needs four.
pub const MIN_TRIANGLES: u64 = 4;

/// Two-sided Hausdorff distance between two meshes, sampled: the largest distance from any
/// vertex, edge midpoint or triangle centroid of either to the surface of the other. Points
/// inside triangles between the samples are not measured, so this is a lower bound of the
/// true distance, closer the smaller the triangles.
pub fn hausdorff(a: &IsoMesh, b: &IsoMesh) -> f64 {
    one_sided(a, b).max(one_sided(b, a))
}

fn one_sided(from: &IsoMesh, to: &IsoMesh) -> f64 {
    use rayon::prelude::*;
    if from.tris.is_empty() || to.tris.is_empty() {
        return 0.0;
    }
    // Buckets about the target's mean edge length.
    let p = |m: &IsoMesh, v: u32| Vec3::from(m.verts[v as usize].p).as_dvec3();
    let edge: f64 = to
        .tris
        .iter()
        .map(|t| (p(to, t[0]) - p(to, t[1])).length())
        .sum::<f64>()
        / to.tris.len() as f64;
    let index = TriangleIndex::new(to, edge.max(1e-9));
    from.tris
        .par_iter()
        .map(|t| {
            let ps = t.map(|v| p(from, v));
            let c = (ps[0] + ps[1] + ps[2]) / 3.0;
            let mid = |i: usize, j: usize| 0.5 * (ps[i] + ps[j]);
            [ps[0], ps[1], ps[2], mid(0, 1), mid(1, 2), mid(2, 0), c]
                .into_iter()
                .map(|q| nearest(&index, q))
                .fold(0.0, f64::max)
        })
        .reduce(|| 0.0, f64::max)
}

/// Distance to the mesh, widening the search until a triangle is found.
fn nearest(index: &TriangleIndex, q: DVec3) -> f64 {
    let mut reach = 1;
    loop {
        if let Some(d) = index.distance(q, reach) {
            return d;
        }
        if reach > 64 {
            return f64::INFINITY;
        }
        reach *= 2;
    }
}

/// A triangle count expected at the requested resolution.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TriangleEstimate {
    /// Expected triangles.
    pub triangles: u64,
    /// The coarse resolutions meshed and their triangle counts.
    pub samples: [(u32, u64); 2],
    /// Growth exponent d in triangles ~ resolution^d, clamped to [2, 3].
    pub exponent: f64,
}

/// Resolution the estimate's finer coarse mesh is made at (the coarser is half).
pub const ESTIMATE_RESOLUTION: u32 = 64;

/// Estimates the triangle count of meshing at `o.resolution` from two coarse meshes (exact
/// when the resolution is at most [`ESTIMATE_RESOLUTION`]).
pub fn estimate_triangles(
    scene: &Scene,
    tape: &Tape,
    o: &MeshOptions,
) -> Result<TriangleEstimate, IsoMeshError> {
    let count = |r: u32| -> Result<u64, IsoMeshError> {
        let co = MeshOptions {
            resolution: r,
            colours: false,
            ..o.clone()
        };
        let p = plan(scene, tape, &co)?;
        let mut sink = crate::Counter::default();
        mesh(scene, tape, &p, &co, &mut sink, &|_, _| {})?;
        Ok(sink.tris)
    };
    let r1 = o.resolution.min(ESTIMATE_RESOLUTION);
    let r0 = (r1 / 2).max(crate::grid::MIN_RESOLUTION);
    let t1 = count(r1)?;
    if r1 == o.resolution {
        return Ok(TriangleEstimate {
            triangles: t1,
            samples: [(r1, t1), (r1, t1)],
            exponent: 2.0,
        });
    }
    let t0 = count(r0)?;
    let exponent = if t0 > 0 && t1 > 0 && r1 > r0 {
        ((t1 as f64 / t0 as f64).ln() / (r1 as f64 / r0 as f64).ln()).clamp(2.0, 3.0)
    } else {
        2.0
    };
    let triangles = (t1 as f64 * (o.resolution as f64 / r1 as f64).powf(exponent)).round() as u64;
    Ok(TriangleEstimate {
        triangles,
        samples: [(r0, t0), (r1, t1)],
        exponent,
    })
}

/// Bytes a mesh of `triangles` triangles takes in `format` (a closed surface has about half
/// as many vertices as triangles; OBJ lines are counted at their typical length).
pub fn file_size(format: crate::write::Format, triangles: u64, colours: bool) -> u64 {
    use crate::write::Format;
    let verts = triangles / 2 + 2;
    match format {
        Format::Stl => 84 + 50 * triangles,
        Format::Ply => 300 + verts * (12 + if colours { 3 } else { 0 }) + triangles * 13,
        Format::Obj => verts * if colours { 60 } else { 40 } + triangles * 24,
        Format::Glb => 1200 + verts * (12 + 12 + if colours { 4 } else { 0 }) + triangles * 12,
    }
}

/// Bytes [`simplify`] needs for a mesh of `triangles` triangles: the mesh (12 bytes a triangle,
/// 16 a vertex), its flat copies for meshoptimizer and meshoptimizer's own tables (about 80
/// bytes a triangle, measured order of magnitude), and the edge check.
pub fn simplify_memory(triangles: u64) -> u64 {
    triangles * (12 + 8 + 12 + 6 + 80 + 48)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Method;
    use fathom_core::presets;

    fn menger(resolution: u32, method: Method) -> (IsoMesh, Scene, Tape, MeshOptions) {
        let scene = presets::load("menger").unwrap();
        let tape = Tape::compile(&scene).unwrap();
        let o = MeshOptions {
            resolution,
            method,
            ..MeshOptions::default()
        };
        let p = plan(&scene, &tape, &o).unwrap();
        let mut m = IsoMesh::default();
        mesh(&scene, &tape, &p, &o, &mut m, &|_, _| {}).unwrap();
        (m, scene, tape, o)
    }

    #[test]
    fn simplification_meets_the_budget_or_refuses_and_never_opens_a_closed_surface() {
        let (m, ..) = menger(54, Method::MarchingCubes);
        assert!(check::edges(&m.tris).is_closed_manifold());
        let voxel = 2.0 * 1.05 / 54.0;
        for (budget, error) in [
            (m.tris.len() as u64 / 2, 0.5 * voxel),
            (m.tris.len() as u64 / 8, 4.0 * voxel),
        ] {
            match simplify(&m, budget, error) {
                Ok(s) => {
                    assert!(s.triangles_after <= budget, "{}", s.triangles_after);
                    assert!(s.edges.is_closed_manifold(), "{:?}", s.edges);
                    let used = s.mesh.tris.iter().flatten().max().copied().unwrap() as usize;
                    assert_eq!(used + 1, s.mesh.verts.len(), "unused vertices dropped");
                    let h = hausdorff(&m, &s.mesh);
                    assert!(h < error + 2.0 * voxel, "Hausdorff {h} vs voxel {voxel}");
                }
                Err(e) => {
                    let e = e.to_string();
                    assert!(
                        e.contains("broke the closed surface") || e.contains("--max-error"),
                        "{e}"
                    );
                }
            }
        }
        assert!(hausdorff(&m, &m) < 1e-6, "{}", hausdorff(&m, &m));
        // Within budget: unchanged.
        let same = simplify(&m, m.tris.len() as u64, voxel).unwrap();
        assert_eq!(same.mesh, m);
        assert!(
            simplify(&m, 3, voxel)
                .unwrap_err()
                .to_string()
                .contains("[4, ")
        );
        // Too tight an error for the budget: refused, not exceeded.
        let e = simplify(&m, 100, 1e-9).unwrap_err().to_string();
        assert!(e.contains("--max-error"), "{e}");
    }

    #[test]
    fn back_to_back_pairs_are_dropped_and_nothing_else() {
        let t = vec![[0, 1, 2], [2, 1, 0], [1, 2, 3], [3, 1, 2], [4, 5, 6]];
        // [3, 1, 2] is [1, 2, 3] rotated (same winding): kept, like [4, 5, 6].
        assert_eq!(drop_back_to_back(t), vec![[1, 2, 3], [3, 1, 2], [4, 5, 6]]);
    }

    #[test]
    fn the_estimate_is_near_the_count() {
        let (m, scene, tape, o) = menger(128, Method::DualContouring);
        let e = estimate_triangles(&scene, &tape, &o).unwrap();
        let real = m.tris.len() as f64;
        let ratio = e.triangles as f64 / real;
        assert!((0.5..2.0).contains(&ratio), "{e:?} vs {real}");
        assert!((2.0..=3.0).contains(&e.exponent));
        let small = MeshOptions {
            resolution: 32,
            ..o.clone()
        };
        let (m32, ..) = menger(32, Method::DualContouring);
        assert_eq!(
            estimate_triangles(&scene, &tape, &small).unwrap().triangles,
            m32.tris.len() as u64
        );
    }
}
