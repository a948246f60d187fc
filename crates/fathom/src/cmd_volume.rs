//! `fathom volume`: grow a physarum network, sample a scene, or read a `.vol` grid, and render
//! it with the volume path tracer (fathom-volume); export grids for Mitsuba 3.

use clap::{Args, ValueEnum};
use fathom_core::{presets, scene_file};
use fathom_volume::VolumeError;
use fathom_volume::WorldBox;
use fathom_volume::exposure;
use fathom_volume::integrator::VolumeScene;
use fathom_volume::light::{Environment, Sun};
use fathom_volume::medium::{Majorant, Medium, MediumParams};
use fathom_volume::physarum::{self, Boundary};
use fathom_volume::pipeline::{self, Placement, Source};
use fathom_volume::render::{self, Progressive};
use glam::{DVec3, Vec3};
use indicatif::{ProgressBar, ProgressStyle};
use std::path::PathBuf;

/// What grows the density.
#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum SimKind {
    /// The 3D slime-mould agent simulation.
    Physarum,
}

/// The boundary rule on the command line.
#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum BoundaryArg {
    Wrap,
    Walls,
}

/// What `--export` writes for a scene.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum ExportField {
    /// The density that is rendered (1 inside, or the --smooth ramp).
    Density,
    /// The signed distance at each voxel centre (world units, negative inside); export only.
    Distance,
}

/// Majorant choice on the command line.
#[derive(Clone, Copy, Debug, PartialEq, ValueEnum)]
pub enum MajorantArg {
    /// A coarse grid of per-block maxima walked by a 3D DDA.
    Grid,
    /// One majorant for the whole grid.
    Global,
}

