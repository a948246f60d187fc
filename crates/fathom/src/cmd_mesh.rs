//! `fathom mesh`: a scene file or preset to a triangle mesh (PLY, STL, OBJ, GLB), streamed in
//! bounded memory by fathom-mesh.

use clap::{Args, ValueEnum};
use fathom_core::scene::Scene;
use fathom_core::{Tape, presets, scene_file};
use fathom_mesh::grid::{human_bytes, parse_bytes};
use fathom_mesh::{IsoMesh, MeshOptions, MeshStats, Method, Window, simplify, write};
use fathom_trace::output;
use glam::DVec3;
use std::path::{Path, PathBuf};

/// How vertices are placed.
#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum MethodArg {
    /// Dual contouring: sharp edges and corners kept (normals from the field's gradient).
    Dc,
    /// Surface nets: smooth, one vertex per surface patch of a cell.
    Sn,
    /// Marching cubes: the watertight-manifold baseline.
    Mc,
}

/// Mesh a scene for 3D printing or other tools.
///
/// The scene is sampled on a grid of --resolution cells along the longest side of --bounds
/// (default: fitted to the scene), skipping space the distance bound proves empty, one layer
/// of 8-cell bricks at a time, so memory follows the surface. The memory estimate is printed
/// first, and runs over --max-memory are refused before anything large is allocated. The
/// format follows the output's extension: .ply (binary, vertex colours), .stl (binary), .obj
/// (vertex colours), .glb (glTF 2.0, vertex colours).
///
/// Before meshing, the triangle count is estimated from two coarse meshes and printed with the
/// file size it means; a mesh of more than 10 million triangles (about 500 MB as STL, more
/// than slicers and viewers open comfortably) is refused unless --yes is given or
/// --max-triangles simplifies it (meshoptimizer; a result that is no longer closed is refused).
///
/// Examples:
///   fathom mesh --preset menger -o menger.stl --resolution 192
///   fathom mesh --preset mandelbulb -o bulb.ply --resolution 1024 --max-memory 2G --yes   (a large mesh on purpose)
///   fathom mesh my.ron -o my.glb --bounds -1,-1,-1,1,1,1 --method mc
///   fathom mesh FILE.fract -o imported.obj --resolution 256
///   fathom mesh docs/examples/mandelbulb-dive.ron --path dive --frames 48 -o dive-meshes/
#[derive(Args, Debug)]
#[command(verbatim_doc_comment)]
pub struct MeshArgs {
    /// Scene file (.ron, or a Mandelbulber .fract).
    pub scene: Option<PathBuf>,
    /// Built-in preset (see `fathom list presets`).
    #[arg(long, conflicts_with = "scene")]
    pub preset: Option<String>,
    /// Output mesh: .ply, .stl, .obj or .glb.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Cells along the longest side of the bounds, [4, 65536].
    #[arg(long, default_value_t = 256)]
    pub resolution: u32,
    /// Box to mesh, x0,y0,z0,x1,y1,z1 (default: fitted to the scene).
    #[arg(long, value_parser = parse_bounds, allow_hyphen_values = true)]
    pub bounds: Option<(DVec3, DVec3)>,
    /// Vertex placement.
    #[arg(long, value_enum, default_value = "dc")]
    pub method: MethodArg,
    /// Refuse runs whose memory estimate exceeds this (e.g. 512M, 2G).
    #[arg(long, default_value = "4G", value_parser = parse_bytes)]
    pub max_memory: u64,
    /// Factor on the culling radius, [1, 16]: raise it if an estimator with a safety factor
    /// reports missing faces.
    #[arg(long, default_value_t = 1.0)]
    pub cull_margin: f64,
    /// No vertex colours (saves one evaluation per vertex).
    #[arg(long)]
    pub no_colours: bool,
    /// Worker threads (default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
    /// No progress bar or summary.
    #[arg(long, short)]
    pub quiet: bool,
    /// Mesh a sequence along the scene's flight path NAME (its parameter keys animate the
    /// shape; docs/scene-format.md): -o is a directory (DIR/NAME-00000.ply, ...) or a pattern
    /// such as out/f-####.stl.
    #[arg(long, requires = "frames")]
    pub path: Option<String>,
    /// Meshes in the sequence, [1, 100000]; the first at the path's start, the last at its end.
    #[arg(long, requires = "path")]
    pub frames: Option<usize>,
    /// Simplify to at most this many triangles, [4, 1431655765] (meshoptimizer's edge
    /// collapses; the mesh is held in memory for it, and a closed surface stays closed).
    #[arg(long)]
    pub max_triangles: Option<u64>,
    /// With --max-triangles: how far simplification may move the surface, in voxels (0, 64]:
    /// collapses past it (which pinch thin parts into sheets) are not taken.
    #[arg(long, default_value_t = 0.5)]
    pub max_error: f64,
    /// Write meshes of more than 10 million triangles (the estimate is printed first).
    #[arg(long, short)]
    pub yes: bool,
}

