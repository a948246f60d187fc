//! The volume backend of a session: the scene drawn as a cloud by fathom-volume's path tracer
//! (docs/volume.md). The scene's tape is sampled into a density grid over its fitted box (the
//! fractal density mode), kept while the scene's shading generation and the volume settings
//! stay the same; each frame path-traces `spp x supersample^2` samples per pixel, so a window's
//! progressive refinement (full resolution, then supersampled) refines the cloud too. Lighting
//! comes from the scene: its sky gradient as the environment and its first light as the sun.
//! The cloud is one medium of one colour: its single-scattering albedo is the volume
//! settings' albedo times the mean material colour of the scene's interior ([`cloud_colour`]),
//! so a red scene makes a red cloud; a colour per voxel would need a colour grid in the volume
//! tracer, which it does not have.
//! Regions are cropped from the whole frame; stereo and geometry-only frames are refused by
//! [`crate::RenderRequest::validate`].

use crate::backend::{Counters, Rendered, report_done};
use crate::control::Control;
use crate::request::{RenderRequest, VolumeSettings};
use crate::stats::{Stats, Timings};
use fathom_core::{Camera, Scene, Tape};
use fathom_volume::integrator::VolumeScene;
use fathom_volume::light::{Environment, Sun};
use fathom_volume::medium::{Medium, MediumParams};
use fathom_volume::render::Progressive;
use fathom_volume::{VolumeError, fractal};
use glam::Vec3;
use std::time::Instant;

/// The mean albedo of the materials inside the scene: the material of the node that wins at
/// each point of a 16^3 lattice over `bbox` with a negative distance (blends counted by their
/// weights); white when no lattice point is inside (a thin shell).
pub fn cloud_colour(tape: &Tape, bbox: fathom_volume::grid::WorldBox) -> Vec3 {
    const N: usize = 16;
    let materials = tape.materials();
    let albedo = |id: f64| {
        materials
            .get(id.max(0.0) as usize)
            .map_or(Vec3::ONE, |m| vec3(m.albedo))
    };
    let (mut sum, mut weight) = (Vec3::ZERO, 0.0f32);
    let extent = bbox.max - bbox.min;
    for i in 0..N * N * N {
        let c = Vec3::new((i % N) as f32, ((i / N) % N) as f32, (i / (N * N)) as f32);
        let p = bbox.min + extent * (c + 0.5) / N as f32;
        let v = tape.eval_f64([p.x as f64, p.y as f64, p.z as f64]);
        if v.d < 0.0 {
            let b = v.blend as f32;
            sum += albedo(v.id) * (1.0 - b) + albedo(v.id2) * b;
            weight += 1.0;
        }
    }
    if weight > 0.0 {
        sum / weight
    } else {
        Vec3::ONE
    }
}

pub(crate) struct VolumeBackend {
    scene: VolumeScene,
    key: (u64, VolumeSettings),
}

fn vec3(c: [f64; 3]) -> Vec3 {
    Vec3::new(c[0] as f32, c[1] as f32, c[2] as f32)
}