/// Render a density grid as a cloud with the volume path tracer.
///
/// The density comes from a physarum simulation (--sim physarum, the default), a scene's
/// interior (--scene FILE or --preset NAME: density 1 where the distance is negative), or a
/// Mitsuba 3 .vol (or fathom .raw) file (--grid FILE). Output .png is tonemapped, .exr is
/// linear float RGB. --export writes the grid for Mitsuba 3 (.vol) or as trail counts (.raw).
///
/// Physarum presets: tendrils, sheets, lattice, cage.
///
/// Examples:
///   fathom volume --sim physarum --preset tendrils --steps 300 --grid 256 -o out.png --spp 64
///   fathom volume --sim physarum --preset lattice --grid 128 --export lattice.vol
///   fathom volume --grid cloud.vol --density-scale 30 --albedo 0.9 --g 0.6 --env 1 --eye 2,1.5,2.5 --target 0.5,0.5,0.5 --fov 35 --size 512x512 --spp 128 -o cloud.exr
///   fathom volume --preset menger --grid 128 --density-scale 20 -o sponge.png --stats sponge.json
///   fathom volume --scene my.ron --grid 192 --smooth 1.5 --sun 0.4,1,0.3 --sky-top 0.3,0.45,0.8 --sky-bottom 0.1,0.1,0.1 -o my.png
///   fathom volume --sim physarum --preset cage --emission 4 --env 0 -o glow.png   (emissive)
///   fathom volume --preset menger --eye 0.1,0.2,0.3 --target 1,0,0 -o inside.png   (camera inside)
#[derive(Args, Debug)]
#[command(verbatim_doc_comment, allow_negative_numbers = true)]
pub struct VolumeArgs {
    /// Grow the density with this simulation (the default when no scene or file is given).
    #[arg(long, value_enum)]
    pub sim: Option<SimKind>,
    /// With --sim: a physarum preset; otherwise: a scene preset (see `fathom list presets`).
    #[arg(long)]
    pub preset: Option<String>,
    /// A scene file whose interior becomes the density.
    #[arg(long, conflicts_with = "sim")]
    pub scene: Option<PathBuf>,
    /// A .vol or .raw file to render; or, with --sim, --scene or --preset, the grid
    /// resolution N (N^3 voxels; default 256 for the simulation, 128 for scenes).
    #[arg(long)]
    pub grid: Option<String>,
    /// Simulation steps.
    #[arg(long, default_value_t = 300)]
    pub steps: u32,
    /// Random seed (simulation and rendering).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Agents (default: the preset's, scaled to the grid).
    #[arg(long)]
    pub agents: Option<u32>,
    /// Angle between the forward and flanking sensors, degrees [0, 180].
    #[arg(long)]
    pub sensor_angle: Option<f32>,
    /// Sensor distance in voxels [0, 256].
    #[arg(long)]
    pub sensor_distance: Option<f32>,
    /// Turn per step toward the strongest sensor, degrees [0, 180].
    #[arg(long)]
    pub turn_angle: Option<f32>,
    /// Move per step in voxels (0, 32].
    #[arg(long)]
    pub step_size: Option<f32>,
    /// Trail count deposited per agent per step, 1..=65535.
    #[arg(long)]
    pub deposit: Option<u32>,
    /// Fraction of the trail kept per step [0, 1].
    #[arg(long)]
    pub decay: Option<f32>,
    /// Mix toward the 3x3x3 mean per step [0, 1].
    #[arg(long)]
    pub diffusion: Option<f32>,
    /// Largest random roll about the forward axis per step, degrees [0, 180].
    #[arg(long)]
    pub roll: Option<f32>,
    /// Grid faces: agents wrap around or reflect.
    #[arg(long, value_enum)]
    pub boundary: Option<BoundaryArg>,
    /// Where the grid sits: for files `unit` (Mitsuba's default), `file` (the .vol header's
    /// box) or x0,y0,z0,x1,y1,z1; for scenes the sampled box (default: fitted).
    #[arg(long = "box", allow_hyphen_values = true)]
    pub bbox: Option<String>,
    /// Scenes: smooth the density over this many voxels across the surface [0, 64].
    #[arg(long, default_value_t = 0.0)]
    pub smooth: f32,
    /// Extinction per unit density and length [0, 1e6]. Default: automatic, from the grid's
    /// statistics (a line crossing the structure meets about 3 optical depths on average; the
    /// value chosen is printed and written to --stats).
    #[arg(long)]
    pub density_scale: Option<f32>,
    /// Single-scattering albedo: A or r,g,b in [0, 1].
    #[arg(long, default_value = "0.8")]
    pub albedo: String,
    /// Henyey-Greenstein asymmetry (-1, 1): 0 isotropic, > 0 forward.
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    pub g: f32,
    /// Constant environment radiance: R or r,g,b. With none of --env, --sky-top and --sun the
    /// default lighting is a sun from 0.4,1,0.3 and a blue sky gradient (docs/volume.md).
    #[arg(long)]
    pub env: Option<String>,
    /// Sky gradient instead of --env: radiance straight up, r,g,b (with --sky-bottom).
    #[arg(long, requires = "sky_bottom")]
    pub sky_top: Option<String>,
    /// Sky gradient: radiance straight down, r,g,b.
    #[arg(long, requires = "sky_top")]
    pub sky_bottom: Option<String>,
    /// A directional light from this direction x,y,z.
    #[arg(long, allow_hyphen_values = true)]
    pub sun: Option<String>,
    /// Sun radiance (as irradiance): R or r,g,b.
    #[arg(long, default_value = "5")]
    pub sun_radiance: String,
    /// Emission strength of the colour map on density (0: none) [0, 1e6].
    #[arg(long, default_value_t = 0.0)]
    pub emission: f32,
    /// Majorants for delta and ratio tracking.
    #[arg(long, value_enum, default_value = "grid")]
    pub majorant: MajorantArg,
    /// Voxels per majorant-grid cell along each axis, 1..=1024.
    #[arg(long, default_value_t = 8)]
    pub majorant_block: u32,
    /// Do not skip lookups in homogeneous majorant cells (and use plain ratio tracking).
    #[arg(long)]
    pub no_homogeneous: bool,
    /// Most scattering events per path, 0..=100000.
    #[arg(long, default_value_t = 1000)]
    pub max_depth: u32,
    /// Russian roulette after this many scattering events.
    #[arg(long, default_value_t = 5)]
    pub rr_depth: u32,
    /// Camera position x,y,z (default: the scene's camera, or framing the grid's occupied
    /// voxels).
    #[arg(long, allow_hyphen_values = true, value_parser = crate::args::parse_vec)]
    pub eye: Option<DVec3>,
    /// Point the camera looks at x,y,z.
    #[arg(long, allow_hyphen_values = true, value_parser = crate::args::parse_vec)]
    pub target: Option<DVec3>,
    /// Camera up vector x,y,z.
    #[arg(long, allow_hyphen_values = true, value_parser = crate::args::parse_vec)]
    pub up: Option<DVec3>,
    /// Vertical field of view in degrees, (0, 179].
    #[arg(long)]
    pub fov: Option<f64>,
    /// Image size WIDTHxHEIGHT.
    #[arg(long, default_value = "512x512")]
    pub size: String,
    /// Samples per pixel, 1..=1048576.
    #[arg(long, default_value_t = 64)]
    pub spp: u32,
    /// Worker threads, [1, 1024] (default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Output image: .png (tonemapped) or .exr (linear float RGB). Default volume.png, or
    /// none when only exporting.
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// Write the density grid: .vol (Mitsuba 3) or .raw (fathom; trail counts when simulated).
    #[arg(long)]
    pub export: Option<PathBuf>,
    /// What --export writes for a scene (--scene or --preset): `density` or `distance` (signed
    /// distances in world units at voxel centres, negative inside, the world box in the .vol
    /// header; for tools that take distance grids; export only, no image).
    #[arg(long, value_enum, default_value = "density")]
    pub export_field: ExportField,
    /// Write render (and simulation) statistics as JSON.
    #[arg(long)]
    pub stats: Option<PathBuf>,
    /// Memory limit for grids and agents, e.g. 4G.
    #[arg(long, default_value = "4G")]
    pub max_memory: String,
    /// No progress bars.
    #[arg(short, long)]
    pub quiet: bool,
}

