//! Unidirectional path tracing over the distance field: one camera path per call, with
//! next-event estimation, multiple importance sampling and Russian roulette (the estimator
//! of pbrt-v4's `PathIntegrator`, Pharr et al. ch. 13, with Veach's power heuristic).
//!
//! At every non-delta vertex each light is sampled once (next-event estimation) and weighed
//! against the BSDF's density of that direction; the BSDF-sampled continuation that happens
//! to reach a light (a sphere light, the environment, or the cone of a directional light)
//! adds that light's radiance weighed against the light's density, so both strategies cover
//! each light once. Emissive surfaces have no explicit sampling (the field gives no area
//! measure of them), so BSDF rays that hit them count with weight 1.
//!
//! **Self-intersection.** The marcher stops within `eps` (the hit epsilon at that distance)
//! of the surface; each new ray, shadow rays included, leaves from the hit point moved
//! [`SURFACE_LIFT`] x `eps` along the normal to the side it goes to (into the object for a
//! refraction), and keeps the same epsilon as its start threshold. The test
//! `no_self_shadowing_at_grazing_angles` checks that on a lit plane and sphere no shadow ray
//! is blocked by the surface it leaves, at every angle; with a lift of 0 it fails.
//!
//! Transmissive objects: a refracted path marches the negated field until it leaves, losing
//! energy to Beer-Lambert absorption of the material it is in. Fog (outside objects only) is
//! single scattering: see [`crate::medium`].
//!
//! Paths whose radiance is not finite are reported so the caller can count and drop them.

use crate::bsdf::Bsdf;
use crate::camera::ThinLens;
use crate::colour::{HitInfo, Look};
use crate::lights::{ConeLight, Environment, LightSample, SphereLight};
use crate::march::{MarchParams, Ray, march, normal};
use crate::material::PbrMaterial;
use crate::medium::{Medium, sample_hg};
use crate::sampler::PixelSampler;
use crate::sampling::{Frame, power_heuristic};
use crate::settings::{PathSettings, PathTraceError, SettingsError, default_fog};
use crate::shared::{MIN_EPSILON, RR_MAX_SURVIVAL, RR_MIN_SURVIVAL, RR_START, SURFACE_LIFT};
use fathom_core::frame::NO_ID;
use fathom_core::{Evaluator, Scene, Tape, V3};
use glam::DVec3;

/// Smallest cos(theta_o) a surface is shaded at.
const MIN_COS: f64 = 1e-4;

/// A scene prepared for path tracing.
#[derive(Clone, Debug)]
pub struct PathTracer {
    tape: Tape,
    looks: Vec<Look>,
    lens: ThinLens,
    params: MarchParams,
    cones: Vec<ConeLight>,
    spheres: Vec<SphereLight>,
    env: Environment,
    /// Scale of the environment where it lights surfaces.
    env_light: f64,
    medium: Option<Medium>,
    max_bounces: u32,
    width: u32,
    height: u32,
    seed: u32,
    light_sampling: bool,
}

/// What one camera path returns.
#[derive(Clone, Copy, Debug)]
pub struct PathSample {
    /// Radiance along the camera ray.
    pub radiance: DVec3,
    /// Albedo of the first surface (1 for misses and media).
    pub albedo: DVec3,
    /// World normal of the first surface (0 for misses).
    pub normal: DVec3,
    /// Distance to the first surface along the camera ray (infinite for misses).
    pub depth: f64,
    /// Distance evaluations spent.
    pub evaluations: u64,
    /// Tape material (node) of the first surface, the one with the larger blend weight;
    /// [`fathom_core::frame::NO_ID`] for misses, media and lights.
    pub id: u32,
}

