//! A microgeometry frame on the CPU: camera rays over 16x16 tiles on rayon, each traced through
//! the shell ([`crate::march`]), shaded ([`crate::shade`]) into a fathom-core [`Frame`]. Every
//! pixel depends only on its own ray and tiles are written back in order, so the image does
//! not depend on the number of threads.

use crate::bvh::ShellBvh;
use crate::error::MicroError;
use crate::limits;
use crate::march::{self, HitKind, MarchParams, Scratch};
use crate::shade::Lighting;
use crate::shell::Shell;
use crate::texture::Texture;
use fathom_core::Camera;
use fathom_core::frame::{Frame, NO_ID};
use fathom_core::scene::Material;
use glam::DVec3;
use rayon::prelude::*;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

/// Material id the frame records for hits on the base mesh.
pub const BASE_ID: u32 = u32::MAX - 1;
/// Tile side in pixels.
pub const TILE: u32 = 16;

/// Everything a frame is made of.
pub struct MicroScene {
    /// The shell of tetrahedra over the mesh.
    pub shell: Shell,
    /// The bounding-volume hierarchy over the shell's tetrahedra.
    pub bvh: ShellBvh,
    /// The distance-field texture pasted into the shell.
    pub texture: Texture,
    /// Lights and sky.
    pub lighting: Lighting,
    /// The base mesh's material; `None` hides it (rays pass through the shell's floor).
    pub base: Option<Material>,
}

impl MicroScene {
    /// A scene of these parts, with the shell's bounding-volume hierarchy built.
    pub fn new(
        shell: Shell,
        texture: Texture,
        lighting: Lighting,
        base: Option<Material>,
    ) -> MicroScene {
        let bvh = ShellBvh::build(&shell);
        MicroScene {
            shell,
            bvh,
            texture,
            lighting,
            base,
        }
    }
}

/// How to render.
#[derive(Clone, Debug)]
pub struct RenderOptions {
    /// Image width, pixels.
    pub width: u32,
    /// Image height, pixels.
    pub height: u32,
    /// The camera.
    pub camera: Camera,
    /// Distance evaluations per ray, [1, 100000].
    pub max_steps: u32,
    /// Hit threshold in pixel footprints, [0.01, 16].
    pub pixel_epsilon: f64,
    /// Rotate texture normals onto the interpolated vertex normals (the seed's fix).
    pub smooth_normals: bool,
}

impl Default for RenderOptions {
    fn default() -> Self {
        RenderOptions {
            width: 640,
            height: 480,
            camera: Camera::default(),
            max_steps: 1024,
            pixel_epsilon: 1.0,
            smooth_normals: true,
        }
    }
}

impl RenderOptions {
    /// Checks sizes and knobs before anything is allocated.
    pub fn validate(&self) -> Result<(), MicroError> {
        let (w, h) = (self.width, self.height);
        if w == 0
            || h == 0
            || w > limits::MAX_SIDE
            || h > limits::MAX_SIDE
            || w as u64 * h as u64 > limits::MAX_PIXELS
        {
            return Err(MicroError::Size(format!(
                "image size {w}x{h} is outside the limits: 1 to {} pixels per side, at most {} pixels",
                limits::MAX_SIDE,
                limits::MAX_PIXELS
            )));
        }
        crate::error::check_range("max steps", self.max_steps as f64, 1.0, 1e5, "[1, 100000]")?;
        crate::error::check_range(
            "pixel epsilon",
            self.pixel_epsilon,
            0.01,
            16.0,
            "[0.01, 16]",
        )?;
        self.camera.validate().map_err(MicroError::Camera)
    }

    /// The march parameters for this view.
    pub fn march_params(&self) -> MarchParams {
        MarchParams {
            max_steps: self.max_steps,
            eps_slope: 0.5 * self.pixel_angle() * self.pixel_epsilon,
            eps_min: 0.0,
        }
    }

    /// Angular size of a pixel at the image centre.
    pub fn pixel_angle(&self) -> f64 {
        self.camera.frame().pixel_angle(self.height)
    }
}

/// Counters and timings of one frame (integers summed, so independent of threads).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MicroStats {
    /// Image width, pixels.
    pub width: u32,
    /// Image height, pixels.
    pub height: u32,
    /// Triangles of the base mesh.
    pub triangles: usize,
    /// Tetrahedra of the shell.
    pub tetrahedra: usize,
    /// Rays that hit the texture or the base mesh.
    pub hits: u64,
    /// Rays that hit the texture.
    pub texture_hits: u64,
    /// Rays that hit the base mesh.
    pub base_hits: u64,
    /// Texture distance evaluations marching rays.
    pub de_march: u64,
    /// Texture distance evaluations shading hits.
    pub de_shade: u64,
    /// Tetrahedra whose spans were marched.
    pub tets_visited: u64,
    /// Wall time of the frame, milliseconds.
    pub ms_total: f64,
}

impl MicroStats {
    /// Zero counters for a `width` x `height` frame of `shell`.
    pub fn new(shell: &Shell, width: u32, height: u32) -> MicroStats {
        MicroStats {
            width,
            height,
            triangles: shell.report.triangles,
            tetrahedra: shell.report.tetrahedra,
            ..Default::default()
        }
    }

    /// Texture distance evaluations per pixel, marching and shading together.
    pub fn de_per_pixel(&self) -> f64 {
        (self.de_march + self.de_shade) as f64 / (self.width as f64 * self.height as f64).max(1.0)
    }
}

/// The longest ray: through the whole shell from the camera.
pub fn t_max(shell: &Shell, cam: &Camera) -> f64 {
    let (lo, hi) = shell.bounds;
    let c = 0.5 * (lo + hi);
    (cam.eye - c).length() + (hi - lo).length()
}