/// Parses `n` comma-separated finite numbers (or one, repeated, when `broadcast`).
fn floats<const N: usize>(name: &str, s: &str, broadcast: bool) -> Result<[f32; N], String> {
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    let bad = || {
        let one = if broadcast {
            " (or one number for all)"
        } else {
            ""
        };
        format!("--{name} `{s}` must be {N} comma-separated numbers{one}")
    };
    let v: Vec<f32> = parts
        .iter()
        .map(|p| p.parse::<f32>().ok())
        .collect::<Option<_>>()
        .ok_or_else(bad)?;
    if let Some((p, _)) = parts.iter().zip(&v).find(|(_, v)| !v.is_finite()) {
        return Err(format!(
            "--{name} `{s}`: `{p}` is not a finite number (f32 holds up to about 3.4e38)"
        ));
    }
    match v.len() {
        1 if broadcast => Ok([v[0]; N]),
        n if n == N => Ok(std::array::from_fn(|i| v[i])),
        _ => Err(bad()),
    }
}

fn vec3(name: &str, s: &str) -> Result<Vec3, String> {
    Ok(Vec3::from_array(floats::<3>(name, s, false)?))
}

fn colour(name: &str, s: &str) -> Result<Vec3, String> {
    Ok(Vec3::from_array(floats::<3>(name, s, true)?))
}

fn parse_box(s: &str) -> Result<WorldBox, String> {
    let b = floats::<6>("box", s, false)?;
    WorldBox::new(Vec3::new(b[0], b[1], b[2]), Vec3::new(b[3], b[4], b[5]))
        .map_err(|e| e.to_string())
}

fn grid_res(a: &VolumeArgs, default: u32) -> Result<u32, String> {
    match &a.grid {
        None => Ok(default),
        Some(g) => g.parse::<u32>().map_err(|_| {
            format!("--grid `{g}`: with --sim, --scene or --preset, --grid is the resolution N (N^3 voxels); to render a file, give --grid FILE.vol alone")
        }),
    }
}

/// The density source the arguments describe.
fn source(a: &VolumeArgs) -> Result<Source, String> {
    let file_given = a.grid.as_ref().is_some_and(|g| g.parse::<u32>().is_err());
    if a.sim.is_some() || (a.scene.is_none() && a.preset.is_none() && !file_given) {
        let res = grid_res(a, 256)?;
        let name = a.preset.as_deref().unwrap_or("tendrils");
        let mut p = physarum::presets::find(name, [res; 3]).map_err(|e| e.to_string())?;
        let set = |v: Option<f32>, f: &mut f32| {
            if let Some(v) = v {
                *f = v;
            }
        };
        if let Some(n) = a.agents {
            p.agents = n;
        }
        set(a.sensor_angle, &mut p.sensor_angle);
        set(a.sensor_distance, &mut p.sensor_distance);
        set(a.turn_angle, &mut p.turn_angle);
        set(a.step_size, &mut p.step_size);
        set(a.decay, &mut p.decay);
        set(a.diffusion, &mut p.diffusion);
        set(a.roll, &mut p.roll);
        if let Some(d) = a.deposit {
            p.deposit = d;
        }
        if let Some(b) = a.boundary {
            p.boundary = match b {
                BoundaryArg::Wrap => Boundary::Wrap,
                BoundaryArg::Walls => Boundary::Walls,
            };
        }
        if a.bbox.is_some() {
            return Err("--box places scenes and files; a simulated grid spans [-1, 1] along its longest side".into());
        }
        return Ok(Source::Physarum {
            params: p,
            res,
            steps: a.steps,
            seed: a.seed,
        });
    }
    if a.scene.is_some() || a.preset.is_some() {
        let scene = match (&a.scene, &a.preset) {
            (Some(path), _) => scene_file::load(path).map_err(|e| e.to_string())?,
            (None, Some(name)) => presets::load(name).map_err(|e| e.to_string())?,
            _ => unreachable!(),
        };
        let bbox = a.bbox.as_deref().map(parse_box).transpose()?;
        return Ok(Source::Fractal {
            scene: Box::new(scene),
            res: grid_res(a, 128)?,
            bbox,
            smooth: a.smooth,
        });
    }
    let path = PathBuf::from(a.grid.as_ref().expect("file_given"));
    let placement = match a.bbox.as_deref() {
        None | Some("unit") => Placement::Default,
        Some("file") => Placement::FromFile,
        Some(s) => Placement::Box(parse_box(s)?),
    };
    Ok(Source::File { path, placement })
}