impl PathTracer {
    /// Prepares `scene` (compiled as `tape`) with `settings`. Validates everything first.
    pub fn new(scene: &Scene, tape: &Tape, settings: PathSettings) -> Result<Self, PathTraceError> {
        settings.validate()?;
        scene.camera.validate()?;
        let r = &scene.render;
        let palette = r.palette;
        let looks = match settings.looks {
            Some(l) => {
                if l.len() != tape.materials().len() {
                    return Err(SettingsError::LookCount {
                        given: l.len(),
                        want: tape.materials().len(),
                    }
                    .into());
                }
                l
            }
            None => tape
                .materials()
                .iter()
                .map(|m| Look::from_legacy(m, palette))
                .collect(),
        };
        for (node, l) in looks.iter().enumerate() {
            l.validate()
                .map_err(|error| PathTraceError::Look { node, error })?;
        }
        let frame = scene.camera.frame();
        let focus = settings
            .focus_distance
            .unwrap_or_else(|| (scene.camera.target - scene.camera.eye).length());
        let pixel_angle = frame.pixel_angle(settings.height);
        let sun_radius = settings
            .sun_radius
            .unwrap_or_else(|| (1.0 / r.shadow_softness.max(1.0)).atan());
        let cones = scene
            .lights
            .iter()
            .filter(|l| l.intensity > 0.0 && l.direction.length_squared() > 0.0)
            .map(|l| ConeLight::from_legacy(l, sun_radius))
            .collect();
        let (env, default_light) = match settings.environment {
            Some(e) => (e, 1.0),
            None => {
                let (top, bottom) = (DVec3::from(r.sky_top), DVec3::from(r.sky_bottom));
                // The sky's mean over the sphere: bottom below the horizon, and above it
                // the mean of lerp(bottom, top, sqrt(y)) over y uniform in [0, 1].
                let mean = crate::sampling::luminance(bottom + (top - bottom) / 3.0);
                let k = if mean > 0.0 { r.ambient / mean } else { 0.0 };
                (Environment::Sky { top, bottom }, k)
            }
        };
        let env_light = settings.sky_light.unwrap_or(default_light);
        let medium = match settings.fog {
            Some(m) => Some(m),
            None => default_fog(r.fog),
        }
        .filter(|m| m.density > 0.0);
        Ok(PathTracer {
            tape: tape.clone(),
            looks,
            lens: ThinLens {
                frame,
                aperture: settings.aperture,
                focus,
            },
            params: MarchParams {
                max_steps: r.max_steps.max(1),
                t_max: r.max_distance,
                eps_slope: 0.5 * pixel_angle * r.pixel_epsilon,
            },
            cones,
            spheres: settings.sphere_lights,
            env,
            env_light,
            medium,
            max_bounces: settings.max_bounces,
            width: settings.width,
            height: settings.height,
            seed: settings.seed,
            light_sampling: settings.light_sampling,
        })
    }

    /// The MIS weight of reaching a light by a continuation drawn with `prev_pdf` (`None`
    /// after the camera or a delta lobe) when light sampling has density `light_pdf` there.
    fn emitter_weight(&self, prev_pdf: Option<f64>, light_pdf: f64) -> f64 {
        match prev_pdf {
            Some(p) if self.light_sampling => power_heuristic(p, light_pdf),
            _ => 1.0,
        }
    }

    /// The same tracer with another sampler seed (independent noise, e.g. for a reference).
    pub fn with_seed(mut self, seed: u32) -> Self {
        self.seed = seed;
        self
    }

    /// Image size.
    pub fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    /// The material at a surface point.
    fn material_at(&self, ev: &mut Evaluator<f64>, p: DVec3, n: DVec3) -> (PbrMaterial, u32) {
        let v = ev.eval(&self.tape, V3::new(p.x, p.y, p.z));
        let last = self.looks.len() - 1;
        let id = (v.id.max(0.0) as usize).min(last);
        let id2 = (v.id2.max(0.0) as usize).min(last);
        let hit = HitInfo {
            position: p,
            normal: n,
            trap: v.trap,
        };
        let a = self.looks[id].at(&hit);
        let w = v.blend.clamp(0.0, 1.0);
        if w > 0.0 && id2 != id {
            let dominant = if w > 0.5 { id2 } else { id };
            (a.lerp(&self.looks[id2].at(&hit), w), dominant as u32)
        } else {
            (a, id as u32)
        }
    }

    /// Whether something blocks the segment from `o` along `d` over `dist`.
    fn occluded(
        &self,
        ev: &mut Evaluator<f64>,
        o: DVec3,
        d: DVec3,
        dist: f64,
        eps: f64,
    ) -> (bool, u64) {
        let m = march(
            ev,
            &self.tape,
            &Ray {
                o,
                d,
                t_max: dist,
                eps0: eps,
                inside: false,
            },
            &self.params,
        );
        (m.hit && m.t < dist, m.steps as u64)
    }

