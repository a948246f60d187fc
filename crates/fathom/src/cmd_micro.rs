//! `fathom micro`: a distance-field texture raymarched in a shell over a triangle mesh
//! (fathom-micro; docs/micro.md). Parses the arguments into a `fathom_micro::request::Request`
//! and writes what the crate renders.

use clap::Args;
use fathom_micro::request::{self, Prepared, Request, TextureSpec};
use fathom_micro::{MicroStats, UvProjection};
use fathom_trace::output;
use glam::DVec3;
use std::path::{Path, PathBuf};

/// Paste a distance-field texture over a triangle mesh, overhangs included.
///
/// MESH is an .obj, .gltf or .glb file, or a built-in mesh: teapot, bush, triangle.
///
/// Examples:
///   fathom micro --demo teapot -o teapot.png
///   fathom micro --demo bush --size 1920x1080 -o bush.png
///   fathom micro teapot --preset menger --shell 0.05 -o t.png
///   fathom micro my.obj --texture leaves.ron --shell 0.02 --uv box -o my.png
///   fathom micro --demo teapot --gpu -o gpu.png
///   fathom micro --demo teapot --bake 128 --stats stats.json -o baked.png
///   fathom micro --cloud fern -o fern.png                  the chaos-game fern on its own
///   fathom micro --cloud fern --fov 8 --target 0.1,0.3,0 -o zoom.png
///   fathom micro bush --cloud fern --shell 0.15 -o ferns.png
///   fathom micro --demo bush --texture-to other.ron --time 1.5 -o frame.png
#[derive(Args, Debug)]
#[command(verbatim_doc_comment)]
pub struct MicroArgs {
    /// Mesh file (.obj, .gltf, .glb) or built-in mesh (teapot, bush, triangle).
    pub mesh: Option<String>,
    /// A shipped demo: teapot or bush (mesh, texture, shell and camera; flags override).
    #[arg(long)]
    pub demo: Option<String>,
    /// Texture scene file (.ron).
    #[arg(long, conflicts_with_all = ["preset", "cloud"])]
    pub texture: Option<PathBuf>,
    /// Texture from a built-in preset (see `fathom list presets`).
    #[arg(long, conflicts_with = "cloud")]
    pub preset: Option<String>,
    /// Texture from a chaos-game point cloud: fern or tree. Without a mesh it is shown alone.
    #[arg(long)]
    pub cloud: Option<String>,
    /// Points in the chaos-game cloud.
    #[arg(long, default_value_t = 400_000)]
    pub cloud_points: u64,
    /// Radius of each point's sphere, in texture units.
    #[arg(long, default_value_t = 0.004)]
    pub cloud_radius: f64,
    /// Second keyframe of an animated texture (same structure as the first).
    #[arg(long)]
    pub texture_to: Option<PathBuf>,
    /// Time in seconds for an animated texture.
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    pub time: f64,
    /// Period of the animation in seconds (keyframe 2 at half the period).
    #[arg(long, default_value_t = 4.0)]
    pub period: f64,
    /// Shell height in world units (default: the demo's, or 3% of the mesh's diagonal).
    #[arg(long)]
    pub shell: Option<f64>,
    /// Texture tiles per UV unit.
    #[arg(long)]
    pub tiles: Option<f64>,
    /// The texture box one tile fills: x0,y0,z0,x1,y1,z1 (default -1,-1,-1,1,1,1).
    #[arg(long, value_parser = request::parse_cell, allow_hyphen_values = true)]
    pub cell: Option<fathom_micro::Cell>,
    /// UV projection for meshes without UVs (overrides the file's): planar, box, spherical.
    #[arg(long, value_parser = UvProjection::parse)]
    pub uv: Option<UvProjection>,
    /// Bake the texture into an N^3 grid (trilinear) instead of evaluating it exactly.
    #[arg(long)]
    pub bake: Option<u32>,
    /// Hide the base mesh under the shell.
    #[arg(long)]
    pub no_base: bool,
    /// Shade with the texture's own normals (faceted across triangles) instead of rotating
    /// them onto the interpolated vertex normals.
    #[arg(long)]
    pub flat_normals: bool,
    /// Output PNG.
    #[arg(short, long, default_value = "micro.png")]
    pub output: PathBuf,
    /// Image size WIDTHxHEIGHT.
    #[arg(long, default_value = "1280x720", value_parser = crate::args::parse_size)]
    pub size: (u32, u32),
    /// Camera position x,y,z (default: fitted to the mesh).
    #[arg(long, value_parser = crate::args::parse_vec, allow_hyphen_values = true)]
    pub eye: Option<DVec3>,
    /// Point the camera looks at x,y,z.
    #[arg(long, value_parser = crate::args::parse_vec, allow_hyphen_values = true)]
    pub target: Option<DVec3>,
    /// Camera up vector x,y,z.
    #[arg(long, value_parser = crate::args::parse_vec, allow_hyphen_values = true)]
    pub up: Option<DVec3>,
    /// Vertical field of view in degrees.
    #[arg(long)]
    pub fov: Option<f64>,
    /// Worker threads, [1, 1024] (default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Render on the GPU (wgpu): rasterised tetrahedra, marched in the fragment shader.
    #[arg(long)]
    pub gpu: bool,
    /// Also write a mask PNG: white where a ray hit.
    #[arg(long)]
    pub mask: Option<PathBuf>,
    /// Also write a heat map PNG of distance evaluations per pixel.
    #[arg(long)]
    pub steps: Option<PathBuf>,
    /// Also write statistics as JSON.
    #[arg(long)]
    pub stats: Option<PathBuf>,
    /// No progress bar.
    #[arg(long, short)]
    pub quiet: bool,
}

