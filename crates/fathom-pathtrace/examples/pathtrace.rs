//! Renders a preset or scene file with the path tracer to PNGs, raw and denoised, and prints
//! the statistics; with `--converge REF_SPP` it also measures how long the image takes to
//! reach 2 % RMSE against a REF_SPP reference, raw and denoised.
//!
//! ```text
//! cargo run --release -p fathom-pathtrace --example pathtrace -- \
//!     --preset mandelbulb --size 640x480 --spp 64 -o /tmp/bulb
//! cargo run --release -p fathom-pathtrace --example pathtrace -- \
//!     --preset model-tree --size 160x120 --converge 4096 -o /tmp/tree
//! ```
//! Options: `--preset NAME` or `--scene FILE.ron`, `--size WxH`, `--spp N`, `-o PREFIX`
//! (writes PREFIX.png and PREFIX-denoised.png), `--bounces N`, `--aperture R`,
//! `--focus D`, `--exposure E`, `--threads N`, `--env FILE.hdr|exr`, `--env-strength S`,
//! `--fog DENSITY`, `--sky-light K`, `--converge REF_SPP`.

use fathom_core::Tape;
use fathom_pathtrace::envmap::EnvMap;
use fathom_pathtrace::lights::Environment;
use fathom_pathtrace::output::{relative_rmse, write_png};
use fathom_pathtrace::{Control, DenoiseSettings, PathSettings, PathTracer, Progressive, denoise};
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

struct Args {
    preset: String,
    scene: Option<PathBuf>,
    size: (u32, u32),
    spp: u32,
    out: String,
    bounces: u32,
    aperture: f64,
    focus: Option<f64>,
    exposure: f32,
    threads: Option<usize>,
    env: Option<PathBuf>,
    env_strength: f64,
    fog: Option<f64>,
    converge: Option<u32>,
    sky_light: Option<f64>,
}

fn parse() -> Result<Args, String> {
    let mut a = Args {
        preset: "mandelbulb".into(),
        scene: None,
        size: (640, 480),
        spp: 64,
        out: "pathtrace".into(),
        bounces: 8,
        aperture: 0.0,
        focus: None,
        exposure: 1.0,
        threads: None,
        env: None,
        env_strength: 1.0,
        fog: None,
        converge: None,
        sky_light: None,
    };
    let mut it = std::env::args().skip(1);
    while let Some(k) = it.next() {
        let mut v = || it.next().ok_or(format!("{k} needs a value"));
        let num = |s: String| s.parse::<f64>().map_err(|e| format!("{k}: {e}"));
        match k.as_str() {
            "--preset" => a.preset = v()?,
            "--scene" => a.scene = Some(v()?.into()),
            "--size" => {
                let s = v()?;
                let (w, h) = s.split_once('x').ok_or("--size WxH")?;
                a.size = (
                    w.parse().map_err(|_| "bad width")?,
                    h.parse().map_err(|_| "bad height")?,
                );
            }
            "--spp" => a.spp = num(v()?)? as u32,
            "-o" => a.out = v()?,
            "--bounces" => a.bounces = num(v()?)? as u32,
            "--aperture" => a.aperture = num(v()?)?,
            "--focus" => a.focus = Some(num(v()?)?),
            "--exposure" => a.exposure = num(v()?)? as f32,
            "--threads" => a.threads = Some(num(v()?)? as usize),
            "--env" => a.env = Some(v()?.into()),
            "--env-strength" => a.env_strength = num(v()?)?,
            "--fog" => a.fog = Some(num(v()?)?),
            "--converge" => a.converge = Some(num(v()?)? as u32),
            "--sky-light" => a.sky_light = Some(num(v()?)?),
            other => return Err(format!("unknown option {other}")),
        }
    }
    Ok(a)
}

fn main() {
    if let Err(e) = run() {
        eprintln!("error: {e}");
        std::process::exit(1);
    }
}

