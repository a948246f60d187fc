//! [`Stats`]: the one statistics type of a rendered frame, serialised once with the same keys
//! for every backend (figures a backend does not have are `null`), so `--stats` files, bench
//! output and the window's overlay read alike whatever drew the frame.

use serde::Serialize;

/// Distance evaluations per pass.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct DeCounts {
    /// In the cone-marching prepass.
    pub prepass: u64,
    /// Marching the primary rays.
    pub trace: u64,
    /// Shading: normals, shadows, ambient occlusion.
    pub shade: u64,
}

/// Wall time per pass, in milliseconds.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct Timings {
    /// The cone-marching prepass (tracer).
    pub prepass: f64,
    /// Primary rays and colouring (tracer), or the octree's ray casting.
    pub trace_and_shade: f64,
    /// Post effects (SSAO, fog, supersampling, scrubbing) and layout.
    pub post: f64,
    /// From submission to the device finishing (GPU only).
    pub gpu: Option<f64>,
    /// Subdivision while settling or stepping (octree only).
    pub subdivide: Option<f64>,
    /// The whole frame, as the caller waited for it.
    pub total: f64,
}

/// Octree figures of the frame.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct OctreeStats {
    /// Frames spent subdividing at the view before it was rendered.
    pub settle_frames: usize,
    /// Nodes in the octree.
    pub nodes: u64,
    /// Distance bricks in the octree.
    pub bricks: u64,
    /// Mean nodes visited per ray.
    pub nodes_per_ray: f64,
    /// Memory the octree's arena holds, bytes.
    pub arena_bytes: u64,
}

/// Path-tracer figures of the frame.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct PathStats {
    /// Samples per pixel accumulated in the image returned.
    pub samples_per_pixel: u32,
    /// Samples per pixel this render added (0 when the view already had enough).
    pub samples_added: u32,
    /// Camera paths per second over all of the accumulator's passes.
    pub paths_per_second: f64,
    /// Estimated remaining noise: the RMS standard error of the pixels' mean luminance,
    /// relative to the image's mean luminance (before denoising).
    pub relative_noise: f64,
    /// Paths whose radiance was NaN or infinite, counted and left out of the pixels.
    pub dropped_non_finite: u64,
    /// Whether the colour is the denoiser's output.
    pub denoised: bool,
}

/// What one frame cost and found.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Stats {
    /// The backend that drew the frame ("trace", "gpu", "svo").
    pub renderer: &'static str,
    /// The GPU adapter (GPU only).
    pub adapter: Option<String>,
    /// Whether that adapter is a software rasteriser (GPU only).
    pub adapter_is_software: Option<bool>,
    /// Width of the frame returned, pixels (the region's, for a region render).
    pub width: u32,
    /// Height of the frame returned, pixels.
    pub height: u32,
    /// Whether the f64 (deep zoom) path ran.
    pub deep_f64_path: bool,
    /// Primary rays traced (samples, margins of a region included; 0 where not counted).
    pub primary_rays: u64,
    /// Shadow rays traced (0 where not counted).
    pub shadow_rays: u64,
    /// Primary rays that hit.
    pub hits: u64,
    /// Distance evaluations per pass.
    pub de_evaluations: DeCounts,
    /// Distance evaluations of the depth passes (prepass and primary rays) per pixel.
    pub depth_de_per_pixel: f64,
    /// Primary-ray evaluations per pixel.
    pub trace_steps_per_pixel: f64,
    /// Wall time per pass.
    pub ms: Timings,
    /// Octree figures (octree only).
    pub octree: Option<OctreeStats>,
    /// Path-tracer figures (path tracer only).
    pub path: Option<PathStats>,
    /// Why the frame was drawn differently from what was asked (a GPU view too deep for f32
    /// drawn by the CPU tracer), if it was.
    pub note: Option<String>,
}

impl Stats {
    /// Fills the per-pixel figures from the counters and the frame size.
    pub(crate) fn finish_rates(&mut self) {
        let px = (self.width as f64 * self.height as f64).max(1.0);
        self.depth_de_per_pixel =
            (self.de_evaluations.prepass + self.de_evaluations.trace) as f64 / px;
        self.trace_steps_per_pixel = self.de_evaluations.trace as f64 / px;
    }

    /// The CPU tracer's counters.
    pub(crate) fn from_trace(s: &fathom_trace::Stats) -> Stats {
        let mut out = Stats {
            renderer: "trace",
            width: s.width,
            height: s.height,
            deep_f64_path: s.deep,
            primary_rays: s.primary_rays,
            shadow_rays: s.shadow_rays,
            hits: s.hits,
            de_evaluations: DeCounts {
                prepass: s.de_prepass,
                trace: s.de_trace,
                shade: s.de_shade,
            },
            ms: Timings {
                prepass: s.ms_prepass,
                trace_and_shade: s.ms_trace,
                post: s.ms_post,
                total: s.ms_total,
                ..Timings::default()
            },
            ..Stats::default()
        };
        out.finish_rates();
        out
    }

    /// As JSON.
    pub fn to_json(&self) -> serde_json::Value {
        serde_json::to_value(self).expect("stats always serialise")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_backend_writes_the_same_keys() {
        let keys = |s: &Stats| -> Vec<String> {
            let mut k: Vec<String> = s.to_json().as_object().unwrap().keys().cloned().collect();
            k.sort();
            k
        };
        let cpu = Stats::from_trace(&fathom_trace::Stats::default());
        let gpu = Stats {
            renderer: "gpu",
            adapter: Some("x".into()),
            ..Stats::default()
        };
        let svo = Stats {
            renderer: "svo",
            octree: Some(OctreeStats::default()),
            ..Stats::default()
        };
        assert_eq!(keys(&cpu), keys(&gpu));
        assert_eq!(keys(&cpu), keys(&svo));
        let path = Stats {
            renderer: "path",
            path: Some(PathStats::default()),
            ..Stats::default()
        };
        assert_eq!(keys(&cpu), keys(&path));
        // The keys `fathom render --stats` wrote before the render layer are all still there.
        let j = cpu.to_json();
        for k in [
            "width",
            "height",
            "deep_f64_path",
            "primary_rays",
            "shadow_rays",
            "hits",
            "depth_de_per_pixel",
            "trace_steps_per_pixel",
        ] {
            assert!(j.get(k).is_some(), "{k}");
        }
        for k in ["prepass", "trace", "shade"] {
            assert!(j["de_evaluations"].get(k).is_some(), "{k}");
        }
        for k in ["prepass", "trace_and_shade", "post", "total", "gpu"] {
            assert!(j["ms"].get(k).is_some(), "{k}");
        }
    }
}