    /// Transmittance of the fog over a segment (1 without fog).
    fn fog_transmittance(&self, o: DVec3, d: DVec3, dist: f64) -> f64 {
        self.medium
            .as_ref()
            .map_or(1.0, |m| m.transmittance(o, d, dist.min(self.params.t_max)))
    }

    /// Next-event estimation at a point: every light sampled once, MIS-weighted against
    /// `density(wi)` (the BSDF's or phase function's), contributions `f(wi)` times cos where
    /// it applies. Returns the radiance and the evaluations spent.
    fn direct(
        &self,
        ev: &mut Evaluator<f64>,
        s: &mut PixelSampler,
        origin: DVec3,
        eps: f64,
        eval: &dyn Fn(DVec3) -> (DVec3, f64),
    ) -> (DVec3, u64) {
        let mut l = DVec3::ZERO;
        let mut evals = 0;
        let mut add = |ls: LightSample, ev: &mut Evaluator<f64>| {
            let (f, density) = eval(ls.wi);
            if f.max_element() <= 0.0 || ls.pdf <= 0.0 {
                return;
            }
            if ls.shadows {
                let (blocked, n) = self.occluded(ev, origin, ls.wi, ls.distance, eps);
                evals += n;
                if blocked {
                    return;
                }
            }
            let tr = self.fog_transmittance(origin, ls.wi, ls.distance);
            let (w, pdf) = if ls.pdf.is_infinite() {
                (1.0, 1.0)
            } else {
                (power_heuristic(ls.pdf, density), ls.pdf)
            };
            l += f * ls.radiance * (tr * w / pdf);
        };
        for c in &self.cones {
            let ls = c.sample(s.next_2d());
            add(ls, ev);
        }
        for sl in &self.spheres {
            let u = s.next_2d();
            if let Some(ls) = sl.sample(origin, u) {
                add(ls, ev);
            }
        }
        if !self.env.is_black() && self.env_light > 0.0 {
            let (wi, radiance, pdf) = self.env.sample(s.next_2d());
            let radiance = radiance * self.env_light;
            add(
                LightSample {
                    wi,
                    radiance,
                    pdf,
                    distance: f64::INFINITY,
                    shadows: true,
                },
                ev,
            );
        }
        (l, evals)
    }

    /// [`PathTracer::direct`] unless light sampling is off. Delta lights (cones of radius 0
    /// or without shadows) can only be reached this way, so they are always sampled.
    fn direct_if_enabled(
        &self,
        ev: &mut Evaluator<f64>,
        s: &mut PixelSampler,
        origin: DVec3,
        eps: f64,
        eval: &dyn Fn(DVec3) -> (DVec3, f64),
    ) -> (DVec3, u64) {
        if self.light_sampling {
            return self.direct(ev, s, origin, eps, eval);
        }
        let mut l = DVec3::ZERO;
        for c in self.cones.iter().filter(|c| c.is_delta()) {
            let ls = c.sample(s.next_2d());
            let (f, _) = eval(ls.wi);
            let visible = !ls.shadows || !self.occluded(ev, origin, ls.wi, ls.distance, eps).0;
            if visible {
                l += f * ls.radiance * self.fog_transmittance(origin, ls.wi, ls.distance);
            }
        }
        (l, 0)
    }

