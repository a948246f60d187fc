//! The colouring pass: turns a packet of primary-ray hits into linear RGB.
//!
//! Normals come from the distance gradient (tetrahedron technique, offset = the pixel
//! footprint), materials from the tape's material ids (blended for smooth combines), then
//! Blinn-Phong per directional light with soft shadows (Aaltonen's improved penumbra estimate,
//! GDC 2018, "GPU-based clay simulation and ray tracing tech in Claybook"), distance-field
//! ambient occlusion, and the orbit-trap cosine palette for fractals. Misses get the sky.

use fathom_core::real::{Mask, Real};
use fathom_core::scene::{Light, RenderSettings};
use fathom_core::{Evaluator, Material, Tape, V3};

pub use fathom_core::shared::{AO_SAMPLES, SHADOW_STEPS};
/// Shadow rays leave the surface this many pixel footprints along the normal (fractal distance
/// estimates undershoot close to the surface; a smaller lift self-shadows).
pub const SHADOW_LIFT: f64 = 4.0;

/// Scene-wide shading inputs, prepared once per render.
pub struct Shading<'a> {
    /// The scene's compiled program.
    pub tape: &'a Tape,
    /// The scene's render settings (materials' palette, fog, AO, sky, ...).
    pub render: &'a RenderSettings,
    /// Lights with unit directions and colour premultiplied by intensity.
    pub lights: Vec<([f64; 3], [f64; 3], bool)>,
    /// Reach of the ambient-occlusion probe, world units.
    pub ao_range: f64,
    /// Shadow rays stop beyond this distance.
    pub shadow_max: f64,
    /// Floor of the lengths shading divides by or offsets with (normal offset, shadow-ray
    /// penumbra terms), world units: 1e-12 for the tracer; the double-double reference, whose
    /// views may be far smaller, scales it with the view ([`crate::deep::deep_frame`]).
    pub min_length: f64,
}

impl<'a> Shading<'a> {
    /// Prepares lights; `view_scale` (distance from eye to target) sets the AO reach.
    pub fn new(
        tape: &'a Tape,
        render: &'a RenderSettings,
        lights: &[Light],
        view_scale: f64,
    ) -> Self {
        Shading {
            tape,
            render,
            lights: lights
                .iter()
                .map(|l| {
                    let d = l.direction.normalize();
                    let c = l.colour.map(|c| c * l.intensity);
                    ([d.x, d.y, d.z], c, l.shadows)
                })
                .collect(),
            ao_range: 0.05 * view_scale,
            shadow_max: render.max_distance,
            min_length: 1e-12,
        }
    }

    /// Sky colour in direction `dir` (linear RGB): a gradient on the world's up axis.
    pub fn sky(&self, dir: [f64; 3]) -> [f32; 3] {
        let u = dir[1].clamp(0.0, 1.0).sqrt();
        let (a, b) = (self.render.sky_bottom, self.render.sky_top);
        [0, 1, 2].map(|i| (a[i] + (b[i] - a[i]) * u) as f32)
    }
}

/// One shaded lane.
#[derive(Clone, Copy, Debug, Default)]
pub struct Shaded {
    /// Linear RGB.
    pub colour: [f32; 3],
    /// Unit surface normal.
    pub normal: [f32; 3],
    /// Material id of the surface hit.
    pub id: u32,
}