impl MicroArgs {
    fn request(&self) -> Request {
        let mut r = Request::new();
        r.mesh = self.mesh.clone();
        r.demo = self.demo.clone();
        r.texture = match (&self.texture, &self.preset, &self.cloud) {
            (Some(p), _, _) => TextureSpec::File(p.clone()),
            (_, Some(n), _) => TextureSpec::Preset(n.clone()),
            (_, _, Some(c)) => TextureSpec::Cloud(c.clone()),
            _ => TextureSpec::Default,
        };
        r.texture_to = self.texture_to.clone();
        (r.time, r.period) = (self.time, self.period);
        (r.shell, r.tiles, r.cell, r.uv, r.bake) =
            (self.shell, self.tiles, self.cell, self.uv, self.bake);
        (r.cloud_points, r.cloud_radius) = (self.cloud_points, self.cloud_radius);
        r.show_base = !self.no_base;
        r.smooth_normals = !self.flat_normals;
        (r.width, r.height) = self.size;
        (r.eye, r.target, r.up, r.fov) = (self.eye, self.target, self.up, self.fov);
        r
    }
}

fn stats_json(s: &MicroStats, extra: serde_json::Value) -> serde_json::Value {
    serde_json::json!({
        "width": s.width,
        "height": s.height,
        "triangles": s.triangles,
        "tetrahedra": s.tetrahedra,
        "hits": s.hits,
        "texture_hits": s.texture_hits,
        "base_hits": s.base_hits,
        "de_evaluations": { "march": s.de_march, "shade": s.de_shade },
        "de_per_pixel": s.de_per_pixel(),
        "tets_visited": s.tets_visited,
        "ms_total": s.ms_total,
        "setup": extra,
    })
}

fn open(
    p: &Option<PathBuf>,
) -> Result<Option<(fathom_core::atomic_file::AtomicFile, &Path)>, String> {
    p.as_deref()
        .map(|p| {
            output::open_output(p)
                .map(|f| (f, p))
                .map_err(|e| e.to_string())
        })
        .transpose()
}

