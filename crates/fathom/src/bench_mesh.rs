//! `fathom bench mesh`: triangles per second, peak resident memory and surface error of the
//! streaming mesher for the Menger sponge and the Mandelbulb at several resolutions, an exact
//! Hausdorff check on a sphere, and the same figures for Mandelbulber2's headless mesh export
//! (`mandelbulber2 --nogui --voxel ply`) where it is installed.
//!
//! Each configuration runs in a child process (`--single`), so the peak resident memory it
//! reports (the kernel's `VmHWM`) belongs to that run alone. Meshes go to a counting sink
//! unless `--write DIR` is given: at 4096^3 the Menger sponge has billions of triangles, more
//! than the disk should take.

use clap::Args;
use fathom_core::{Evaluator, Tape, V3, presets};
use fathom_mesh::{Counter, IsoMesh, IsoMeshError, MeshOptions, MeshSink, Method, Vertex, Window};
use glam::DVec3;
use std::path::PathBuf;
use std::process::Command;
use std::time::Instant;

#[derive(Args)]
pub struct MeshBenchArgs {
    /// Presets to mesh.
    #[arg(long, value_delimiter = ',', default_value = "menger,mandelbulb")]
    presets: Vec<String>,
    /// Cells along the longest side.
    #[arg(long, value_delimiter = ',', default_value = "512,1024,4096")]
    resolutions: Vec<u32>,
    /// Vertex placement: dc, sn or mc.
    #[arg(long, value_enum, default_value = "dc")]
    method: crate::cmd_mesh::MethodArg,
    /// Worker threads.
    #[arg(long, default_value_t = 2)]
    threads: usize,
    /// Write PLY files here instead of counting.
    #[arg(long)]
    write: Option<PathBuf>,
    /// Mandelbulber2 voxel export resolutions to compare.
    #[arg(long, value_delimiter = ',', default_value = "256,512")]
    mandelbulber: Vec<u32>,
    /// Mesh only this part of the fitted bounds along z, as fractions `F0,F1` of its height
    /// (the cell size stays that of the full resolution): peak memory and throughput at a
    /// high effective resolution without meshing every layer.
    #[arg(long, value_delimiter = ',', num_args = 1..=2)]
    z_slab: Option<Vec<f64>>,
    /// Skip the Mandelbulber2 comparison.
    #[arg(long)]
    skip_mandelbulber: bool,
    /// Internal: run one configuration `PRESET,RESOLUTION` and print its JSON.
    #[arg(long, hide = true)]
    single: Option<String>,
}

/// Counts, and measures the field at every 61st vertex (|d| there bounds how far the mesh
/// strays from the surface, in the estimator's units).
struct Probe<'a> {
    inner: Box<dyn MeshSink + 'a>,
    tape: &'a Tape,
    ev: Evaluator<f64>,
    seen: u64,
    worst: f64,
    sum: f64,
    probed: u64,
}

impl MeshSink for Probe<'_> {
    fn vertices(&mut self, v: &[Vertex]) -> Result<(), IsoMeshError> {
        for x in v {
            if self.seen.is_multiple_of(61) {
                let p = x.p.map(|c| c as f64);
                let d = self.ev.distance(self.tape, V3::new(p[0], p[1], p[2])).abs();
                self.worst = self.worst.max(d);
                self.sum += d;
                self.probed += 1;
            }
            self.seen += 1;
        }
        self.inner.vertices(v)
    }
    fn triangles(&mut self, t: &[[u32; 3]], w: &Window) -> Result<(), IsoMeshError> {
        self.inner.triangles(t, w)
    }
    fn finish(&mut self) -> Result<(), IsoMeshError> {
        self.inner.finish()
    }
}

/// Peak and current resident memory of this process, bytes.
fn rss() -> (u64, u64) {
    let s = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    let field = |name: &str| {
        s.lines()
            .find(|l| l.starts_with(name))
            .and_then(|l| l.split_whitespace().nth(1))
            .and_then(|v| v.parse::<u64>().ok())
            .unwrap_or(0)
            * 1024
    };
    (field("VmHWM:"), field("VmRSS:"))
}