    /// Traces sample `index` of pixel (`x`, `y`).
    pub fn sample(&self, ev: &mut Evaluator<f64>, x: u32, y: u32, index: u32) -> PathSample {
        let mut s = PixelSampler::new(x, y, index, self.seed);
        let jitter = s.next_2d();
        let lens_u = s.next_2d();
        let (o, d) = self.lens.ray(
            x as f64 + jitter[0],
            y as f64 + jitter[1],
            self.width,
            self.height,
            lens_u,
        );
        let mut out = PathSample {
            radiance: DVec3::ZERO,
            albedo: DVec3::ONE,
            normal: DVec3::ZERO,
            depth: f64::INFINITY,
            evaluations: 0,
            id: NO_ID,
        };
        let mut ray = Ray {
            o,
            d,
            t_max: f64::INFINITY,
            eps0: MIN_EPSILON,
            inside: false,
        };
        let mut beta = DVec3::ONE;
        // Density the last continuation was drawn with; `None` after the camera or a delta
        // lobe (then whatever it reaches counts fully).
        let mut prev_pdf: Option<f64> = None;
        // Whether every vertex so far was a delta lobe (the camera sees through mirrors).
        let mut seen_from_camera = true;
        let mut scattered = false;
        let mut interior = DVec3::ZERO;
        let mut interior_material: Option<PbrMaterial> = None;
        for bounce in 0..=self.max_bounces {
            let m = march(ev, &self.tape, &ray, &self.params);
            out.evaluations += m.steps as u64;
            let surf_t = if m.hit { m.t } else { f64::INFINITY };
            // The nearest sphere light in front of the surface.
            let mut light_hit: Option<(f64, usize)> = None;
            if !ray.inside {
                for (i, sl) in self.spheres.iter().enumerate() {
                    if let Some(t) = sl.intersect(ray.o, ray.d)
                        && t < surf_t
                        && light_hit.is_none_or(|(lt, _)| t < lt)
                    {
                        light_hit = Some((t, i));
                    }
                }
            }
            let seg_end = light_hit.map_or(surf_t, |(t, _)| t);
            if ray.inside {
                let t = if m.hit { m.t } else { self.params.t_max };
                beta *= DVec3::new(
                    (-interior.x * t).exp(),
                    (-interior.y * t).exp(),
                    (-interior.z * t).exp(),
                );
            } else if let Some(med) = &self.medium {
                let seg = seg_end.min(self.params.t_max);
                if !scattered {
                    let u = s.next_1d();
                    if let Some(ts) = med.sample_distance(ray.o, ray.d, seg, u) {
                        // A scattering event in the fog: the single one this path gets.
                        scattered = true;
                        beta *= med.albedo();
                        let p = ray.o + ray.d * ts;
                        if bounce == 0 {
                            out.depth = ts;
                        }
                        if bounce == self.max_bounces {
                            break;
                        }
                        let eps = ray.eps0 + self.params.eps_slope * ts;
                        let g = med.g;
                        let dir = ray.d;
                        let (ld, n) = self.direct_if_enabled(ev, &mut s, p, eps, &|wi| {
                            let ph = crate::medium::hg(dir.dot(wi), g);
                            (DVec3::splat(ph), ph)
                        });
                        out.evaluations += n;
                        out.radiance += beta * ld;
                        let (wi, pdf) = sample_hg(ray.d, g, s.next_2d());
                        prev_pdf = Some(pdf);
                        seen_from_camera = false;
                        ray = Ray {
                            o: p,
                            d: wi,
                            t_max: f64::INFINITY,
                            eps0: eps,
                            inside: false,
                        };
                        continue;
                    }
                    // No event: the probability T of this cancels the transmittance.
                } else {
                    beta *= med.transmittance(ray.o, ray.d, seg);
                }
            }
            if let Some((t, i)) = light_hit {
                let sl = &self.spheres[i];
                let w = self.emitter_weight(prev_pdf, sl.pdf(ray.o));
                out.radiance += beta * sl.radiance() * w;
                if bounce == 0 {
                    out.depth = t;
                }
                break;
            }
            if !m.hit {
                if !ray.inside {
                    // The environment and the cones of directional lights; fog was
                    // accounted for above.
                    // Seen directly or through mirrors: the background as it is; after a
                    // diffuse or glossy bounce: the environment as a light.
                    let scale = if seen_from_camera {
                        1.0
                    } else {
                        self.env_light
                    };
                    let light_pdf = if self.env_light > 0.0 {
                        self.env.pdf(ray.d)
                    } else {
                        0.0
                    };
                    let mut l =
                        self.env.radiance(ray.d) * scale * self.emitter_weight(prev_pdf, light_pdf);
                    for c in &self.cones {
                        if let Some((radiance, pdf)) = c.seen(ray.d) {
                            l += radiance * self.emitter_weight(prev_pdf, pdf);
                        }
                    }
                    out.radiance += beta * l;
                }
                break;
            }
            // A surface.
            let p = ray.o + ray.d * m.t;
            let eps = m.eps.max(MIN_EPSILON);
            let n_out = normal(ev, &self.tape, p, eps);
            out.evaluations += 6;
            let wo_world = -ray.d;
            let (n, bsdf, mat, id) = if ray.inside {
                let mat = interior_material.clone().unwrap_or_default();
                (-n_out, Bsdf::interior(&mat), mat, NO_ID)
            } else {
                let (mat, id) = self.material_at(ev, p, n_out);
                out.evaluations += 1;
                (n_out, Bsdf::new(&mat), mat, id)
            };
            if !ray.inside {
                out.radiance += beta * mat.emitted();
            }
            if bounce == 0 {
                out.albedo = bsdf.albedo();
                out.normal = n_out;
                out.depth = m.t;
                out.id = id;
            }
            if bounce == self.max_bounces {
                break;
            }
            let frame = Frame::new(n);
            // A ray that grazes a surface within the pixel footprint counts as a hit while
            // still going away from it (wo below the surface): shade it as seen at grazing
            // incidence from outside, as the Blinn-Phong shader does.
            let mut wo = frame.to_local(wo_world);
            if wo.z < MIN_COS {
                wo.z = MIN_COS;
                wo = wo.normalize();
            }
            let lift = SURFACE_LIFT * eps;
            if bsdf.has_smooth_part() {
                let origin = p + n * lift;
                let (ld, k) = self.direct_if_enabled(ev, &mut s, origin, eps, &|wi| {
                    let wl = frame.to_local(wi);
                    if wl.z <= 0.0 {
                        return (DVec3::ZERO, 0.0);
                    }
                    (bsdf.eval(wo, wl) * wl.z, bsdf.pdf(wo, wl))
                });
                out.evaluations += k;
                out.radiance += beta * ld;
            }
            let u_lobe = s.next_1d();
            let u = s.next_2d();
            let Some(bs) = bsdf.sample(wo, u_lobe, u) else {
                break;
            };
            beta *= bs.weight;
            let wi = frame.to_world(bs.wi);
            let mut inside = ray.inside;
            if bs.transmitted {
                inside = !inside;
                if inside {
                    interior = DVec3::from(mat.absorption);
                    interior_material = Some(mat);
                }
            }
            prev_pdf = if bs.delta { None } else { Some(bs.pdf) };
            seen_from_camera &= bs.delta;
            if bounce >= RR_START {
                let q = beta.max_element().clamp(RR_MIN_SURVIVAL, RR_MAX_SURVIVAL);
                if s.next_1d() >= q {
                    break;
                }
                beta /= q;
            }
            if beta.max_element() <= 0.0 {
                break;
            }
            let side = if wi.dot(n) >= 0.0 { 1.0 } else { -1.0 };
            ray = Ray {
                o: p + n * (side * lift),
                d: wi,
                t_max: f64::INFINITY,
                eps0: eps,
                inside,
            };
        }
        out
    }
}