/// The medium's parameters; an automatic density scale is 1 until the grid is built.
fn medium_params(a: &VolumeArgs) -> Result<MediumParams, String> {
    Ok(MediumParams {
        density_scale: a.density_scale.unwrap_or(1.0),
        albedo: colour("albedo", &a.albedo)?,
        g: a.g,
        emission: a.emission,
        majorant: match a.majorant {
            MajorantArg::Global => Majorant::Global,
            MajorantArg::Grid => Majorant::Grid {
                block: a.majorant_block,
            },
        },
        homogeneous_cells: !a.no_homogeneous,
    })
}

/// Where the default sun comes from (towards it), when no lighting is given.
pub const DEFAULT_SUN: [f32; 3] = [0.4, 1.0, 0.3];
/// The default sky gradient: straight up, straight down.
pub const DEFAULT_SKY: ([f32; 3], [f32; 3]) = ([0.35, 0.5, 0.9], [0.1, 0.09, 0.08]);

fn lighting(a: &VolumeArgs) -> Result<(Environment, Option<Sun>), String> {
    let defaults = a.env.is_none() && a.sky_top.is_none() && a.sun.is_none();
    let env = match (&a.sky_top, &a.sky_bottom, &a.env) {
        (Some(t), Some(b), _) => Environment::Sky {
            top: colour("sky-top", t)?,
            bottom: colour("sky-bottom", b)?,
            up: Vec3::Y,
        },
        (_, _, Some(e)) => Environment::Constant(colour("env", e)?),
        _ => Environment::Sky {
            top: Vec3::from(DEFAULT_SKY.0),
            bottom: Vec3::from(DEFAULT_SKY.1),
            up: Vec3::Y,
        },
    };
    let sun = match &a.sun {
        None if defaults => Some(Sun {
            towards: Vec3::from(DEFAULT_SUN).normalize(),
            radiance: colour("sun-radiance", &a.sun_radiance)?,
        }),
        None => None,
        Some(s) => {
            let d = vec3("sun", s)?;
            if d.length() == 0.0 {
                return Err("--sun 0,0,0: give the direction toward the sun".into());
            }
            Some(Sun {
                towards: d.normalize(),
                radiance: colour("sun-radiance", &a.sun_radiance)?,
            })
        }
    };
    Ok((env, sun))
}

fn bar(quiet: bool, len: u64, what: &str) -> ProgressBar {
    if quiet {
        return ProgressBar::hidden();
    }
    let pb = ProgressBar::new(len);
    pb.set_style(
        ProgressStyle::with_template("{msg:>9} [{bar:40}] {pos}/{len} ({eta})")
            .expect("a valid template")
            .progress_chars("=> "),
    );
    pb.set_message(what.to_string());
    pb
}

pub fn run(a: VolumeArgs) -> Result<(), String> {
    let (width, height) = crate::args::parse_size(&a.size)?;
    render::check_spp(a.spp).map_err(|e| e.to_string())?;
    let limit = crate::args::parse_bytes(&a.max_memory)? as u64;
    let src = source(&a)?;
    if a.export_field == ExportField::Distance {
        return export_distance(&a, src, limit);
    }
    let params = medium_params(&a)?;
    params.validate().map_err(|e| e.to_string())?;
    if a.sky_top.is_some() && a.env.is_some() {
        return Err("--env and --sky-top both set the environment: give one".into());
    }
    let (environment, sun) = lighting(&a)?;
    let output = match (&a.output, &a.export) {
        (Some(o), _) => Some(o.clone()),
        (None, None) => Some(PathBuf::from("volume.png")),
        (None, Some(_)) => None,
    };
    if let Some(o) = &output {
        image_format(o)?;
    }
    if let Some(e) = &a.export {
        grid_format(e)?;
    }
    // Fail on unwritable outputs before the long work, without touching what is there.
    for p in output.iter().chain(&a.export).chain(&a.stats) {
        probe_output(p)?;
    }
    let pool = crate::args::thread_pool(a.threads)?;
    pool.install(|| {
        run_in_pool(
            &a,
            src,
            params,
            environment,
            sun,
            output,
            (width, height),
            limit,
        )
    })
}