fn load_average() -> String {
    std::fs::read_to_string("/proc/loadavg")
        .map(|s| s.split_whitespace().take(3).collect::<Vec<_>>().join(" "))
        .unwrap_or_default()
}

fn single(a: &MeshBenchArgs, spec: &str) -> Result<serde_json::Value, String> {
    let (name, res) = spec.split_once(',').ok_or("--single PRESET,RESOLUTION")?;
    let res: u32 = res.parse().map_err(|_| "bad resolution")?;
    let scene = presets::load(name).map_err(|e| e.to_string())?;
    let tape = Tape::compile(&scene).map_err(|e| e.to_string())?;
    let mut o = MeshOptions {
        resolution: res,
        method: crate::cmd_mesh::MeshArgs::method_of(a.method),
        max_memory: 16 << 30,
        ..MeshOptions::default()
    };
    if let Some(f) = &a.z_slab {
        let (lo, hi) = fathom_mesh::fit::fit_bounds(&scene, &tape).map_err(|e| e.to_string())?;
        let z = |t: f64| lo.z + (hi.z - lo.z) * t.clamp(0.0, 1.0);
        o.bounds = Some((
            DVec3::new(lo.x, lo.y, z(f[0])),
            DVec3::new(hi.x, hi.y, z(f[1])),
        ));
        if (hi.z - lo.z) > (hi - lo).max_element() * 0.999 && f[1] - f[0] < 1.0 {
            // z was the longest side: keep the cell size of the whole box.
            let full = (hi - lo).max_element();
            let part = (z(f[1]) - z(f[0])).max((hi - lo).x).max((hi - lo).y);
            o.resolution = ((res as f64) * part / full).round() as u32;
        }
    }
    let plan = fathom_mesh::plan(&scene, &tape, &o).map_err(|e| e.to_string())?;
    let inner: Box<dyn MeshSink> = match &a.write {
        Some(dir) => fathom_mesh::write::create(&dir.join(format!("{name}-{res}.ply")))
            .map_err(|e| e.to_string())?,
        None => Box::new(Counter::default()),
    };
    let mut probe = Probe {
        inner,
        tape: &tape,
        ev: Evaluator::new(),
        seen: 0,
        worst: 0.0,
        sum: 0.0,
        probed: 0,
    };
    let t = Instant::now();
    let s = fathom_mesh::mesh(&scene, &tape, &plan, &o, &mut probe, &|_, _| {})
        .map_err(|e| e.to_string())?;
    let secs = t.elapsed().as_secs_f64();
    let (peak, _) = rss();
    let h = plan.grid.h;
    Ok(serde_json::json!({
        "preset": name,
        "resolution": res,
        "z_slab": a.z_slab,
        "method": o.method.name(),
        "cells": plan.grid.cells,
        "voxel": h,
        "triangles": s.triangles,
        "vertices": s.vertices,
        "seconds": secs,
        "triangles_per_second": s.triangles as f64 / secs,
        "peak_rss_bytes": peak,
        "peak_rss_gib": peak as f64 / (1u64 << 30) as f64,
        "memory_estimate_bytes": plan.estimate.total(),
        "bricks_meshed": s.bricks_meshed,
        "bricks_total": s.bricks_total,
        "evaluations": s.evaluations,
        "dense_evaluations": plan.grid.total_cells(),
        "missing_faces": s.missing_faces,
        "vertex_field_error_voxels": { "max": probe.worst / h, "mean": probe.sum / probe.probed.max(1) as f64 / h, "sampled": probe.probed },
        "load_average": load_average(),
    }))
}

