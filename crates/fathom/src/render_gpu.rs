//! `fathom render --gpu` and `fathom render --stereo sbs|ods`: the GPU renderer (fathom-gpu)
//! and the stereo layouts, kept apart from the CPU path in `cmd_render`.
//!
//! - `--gpu`: the same scene through the WGSL tape interpreter. With no adapter at all it says
//!   so and suggests the CPU path; a view zoomed past f32 precision is handed to the CPU tracer
//!   (which switches to f64) with a note.
//! - `--stereo sbs`: left and right views side by side (output twice as wide), eyes
//!   `--eye-separation` apart along the camera's right axis, parallel (no toe-in). On the CPU
//!   this renders the two views one after the other.
//! - `--stereo ods`: omni-directional stereo, equirectangular 360 x 180 degrees per eye, left
//!   eye on top (output twice as tall), the format VR headsets and 360 video players read.
//!   GPU only for now.

use clap::ValueEnum;
use fathom_core::Scene;
use fathom_core::frame::Frame;
use fathom_gpu::{GpuError, Projection, RenderOptions, Renderer};

/// Stereo layout.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum StereoKind {
    /// Side-by-side pair of parallel pinhole views.
    Sbs,
    /// Omni-directional stereo, equirectangular, top (left eye) / bottom (right eye).
    Ods,
}

/// What the GPU/stereo path rendered, with its statistics as JSON.
pub struct Rendered {
    pub frame: Frame,
    pub stats: serde_json::Value,
    /// Wall time of the whole render.
    pub ms_total: f64,
}

/// Checks the GPU and stereo options before any output file is opened.
pub fn check(gpu: bool, stereo: Option<StereoKind>, eye_separation: f64) -> Result<(), String> {
    if !(eye_separation.is_finite() && (0.0..=1e6).contains(&eye_separation)) {
        return Err(format!(
            "--eye-separation = {eye_separation} is out of range [0, 1e6] (scene units)"
        ));
    }
    if stereo == Some(StereoKind::Ods) && !gpu {
        return Err(
            "--stereo ods renders on the GPU only for now; add --gpu (a machine without a \
             GPU can run it through Mesa's lavapipe: scripts/setup.sh installs it)"
                .into(),
        );
    }
    Ok(())
}

/// Renders `scene` on the GPU or (for stereo without `--gpu`) on the CPU.
pub fn render(
    scene: &Scene,
    cpu: &fathom_trace::Options,
    gpu: bool,
    stereo: Option<StereoKind>,
    eye_separation: f64,
) -> Result<Rendered, String> {
    check(gpu, stereo, eye_separation)?;
    let projection = match stereo {
        None => Projection::Mono,
        Some(StereoKind::Sbs) => Projection::SideBySide { eye_separation },
        Some(StereoKind::Ods) => Projection::Ods { eye_separation },
    };
    if !gpu {
        return match stereo {
            Some(StereoKind::Sbs) => cpu_side_by_side(scene, cpu, eye_separation),
            Some(StereoKind::Ods) => Err("internal: ODS without --gpu passed the check".into()),
            None => Err("internal: the GPU path was asked for a CPU mono render".into()),
        };
    }
    let mut r = Renderer::headless().map_err(|e| e.to_string())?;
    let ss = cpu.supersample;
    let opts = RenderOptions {
        width: cpu.width * ss,
        height: cpu.height * ss,
        projection,
        prepass: cpu.prepass,
    };
    match r.render_scene(scene, &opts) {
        Ok((mut frame, s)) => Ok(Rendered {
            frame: {
                // The CPU path's post effects, on the GPU's frame.
                if cpu.ssao > 0.0 && projection == Projection::Mono {
                    let pa = scene.camera.frame().pixel_angle(opts.height);
                    fathom_trace::post::ssao(&mut frame, cpu.ssao, pa as f32);
                }
                if ss > 1 {
                    frame = fathom_trace::post::downsample(&frame, ss);
                }
                frame
            },
            ms_total: s.ms_total,
            stats: serde_json::json!({
                "renderer": "gpu",
                "adapter": r.gpu().adapter_name(),
                "adapter_is_software": r.gpu().is_software(),
                "width": s.width,
                "height": s.height,
                "hits": s.hits,
                "de_evaluations": {
                    "prepass": s.de_prepass,
                    "trace": s.de_trace,
                    "shade": s.de_shade,
                },
                "depth_de_per_pixel": s.de_per_pixel(),
                "ms": { "gpu": s.ms_gpu, "total": s.ms_total },
            }),
        }),
        Err(GpuError::TooDeep { .. }) if stereo.is_none() => {
            eprintln!(
                "fathom: note: the view is zoomed past f32 precision; rendering on the CPU (f64)"
            );
            let (frame, s) = fathom_trace::render(scene, cpu, &|_, _| {})?;
            Ok(Rendered {
                frame,
                ms_total: s.ms_total,
                stats: crate::cmd_render::stats_json(&s),
            })
        }
        Err(e) => Err(e.to_string()),
    }
}

/// Two CPU renders from cameras moved half the separation left and right (parallel axes),
/// joined side by side.
fn cpu_side_by_side(
    scene: &Scene,
    o: &fathom_trace::Options,
    sep: f64,
) -> Result<Rendered, String> {
    let right = scene.camera.frame().right;
    let mut frames = Vec::new();
    let mut ms = 0.0;
    for side in [-0.5, 0.5] {
        let mut s = scene.clone();
        s.camera.eye += right * (side * sep);
        s.camera.target += right * (side * sep);
        let (f, st) = fathom_trace::render(&s, o, &|_, _| {})?;
        ms += st.ms_total;
        frames.push(f);
    }
    let frame = join_side_by_side(&frames[0], &frames[1]);
    Ok(Rendered {
        stats: serde_json::json!({
            "renderer": "cpu",
            "stereo": "sbs",
            "width": frame.width,
            "height": frame.height,
            "ms": { "total": ms },
        }),
        frame,
        ms_total: ms,
    })
}

/// Places two equally sized frames next to each other.
pub fn join_side_by_side(l: &Frame, r: &Frame) -> Frame {
    let (w, h) = (l.width, l.height);
    let mut f = Frame::new(2 * w, h);
    for y in 0..h {
        for x in 0..2 * w {
            let (src, sx) = if x < w { (l, x) } else { (r, x - w) };
            let i = src.index(sx, y);
            let o = f.index(x, y);
            f.colour[o] = src.colour[i];
            f.depth[o] = src.depth[i];
            f.normal[o] = src.normal[i];
            f.id[o] = src.id[i];
            f.steps[o] = src.steps[i];
        }
    }
    f
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frames_join_left_then_right() {
        let mut l = Frame::new(2, 1);
        let mut r = Frame::new(2, 1);
        l.steps = vec![1, 2];
        r.steps = vec![3, 4];
        let f = join_side_by_side(&l, &r);
        assert_eq!((f.width, f.height), (4, 1));
        assert_eq!(f.steps, vec![1, 2, 3, 4]);
    }

    #[test]
    fn ods_without_gpu_and_bad_separation_explain_themselves() {
        let scene = fathom_core::presets::load("mandelbulb").unwrap();
        let o = fathom_trace::Options {
            width: 8,
            height: 4,
            ..Default::default()
        };
        let e = render(&scene, &o, false, Some(StereoKind::Ods), 0.06)
            .err()
            .unwrap();
        assert!(e.contains("--gpu"), "{e}");
        let e = render(&scene, &o, false, Some(StereoKind::Sbs), f64::NAN)
            .err()
            .unwrap();
        assert!(e.contains("eye-separation"), "{e}");
    }
}