struct TileOut {
    colour: Vec<[f32; 3]>,
    depth: Vec<f32>,
    normal: Vec<[f32; 3]>,
    id: Vec<u32>,
    steps: Vec<u32>,
    stats: MicroStats,
}

/// Renders a frame. `progress(done, total)` is called as tiles finish.
pub fn render(
    scene: &MicroScene,
    o: &RenderOptions,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<(Frame, MicroStats), MicroError> {
    let start = Instant::now();
    o.validate()?;
    let cam = o.camera.frame();
    let params = o.march_params();
    let pixel_angle = o.pixel_angle();
    let tmax = t_max(&scene.shell, &o.camera);
    let (w, h) = (o.width, o.height);
    let (tx, ty) = (w.div_ceil(TILE), h.div_ceil(TILE));
    let total = (tx * ty) as usize;
    let done = AtomicUsize::new(0);
    let tiles: Vec<TileOut> = (0..total)
        .into_par_iter()
        .map_init(Scratch::default, |s, i| {
            let (x0, y0) = ((i as u32 % tx) * TILE, (i as u32 / tx) * TILE);
            let (tw, th) = (TILE.min(w - x0), TILE.min(h - y0));
            let n = (tw * th) as usize;
            let mut t = TileOut {
                colour: vec![[0.0; 3]; n],
                depth: vec![f32::INFINITY; n],
                normal: vec![[0.0; 3]; n],
                id: vec![NO_ID; n],
                steps: vec![0; n],
                stats: MicroStats::default(),
            };
            for k in 0..n {
                let (x, y) = (x0 + k as u32 % tw, y0 + k as u32 / tw);
                let d = cam.ray_dir(x as f64 + 0.5, y as f64 + 0.5, w, h);
                let r = march::trace(
                    &scene.shell,
                    &scene.bvh,
                    &scene.texture,
                    scene.base.is_some(),
                    s,
                    cam.eye,
                    d,
                    tmax,
                    &params,
                );
                t.steps[k] = r.steps;
                t.stats.de_march += r.steps as u64;
                t.stats.tets_visited += r.tets_visited as u64;
                let Some(hit) = r.hit else {
                    t.colour[k] = scene.lighting.sky(d).as_vec3().to_array();
                    continue;
                };
                let (nrm, id, evals) = march::surface(
                    &scene.shell,
                    &scene.texture,
                    &mut s.ev,
                    &hit,
                    cam.eye,
                    d,
                    pixel_angle * hit.t,
                    o.smooth_normals,
                );
                t.stats.de_shade += evals as u64;
                t.stats.hits += 1;
                let (mat, fid) = match hit.kind {
                    HitKind::Base => {
                        t.stats.base_hits += 1;
                        (
                            scene.base.as_ref().expect("base hits only when shown"),
                            BASE_ID,
                        )
                    }
                    HitKind::Texture { .. } => {
                        t.stats.texture_hits += 1;
                        (&scene.texture.materials[id as usize], id)
                    }
                };
                t.colour[k] = scene.lighting.shade(mat, nrm, d).as_vec3().to_array();
                t.depth[k] = hit.t as f32;
                t.normal[k] = nrm.as_vec3().to_array();
                t.id[k] = fid;
            }
            progress(done.fetch_add(1, Ordering::Relaxed) + 1, total);
            t
        })
        .collect();
    let mut frame = Frame::new(w, h);
    let mut stats = MicroStats::new(&scene.shell, w, h);
    for (i, t) in tiles.iter().enumerate() {
        let (x0, y0) = ((i as u32 % tx) * TILE, (i as u32 / tx) * TILE);
        let tw = TILE.min(w - x0);
        for k in 0..t.depth.len() {
            let j = frame.index(x0 + k as u32 % tw, y0 + k as u32 / tw);
            frame.colour[j] = t.colour[k];
            frame.depth[j] = t.depth[k];
            frame.normal[j] = t.normal[k];
            frame.id[j] = t.id[k];
            frame.steps[j] = t.steps[k];
        }
        let s = &t.stats;
        stats.hits += s.hits;
        stats.texture_hits += s.texture_hits;
        stats.base_hits += s.base_hits;
        stats.de_march += s.de_march;
        stats.de_shade += s.de_shade;
        stats.tets_visited += s.tets_visited;
    }
    stats.ms_total = start.elapsed().as_secs_f64() * 1e3;
    Ok((frame, stats))
}

/// A camera looking at the middle of `bounds` from direction `from` (need not be unit), just
/// far enough that all eight corners of the box fit in a `fov`-degree view of aspect `aspect`
/// (width / height), with 5% to spare.
pub fn fit_camera(bounds: (DVec3, DVec3), from: DVec3, fov: f64, aspect: f64) -> Camera {
    let (lo, hi) = bounds;
    let c = 0.5 * (lo + hi);
    let mut cam = Camera {
        eye: c + from.normalize(),
        target: c,
        up: DVec3::Y,
        fov,
    };
    let f = cam.frame();
    let ty = (0.5 * fov.to_radians()).tan();
    let tx = ty * aspect;
    let mut dist: f64 = 1e-9;
    for k in 0..8 {
        let v = DVec3::new(
            if k & 1 == 0 { lo.x } else { hi.x },
            if k & 2 == 0 { lo.y } else { hi.y },
            if k & 4 == 0 { lo.z } else { hi.z },
        ) - c;
        let back = v.dot(-f.forward);
        dist = dist
            .max(back + v.dot(f.right).abs() / tx)
            .max(back + v.dot(f.up).abs() / ty);
    }
    cam.eye = c - f.forward * (dist * 1.05);
    cam
}