/// Exact two-sided Hausdorff distance of a sphere's mesh, in voxels.
fn sphere_hausdorff(method: Method, res: u32) -> Result<serde_json::Value, String> {
    use fathom_core::primitives::Primitive;
    let scene = fathom_core::Scene::new(fathom_core::Node::new(
        fathom_core::Call::new(Primitive::Sphere).with("radius", &[0.9]),
    ));
    let tape = Tape::compile(&scene).map_err(|e| e.to_string())?;
    let o = MeshOptions {
        bounds: Some((DVec3::splat(-1.0), DVec3::splat(1.0))),
        resolution: res,
        method,
        colours: false,
        ..MeshOptions::default()
    };
    let plan = fathom_mesh::plan(&scene, &tape, &o).map_err(|e| e.to_string())?;
    let mut m = IsoMesh::default();
    fathom_mesh::mesh(&scene, &tape, &plan, &o, &mut m, &|_, _| {}).map_err(|e| e.to_string())?;
    let sdf = |p: DVec3| p.length() - 0.9;
    let samples: Vec<DVec3> = (0..4000)
        .map(|i| {
            let (u, v) = (i as f64 * 0.618_034 % 1.0, (i as f64 + 0.5) / 4000.0);
            let (th, z) = (std::f64::consts::TAU * u, 2.0 * v - 1.0);
            let r = (1.0 - z * z).sqrt();
            DVec3::new(r * th.cos(), r * th.sin(), z) * 0.9
        })
        .collect();
    let (a, b) = fathom_mesh::check::hausdorff(&m, &sdf, &samples, plan.grid.h);
    let e = fathom_mesh::check::edges(&m.tris);
    Ok(serde_json::json!({
        "shape": "sphere r=0.9 in [-1,1]^3", "resolution": res, "method": method.name(),
        "hausdorff_mesh_to_surface_voxels": a / plan.grid.h,
        "hausdorff_surface_to_mesh_voxels": b / plan.grid.h,
        "closed_manifold": e.is_closed_manifold(), "triangles": m.tris.len(),
    }))
}

/// Mandelbulber2's headless voxel-to-mesh export of the same fractal, timed with
/// `/usr/bin/time -v` (its peak resident memory).
fn mandelbulber(name: &str, res: u32) -> Result<serde_json::Value, String> {
    let dir = std::env::temp_dir().join(format!(
        "fathom-bench-mb-{}-{name}-{res}",
        std::process::id()
    ));
    std::fs::create_dir_all(&dir).map_err(|e| e.to_string())?;
    let (formula, params, half, iters) = match name {
        "menger" => ("7", "N=5", 1.05, 5),
        "mandelbulb" => (
            "2",
            "N=12#fractal1_power=8#bailout=4#use_default_bailout=0",
            1.25,
            12,
        ),
        _ => return Err(format!("no Mandelbulber equivalent for {name}")),
    };
    let settings = dir.join("s.fract");
    std::fs::write(
        &settings,
        format!("# Mandelbulber settings file\n# version 2.20\n[main_parameters]\nformula_1 {formula};\n[fractal_1]\n"),
    )
    .map_err(|e| e.to_string())?;
    let o = format!(
        "{params}#voxel_custom_limit_enabled=1#voxel_limit_min=-{half} -{half} -{half}#\
         voxel_limit_max={half} {half} {half}#voxel_samples_x={res}#voxel_samples_y={res}#\
         voxel_samples_z={res}#voxel_max_iter={iters}#voxel_image_path={}/",
        dir.display()
    );
    // Mandelbulber 2.2x ignores `voxel_image_path` in --nogui mode and writes
    // ~/.mandelbulber/slices/output.ply: clear it first so a stale mesh is never counted.
    let home_ply =
        std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".mandelbulber/slices/output.ply"));
    if let Some(p) = &home_ply {
        let _ = std::fs::remove_file(p);
    }
    let t = Instant::now();
    let out = Command::new("/usr/bin/time")
        .args(["-v", "mandelbulber2", "--nogui", "--voxel", "ply", "-O", &o])
        .arg(&settings)
        .env("QT_QPA_PLATFORM", "offscreen")
        .output()
        .map_err(|e| format!("cannot run mandelbulber2: {e}"))?;
    let secs = t.elapsed().as_secs_f64();
    let err = String::from_utf8_lossy(&out.stderr);
    let peak_kb: u64 = err
        .lines()
        .find(|l| l.contains("Maximum resident set size"))
        .and_then(|l| l.rsplit(':').next())
        .and_then(|v| v.trim().parse().ok())
        .unwrap_or(0);
    let ply = [Some(dir.join("output.ply")), home_ply]
        .into_iter()
        .flatten()
        .find(|p| p.exists())
        .ok_or("mandelbulber2 wrote no output.ply (looked in its voxel path and ~/.mandelbulber/slices)")?;
    let header = std::fs::read(&ply).unwrap_or_default();
    let text = String::from_utf8_lossy(&header[..header.len().min(4096)]);
    let count = |el: &str| {
        text.lines()
            .find(|l| l.starts_with(&format!("element {el} ")))
            .and_then(|l| l.split_whitespace().nth(2))
            .and_then(|v| v.parse::<u64>().ok())
            .unwrap_or(0)
    };
    let tris = count("face");
    let _ = std::fs::remove_dir_all(&dir);
    Ok(serde_json::json!({
        "tool": "mandelbulber2 --nogui --voxel ply",
        "preset": name, "resolution": res, "exit_ok": out.status.success(),
        "seconds": secs, "triangles": tris, "vertices": count("vertex"),
        "triangles_per_second": tris as f64 / secs,
        "peak_rss_bytes": peak_kb * 1024,
        "load_average": load_average(),
    }))
}

