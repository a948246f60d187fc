//! One whole frame: render, subdivide (a still view goes on settling within the budget), and
//! every few frames or when memory runs short, unify; with the frame's stats.

use super::OctreeView;
use super::anchor::DeepEye;
use super::frame_stats::FrameStats;
use super::frame_stats::resident_bytes;
use super::image::SvoImage;
use super::settling::Settling;
use super::unify::IDLE_UNIFICATIONS;
use fathom_core::Camera;
use std::time::Instant;

impl OctreeView {
    /// Runs one whole frame: render, subdivide, maybe unify. Returns the image (as rendered:
    /// the tree changes only after it is complete) and the stats.
    pub fn step(&mut self, cam: &Camera) -> (SvoImage, FrameStats) {
        self.step_deep(cam, &DeepEye::of(cam))
    }

    /// [`OctreeView::step`] with an eye known more precisely than f64 (see [`DeepEye`]).
    pub fn step_deep(&mut self, cam: &Camera, deep: &DeepEye) -> (SvoImage, FrameStats) {
        self.step_deep_until(cam, deep, false, &|| false)
    }

    /// [`OctreeView::step_deep`] whose subdivision stops early once `stop` returns true
    /// ([`OctreeView::subdivide_until`]); the frame is rendered whole either way. A `still`
    /// step (a view that is not moving, the camera the same as the last step's) goes on
    /// settling within its budget once the render's requests are split: probes of the pixels
    /// the render left unsettled ([`OctreeView::probe_settling`]), and their splits, a level of
    /// detail each, so a still view settles in fewer steps.
    pub fn step_deep_until(
        &mut self,
        cam: &Camera,
        deep: &DeepEye,
        still: bool,
        stop: &dyn Fn() -> bool,
    ) -> (SvoImage, FrameStats) {
        let t0 = Instant::now();
        let ((img, reqs, c), unsettled) = self.render_frame(cam, deep, self.drawing(), still);
        let render_ms = t0.elapsed().as_secs_f64() * 1e3;
        let t1 = Instant::now();
        let nreq = reqs.len() as u64;
        let budget = self.cfg.subdivide_budget(render_ms);
        let mut sub = self.subdivide_until(reqs, budget, stop);
        if still {
            let mut settling = Settling {
                pixels: Some(unsettled),
            };
            // What a probe's ray costs, first from the render's (tile starts make those
            // cheaper), then from the last probe's.
            let mut ray_ms = render_ms / c[0].max(1) as f64;
            loop {
                let left = budget - t1.elapsed().as_secs_f64() * 1e3;
                let pending = if self.probes_every_pixel(&settling) {
                    (self.cfg.width * self.cfg.height) as usize
                } else {
                    settling.pending().unwrap_or_default()
                };
                // A round starts only when its probe is expected to fit in what is left and
                // the memory budget has room, and ends the loop when it split and emptied
                // nothing (only requests no split can serve).
                let full = self.tree.is_full();
                if full || pending as f64 * ray_ms > left || stop() {
                    break;
                }
                let tp = Instant::now();
                let Some((reqs, pc)) = self.probe_settling_until(cam, deep, &mut settling, stop)
                else {
                    break;
                };
                ray_ms = tp.elapsed().as_secs_f64() * 1e3 / pc[0].max(1) as f64;
                if reqs.is_empty() {
                    break;
                }
                let left = budget - t1.elapsed().as_secs_f64() * 1e3;
                let more = self.subdivide_within(reqs, left, 0, stop);
                sub = std::array::from_fn(|i| sub[i] + more[i]);
                if more[0] + more[1] == 0 {
                    break;
                }
            }
        }
        let subdivide_ms = t1.elapsed().as_secs_f64() * 1e3;
        let t2 = Instant::now();
        let pressure = self.tree.counts().nodes as f64 > 0.9 * self.tree.max_nodes as f64;
        let unified = if pressure {
            self.unify_idle(1) as u64
        } else if self.frame % self.cfg.unify_every as u64 == self.cfg.unify_every as u64 - 1 {
            self.unify_idle(IDLE_UNIFICATIONS) as u64
        } else {
            0
        };
        let unify_ms = t2.elapsed().as_secs_f64() * 1e3;
        let counts = self.tree.counts();
        let stats = FrameStats {
            frame: self.frame,
            frame_ms: t0.elapsed().as_secs_f64() * 1e3,
            render_ms,
            subdivide_ms,
            unify_ms,
            rays: c[0],
            hits: c[1],
            nodes_per_ray: c[2] as f64 / c[0].max(1) as f64,
            requests: nreq,
            subdivisions: sub[0],
            emptied: sub[1],
            no_memory: sub[2],
            unified,
            node_count: counts.nodes as u64,
            brick_count: counts.bricks as u64,
            arena_bytes: self.tree.arena_bytes() as u64,
            resident_bytes: resident_bytes(),
            skip_depth: self.skip.map(|s| s.1.depth as i32).unwrap_or(-1),
            anchor_depth: self.tree.anchor.depth,
            largest_voxel_px: img.largest_voxel_px,
            beam_nodes_per_ray: self.beam_steps as f64 / c[0].max(1) as f64,
            rays_from_skip: self.rays_from_skip,
            filled: self.filled,
        };
        self.frame += 1;
        (img, stats)
    }
}
