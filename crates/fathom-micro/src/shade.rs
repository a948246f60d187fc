//! Lighting of microgeometry hits, the same on the CPU and in `gpu/micro.wgsl`: hemisphere
//! ambient plus Blinn-Phong per directional light, the sky gradient of fathom-trace for
//! misses. No shadows or occlusion (the rasterised GPU path has no rays to cast them with), so
//! the two paths can agree pixel for pixel.

use fathom_core::scene::{Material, Scene};
use glam::DVec3;

/// Lights and sky, taken from the texture's scene.
#[derive(Clone, Debug)]
pub struct Lighting {
    /// (unit direction towards the light, colour times intensity), at most 8.
    pub lights: Vec<(DVec3, DVec3)>,
    /// Sky colour straight up, linear RGB.
    pub sky_top: DVec3,
    /// Sky colour at the horizon and below, linear RGB.
    pub sky_bottom: DVec3,
    /// Ambient light level.
    pub ambient: f64,
}

/// Most lights the GPU path takes.
pub const MAX_LIGHTS: usize = 8;

impl Lighting {
    /// The lights, sky and ambient level of a scene.
    pub fn from_scene(s: &Scene) -> Lighting {
        Lighting {
            lights: s
                .lights
                .iter()
                .take(MAX_LIGHTS)
                .map(|l| {
                    (
                        l.direction.normalize(),
                        DVec3::from_array(l.colour) * l.intensity,
                    )
                })
                .collect(),
            sky_top: DVec3::from_array(s.render.sky_top),
            sky_bottom: DVec3::from_array(s.render.sky_bottom),
            ambient: s.render.ambient,
        }
    }

    /// The sky in direction `dir`.
    pub fn sky(&self, dir: DVec3) -> DVec3 {
        let u = dir.y.clamp(0.0, 1.0).sqrt();
        self.sky_bottom + (self.sky_top - self.sky_bottom) * u
    }

    /// The colour of a surface with material `m` and unit normal `n` seen along `dir`.
    pub fn shade(&self, m: &Material, n: DVec3, dir: DVec3) -> DVec3 {
        let albedo = DVec3::from_array(m.albedo);
        let mut c = albedo * (self.ambient * (0.7 + 0.3 * n.y));
        for &(l, lc) in &self.lights {
            let ndl = n.dot(l).max(0.0);
            let h = (l - dir).normalize_or_zero();
            let sp = m.specular * n.dot(h).max(1e-6).powf(m.shininess);
            c += (albedo + DVec3::splat(sp)) * lc * ndl;
        }
        c
    }
}