impl VolumeBackend {
    /// The sampled cloud of `scene` (shading generation `generation`) for `req`'s settings,
    /// sampled anew when either changed.
    pub fn get<'a>(
        slot: &'a mut Option<VolumeBackend>,
        scene: &Scene,
        tape: &Tape,
        generation: u64,
        req: &RenderRequest,
        counters: &mut Counters,
    ) -> Result<&'a mut VolumeBackend, VolumeError> {
        let key = (generation, req.volume.clone());
        if slot.as_ref().is_none_or(|v| v.key != key) {
            *slot = None;
            let v = &req.volume;
            let bbox = fractal::fit_box(tape)?;
            let density = fractal::sample(tape, [v.grid; 3], bbox, v.smooth, 1 << 31, &|| {})?;
            let params = MediumParams {
                density_scale: v.density_scale,
                albedo: Vec3::splat(v.albedo) * cloud_colour(tape, bbox),
                g: v.g,
                ..MediumParams::default()
            };
            let r = &scene.render;
            let environment = Environment::Sky {
                top: vec3(r.sky_top),
                bottom: vec3(r.sky_bottom),
                up: Vec3::Y,
            };
            let sun = scene.lights.first().map(|l| {
                let d = l.direction.normalize();
                Sun {
                    towards: Vec3::new(d.x as f32, d.y as f32, d.z as f32),
                    radiance: vec3(l.colour.map(|c| c * l.intensity)),
                }
            });
            let vs = VolumeScene {
                medium: Medium::new(density, &params)?,
                environment,
                sun,
                max_depth: 64,
                rr_depth: 5,
            };
            counters.volumes_sampled += 1;
            *slot = Some(VolumeBackend { scene: vs, key });
        }
        Ok(slot.as_mut().expect("sampled above"))
    }

    /// Path-traces the frame from `camera`.
    pub fn render(
        &self,
        camera: &Camera,
        req: &RenderRequest,
        control: &Control,
        pool: Option<&rayon::ThreadPool>,
    ) -> Result<Rendered, crate::RenderError> {
        let t0 = Instant::now();
        let spp = req.volume.spp * req.supersample * req.supersample;
        let mut prog = Progressive::new(&self.scene, camera, req.width, req.height, 1)?;
        let run = |prog: &mut Progressive| -> Result<(), crate::RenderError> {
            while prog.samples() < spp {
                if control.cancelled() {
                    return Err(crate::RenderError::Cancelled);
                }
                prog.add_samples(1, &|| {})?;
            }
            Ok(())
        };
        match pool {
            Some(p) => p.install(|| run(&mut prog))?,
            None => run(&mut prog)?,
        }
        let whole = prog.frame();
        let frame = match req.region {
            Some(r) => whole.crop(r),
            None => whole,
        };
        let st = prog.stats();
        let stats = Stats {
            renderer: "volume",
            width: frame.width,
            height: frame.height,
            primary_rays: (req.width as u64) * (req.height as u64) * spp as u64,
            ms: Timings {
                trace_and_shade: t0.elapsed().as_secs_f64() * 1e3,
                ..Timings::default()
            },
            note: Some(format!(
                "volume: {spp} samples per pixel, {:.2} M paths/s, {:.2} scatterings per path",
                st.paths_per_second / 1e6,
                st.mean_path_length
            )),
            ..Stats::default()
        };
        report_done(control);
        Ok(Rendered { frame, stats })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use fathom_core::combine::Combine;
    use fathom_core::primitives::Primitive;
    use fathom_core::scene::{Call, DomainOp, Material, Node};
    use fathom_core::transforms::Transform;

    fn coloured(c: [f64; 3]) -> Material {
        Material {
            albedo: c,
            ..Material::default()
        }
    }

    /// The cloud takes the colour of what it is made of: a red sphere gives a red cloud, and
    /// a red and a blue sphere of one size side by side give their even mix.
    #[test]
    fn the_cloud_is_the_mean_colour_of_the_scene_s_interior() {
        let red = [0.9, 0.1, 0.1];
        let blue = [0.1, 0.2, 0.8];
        let bbox = fathom_volume::grid::WorldBox {
            min: Vec3::splat(-2.0),
            max: Vec3::splat(2.0),
        };
        let one = Scene::new(Node::new(Primitive::Sphere).material(coloured(red)));
        let c = cloud_colour(&Tape::compile(&one).unwrap(), bbox);
        assert!((c - vec3(red)).abs().max_element() < 1e-4, "{c}");

        // Point operators apply to a node's subtree: the child moves 2 from its parent.
        let shifted = |dx: f64, m| {
            Node::new(Primitive::Sphere)
                .op(
                    Call::<DomainOp>::new(DomainOp::Transform(Transform::Translate))
                        .with("offset", &[dx, 0.0, 0.0]),
                )
                .material(m)
        };
        let two = Scene::new(
            shifted(-1.0, coloured(red))
                .child(shifted(2.0, coloured(blue)).combine(Combine::Union)),
        );
        let c = cloud_colour(&Tape::compile(&two).unwrap(), bbox);
        let mix = (vec3(red) + vec3(blue)) * 0.5;
        assert!((c - mix).abs().max_element() < 0.02, "{c} vs {mix}");
    }
}