pub fn run(a: MeshBenchArgs) -> Result<(), String> {
    if a.threads == 0 || a.threads > 1024 {
        return Err("--threads must be in [1, 1024]".into());
    }
    if let Some(f) = &a.z_slab
        && !(f.len() == 2 && 0.0 <= f[0] && f[0] < f[1] && f[1] <= 1.0)
    {
        return Err(format!(
            "--z-slab takes two fractions F0,F1 with 0 <= F0 < F1 <= 1, not {f:?}"
        ));
    }
    if let Some(spec) = &a.single {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(a.threads)
            .build()
            .map_err(|e| e.to_string())?;
        let v = pool.install(|| single(&a, spec))?;
        println!("{v}");
        return Ok(());
    }
    let exe = std::env::current_exe().map_err(|e| e.to_string())?;
    let mut runs = Vec::new();
    for name in &a.presets {
        for &res in &a.resolutions {
            let mut cmd = Command::new(&exe);
            cmd.args(["bench", "mesh", "--threads", &a.threads.to_string()])
                .args([
                    "--method",
                    a.method_name(),
                    "--single",
                    &format!("{name},{res}"),
                ]);
            if let Some(w) = &a.write {
                cmd.arg("--write").arg(w);
            }
            if let Some(f) = &a.z_slab {
                cmd.arg("--z-slab")
                    .arg(f[0].to_string())
                    .arg(f[1].to_string());
            }
            let out = cmd.output().map_err(|e| e.to_string())?;
            let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap_or_else(|_| {
                serde_json::json!({"preset": name, "resolution": res,
                    "error": String::from_utf8_lossy(&out.stderr).trim().to_string()})
            });
            eprintln!("{v}");
            runs.push(v);
        }
    }
    let method = crate::cmd_mesh::MeshArgs::method_of(a.method);
    let sphere: Vec<_> = [128, 512]
        .into_iter()
        .map(|r| sphere_hausdorff(method, r).unwrap_or_else(|e| serde_json::json!({"error": e})))
        .collect();
    let mut mb = Vec::new();
    if !a.skip_mandelbulber && std::path::Path::new("/usr/bin/mandelbulber2").exists() {
        for name in &a.presets {
            for &res in &a.mandelbulber {
                let v = mandelbulber(name, res).unwrap_or_else(|e| serde_json::json!({"error": e}));
                eprintln!("{v}");
                mb.push(v);
            }
        }
    }
    let report = serde_json::json!({
        "bench": "mesh",
        "threads": a.threads,
        "load_average_at_end": load_average(),
        "fathom": runs,
        "sphere_hausdorff": sphere,
        "mandelbulber2": mb,
    });
    println!(
        "{}",
        serde_json::to_string_pretty(&report).map_err(|e| e.to_string())?
    );
    Ok(())
}

impl MeshBenchArgs {
    fn method_name(&self) -> &'static str {
        use clap::ValueEnum;
        let v = self
            .method
            .to_possible_value()
            .expect("no skipped variants");
        match v.get_name() {
            "dc" => "dc",
            "sn" => "sn",
            _ => "mc",
        }
    }
}