/// What [`PathTracer::new`] prepared from the scene and settings, for a port that runs the same
/// estimator elsewhere: fathom-gpu's WGSL path tracer bakes exactly these into its buffers, so
/// the two cannot read a scene differently.
impl PathTracer {
    /// One look per tape material.
    pub fn looks(&self) -> &[Look] {
        &self.looks
    }
    /// The thin-lens camera.
    pub fn lens(&self) -> &ThinLens {
        &self.lens
    }
    /// How rays march (steps, distance, hit threshold slope).
    pub fn march_params(&self) -> &MarchParams {
        &self.params
    }
    /// Directional lights.
    pub fn cone_lights(&self) -> &[ConeLight] {
        &self.cones
    }
    /// Spherical area lights.
    pub fn sphere_lights(&self) -> &[SphereLight] {
        &self.spheres
    }
    /// The environment.
    pub fn environment(&self) -> &Environment {
        &self.env
    }
    /// Scale of the environment where it lights surfaces.
    pub fn environment_light(&self) -> f64 {
        self.env_light
    }
    /// The fog, if any.
    pub fn medium(&self) -> Option<&Medium> {
        self.medium.as_ref()
    }
    /// Most bounces of a path.
    pub fn max_bounces(&self) -> u32 {
        self.max_bounces
    }
    /// The sampler's scene-wide seed.
    pub fn seed(&self) -> u32 {
        self.seed
    }
    /// Whether next-event estimation is on.
    pub fn light_sampling(&self) -> bool {
        self.light_sampling
    }
}

#[cfg(test)]
mod tests;
