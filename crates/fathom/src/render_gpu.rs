//! `fathom render --gpu` and `fathom render --stereo sbs|ods`: the GPU renderer (fathom-gpu)
//! and the stereo layouts, kept apart from the CPU path in `cmd_render`.
//!
//! - `--gpu`: the same scene through the WGSL tape interpreter. With no adapter at all it says
//!   so and suggests the CPU path; a view zoomed past f32 precision is handed to the CPU tracer
//!   (which switches to f64) with a note.
//! - `--stereo sbs`: left and right views side by side (output twice as wide), eyes
//!   `--eye-separation` apart along the camera's right axis, parallel (no toe-in).
//! - `--stereo ods`: omni-directional stereo, equirectangular 360 x 180 degrees per eye, left
//!   eye on top (output twice as tall), the format VR headsets and 360 video players read.
//!
//! Both layouts run on the GPU and on the CPU tracer (`fathom_trace::Options::projection`), with
//! the same [`Projection`] from fathom-core; the octree renderer draws mono views only.

use clap::ValueEnum;
use fathom_core::Scene;
use fathom_core::camera::MAX_EYE_SEPARATION;
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

/// Checks the stereo options before any output file is opened, and turns them into a
/// [`Projection`]. `svo`: the octree renderer was chosen, which draws mono views only.
pub fn projection(
    stereo: Option<StereoKind>,
    eye_separation: f64,
    svo: bool,
) -> Result<Projection, String> {
    if !(eye_separation.is_finite() && (0.0..=MAX_EYE_SEPARATION).contains(&eye_separation)) {
        return Err(format!(
            "--eye-separation = {eye_separation} is out of range [0, {MAX_EYE_SEPARATION}] (scene units)"
        ));
    }
    if svo && stereo.is_some() {
        return Err(
            "--stereo is not supported by --renderer svo (the octree renders one mono \
                    view); leave out --renderer svo to render stereo with the sphere tracer"
                .into(),
        );
    }
    Ok(match stereo {
        None => Projection::Mono,
        Some(StereoKind::Sbs) => Projection::SideBySide { eye_separation },
        Some(StereoKind::Ods) => Projection::Ods { eye_separation },
    })
}

/// Renders `scene` on the GPU with the CPU tracer's options (size per eye, projection,
/// prepass, supersampling, SSAO). A view zoomed past f32 precision goes to the CPU tracer.
pub fn render(scene: &Scene, cpu: &fathom_trace::Options) -> Result<Rendered, String> {
    cpu.validate()?;
    let projection = cpu.projection;
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
                // The CPU path's post effects, on the GPU's frame: SSAO on each eye's view,
                // as the CPU tracer does (none for ODS, whose screen wraps around).
                if cpu.ssao > 0.0 && projection.screen_space() {
                    let cam = projection.frame(&scene.camera);
                    let pa = projection.pixel_angle(&cam, opts.width, opts.height) as f32;
                    let mut views = fathom_trace::stereo::split(projection, frame);
                    for v in &mut views {
                        fathom_trace::post::ssao(v, cpu.ssao, pa);
                    }
                    frame = fathom_trace::stereo::assemble(projection, views);
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
        Err(GpuError::TooDeep { .. }) => {
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stereo_options_become_projections_or_explain_themselves() {
        assert_eq!(projection(None, 0.065, false), Ok(Projection::Mono));
        assert_eq!(
            projection(Some(StereoKind::Ods), 0.1, false),
            Ok(Projection::Ods {
                eye_separation: 0.1
            })
        );
        for sep in [f64::NAN, -1.0, 2e6] {
            let e = projection(Some(StereoKind::Sbs), sep, false).unwrap_err();
            assert!(e.contains("--eye-separation"), "{e}");
        }
        let e = projection(Some(StereoKind::Ods), 0.065, true).unwrap_err();
        assert!(
            e.contains("--renderer svo") && e.contains("--stereo"),
            "{e}"
        );
        assert_eq!(projection(None, 0.065, true), Ok(Projection::Mono));
    }
}