/// Triangles past which a mesh needs --yes (or --max-triangles): about 500 MB as binary STL.
pub const LARGE_TRIANGLES: u64 = 10_000_000;

/// Most meshes in one `--path` sequence.
pub const MAX_MESH_FRAMES: usize = 100_000;

fn parse_bounds(s: &str) -> Result<(DVec3, DVec3), String> {
    let v: Vec<f64> = s
        .split(',')
        .map(|x| x.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| format!("`{s}` should be six numbers x0,y0,z0,x1,y1,z1"))?;
    match v[..] {
        [a, b, c, d, e, f] => Ok((DVec3::new(a, b, c), DVec3::new(d, e, f))),
        _ => Err(format!("`{s}` should be six numbers x0,y0,z0,x1,y1,z1")),
    }
}

impl MeshArgs {
    /// The mesher's method for a `--method` value.
    pub fn method_of(m: MethodArg) -> Method {
        match m {
            MethodArg::Dc => Method::DualContouring,
            MethodArg::Sn => Method::SurfaceNets,
            MethodArg::Mc => Method::MarchingCubes,
        }
    }

    /// The mesher's options.
    pub fn options(&self) -> MeshOptions {
        MeshOptions {
            bounds: self.bounds,
            resolution: self.resolution,
            method: MeshArgs::method_of(self.method),
            colours: !self.no_colours,
            max_memory: self.max_memory,
            cull_margin: self.cull_margin,
            in_memory: false,
        }
    }
}

pub fn run(a: MeshArgs) -> Result<(), String> {
    let scene = match (&a.scene, &a.preset) {
        (Some(path), _) => scene_file::load(path).map_err(|e| e.to_string())?,
        (None, Some(p)) => presets::load(p).map_err(|e| e.to_string())?,
        (None, None) => return Err("give a scene FILE or --preset NAME (see --help)".into()),
    };
    let pool = crate::args::thread_pool(a.threads)?;
    match &a.path {
        Some(name) => run_sequence(&a, &scene, name, &pool),
        None => mesh_one(&a, &scene, &a.output, &pool),
    }
}

/// `--path NAME --frames N`: one mesh per frame of the path's animation.
fn run_sequence(
    a: &MeshArgs,
    scene: &Scene,
    name: &str,
    pool: &rayon::ThreadPool,
) -> Result<(), String> {
    let frames = a.frames.unwrap_or(1);
    if frames == 0 || frames > MAX_MESH_FRAMES {
        return Err(format!(
            "--frames {frames} is out of range 1..={MAX_MESH_FRAMES}"
        ));
    }
    let ext = a
        .output
        .extension()
        .map(|e| e.to_string_lossy().into_owned())
        .unwrap_or_else(|| "ply".into());
    let pattern = crate::cmd_flight::frame_pattern(&a.output, name, &ext);
    let last = output::sequence_path(&pattern, frames as u64 - 1)?;
    if let Some(dir) = last.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir)
            .map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    }
    let path = scene.path(name).map_err(|e| e.to_string())?;
    let flight = path
        .prepare(scene, None)
        .map_err(|e| format!("path `{name}`: {e}"))?;
    let start = std::time::Instant::now();
    for i in 0..frames {
        let t = fathom_render::flight::frame_time(i, frames, flight.duration());
        let mut s = scene.clone();
        flight.apply(t, &mut s);
        let file = output::sequence_path(&pattern, i as u64)?;
        if !a.quiet {
            eprintln!("mesh {}/{frames} (t = {t:.3} s): {}", i + 1, file.display());
        }
        mesh_one(a, &s, &file, pool)?;
    }
    if !a.quiet {
        eprintln!(
            "wrote {frames} meshes of path `{name}` ({}, ...) in {:.1} s",
            output::sequence_path(&pattern, 0)?.display(),
            start.elapsed().as_secs_f64()
        );
    }
    Ok(())
}