/// Shades a packet of hits at `origin + dir * t`; `footprint` is the pixel footprint at each
/// hit. Returns the shaded lanes and the distance evaluations spent (live lanes only).
#[allow(clippy::too_many_arguments)]
pub fn shade<S: Real>(
    ev: &mut Evaluator<S>,
    sh: &Shading,
    origin: V3<S>,
    dir: V3<S>,
    t: S,
    footprint: S,
    live: S::Mask,
    out: &mut [Shaded],
) -> u64 {
    let tape = sh.tape;
    let r = sh.render;
    let zero = S::zero();
    let one = S::one();
    let p = origin + dir * t;
    let v = ev.eval(tape, p);
    let h = footprint.max(S::splat(sh.min_length));
    let n = ev.normal(tape, p, h * S::splat(0.5));
    let mut evals = 5 * S::LANES as u64;

    // Per-lane material lookups.
    let mats = tape.materials();
    let mut alb = [[0f64; 8]; 3];
    let mut spec = [0f64; 8];
    let mut shin = [0f64; 8];
    let mut trapw = [0f64; 8];
    for (l, o) in out.iter_mut().enumerate().take(S::LANES) {
        let id = (v.id.lane(l).max(0.0) as usize).min(mats.len() - 1);
        let id2 = (v.id2.lane(l).max(0.0) as usize).min(mats.len() - 1);
        let w = v.blend.lane(l).clamp(0.0, 1.0);
        let mix = |f: &dyn Fn(&Material) -> f64| f(&mats[id]) * (1.0 - w) + f(&mats[id2]) * w;
        for (c, a) in alb.iter_mut().enumerate() {
            a[l] = mix(&|m| m.albedo[c]);
        }
        spec[l] = mix(&|m| m.specular);
        shin[l] = mix(&|m| m.shininess);
        trapw[l] = mix(&|m| m.trap_colour);
        o.id = id as u32;
    }
    let lanes = |a: &[f64; 8]| S::from_lanes(&a[..S::LANES]);
    // Orbit-trap palette a + b cos(2 pi (c t + d)), mixed into the albedo.
    let trap = v.trap.min(S::splat(4.0));
    let pal = r.palette;
    let tw = lanes(&trapw);
    let albedo: [S; 3] = [0, 1, 2].map(|c| {
        let x =
            S::splat(std::f64::consts::TAU) * (S::splat(pal[2][c]) * trap + S::splat(pal[3][c]));
        let pc = (S::splat(pal[0][c]) + S::splat(pal[1][c]) * x.cos()).clamp(zero, one);
        S::lerp(lanes(&alb[c]), pc, tw)
    });

    // Distance-field ambient occlusion (after Quilez), as the weighted shortfall of the field
    // along the normal relative to the probe distance. The ratio keeps fractal estimates, which
    // undershoot the true distance, from blackening everything.
    let mut occ = zero;
    let mut w = one;
    let mut wsum = 0.0;
    for i in 0..AO_SAMPLES {
        let hh = S::splat(sh.ao_range * (0.1 + 0.9 * i as f64 / (AO_SAMPLES - 1) as f64));
        let d = ev.distance(tape, p + n * hh);
        occ += (one - d / hh).clamp(zero, one) * w;
        wsum += 0.7f64.powi(i as i32);
        w *= S::splat(0.7);
    }
    evals += AO_SAMPLES as u64 * S::LANES as u64;
    let ao = (one - S::splat(r.ao / wsum) * occ).clamp(zero, one);

    let ambient = S::splat(r.ambient) * ao;
    // Hemisphere ambient: brighter for normals facing the sky.
    let hemi = S::splat(0.7) + S::splat(0.3) * n.y;
    let mut col: [S; 3] = [0, 1, 2].map(|c| albedo[c] * ambient * hemi);

    let view = -dir;
    for &(ld, lc, shadows) in &sh.lights {
        let l = V3::c(ld[0], ld[1], ld[2]);
        let ndl = n.dot(l).max(zero);
        let lit = live & ndl.gt(zero);
        let mut vis = one;
        if shadows && lit.any() {
            let (s, e) = soft_shadow(
                ev,
                tape,
                p + n * (h * S::splat(2.0)),
                l,
                lit,
                h,
                sh,
                r.shadow_softness,
            );
            vis = s;
            evals += e;
        }
        let half = (l + view).normalize();
        let ndh = n.dot(half).max(zero);
        let sp = lanes(&spec) * ndh.max(S::splat(1e-6)).powf(lanes(&shin));
        for c in 0..3 {
            let lcol = S::splat(lc[c]) * vis * ndl;
            col[c] += (albedo[c] + sp) * lcol;
        }
    }
    for (l, o) in out.iter_mut().enumerate().take(S::LANES) {
        o.colour = [0, 1, 2].map(|c| col[c].lane(l) as f32);
        let nl = n.lane(l);
        o.normal = nl.map(|x| x as f32);
    }
    evals
}

/// Shades primary-ray hits at `origin + dir * t` as the tracer does: [`shade`] with the pixel
/// footprint `t * pixel_angle`. Shared by the tracer's tiles and the double-double reference
/// ([`crate::deep::deep_frame`]), so both colour a hit alike.
#[allow(clippy::too_many_arguments)]
pub fn shade_hits<S: Real>(
    ev: &mut Evaluator<S>,
    sh: &Shading,
    origin: V3<S>,
    dir: V3<S>,
    t: S,
    pixel_angle: f64,
    live: S::Mask,
    out: &mut [Shaded],
) -> u64 {
    let footprint = t * S::splat(pixel_angle);
    shade(ev, sh, origin, dir, t, footprint, live, out)
}

/// Soft-shadow factor in [0, 1] along `l` from `ro` (Aaltonen's improved penumbra estimate).
/// `eps` is the primary hit's pixel footprint: per Keinert et al., a shadow ray needs no more
/// precision than the pixel it shades, so it counts as blocked below that distance.
#[allow(clippy::too_many_arguments)]
fn soft_shadow<S: Real>(
    ev: &mut Evaluator<S>,
    tape: &Tape,
    ro: V3<S>,
    l: V3<S>,
    live: S::Mask,
    eps: S,
    sh: &Shading,
    k: f64,
) -> (S, u64) {
    let zero = S::zero();
    let one = S::one();
    let k = S::splat(k);
    let mut res = one;
    let mut ph = S::splat(1e20);
    let mut t = eps;
    let mut active = live;
    let mut evals = 0u64;
    let t_max = S::splat(sh.shadow_max);
    for _ in 0..SHADOW_STEPS {
        if !active.any() {
            break;
        }
        let h = ev.distance(tape, ro + l * t);
        evals += S::LANES as u64;
        let hp = h.max(zero);
        // Where this and the previous unbounding sphere intersect; when this sphere is more than
        // twice the previous one they do not constrain each other and the classic estimate
        // (y = 0, d = h) applies.
        let y0 = hp * hp / (S::splat(2.0) * ph);
        let far = y0.ge(hp);
        let y = S::select(far, zero, y0);
        let d = S::select(far, hp, (hp * hp - y * y).max(zero).sqrt());
        let est = k * d / (t - y).max(S::splat(sh.min_length));
        let blocked = h.lt(eps * S::splat(0.25));
        res = S::select(active, S::select(blocked, zero, res.min(est)), res);
        ph = S::select(active, hp.max(S::splat(sh.min_length)), ph);
        t = S::select(active, t + hp.max(eps), t);
        active = active & !blocked & res.gt(S::splat(1e-3)) & t.lt(t_max) & h.is_finite();
    }
    let res = res.clamp(zero, one);
    (res * res * (S::splat(3.0) - S::splat(2.0) * res), evals)
}
