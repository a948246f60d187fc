//! Settling loops at a fixed camera: probes (renders whose image is not wanted, only the
//! subdivision requests) and the settle loops that probe and split until nothing asks.

use super::OctreeView;
use super::anchor::DeepEye;
use super::render::{Drawing, cast};
use super::settling::{PROBE_SLICE, SETTLING_CHUNK, Settling, settling_wide};
use crate::geometry::{Ray, dim_at};
use crate::ray_grid::RayGrid;
use crate::traverse::Request;
use fathom_core::Camera;
use rayon::prelude::*;
use std::time::Instant;

impl OctreeView {
    /// [`OctreeView::render_deep`] for a caller that needs only the requests and counts (the
    /// settling loops): the image is dropped, so it is not drawn smooth.
    pub fn probe_deep(&mut self, cam: &Camera, deep: &DeepEye) -> (Vec<Request>, [u64; 3]) {
        let ((img, reqs, counts), _) = self.render_frame(cam, deep, Drawing::Probe, false);
        self.recycle(img);
        (reqs, counts)
    }

    /// [`OctreeView::probe_deep`] for an f64 eye.
    pub fn probe(&mut self, cam: &Camera) -> (Vec<Request>, [u64; 3]) {
        self.probe_deep(cam, &DeepEye::of(cam))
    }

    /// One probe of a settling loop at a fixed camera (subdivisions alone between its
    /// probes, `settling` kept from one probe to the next): the first casts every pixel, each
    /// later one only the pixels whose voxel could still change (`settling_wide`). The
    /// requests are the ones [`OctreeView::probe_deep`] would find: subdivision splits only
    /// full leaves some ray asked for and only empties space (links and starts may change,
    /// the leaf a ray meets does not), so a pixel that missed misses again, and one that
    /// stopped on a voxel no ray could ask for stops on it again. With surface planes drawn
    /// (rays pass wide leaves) every probe casts every pixel.
    pub fn probe_settling(
        &mut self,
        cam: &Camera,
        deep: &DeepEye,
        settling: &mut Settling,
    ) -> (Vec<Request>, [u64; 3]) {
        self.probe_settling_until(cam, deep, settling, &|| false)
            .unwrap_or_default()
    }

    /// True when the next probe of `settling` casts every pixel: its first, and all of them
    /// while surface planes are drawn (rays pass wide leaves, so a pixel settled at one probe
    /// may stop elsewhere at the next). Otherwise it casts the pixels the last one left
    /// pending ([`Settling::pending`]).
    pub(super) fn probes_every_pixel(&self, settling: &Settling) -> bool {
        settling.pixels.is_none() || self.cfg.planes
    }

    /// [`OctreeView::probe_settling`], giving way when `stop` returns true before one of its
    /// slices of [`PROBE_SLICE`] pixels: `None`, its requests released and `settling` left
    /// without pixels (the next probe casts every pixel).
    pub fn probe_settling_until(
        &mut self,
        cam: &Camera,
        deep: &DeepEye,
        settling: &mut Settling,
        stop: &dyn Fn() -> bool,
    ) -> Option<(Vec<Request>, [u64; 3])> {
        if self.probes_every_pixel(settling) {
            if stop() {
                return None;
            }
            let ((img, reqs, counts), wide) = self.render_frame(cam, deep, Drawing::Probe, true);
            self.recycle(img);
            settling.pixels = Some(wide);
            return Some((reqs, counts));
        }
        let pixels = settling.pixels.take().unwrap_or_default();
        let (o, frame, lod) = self.begin_frame(cam, deep);
        let w = self.cfg.width as usize;
        let grid = RayGrid::new(&frame, self.cfg.width, self.cfg.height);
        let (tree, skip, trav) = (&self.tree, self.skip, self.cfg.traversal);
        let wide_at = settling_wide(lod);
        let (mut reqs, mut wide, mut counts) = (Vec::new(), Vec::new(), [0u64; 3]);
        for slice in pixels.chunks(PROBE_SLICE) {
            if stop() {
                self.release_requests(&reqs);
                return None;
            }
            let (r, wd, c) = self.pool.install(|| {
                slice
                    .par_chunks(SETTLING_CHUNK)
                    .map(|chunk| {
                        let (mut reqs, mut wide, mut c) = (Vec::new(), Vec::new(), [0u64; 3]);
                        let mut entry = None;
                        for &i in chunk {
                            let d = grid.dir(i as usize % w, i as usize / w);
                            let hit = cast(
                                tree,
                                &Ray::new(o, d.into(), lod),
                                skip,
                                &mut entry,
                                trav,
                                &mut reqs,
                            );
                            c[0] += 1;
                            c[2] += hit.steps as u64;
                            if hit.is_hit() {
                                c[1] += 1;
                                if dim_at(hit.depth) >= wide_at * hit.t {
                                    wide.push(i);
                                }
                            }
                        }
                        (reqs, wide, c)
                    })
                    .reduce(
                        || (Vec::new(), Vec::new(), [0u64; 3]),
                        |(mut ra, mut wa, ca), (rb, wb, cb)| {
                            ra.extend(rb);
                            wa.extend(wb);
                            (ra, wa, std::array::from_fn(|i| ca[i] + cb[i]))
                        },
                    )
            });
            reqs.extend(r);
            wide.extend(wd);
            counts = std::array::from_fn(|i| counts[i] + c[i]);
        }
        settling.pixels = Some(wide);
        Some((reqs, counts))
    }

    /// Renders and subdivides at a fixed camera (eye known as [`DeepEye`]) until no leaf asks
    /// for subdivision, `max_frames` pass or `budget_ms` of wall time has passed (the last
    /// subdivision gets what is left of it); returns the frames taken. With a time budget
    /// alone, a zoom's warm start: its first frame then shows the scene, not the root cube.
    pub fn settle_deep(
        &mut self,
        cam: &Camera,
        deep: &DeepEye,
        max_frames: usize,
        budget_ms: f64,
    ) -> usize {
        let t0 = Instant::now();
        let mut settling = Settling::default();
        for i in 0..max_frames {
            let left = budget_ms - t0.elapsed().as_secs_f64() * 1e3;
            if left <= 0.0 {
                return i;
            }
            let (reqs, _) = self.probe_settling(cam, deep, &mut settling);
            if reqs.is_empty() {
                return i;
            }
            self.subdivide(reqs, left);
        }
        max_frames
    }

    /// Renders and subdivides at a fixed camera until no leaf asks for subdivision (or
    /// `max_frames` pass); returns the frames taken.
    pub fn settle(&mut self, cam: &Camera, max_frames: usize) -> usize {
        self.settle_deep(cam, &DeepEye::of(cam), max_frames, f64::INFINITY)
    }
}