pub fn run(a: MicroArgs) -> Result<(), String> {
    // Unwritable outputs fail before any work.
    let out = output::open_output(&a.output).map_err(|e| e.to_string())?;
    let (mask, steps, stats_file) = (open(&a.mask)?, open(&a.steps)?, open(&a.stats)?);
    let pool = crate::args::thread_pool(a.threads)?;
    let bar = if a.quiet {
        indicatif::ProgressBar::hidden()
    } else {
        let b = indicatif::ProgressBar::new(0);
        b.set_style(
            indicatif::ProgressStyle::with_template(
                "{spinner} {msg} [{bar:40}] {percent}% {elapsed}",
            )
            .map_err(|e| e.to_string())?
            .progress_chars("=> "),
        );
        b
    };
    bar.set_message("preparing");
    let prepared = pool
        .install(|| a.request().prepare())
        .map_err(|e| e.to_string())?;
    let progress = |done: usize, total: usize| {
        bar.set_message("rendering");
        bar.set_length(total as u64);
        bar.set_position(done as u64);
    };
    let (frame, stats, extra) = match prepared {
        Prepared::Alone {
            texture,
            cell,
            lighting,
            options,
        } => {
            if a.gpu {
                return Err("a cloud on its own renders on the CPU only; leave out --gpu".into());
            }
            bar.set_message("rendering");
            let (f, s) = pool
                .install(|| fathom_micro::alone::render(&texture, &cell, &lighting, &options))
                .map_err(|e| e.to_string())?;
            (
                f,
                s,
                serde_json::json!({ "texture": texture.origin, "alone": true }),
            )
        }
        Prepared::Shell {
            scene,
            options,
            mesh_report,
            texture_scene,
        } => {
            let extra = serde_json::json!({
                "texture": scene.texture.origin,
                "mesh": mesh_report.to_string(),
                "shell": format!("{:?}", scene.shell.report),
                "shell_height": scene.shell.height,
                "renderer": if a.gpu { "gpu" } else { "cpu" },
            });
            let (f, s) = if a.gpu {
                bar.set_message("rendering on the GPU");
                bar.tick();
                let tape = texture_scene.as_ref().and(scene.texture.tape()).ok_or(
                    "--gpu takes exact textures only (not --bake or --cloud); leave out --gpu",
                )?;
                let mut g = fathom_micro::gpu::MicroGpu::headless().map_err(|e| e.to_string())?;
                let (f, s) = g
                    .render(&scene, tape, &options)
                    .map_err(|e| e.to_string())?;
                if !a.quiet && g.is_software() {
                    eprintln!(
                        "fathom: note: {} is a CPU implementation of Vulkan",
                        g.adapter_name()
                    );
                }
                (f, s)
            } else {
                pool.install(|| fathom_micro::render(&scene, &options, &progress))
                    .map_err(|e| e.to_string())?
            };
            (f, s, extra)
        }
    };
    bar.finish_and_clear();
    let mut frame = frame;
    fathom_trace::post::sanitize(&mut frame);
    output::save_colour(&frame, out, &a.output).map_err(|e| e.to_string())?;
    if let Some((f, p)) = mask {
        output::save_mask(&frame, f, p).map_err(|e| e.to_string())?;
    }
    if let Some((f, p)) = steps {
        output::save_steps(&frame, f, p).map_err(|e| e.to_string())?;
    }
    if let Some((f, p)) = stats_file {
        let j = stats_json(&stats, extra);
        output::save_json(&j, f, p).map_err(|e| e.to_string())?;
    }
    if !a.quiet {
        eprintln!(
            "fathom: wrote {} ({}x{}, {:.0} ms, {:.1} evaluations per pixel, {} triangles, {} tetrahedra)",
            a.output.display(),
            stats.width,
            stats.height,
            stats.ms_total,
            stats.de_per_pixel(),
            stats.triangles,
            stats.tetrahedra
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::FromArgMatches;

    fn args(list: &[&str]) -> MicroArgs {
        let cmd = MicroArgs::augment_args(clap::Command::new("micro"));
        let m = cmd
            .try_get_matches_from(std::iter::once("micro").chain(list.iter().copied()))
            .unwrap_or_else(|e| panic!("{list:?}: {e}"));
        MicroArgs::from_arg_matches(&m).unwrap()
    }

    fn tmp(name: &str) -> String {
        let d = std::env::temp_dir().join(format!("fathom-cmd-micro-{}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        d.join(name).display().to_string()
    }

    #[test]
    fn a_demo_renders_with_its_side_outputs() {
        let (out, mask, stats) = (tmp("t.png"), tmp("t-mask.png"), tmp("t.json"));
        let a = args(&[
            "--demo",
            "teapot",
            "--size",
            "48x36",
            "--threads",
            "2",
            "--quiet",
            "-o",
            &out,
            "--mask",
            &mask,
            "--stats",
            &stats,
        ]);
        run(a).unwrap();
        let img = image::open(&out).unwrap().to_rgb8();
        assert_eq!(img.dimensions(), (48, 36));
        let m = image::open(&mask).unwrap().to_luma8();
        let hits = m.pixels().filter(|p| p.0[0] > 127).count();
        assert!(
            hits > 100 && hits < 48 * 36,
            "the teapot covers part of the view ({hits} of {} pixels)",
            48 * 36
        );
        let j: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&stats).unwrap()).unwrap();
        assert!(j.to_string().contains("tetrahedra"), "{j}");
    }

    #[test]
    fn bad_input_gives_clear_errors_and_writes_nothing() {
        let out = tmp("bad.png");
        let cases: Vec<(Vec<&str>, &str)> = vec![
            (vec!["--demo", "kettle"], "teapot"),
            (vec!["--demo", "teapot", "--shell=-1"], "shell"),
            (vec!["--demo", "teapot", "--period", "0"], "period"),
            (
                vec!["--demo", "teapot", "--bake", "1"],
                "out of range [2, 512]",
            ),
            (
                vec!["/nonexistent/mesh.obj", "--preset", "menger"],
                "/nonexistent/mesh.obj",
            ),
            (vec!["--cloud", "fern", "--gpu"], "CPU only"),
        ];
        for (list, want) in cases {
            std::fs::remove_file(&out).ok();
            let mut full = list.clone();
            full.extend(["--size", "32x24", "--quiet", "-o", &out]);
            let e = run(args(&full)).expect_err(&format!("{list:?} should fail"));
            assert!(e.contains(want), "{list:?}: `{e}` should mention `{want}`");
            assert!(
                !std::path::Path::new(&out).exists() || std::fs::metadata(&out).unwrap().len() == 0,
                "{list:?} left an image behind"
            );
        }
    }
}
