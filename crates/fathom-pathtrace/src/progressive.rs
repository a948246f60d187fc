//! Progressive accumulation: samples are added in batches to a running per-pixel mean with a
//! variance estimate, and a [`Frame`] (colour, albedo, normal, depth, variance) can be taken
//! at any time.
//!
//! **Determinism.** A sample depends only on (pixel, sample index, seed) (see
//! [`crate::sampler`]), each pixel's samples are added in index order inside one task, and
//! tiles are written back in tile order, so the image is bit-identical for any number of
//! threads and any scheduling.
//!
//! **Variance.** Welford's running mean and sum of squared deviations of each pixel's
//! luminance give the sample variance; variance / n is the variance of the pixel's mean, and
//! [`Frame::relative_noise`] turns it into the estimated remaining noise (relative standard
//! error) the caller can stop on. The denoiser reads it too.
//!
//! **Robustness.** A path whose radiance is not finite is counted in
//! [`Stats::dropped_non_finite`] and not added: the pixel's mean is over its finite samples.
//! [`Progressive::add_samples`] checks for cancellation before every tile and, once
//! cancelled, discards the whole batch, so the accumulator always holds whole batches.

use crate::integrator::PathTracer;
use crate::sampling::luminance;
use crate::shared::TILE;
use fathom_core::Evaluator;
use glam::DVec3;
use rayon::prelude::*;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::time::Instant;

/// Cancellation and progress of one batch (fathom-render's `CancelToken::flag()` fits
/// `cancel`).
#[derive(Clone, Copy, Default)]
pub struct Control<'a> {
    /// Set from any thread to abandon the batch.
    pub cancel: Option<&'a AtomicBool>,
    /// `progress(tiles done, tiles in the batch)`, from worker threads.
    pub progress: Option<&'a (dyn Fn(usize, usize) + Sync)>,
}

impl Control<'_> {
    fn cancelled(&self) -> bool {
        self.cancel.is_some_and(|c| c.load(Ordering::Relaxed))
    }
}

/// Counters of everything accumulated so far.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Stats {
    /// Samples per pixel taken (batches added).
    pub samples_per_pixel: u32,
    /// Camera paths traced.
    pub paths: u64,
    /// Paths whose radiance was NaN or infinite (dropped).
    pub dropped_non_finite: u64,
    /// Distance evaluations.
    pub evaluations: u64,
    /// Wall-clock seconds spent in [`Progressive::add_samples`].
    pub seconds: f64,
}

impl Stats {
    /// Camera paths per second of wall-clock time.
    pub fn paths_per_second(&self) -> f64 {
        if self.seconds > 0.0 {
            self.paths as f64 / self.seconds
        } else {
            0.0
        }
    }
}

/// The running state of one pixel.
#[derive(Clone, Copy, Debug, Default)]
struct Pixel {
    /// Finite samples added.
    n: u32,
    sum: DVec3,
    /// Welford's mean and M2 of luminance.
    mean_l: f64,
    m2_l: f64,
    albedo: DVec3,
    normal: DVec3,
    depth_sum: f64,
    hits: u32,
    /// Material of the latest sample that hit a surface first.
    id: Option<u32>,
    /// Distance evaluations of every sample.
    evaluations: u64,
}

/// A snapshot of the accumulated image and its guide buffers (row-major, top row first).
#[derive(Clone, Debug, PartialEq)]
pub struct Frame {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Mean radiance, linear RGB.
    pub colour: Vec<[f32; 3]>,
    /// Mean first-hit albedo (1 for misses).
    pub albedo: Vec<[f32; 3]>,
    /// Mean first-hit normal, normalised (0 for misses).
    pub normal: Vec<[f32; 3]>,
    /// Mean first-hit distance (infinite when most samples missed).
    pub depth: Vec<f32>,
    /// Variance of the pixel's mean luminance (sample variance / n).
    pub variance: Vec<f32>,
    /// Tape material of the first surface ([`fathom_core::frame::NO_ID`] where most samples
    /// missed).
    pub id: Vec<u32>,
    /// Mean distance evaluations per sample (the whole path's, not only the camera ray's).
    pub steps: Vec<u32>,
    /// Samples per pixel.
    pub samples: u32,
}

impl Frame {
    /// Estimated remaining noise: the root-mean-square over pixels of the standard error of
    /// each pixel's mean luminance, relative to the image's mean luminance.
    pub fn relative_noise(&self) -> f64 {
        let n = self.colour.len().max(1) as f64;
        let mean: f64 = self
            .colour
            .iter()
            .map(|c| luminance(DVec3::new(c[0] as f64, c[1] as f64, c[2] as f64)))
            .sum::<f64>()
            / n;
        let var: f64 = self.variance.iter().map(|&v| v as f64).sum::<f64>() / n;
        if mean > 0.0 { var.sqrt() / mean } else { 0.0 }
    }
}

/// A path tracer's image being refined.
pub struct Progressive {
    tracer: PathTracer,
    pixels: Vec<Pixel>,
    stats: Stats,
}

/// One tile's updated pixels.
struct TileOut {
    index: usize,
    pixels: Vec<Pixel>,
    dropped: u64,
    evaluations: u64,
}

impl Progressive {
    /// An empty accumulator for `tracer`'s image.
    pub fn new(tracer: PathTracer) -> Self {
        let (w, h) = tracer.size();
        Progressive {
            pixels: vec![Pixel::default(); w as usize * h as usize],
            tracer,
            stats: Stats::default(),
        }
    }