/// Meshes `scene` into `out` (format by extension).
fn mesh_one(
    a: &MeshArgs,
    scene: &Scene,
    out: &Path,
    pool: &rayon::ThreadPool,
) -> Result<(), String> {
    let tape = Tape::compile(scene).map_err(|e| e.to_string())?;
    let o = a.options();
    // The output's temporary file is created first, so an unwritable path fails before any
    // work; a refused plan drops it, leaving an existing output as it was.
    let mut sink = write::create(out).map_err(|e| e.to_string())?;
    let plan = pool
        .install(|| fathom_mesh::plan(scene, &tape, &o))
        .map_err(|e| e.to_string())?;
    let g = plan.grid;
    let format = write::Format::of(out).map_err(|e| e.to_string())?;
    let est = pool
        .install(|| fathom_mesh::simplify::estimate_triangles(scene, &tape, &o))
        .map_err(|e| e.to_string())?;
    let kept = a
        .max_triangles
        .map_or(est.triangles, |m| m.min(est.triangles));
    let size = simplify::file_size(format, kept, !a.no_colours);
    if !a.quiet {
        let how = if est.samples[0] == est.samples[1] {
            "counted".to_string()
        } else {
            format!(
                "from {} and {} triangles at resolutions {} and {}: growth r^{:.2}",
                est.samples[0].1,
                est.samples[1].1,
                est.samples[0].0,
                est.samples[1].0,
                est.exponent
            )
        };
        eprintln!(
            "estimate: about {} triangles ({how}); {} written: about {}",
            est.triangles,
            match a.max_triangles {
                Some(m) if m < est.triangles => format!("simplified to {m}"),
                _ => "as meshed".into(),
            },
            human_bytes(size)
        );
    }
    if kept > LARGE_TRIANGLES && !a.yes {
        return Err(format!(
            "{}: the mesh would have about {} triangles (about {}), more than the {} that slicers and viewers open comfortably; add --max-triangles N to simplify it (e.g. --max-triangles 1000000; see docs/files.md for its limits), lower --resolution, or pass --yes to write it anyway",
            out.display(),
            kept,
            human_bytes(size),
            LARGE_TRIANGLES
        ));
    }
    if !(a.max_error > 0.0 && a.max_error <= 64.0) {
        return Err(format!(
            "--max-error {} is out of range (0, 64] voxels",
            a.max_error
        ));
    }
    if let Some(m) = a.max_triangles {
        if m < simplify::MIN_TRIANGLES || m > u32::MAX as u64 / 3 {
            return Err(format!(
                "--max-triangles {m} is out of range [{}, {}]",
                simplify::MIN_TRIANGLES,
                u32::MAX / 3
            ));
        }
        let need = plan.estimate.total() + simplify::simplify_memory(est.triangles);
        if need > a.max_memory {
            return Err(format!(
                "simplifying holds the whole mesh in memory: about {} for {} triangles, more than --max-memory {} (lower --resolution or raise --max-memory)",
                human_bytes(need),
                est.triangles,
                human_bytes(a.max_memory)
            ));
        }
    }
    if !a.quiet {
        eprintln!(
            "meshing {}x{}x{} cells of {:.3e} over {:.3?} .. {:.3?}; memory {}",
            g.cells[0],
            g.cells[1],
            g.cells[2],
            g.h,
            g.origin.to_array(),
            (g.origin + DVec3::from(g.cells.map(|c| c as f64)) * g.h).to_array(),
            plan.estimate
        );
    }
    let bar = if a.quiet {
        indicatif::ProgressBar::hidden()
    } else {
        let b = indicatif::ProgressBar::new(g.bricks()[2] as u64);
        b.set_style(
            indicatif::ProgressStyle::with_template(
                "{spinner} meshing [{bar:40}] {pos}/{len} layers {elapsed} (eta {eta})",
            )
            .map_err(|e| e.to_string())?
            .progress_chars("=> "),
        );
        b
    };
    let progress = |done: u64, _total: u64| bar.set_position(done);
    let stats = match a.max_triangles {
        None => pool
            .install(|| fathom_mesh::mesh(scene, &tape, &plan, &o, sink.as_mut(), &progress))
            .map_err(|e| e.to_string())?,
        Some(budget) => {
            let mut whole = IsoMesh::default();
            let stats = pool
                .install(|| fathom_mesh::mesh(scene, &tape, &plan, &o, &mut whole, &progress))
                .map_err(|e| e.to_string())?;
            bar.finish_and_clear();
            let spin = if a.quiet {
                indicatif::ProgressBar::hidden()
            } else {
                indicatif::ProgressBar::new_spinner()
                    .with_message(format!("simplifying {} triangles", whole.tris.len()))
            };
            spin.enable_steady_tick(std::time::Duration::from_millis(200));
            let t = std::time::Instant::now();
            let s = pool
                .install(|| simplify::simplify(&whole, budget, a.max_error * g.h))
                .map_err(|e| e.to_string())?;
            spin.finish_and_clear();
            drop(whole);
            if !a.quiet {
                eprintln!(
                    "simplified {} to {} triangles in {:.1} s (meshoptimizer's error bound {:.3e}; {})",
                    s.triangles_before,
                    s.triangles_after,
                    t.elapsed().as_secs_f64(),
                    s.error,
                    if s.edges.is_closed_manifold() {
                        "closed and manifold"
                    } else {
                        "not closed: the meshed surface was not either"
                    }
                );
            }
            let m = s.mesh;
            sink.vertices(&m.verts).map_err(|e| e.to_string())?;
            let window = Window {
                first: 0,
                parts: [&m.verts[..], &[]],
            };
            sink.triangles(&m.tris, &window)
                .map_err(|e| e.to_string())?;
            sink.finish().map_err(|e| e.to_string())?;
            MeshStats {
                triangles: m.tris.len() as u64,
                vertices: m.verts.len() as u64,
                ..stats
            }
        }
    };
    bar.finish_and_clear();
    if stats.missing_faces > 0 {
        eprintln!(
            "fathom: warning: {} faces were dropped where the estimator undershot the culling \
             test (the mesh has holes there); rerun with --cull-margin 2",
            stats.missing_faces
        );
    }
    if !a.quiet {
        let size = std::fs::metadata(out).map(|m| m.len()).unwrap_or(0);
        eprintln!(
            "wrote {} ({} triangles, {} vertices, {}) in {:.1} s: {:.2} M triangles/s, {} of {} bricks meshed",
            out.display(),
            stats.triangles,
            stats.vertices,
            human_bytes(size),
            stats.seconds,
            stats.triangles as f64 / stats.seconds.max(1e-9) / 1e6,
            stats.bricks_meshed,
            stats.bricks_total
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use fathom_core::flight::{FlightPath, Keyframe};

    fn args(out: &str) -> MeshArgs {
        MeshArgs {
            scene: None,
            preset: Some("menger".into()),
            output: PathBuf::from(out),
            resolution: 24,
            bounds: None,
            method: MethodArg::Mc,
            max_memory: 1 << 30,
            cull_margin: 1.0,
            no_colours: false,
            threads: Some(1),
            quiet: true,
            path: None,
            frames: None,
            max_triangles: None,
            max_error: 0.5,
            yes: false,
        }
    }

    #[test]
    fn a_flight_path_gives_a_mesh_sequence_whose_shape_follows_the_parameters() {
        let dir = std::env::temp_dir().join(format!("fathom-mesh-seq-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        // The bulb's power animates from 8 to 3 along the path `morph`.
        let mut scene = presets::load("mandelbulb").unwrap();
        let mut keys = vec![Keyframe::from_camera(&scene.camera); 2];
        keys[0].params.insert("root.shape.power".into(), 8.0);
        keys[1].params.insert("root.shape.power".into(), 3.0);
        scene.paths.push(FlightPath::new("morph", 2.0, keys));
        let file = dir.join("morph.ron");
        scene_file::save(&file, &scene).unwrap();
        let mut a = args("");
        a.preset = None;
        a.scene = Some(file);
        a.output = dir.join("bulb-##.stl");
        a.resolution = 20;
        a.path = Some("morph".into());
        a.frames = Some(3);
        run(a).unwrap();
        let tris: Vec<u64> = (0..3)
            .map(|i| {
                let b = std::fs::read(dir.join(format!("bulb-0{i}.stl"))).unwrap();
                let n = u32::from_le_bytes(b[80..84].try_into().unwrap()) as u64;
                assert_eq!(b.len() as u64, 84 + 50 * n, "frame {i} is a whole STL");
                n
            })
            .collect();
        assert!(tris.iter().all(|&n| n > 100), "{tris:?}");
        assert_ne!(tris[0], tris[2], "the path's power key changes the shape");
        let mut bad = args(dir.join("x.ply").to_str().unwrap());
        bad.path = Some("nope".into());
        bad.frames = Some(2);
        assert!(run(bad).unwrap_err().contains("has no paths"));
        let mut bad = args(dir.join("x.ply").to_str().unwrap());
        bad.path = Some("morph".into());
        bad.frames = Some(0);
        assert!(run(bad).unwrap_err().contains("--frames 0"));
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn large_meshes_need_yes_or_a_budget_and_the_budget_keeps_them_closed() {
        let dir = std::env::temp_dir().join(format!("fathom-cmd-mesh-big-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        // Menger at 2048: the estimate is far past 10M triangles; refused before meshing.
        let out = dir.join("big.stl");
        let mut big = args(out.to_str().unwrap());
        big.resolution = 2048;
        let t = std::time::Instant::now();
        let e = run(big).unwrap_err();
        assert!(e.contains("--yes") && e.contains("--max-triangles"), "{e}");
        assert!(!out.exists(), "a refused run leaves no file");
        assert!(t.elapsed().as_secs_f64() < 20.0);
        // A budget: at most that many triangles, still closed (marching cubes is manifold).
        let out = dir.join("small.stl");
        let mut a = args(out.to_str().unwrap());
        a.resolution = 48;
        a.max_triangles = Some(3000);
        a.max_error = 2.0;
        // Either the budget is met with a closed surface, or the run is refused and writes
        // nothing (meshoptimizer can pinch the sponge's bars: docs/files.md).
        match run(a) {
            Ok(()) => {
                let b = std::fs::read(&out).unwrap();
                let n = u32::from_le_bytes(b[80..84].try_into().unwrap()) as usize;
                assert!(n <= 3000, "{n} triangles");
                let mesh = stl_triangles(&b);
                assert!(fathom_mesh::check::edges(&mesh).is_closed_manifold());
            }
            Err(e) => {
                assert!(
                    e.contains("broke the closed surface") || e.contains("--max-error"),
                    "{e}"
                );
                assert!(!out.exists(), "a refused simplification leaves no file");
            }
        }
        let mut bad = args(dir.join("x.stl").to_str().unwrap());
        bad.max_triangles = Some(2);
        assert!(
            run(bad)
                .unwrap_err()
                .contains("--max-triangles 2 is out of range [4, ")
        );
        std::fs::remove_dir_all(&dir).ok();
    }

    /// Welds an STL's corners back into indexed triangles (exact positions).
    fn stl_triangles(b: &[u8]) -> Vec<[u32; 3]> {
        let mut ids = std::collections::HashMap::new();
        b[84..]
            .chunks_exact(50)
            .map(|t| {
                std::array::from_fn(|k| {
                    let c = &t[12 + 12 * k..24 + 12 * k];
                    let n = ids.len() as u32;
                    *ids.entry(c.to_vec()).or_insert(n)
                })
            })
            .collect()
    }

    #[test]
    fn meshes_a_preset_and_fails_fast_on_bad_input() {
        let dir = std::env::temp_dir().join(format!("fathom-cmd-mesh-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let out = dir.join("m.stl");
        run(args(out.to_str().unwrap())).unwrap();
        assert!(std::fs::metadata(&out).unwrap().len() > 84);
        let t = std::time::Instant::now();
        let mut big = args("/nonexistent-dir/m.ply");
        big.resolution = 65536;
        assert!(run(big).unwrap_err().contains("/nonexistent-dir/m.ply"));
        let mut big = args(dir.join("big.ply").to_str().unwrap());
        big.resolution = 65536;
        big.max_memory = 1 << 20;
        let e = run(big).unwrap_err();
        assert!(e.contains("--max-memory"), "{e}");
        assert!(
            !dir.join("big.ply").exists(),
            "a refused run leaves no file"
        );
        assert!(t.elapsed().as_secs_f64() < 30.0);
        assert!(parse_bounds("-1,-1,-1,1,1,1").is_ok() && parse_bounds("1,2").is_err());
        std::fs::remove_dir_all(&dir).ok();
    }
}