fn run() -> Result<(), Box<dyn std::error::Error>> {
    let a = parse()?;
    if let Some(t) = a.threads {
        rayon::ThreadPoolBuilder::new()
            .num_threads(t)
            .build_global()?;
    }
    let scene = match &a.scene {
        Some(p) => fathom_core::scene_file::load(p)?,
        None => fathom_core::presets::load(&a.preset)?,
    };
    let tape = Tape::compile(&scene)?;
    let mut settings = PathSettings::new(a.size.0, a.size.1);
    settings.max_bounces = a.bounces;
    settings.aperture = a.aperture;
    settings.focus_distance = a.focus;
    settings.sky_light = a.sky_light;
    if let Some(p) = &a.env {
        settings.environment = Some(Environment::Map {
            map: Arc::new(EnvMap::load(p)?),
            strength: a.env_strength,
            rotation: 0.0,
        });
    }
    if let Some(d) = a.fog {
        settings.fog = fathom_pathtrace::settings::default_fog(d);
    }
    let tracer = PathTracer::new(&scene, &tape, settings)?;
    if let Some(reference_spp) = a.converge {
        return converge(&a, tracer, reference_spp);
    }
    let mut prog = Progressive::new(tracer);
    let t = Instant::now();
    prog.add_samples(a.spp, &Control::default())?;
    let secs = t.elapsed().as_secs_f64();
    let frame = prog.frame();
    let st = prog.stats();
    println!(
        "{}x{} {} spp: {:.2} s, {:.0} paths/s, {:.1} distance evaluations per path, {} non-finite paths dropped, estimated noise {:.2} %",
        a.size.0,
        a.size.1,
        a.spp,
        secs,
        st.paths_per_second(),
        st.evaluations as f64 / st.paths as f64,
        st.dropped_non_finite,
        100.0 * frame.relative_noise()
    );
    let raw = format!("{}.png", a.out);
    write_png(raw.as_ref(), a.size.0, a.size.1, &frame.colour, a.exposure)?;
    let t = Instant::now();
    let den = denoise(&frame, &DenoiseSettings::default());
    let dsecs = t.elapsed().as_secs_f64();
    let dn = format!("{}-denoised.png", a.out);
    write_png(dn.as_ref(), a.size.0, a.size.1, &den, a.exposure)?;
    println!("wrote {raw} and {dn} (denoiser {:.0} ms)", dsecs * 1e3);
    Ok(())
}

/// Measures time to 2 % RMSE against a reference of `reference_spp`, raw and denoised.
fn converge(
    a: &Args,
    tracer: PathTracer,
    reference_spp: u32,
) -> Result<(), Box<dyn std::error::Error>> {
    // The reference uses another seed so its noise is independent of the measured runs.
    let mut ref_settings_tracer = Progressive::new(tracer.clone().with_seed(0x5eed_0001));
    let t = Instant::now();
    ref_settings_tracer.add_samples(reference_spp, &Control::default())?;
    let reference = ref_settings_tracer.frame();
    println!(
        "reference: {reference_spp} spp in {:.1} s, estimated noise {:.3} %",
        t.elapsed().as_secs_f64(),
        100.0 * reference.relative_noise()
    );
    write_png(
        format!("{}-reference.png", a.out).as_ref(),
        a.size.0,
        a.size.1,
        &reference.colour,
        a.exposure,
    )?;
    let mut prog = Progressive::new(tracer);
    let mut spp = 0;
    let mut render_secs = 0.0;
    let (mut raw_done, mut den_done) = (None, None);
    println!("spp  seconds  rmse_raw  rmse_denoised  denoise_ms");
    while spp < reference_spp / 4 && (raw_done.is_none() || den_done.is_none()) {
        let add = spp.max(1);
        let t = Instant::now();
        prog.add_samples(add, &Control::default())?;
        render_secs += t.elapsed().as_secs_f64();
        spp += add;
        let f = prog.frame();
        let raw = relative_rmse(&f.colour, &reference.colour);
        let t = Instant::now();
        let d = denoise(&f, &DenoiseSettings::default());
        let dsecs = t.elapsed().as_secs_f64();
        let den = relative_rmse(&d, &reference.colour);
        println!(
            "{spp:4} {render_secs:8.2} {:8.2}% {:12.2}% {:10.0}",
            100.0 * raw,
            100.0 * den,
            dsecs * 1e3
        );
        if raw <= 0.02 && raw_done.is_none() {
            raw_done = Some((spp, render_secs));
        }
        if den <= 0.02 && den_done.is_none() {
            den_done = Some((spp, render_secs + dsecs));
        }
    }
    let show = |x: Option<(u32, f64)>| {
        x.map_or("not reached".to_string(), |(s, t)| {
            format!("{s} spp, {t:.2} s")
        })
    };
    println!(
        "time to 2 % RMSE: raw {}, denoised {}",
        show(raw_done),
        show(den_done)
    );
    Ok(())
}