    /// The tracer.
    pub fn tracer(&self) -> &PathTracer {
        &self.tracer
    }

    /// Counters so far.
    pub fn stats(&self) -> &Stats {
        &self.stats
    }

    /// Forgets every sample (after a change of view, say).
    pub fn reset(&mut self) {
        self.pixels.fill(Pixel::default());
        self.stats = Stats::default();
    }

    /// Adds `n` samples to every pixel, over rayon's pool in tiles. On cancellation nothing
    /// is added and `Err(Cancelled)` is returned.
    pub fn add_samples(
        &mut self,
        n: u32,
        control: &Control,
    ) -> Result<(), crate::settings::PathTraceError> {
        let start = Instant::now();
        let (w, h) = self.tracer.size();
        let tiles_x = w.div_ceil(TILE);
        let tiles_y = h.div_ceil(TILE);
        let count = (tiles_x * tiles_y) as usize;
        let first = self.stats.samples_per_pixel;
        let done = AtomicUsize::new(0);
        let tracer = &self.tracer;
        let pixels = &self.pixels;
        let outs: Vec<Option<TileOut>> = (0..count)
            .into_par_iter()
            .map_init(Evaluator::<f64>::new, |ev, index| {
                if control.cancelled() {
                    return None;
                }
                let tx = index as u32 % tiles_x * TILE;
                let ty = index as u32 / tiles_x * TILE;
                let mut out = TileOut {
                    index,
                    pixels: Vec::with_capacity((TILE * TILE) as usize),
                    dropped: 0,
                    evaluations: 0,
                };
                for y in ty..(ty + TILE).min(h) {
                    for x in tx..(tx + TILE).min(w) {
                        let mut px = pixels[(y * w + x) as usize];
                        for k in 0..n {
                            let s = tracer.sample(ev, x, y, first + k);
                            out.evaluations += s.evaluations;
                            px.evaluations += s.evaluations;
                            if s.id != fathom_core::frame::NO_ID {
                                px.id = Some(s.id);
                            }
                            let r = s.radiance;
                            if !r.is_finite() {
                                out.dropped += 1;
                                continue;
                            }
                            px.n += 1;
                            px.sum += r;
                            let l = luminance(r);
                            let delta = l - px.mean_l;
                            px.mean_l += delta / px.n as f64;
                            px.m2_l += delta * (l - px.mean_l);
                            px.albedo += s.albedo;
                            px.normal += s.normal;
                            if s.depth.is_finite() {
                                px.depth_sum += s.depth;
                                px.hits += 1;
                            }
                        }
                        out.pixels.push(px);
                    }
                }
                if let Some(p) = control.progress {
                    p(done.fetch_add(1, Ordering::Relaxed) + 1, count);
                }
                Some(out)
            })
            .collect();
        if control.cancelled() || outs.iter().any(Option::is_none) {
            return Err(crate::settings::PathTraceError::Cancelled);
        }
        for t in outs.into_iter().flatten() {
            let tx = t.index as u32 % tiles_x * TILE;
            let ty = t.index as u32 / tiles_x * TILE;
            let tw = (tx + TILE).min(w) - tx;
            for (k, px) in t.pixels.into_iter().enumerate() {
                let (x, y) = (tx + k as u32 % tw, ty + k as u32 / tw);
                self.pixels[(y * w + x) as usize] = px;
            }
            self.stats.dropped_non_finite += t.dropped;
            self.stats.evaluations += t.evaluations;
        }
        self.stats.samples_per_pixel += n;
        self.stats.paths += n as u64 * w as u64 * h as u64;
        self.stats.seconds += start.elapsed().as_secs_f64();
        Ok(())
    }

    /// The image so far.
    pub fn frame(&self) -> Frame {
        let (w, h) = self.tracer.size();
        let f3 = |v: DVec3| [v.x as f32, v.y as f32, v.z as f32];
        let mut f = Frame {
            width: w,
            height: h,
            colour: Vec::with_capacity(self.pixels.len()),
            albedo: Vec::with_capacity(self.pixels.len()),
            normal: Vec::with_capacity(self.pixels.len()),
            depth: Vec::with_capacity(self.pixels.len()),
            variance: Vec::with_capacity(self.pixels.len()),
            id: Vec::with_capacity(self.pixels.len()),
            steps: Vec::with_capacity(self.pixels.len()),
            samples: self.stats.samples_per_pixel,
        };
        for p in &self.pixels {
            let n = p.n.max(1) as f64;
            f.colour.push(f3(p.sum / n));
            f.albedo
                .push(f3(if p.n > 0 { p.albedo / n } else { DVec3::ONE }));
            f.normal.push(f3(p.normal.normalize_or_zero()));
            let hit = p.hits * 2 > p.n;
            f.depth.push(if hit {
                (p.depth_sum / p.hits as f64) as f32
            } else {
                f32::INFINITY
            });
            f.id.push(match p.id {
                Some(id) if hit => id,
                _ => fathom_core::frame::NO_ID,
            });
            let samples = self.stats.samples_per_pixel.max(1) as u64;
            f.steps
                .push((p.evaluations / samples).min(u32::MAX as u64) as u32);
            f.variance.push(if p.n > 1 {
                (p.m2_l / (p.n - 1) as f64 / n) as f32
            } else {
                0.0
            });
        }
        f
    }
}
