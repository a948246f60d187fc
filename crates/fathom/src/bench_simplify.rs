//! `fathom bench simplify`: what `fathom mesh --max-triangles` does to a mesh. Meshes a preset
//! in memory, prints the estimate made before meshing against the real count, simplifies to the
//! budget and prints JSON: triangles and binary-STL bytes before and after, the two-sided
//! Hausdorff distance between the two meshes (sampled: the vertices, edge midpoints and
//! triangle centroids of each to the other's surface, so a lower bound), meshoptimizer's own error bound, whether each is a closed manifold, and
//! the seconds each step took.

use clap::Args;
use fathom_core::{Tape, presets};
use fathom_mesh::simplify::{self, file_size};
use fathom_mesh::write::Format;
use fathom_mesh::{IsoMesh, MeshOptions, check};
use std::time::Instant;

#[derive(Args)]
pub struct SimplifyBenchArgs {
    /// Preset to mesh.
    #[arg(long, default_value = "menger")]
    preset: String,
    /// Cells along the longest side.
    #[arg(long, default_value_t = 256)]
    resolution: u32,
    /// Triangle budget.
    #[arg(long, default_value_t = 1_000_000)]
    max_triangles: u64,
    /// Largest surface movement, in voxels.
    #[arg(long, default_value_t = 0.5)]
    max_error: f64,
    /// Report a simplification that opened the surface instead of failing (its edge counts
    /// are in the JSON).
    #[arg(long)]
    allow_open: bool,
    /// Vertex placement: dc, sn or mc.
    #[arg(long, value_enum, default_value = "dc")]
    method: crate::cmd_mesh::MethodArg,
}

pub fn run(a: SimplifyBenchArgs) -> Result<(), String> {
    let scene = presets::load(&a.preset).map_err(|e| e.to_string())?;
    let tape = Tape::compile(&scene).map_err(|e| e.to_string())?;
    let o = MeshOptions {
        resolution: a.resolution,
        method: crate::cmd_mesh::MeshArgs::method_of(a.method),
        max_memory: u64::MAX,
        ..MeshOptions::default()
    };
    let t = Instant::now();
    let est = simplify::estimate_triangles(&scene, &tape, &o).map_err(|e| e.to_string())?;
    let estimate_s = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let plan = fathom_mesh::plan(&scene, &tape, &o).map_err(|e| e.to_string())?;
    let mut m = IsoMesh::default();
    fathom_mesh::mesh(&scene, &tape, &plan, &o, &mut m, &|_, _| {}).map_err(|e| e.to_string())?;
    let mesh_s = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let s = simplify::simplify_checked(
        &m,
        a.max_triangles,
        a.max_error * plan.grid.h,
        !a.allow_open,
    )
    .map_err(|e| e.to_string())?;
    let simplify_s = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let h = simplify::hausdorff(&m, &s.mesh);
    let hausdorff_s = t.elapsed().as_secs_f64();
    let before = check::edges(&m.tris);
    let stl = |n: u64| file_size(Format::Stl, n, false);
    let out = serde_json::json!({
        "preset": a.preset,
        "resolution": a.resolution,
        "method": crate::cmd_mesh::MeshArgs::method_of(a.method).name(),
        "voxel": plan.grid.h,
        "estimate": {
            "triangles": est.triangles,
            "exponent": est.exponent,
            "samples": est.samples,
            "ratio_to_real": est.triangles as f64 / m.tris.len().max(1) as f64,
            "seconds": estimate_s,
        },
        "before": {
            "triangles": m.tris.len(),
            "vertices": m.verts.len(),
            "stl_bytes": stl(m.tris.len() as u64),
            "closed_manifold": before.is_closed_manifold(),
            "mesh_seconds": mesh_s,
        },
        "after": {
            "max_triangles": a.max_triangles,
            "triangles": s.triangles_after,
            "vertices": s.mesh.verts.len(),
            "stl_bytes": stl(s.triangles_after),
            "closed_manifold": s.edges.is_closed_manifold(),
            "boundary_edges": s.edges.boundary,
            "non_manifold_edges": s.edges.non_manifold,
            "misoriented_edges": s.edges.misoriented,
            "simplify_seconds": simplify_s,
        },
        "hausdorff": h,
        "hausdorff_voxels": h / plan.grid.h,
        "hausdorff_seconds": hausdorff_s,
        "meshopt_error": s.error,
    });
    println!(
        "{}",
        serde_json::to_string_pretty(&out).map_err(|e| e.to_string())?
    );
    Ok(())
}