/// Checks `path` can be written (its directory exists and takes a new file) by creating and
/// removing its temporary file: the file itself is written atomically at the end, so a
/// refused or failed run leaves an existing one as it was.
fn probe_output(path: &std::path::Path) -> Result<(), String> {
    fathom_core::atomic_file::AtomicFile::create(path)
        .map(drop)
        .map_err(|e| e.to_string())
}

/// Whether the image output is EXR (true) or PNG (false); other extensions are refused
/// rather than written as PNG bytes under a name that says otherwise.
fn image_format(path: &std::path::Path) -> Result<bool, String> {
    match path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .as_deref()
    {
        Some("exr") => Ok(true),
        Some("png") => Ok(false),
        other => Err(format!(
            "{}: cannot write images {}; choose .png (tonemapped) or .exr (linear float RGB)",
            path.display(),
            match other {
                Some(e) => format!("with extension `.{e}`"),
                None => "without an extension".into(),
            }
        )),
    }
}

/// Checks an `--export` path names a grid format before any work.
fn grid_format(path: &std::path::Path) -> Result<(), String> {
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase());
    match ext.as_deref() {
        Some("vol") | Some("raw") => Ok(()),
        _ => Err(format!(
            "{}: unknown grid format (valid extensions: .vol for Mitsuba 3, .raw for fathom's \
             raw grids)",
            path.display()
        )),
    }
}

/// `--export-field distance`: the scene's signed distance sampled into a `.vol` grid.
fn export_distance(a: &VolumeArgs, src: Source, limit: u64) -> Result<(), String> {
    if !matches!(src, Source::Fractal { .. }) {
        return Err(
            "--export-field distance samples a scene: give --scene FILE or --preset NAME".into(),
        );
    }
    let Some(path) = &a.export else {
        return Err("--export-field distance needs --export FILE.vol".into());
    };
    if !path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("vol"))
    {
        return Err(format!(
            "{}: a distance grid is written as .vol (Mitsuba 3's grid format)",
            path.display()
        ));
    }
    if a.output.is_some() {
        return Err(
            "--export-field distance only exports: a distance grid is not a density to render \
             (leave out -o, or export the density)"
                .into(),
        );
    }
    probe_output(path)?;
    let pool = crate::args::thread_pool(a.threads)?;
    let pb = std::sync::Mutex::new(None::<ProgressBar>);
    let grid = pool
        .install(|| {
            pipeline::distance_grid(&src, limit, &|what, done, total| {
                let mut g = pb.lock().expect("progress lock");
                g.get_or_insert_with(|| bar(a.quiet, total, what))
                    .set_position(done);
            })
        })
        .map_err(|e| e.to_string())?;
    if let Some(b) = pb.lock().expect("progress lock").take() {
        b.finish_and_clear();
    }
    fathom_volume::vol_file::write(path, &grid).map_err(|e| e.to_string())?;
    if !a.quiet {
        let (r, b) = (grid.res(), grid.bbox);
        eprintln!(
            "volume: wrote the signed distance on a {}x{}x{} grid over {:?} .. {:?} to {}",
            r[0],
            r[1],
            r[2],
            b.min.to_array(),
            b.max.to_array(),
            path.display()
        );
    }
    Ok(())
}

