//! Images of a [`VolumeScene`]: progressive accumulation over rayon, one row per task.
//!
//! Sample `s` of pixel `p` draws from the stream `(seed, p, s)` and a pixel's samples are
//! summed in sample order, so the image is the same bytes whatever the thread count and
//! however the samples are split into passes (64 at once, or 1 at a time while the camera
//! rests). The camera is the core's pinhole [`Camera`]; it may sit inside the volume.

use crate::error::VolumeError;
use crate::integrator::{PathCounters, VolumeScene};
use crate::sampling::Stream;
use fathom_core::camera::{Camera, CameraFrame};
use fathom_core::frame::Frame;
use glam::Vec3;
use rayon::prelude::*;
use serde::Serialize;
use std::time::Instant;

/// Largest image side.
pub const MAX_SIDE: u32 = 16384;
/// Most pixels in one image.
pub const MAX_PIXELS: u64 = 64 << 20;
/// Most samples per pixel.
pub const MAX_SPP: u32 = 1 << 20;

/// Checks an image size.
pub fn check_size(width: u32, height: u32) -> Result<(), VolumeError> {
    if width == 0 || height == 0 || width > MAX_SIDE || height > MAX_SIDE {
        return Err(VolumeError::param(
            "size",
            format!("{width}x{height}"),
            format!("1..={MAX_SIDE} pixels per side"),
        ));
    }
    if width as u64 * height as u64 > MAX_PIXELS {
        return Err(VolumeError::param(
            "size",
            format!("{width}x{height}"),
            format!("at most {MAX_PIXELS} pixels"),
        ));
    }
    Ok(())
}

/// Checks a sample count.
pub fn check_spp(spp: u32) -> Result<(), VolumeError> {
    if spp == 0 || spp > MAX_SPP {
        return Err(VolumeError::param(
            "spp",
            spp,
            format!("1..={MAX_SPP} samples per pixel"),
        ));
    }
    Ok(())
}

/// Rendering statistics (also the `--stats` JSON of `fathom volume`).
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct RenderStats {
    pub width: u32,
    pub height: u32,
    pub spp: u32,
    pub seconds: f64,
    pub paths_per_second: f64,
    /// Real scattering events per camera path.
    pub mean_path_length: f64,
    /// Majorant-grid cells entered per camera path (free flights and shadow rays).
    pub majorant_steps_per_path: f64,
    /// Density lookups per camera path.
    pub lookups_per_path: f64,
    #[serde(flatten)]
    pub counters: PathCounters,
}

/// A progressively refined image.
pub struct Progressive<'a> {
    scene: &'a VolumeScene,
    frame: CameraFrame,
    width: u32,
    height: u32,
    seed: u64,
    sum: Vec<Vec3>,
    samples: u32,
    counters: PathCounters,
    seconds: f64,
}

impl<'a> Progressive<'a> {
    /// An empty image of `width` x `height` seen by `camera`.
    pub fn new(
        scene: &'a VolumeScene,
        camera: &Camera,
        width: u32,
        height: u32,
        seed: u64,
    ) -> Result<Self, VolumeError> {
        check_size(width, height)?;
        scene.validate()?;
        camera
            .validate()
            .map_err(|e| VolumeError::Invalid(e.to_string()))?;
        Ok(Progressive {
            scene,
            frame: camera.frame(),
            width,
            height,
            seed,
            sum: vec![Vec3::ZERO; width as usize * height as usize],
            samples: 0,
            counters: PathCounters::default(),
            seconds: 0.0,
        })
    }

    /// Samples per pixel so far.
    pub fn samples(&self) -> u32 {
        self.samples
    }

    /// Adds `n` samples to every pixel; `row_done` is called (from worker threads) after each
    /// row.
    pub fn add_samples(&mut self, n: u32, row_done: &(dyn Fn() + Sync)) -> Result<(), VolumeError> {
        let total = self.samples as u64 + n as u64;
        if n == 0 || total > MAX_SPP as u64 {
            return Err(VolumeError::param(
                "spp",
                total,
                format!("1..={MAX_SPP} samples per pixel"),
            ));
        }
        let start = Instant::now();
        let (w, h) = (self.width, self.height);
        let (scene, frame, seed, first) = (self.scene, &self.frame, self.seed, self.samples);
        let eye = frame.eye.as_vec3();
        let counters = self
            .sum
            .par_chunks_mut(w as usize)
            .enumerate()
            .map(|(y, row)| {
                let mut c = PathCounters::default();
                for (x, acc) in row.iter_mut().enumerate() {
                    let pixel = y as u64 * w as u64 + x as u64;
                    for s in first..first + n {
                        let mut rng = Stream::new(seed, pixel, s as u64);
                        let (jx, jy) = (rng.f32(), rng.f32());
                        let d = frame
                            .ray_dir(x as f64 + jx as f64, y as f64 + jy as f64, w, h)
                            .as_vec3();
                        let l = scene.radiance(eye, d, &mut rng, &mut c);
                        // A non-finite sample would poison the pixel forever: drop it.
                        if l.is_finite() {
                            *acc += l;
                        }
                    }
                }
                row_done();
                c
            })
            .reduce(PathCounters::default, |mut a, b| {
                a.add(&b);
                a
            });
        self.counters.add(&counters);
        self.samples += n;
        self.seconds += start.elapsed().as_secs_f64();
        Ok(())
    }

    /// The image so far: the mean of the samples (linear RGB), with no surface geometry.
    pub fn frame(&self) -> Frame {
        let mut f = Frame::new(self.width, self.height);
        let inv = 1.0 / self.samples.max(1) as f32;
        for (c, s) in f.colour.iter_mut().zip(&self.sum) {
            *c = (*s * inv).to_array();
        }
        f
    }

    /// Statistics of the samples so far.
    pub fn stats(&self) -> RenderStats {
        let c = self.counters;
        let paths = c.paths.max(1) as f64;
        RenderStats {
            width: self.width,
            height: self.height,
            spp: self.samples,
            seconds: self.seconds,
            paths_per_second: c.paths as f64 / self.seconds.max(1e-9),
            mean_path_length: c.scatter_events as f64 / paths,
            majorant_steps_per_path: c.track.dda_steps as f64 / paths,
            lookups_per_path: c.track.lookups as f64 / paths,
            counters: c,
        }
    }
}

/// Renders `spp` samples per pixel in one go.
pub fn render(
    scene: &VolumeScene,
    camera: &Camera,
    width: u32,
    height: u32,
    spp: u32,
    seed: u64,
) -> Result<(Frame, RenderStats), VolumeError> {
    check_spp(spp)?;
    let mut p = Progressive::new(scene, camera, width, height, seed)?;
    p.add_samples(spp, &|| {})?;
    Ok((p.frame(), p.stats()))
}

#[cfg(test)]
mod tests;