#[allow(clippy::too_many_arguments)]
fn run_in_pool(
    a: &VolumeArgs,
    src: Source,
    params: MediumParams,
    environment: Environment,
    sun: Option<Sun>,
    output: Option<PathBuf>,
    (width, height): (u32, u32),
    limit: u64,
) -> Result<(), String> {
    let scene_camera = matches!(src, Source::Fractal { .. });
    let pb = std::sync::Mutex::new(None::<ProgressBar>);
    let built = pipeline::build(&src, limit, &|what, done, total| {
        let mut g = pb.lock().expect("progress lock");
        let b = g.get_or_insert_with(|| bar(a.quiet, total, what));
        b.set_position(done);
    })
    .map_err(|e: VolumeError| e.to_string())?;
    if let Some(b) = pb.lock().expect("progress lock").take() {
        b.finish();
    }
    if let Some(p) = &a.export {
        pipeline::export(p, &built).map_err(|e| e.to_string())?;
        if !a.quiet {
            let r = built.density.res();
            eprintln!(
                "volume: wrote {}x{}x{} grid to {}",
                r[0],
                r[1],
                r[2],
                p.display()
            );
        }
    }
    let mut stats = serde_json::Map::new();
    if let Some(s) = &built.sim {
        stats.insert(
            "simulation".into(),
            serde_json::to_value(s).map_err(|e| e.to_string())?,
        );
    }
    if let Some(out) = &output {
        let mut params = params;
        let exposure = exposure::auto(&built.density);
        let mut camera = if scene_camera {
            built.camera.clone()
        } else {
            pipeline::framing_camera(&exposure.occupied_box)
        };
        if a.density_scale.is_none() {
            params.density_scale = exposure.density_scale;
            if !a.quiet {
                eprintln!(
                    "volume: density scale {:.4} (automatic: {:.2}% of the voxels are structure, mean chord {:.4}, mean density {:.3}; set --density-scale to override)",
                    exposure.density_scale,
                    100.0 * exposure.occupied_fraction,
                    exposure.mean_chord,
                    exposure.mean_density
                );
            }
        }
        let mut ex = serde_json::to_value(exposure).map_err(|e| e.to_string())?;
        ex["density_scale_used"] = params.density_scale.into();
        ex["automatic"] = a.density_scale.is_none().into();
        stats.insert("exposure".into(), ex);
        for (field, v) in [
            (&mut camera.eye, a.eye),
            (&mut camera.target, a.target),
            (&mut camera.up, a.up),
        ] {
            if let Some(v) = v {
                *field = v;
            }
        }
        if let Some(f) = a.fov {
            camera.fov = f;
        }
        let scene = VolumeScene {
            medium: Medium::new(built.density, &params).map_err(|e| e.to_string())?,
            environment,
            sun,
            max_depth: a.max_depth,
            rr_depth: a.rr_depth,
        };
        let mut prog =
            Progressive::new(&scene, &camera, width, height, a.seed).map_err(|e| e.to_string())?;
        let pb = bar(a.quiet, a.spp as u64 * height as u64, "render");
        // Passes of a few samples: the same image as one pass (each sample has its own stream).
        let pass = (a.spp / 8).max(1);
        while prog.samples() < a.spp {
            let n = pass.min(a.spp - prog.samples());
            prog.add_samples(n, &|| pb.inc(n as u64))
                .map_err(|e| e.to_string())?;
        }
        pb.finish();
        let frame = prog.frame();
        if image_format(out)? {
            pipeline::save_exr(&frame, out).map_err(|e| e.to_string())?;
        } else {
            let f = fathom_trace::output::open_output(out).map_err(|e| e.to_string())?;
            fathom_trace::output::save_colour(&frame, f, out).map_err(|e| e.to_string())?;
        }
        let st = prog.stats();
        if !a.quiet {
            eprintln!(
                "volume: {} ({}x{}, {} spp): {:.2} M paths/s, {:.2} scatterings per path, {:.1} majorant steps per path",
                out.display(),
                width,
                height,
                a.spp,
                st.paths_per_second / 1e6,
                st.mean_path_length,
                st.majorant_steps_per_path
            );
        }
        stats.insert(
            "render".into(),
            serde_json::to_value(st).map_err(|e| e.to_string())?,
        );
    }
    if let Some(p) = &a.stats {
        let text = serde_json::to_string_pretty(&serde_json::Value::Object(stats))
            .map_err(|e| e.to_string())?;
        fathom_core::atomic_file::write(p, text).map_err(|e| e.to_string())?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::FromArgMatches;

    fn args(list: &[&str]) -> VolumeArgs {
        let cmd = VolumeArgs::augment_args(clap::Command::new("volume"));
        let m = cmd
            .try_get_matches_from(std::iter::once("volume").chain(list.iter().copied()))
            .unwrap_or_else(|e| panic!("{list:?}: {e}"));
        VolumeArgs::from_arg_matches(&m).unwrap()
    }

    fn tmp(name: &str) -> String {
        let d = std::env::temp_dir().join(format!("fathom-cmd-volume-{}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        d.join(name).display().to_string()
    }

    #[test]
    fn a_scene_exports_its_signed_distance_as_a_vol_grid() {
        let vol = tmp("sdf.vol");
        run(args(&[
            "--preset",
            "menger",
            "--grid",
            "12",
            "--box",
            "-1.5,-1.5,-1.5,1.5,1.5,1.5",
            "--export",
            &vol,
            "--export-field",
            "distance",
            "--quiet",
        ]))
        .unwrap();
        let bytes = std::fs::read(&vol).unwrap();
        assert_eq!(&bytes[..4], b"VOL\x03");
        let header = 48;
        assert_eq!(bytes.len(), header + 12 * 12 * 12 * 4);
        let values: Vec<f32> = bytes[header..]
            .chunks_exact(4)
            .map(|c| f32::from_le_bytes(c.try_into().unwrap()))
            .collect();
        // The sponge spans [-1, 1]^3: the corner voxel (centre -1.375) is outside, the one
        // nearest the centre of a face is inside the solid frame; the grid matches the tape.
        let tape = fathom_core::Tape::compile(&presets::load("menger").unwrap()).unwrap();
        let mut ev = fathom_core::Evaluator::<f64>::new();
        for (i, v) in values.iter().enumerate() {
            let c = |k: usize| -1.5 + (k as f64 + 0.5) * 0.25;
            let p = fathom_core::V3::new(c(i % 12), c(i / 12 % 12), c(i / 144));
            let want = ev.distance(&tape, p);
            assert!((*v as f64 - want).abs() < 1e-4, "voxel {i}: {v} vs {want}");
        }
        assert!(values[0] > 0.0 && values.iter().any(|v| *v < 0.0));
        // What it refuses.
        for (list, want) in [
            (vec!["--sim", "physarum", "--grid", "8"], "samples a scene"),
            (vec!["--preset", "menger", "--grid", "8"], "needs --export"),
            (
                vec![
                    "--preset", "menger", "--grid", "8", "--export", &vol, "-o", "x.png",
                ],
                "only exports",
            ),
        ] {
            let mut full = list.clone();
            full.extend(["--export-field", "distance", "--quiet"]);
            let e = run(args(&full)).unwrap_err();
            assert!(e.contains(want), "{list:?}: {e}");
        }
        let raw = tmp("sdf.raw");
        let e = run(args(&[
            "--preset",
            "menger",
            "--grid",
            "8",
            "--export",
            &raw,
            "--export-field",
            "distance",
        ]))
        .unwrap_err();
        assert!(e.contains(".vol"), "{e}");
    }

    #[test]
    fn bad_input_gives_clear_errors() {
        let out = tmp("bad.png");
        let truncated = tmp("truncated.vol");
        std::fs::write(&truncated, b"VOL\x03\x01\0\0\0\x02\0\0\0").unwrap();
        // One voxel of a finite density whose extinction overflows (once hung the tracker).
        let one_voxel = |name: &str, d: f32| {
            let p = tmp(name);
            let mut b = b"VOL\x03\x01\0\0\0\x01\0\0\0\x01\0\0\0\x01\0\0\0\x01\0\0\0".to_vec();
            for v in [0.0f32, 0.0, 0.0, 1.0, 1.0, 1.0, d] {
                b.extend_from_slice(&v.to_le_bytes());
            }
            std::fs::write(&p, b).unwrap();
            p
        };
        let (dense, denser) = (one_voxel("1e36.vol", 1e36), one_voxel("1e38.vol", 1e38));
        let cases: Vec<(Vec<&str>, &str)> = vec![
            (vec!["--grid", denser.as_str()], "more than the 1e12"),
            (
                vec!["--grid", dense.as_str(), "--density-scale", "1e6"],
                "more than the 1e12",
            ),
            (vec!["--spp", "0"], "spp = 0 is out of range: 1..="),
            (vec!["--g", "1"], "g = 1 is out of range: (-1, 1)"),
            (
                vec!["--albedo", "0.5,2,0.5"],
                "albedo = 2 is out of range: [0, 1]",
            ),
            (
                vec!["--albedo", "red"],
                "--albedo `red` must be 3 comma-separated numbers (or one number for all)",
            ),
            (
                vec!["--env", "nan"],
                "--env `nan`: `nan` is not a finite number",
            ),
            (
                vec!["--env", "inf"],
                "--env `inf`: `inf` is not a finite number",
            ),
            (
                vec!["--threads", "0"],
                "--threads 0 is out of range [1, 1024]",
            ),
            (
                vec!["--threads", "100000"],
                "--threads 100000 is out of range [1, 1024]",
            ),
            (
                vec!["--env", "2e6"],
                "environment = constant 2000000,2000000,2000000",
            ),
            (vec!["--max-memory", "0"], "(0, 1e15] bytes"),
            (vec!["--density-scale", "-3"], "density scale = -3"),
            (
                vec!["--sim", "physarum", "--grid", "0"],
                "grid = 0 is out of range: 1..=8192",
            ),
            (
                vec!["--sim", "physarum", "--grid", "big"],
                "--grid `big`: with --sim, --scene or --preset, --grid is the resolution",
            ),
            (
                vec!["--sim", "physarum", "--preset", "tendril"],
                "valid presets: tendrils, sheets, lattice, cage",
            ),
            (
                vec!["--sim", "physarum", "--decay", "2"],
                "decay = 2 is out of range: [0, 1]",
            ),
            (vec!["--sim", "physarum", "--grid", "4096"], "memory limit"),
            (vec!["--preset", "menger", "--box", "1,1,1,0,0,0"], "box ="),
            (vec!["--preset", "mengr"], "did you mean `menger`"),
            (vec!["--grid", "/nonexistent/x.vol"], "/nonexistent/x.vol"),
            (
                vec!["--grid", truncated.as_str()],
                "truncated inside its header (expected the y resolution)",
            ),
            (vec!["--sun", "0,0,0"], "--sun 0,0,0"),
            (vec!["--size", "0x10"], "size"),
            (vec!["--max-depth", "1000000"], "max depth = 1000000"),
        ];
        for (list, want) in cases {
            let mut full = list.clone();
            for (flag, value) in [("--size", "8x8"), ("--spp", "1"), ("--steps", "1")] {
                if !list.contains(&flag) {
                    full.extend([flag, value]);
                }
            }
            full.extend(["-o", out.as_str(), "--quiet"]);
            let e = run(args(&full))
                .err()
                .unwrap_or_else(|| panic!("{list:?} should fail"));
            assert!(e.contains(want), "{list:?}: expected `{want}` in: {e}");
        }
    }

    #[test]
    fn the_default_lighting_and_density_scale_show_the_structure() {
        let (png, stats) = (tmp("auto.png"), tmp("auto.json"));
        run(args(&[
            "--sim", "physarum", "--grid", "48", "--steps", "80", "--size", "48x48", "--spp", "8",
            "-o", &png, "--stats", &stats, "--quiet",
        ]))
        .unwrap();
        let s: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&stats).unwrap()).unwrap();
        let ex = &s["exposure"];
        assert_eq!(ex["automatic"], true, "{s}");
        let scale = ex["density_scale_used"].as_f64().unwrap();
        let depth =
            scale * ex["mean_chord"].as_f64().unwrap() * ex["mean_density"].as_f64().unwrap();
        assert!((depth - 3.0).abs() < 0.01, "{ex}");
        // Lit, not a white haze: the picture is far from one colour.
        let img = image::open(&png).unwrap().to_luma8();
        let v: Vec<f64> = img.pixels().map(|p| p.0[0] as f64).collect();
        let mean = v.iter().sum::<f64>() / v.len() as f64;
        let sd = (v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / v.len() as f64).sqrt();
        assert!(sd > 10.0, "flat picture: mean {mean}, sd {sd}");
        // An explicit scale is used as given.
        run(args(&[
            "--sim",
            "physarum",
            "--grid",
            "16",
            "--steps",
            "4",
            "--size",
            "8x8",
            "--spp",
            "1",
            "--density-scale",
            "7",
            "-o",
            &png,
            "--stats",
            &stats,
            "--quiet",
        ]))
        .unwrap();
        let s: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&stats).unwrap()).unwrap();
        assert_eq!(s["exposure"]["density_scale_used"], 7.0);
        assert_eq!(s["exposure"]["automatic"], false);
        let e = run(args(&[
            "--env",
            "1",
            "--sky-top",
            "1,1,1",
            "--sky-bottom",
            "0,0,0",
            "--size",
            "8x8",
        ]))
        .unwrap_err();
        assert!(e.contains("--env and --sky-top"), "{e}");
    }

    #[test]
    fn a_small_simulation_renders_exports_and_reports() {
        let (png, exr, vol, raw, stats) = (
            tmp("s.png"),
            tmp("s.exr"),
            tmp("s.vol"),
            tmp("s.raw"),
            tmp("s.json"),
        );
        let common = [
            "--sim", "physarum", "--grid", "16", "--steps", "4", "--size", "8x6", "--spp", "2",
            "--quiet",
        ];
        run(args(
            &[
                &common[..],
                &["-o", &png, "--export", &vol, "--stats", &stats],
            ]
            .concat(),
        ))
        .unwrap();
        let s: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&stats).unwrap()).unwrap();
        assert!(
            s["render"]["paths_per_second"].as_f64().unwrap() > 0.0,
            "{s}"
        );
        assert_eq!(s["simulation"]["steps"], 4);
        assert_eq!(image::open(&png).unwrap().width(), 8);
        run(args(
            &[&common[..], &["-o", &exr, "--export", &raw]].concat(),
        ))
        .unwrap();
        assert!(
            image::open(&exr).unwrap().as_rgb32f().is_some(),
            "EXR is float RGB"
        );
        // The exported grid renders from the file.
        run(args(&[
            "--grid", &vol, "--box", "file", "--size", "4x4", "--spp", "1", "-o", &png, "--quiet",
        ]))
        .unwrap();
        run(args(&[
            "--grid", &raw, "--size", "4x4", "--spp", "1", "-o", &png, "--quiet",
        ]))
        .unwrap();
    }
}
