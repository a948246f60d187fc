//! Colouring a full voxel: the sphere tracer's lighting and distance-field occlusion at the
//! voxel's surface point, and the surface plane through that point ([`Surface`]).

use super::sight::SightHit;
use super::{Probe, Shader};
use crate::node::pack_rgb;
use crate::plane::SurfacePlane;
use fathom_core::shared::AO_SAMPLES;
use glam::DVec3;

impl Shader {
    /// Colour of a full voxel at world centre `c` (half side `h`, centre distance `d`): the sphere
    /// tracer's shading (`fathom_trace::shade`: material and orbit-trap palette, distance-field
    /// ambient occlusion, hemisphere ambient, Blinn-Phong per light seen from [`Shader::view`])
    /// at the voxel's surface point, without soft shadows (a shadow ray per voxel would cost
    /// up to 96 evaluations). The surface point is the first one the line of sight meets,
    /// in the voxel or behind it (`sight_point`); the normal is the tetrahedron gradient of
    /// the tape there ([`Shader::gradient`]) with a step of half the voxel's side, the
    /// tracer's (half a pixel footprint) once voxels are pixel sized. Shading at the surface
    /// rather than the centre keeps neighbouring voxels of a smooth surface from taking the
    /// gradient at different offsets from it, the grain of a field of pixel-sized cubes.
    ///
    /// Also returns the voxel's [`SurfacePlane`]: through the surface point, with the normal
    /// the colour was shaded with; [`SurfacePlane::behind`] when the point is behind the
    /// voxel; none with flat colours or where no surface point was found.
    pub fn colour(&self, ev: &mut Probe, c: DVec3, h: f64, d: f64) -> (u32, SurfacePlane) {
        let s = self.surface(ev, c, h, d);
        (self.shade(ev, &s), s.plane)
    }

    /// The first half of [`Shader::colour`]: the voxel's surface point, the value and the
    /// distance gradient there, and its plane (enough to tell a voxel whose plane is clear of
    /// it before shading it).
    pub fn surface(&self, ev: &mut Probe, c: DVec3, h: f64, d: f64) -> Surface {
        let h = h.max(1e-300);
        let sight = if self.traces(d) {
            self.sight_point(ev, c, h)
        } else {
            None
        };
        self.surface_from(ev, c, h, d, sight)
    }

    /// [`Shader::surface`] of up to four voxels of one size at once (the first `live` of
    /// `c` and `d`): their lines of sight are traced four lanes at a time
    /// ([`Shader::sight_points`]). The surfaces are those of [`Shader::surface`] up to the
    /// packet's rounding (a few ulps per distance), which can move a surface point by one
    /// step of the trace where a distance lies within that of the stopping threshold. The
    /// tests' reference: splits trace in two stretches ([`eval_children`]).
    #[cfg(test)]
    pub fn surfaces4(
        &self,
        ev: &mut Probe,
        c: [DVec3; 4],
        d: [f64; 4],
        live: usize,
        h: f64,
    ) -> [Surface; 4] {
        let h = h.max(1e-300);
        let traced: [bool; 4] = std::array::from_fn(|i| i < live && self.traces(d[i]));
        let sight = self.sight_points(ev, c, traced, h);
        std::array::from_fn(|i| {
            if i < live {
                self.surface_from(ev, c[i], h, d[i], sight[i])
            } else {
                Surface::NONE
            }
        })
    }

    /// Whether a voxel whose centre distance is `d` has its line of sight traced.
    pub(crate) fn traces(&self, d: f64) -> bool {
        self.gradient_shading && d.is_finite()
    }

    /// [`Shader::surface`] once the line of sight's point (`sight`) is known.
    pub(crate) fn surface_from(
        &self,
        ev: &mut Probe,
        c: DVec3,
        h: f64,
        d: f64,
        sight: Option<SightHit>,
    ) -> Surface {
        let found = match sight {
            Some(s) => Some(s),
            None if self.traces(d) => self.newton_point(ev, c, h),
            None => None,
        };
        let (p, v) = found.map_or_else(|| (c, self.eval(ev, c)), |s| (s.p, s.v));
        if !self.gradient_shading {
            return Surface {
                p,
                v,
                g: DVec3::ZERO,
                plane: SurfacePlane::NONE,
            };
        }
        let g = self.gradient(ev, p, h);
        // The plane goes through the surface, not through `p`: a line of sight stops up to a
        // quarter side in front of it, and planes that far off, each leaf's by its own
        // amount, showed as steps between neighbouring leaves in the depth the occlusion reads.
        let on = onto_surface(p, v.d, g, h);
        let plane = match found {
            Some(SightHit {
                behind: Some(dir), ..
            }) => SurfacePlane::behind(g, -dir, on, c, h),
            Some(_) => SurfacePlane::new(g, on, c, h),
            None => SurfacePlane::NONE,
        };
        Surface { p, v, g, plane }
    }

    /// The second half of [`Shader::colour`]: the colour shaded at a voxel's [`Surface`].
    pub fn shade(&self, ev: &mut Probe, s: &Surface) -> u32 {
        let ds = if self.gradient_shading {
            self.distances(ev, &self.occlusion_points(s))
        } else {
            [0.0; AO_N]
        };
        self.shade_with(s, &ds)
    }

    /// [`Shader::shade`] of up to four surfaces (the first `live`), their occlusion samples
    /// evaluated together, four lanes at a time: 5 packets for four surfaces where one at a
    /// time took 8 (each surface's 5 samples padded to two packets). Lanes compute what the
    /// scalar path of the same packet kind computes, so the colours are [`Shader::shade`]'s.
    pub fn shade4(&self, ev: &mut Probe, s: [&Surface; 4], live: usize) -> [u32; 4] {
        let mut ds = [0.0; 4 * AO_N];
        if self.gradient_shading {
            let mut pts = [DVec3::ZERO; 4 * AO_N];
            for (k, s) in s.iter().take(live).enumerate() {
                pts[k * AO_N..(k + 1) * AO_N].copy_from_slice(&self.occlusion_points(s));
            }
            let n = live * AO_N;
            self.distances_into(ev, &pts[..n], &mut ds[..n]);
        }
        std::array::from_fn(|k| {
            if k < live {
                let d: &[f64; AO_N] = ds[k * AO_N..(k + 1) * AO_N].try_into().unwrap();
                self.shade_with(s[k], d)
            } else {
                0
            }
        })
    }

    /// Where a surface's ambient occlusion is sampled: along its normal, as the tracer does.
    fn occlusion_points(&self, s: &Surface) -> [DVec3; AO_N] {
        let n = s.g.normalize_or(DVec3::Y);
        std::array::from_fn(|i| s.p + n * self.occlusion_reach(i as u32))
    }

    /// How far along the normal the occlusion's sample `i` lies.
    fn occlusion_reach(&self, i: u32) -> f64 {
        0.05 * self.view.scale * (0.1 + 0.9 * i as f64 / (AO_SAMPLES - 1) as f64)
    }

    /// [`Shader::shade`] given the distances at the surface's occlusion samples (`ds`, in
    /// the order of `occlusion_points`; unused with flat colours).
    fn shade_with(&self, s: &Surface, ds: &[f64; AO_N]) -> u32 {
        let (p, v) = (s.p, s.v);
        let mats = self.tape.materials();
        let pick = |id: f64| (id.max(0.0) as usize).min(mats.len().saturating_sub(1));
        let (albedo, spec, shin, mix) = match (mats.get(pick(v.id)), mats.get(pick(v.id2))) {
            (Some(a), Some(b)) => {
                let w = v.blend.clamp(0.0, 1.0);
                let l = |x: f64, y: f64| x * (1.0 - w) + y * w;
                (
                    std::array::from_fn::<f64, 3, _>(|i| l(a.albedo[i], b.albedo[i])),
                    l(a.specular, b.specular),
                    l(a.shininess, b.shininess),
                    l(a.trap_colour, b.trap_colour),
                )
            }
            _ => ([0.75; 3], 0.0, 1.0, 0.0),
        };
        let t = v.trap.min(4.0);
        let pal = &self.palette;
        let base: [f64; 3] = std::array::from_fn(|i| {
            let x = std::f64::consts::TAU * (pal[2][i] * t + pal[3][i]);
            let pc = (pal[0][i] + pal[1][i] * x.cos()).clamp(0.0, 1.0);
            albedo[i] + (pc - albedo[i]) * mix
        });
        if !self.gradient_shading {
            return pack_rgb(base);
        }
        let n = s.g.normalize_or(DVec3::Y);
        // Distance-field ambient occlusion, as the tracer computes it.
        let (mut occ, mut w, mut wsum) = (0.0, 1.0, 0.0);
        for i in 0..AO_SAMPLES {
            let hh = self.occlusion_reach(i);
            let d = ds[i as usize];
            occ += (1.0 - d / hh).clamp(0.0, 1.0) * w;
            wsum += 0.7f64.powi(i as i32);
            w *= 0.7;
        }
        let ao = (1.0 - self.ao / wsum * occ).clamp(0.0, 1.0);
        let hemi = 0.7 + 0.3 * n.y;
        let mut col = base.map(|b| b * self.ambient * ao * hemi);
        let view = (self.view.eye - p).normalize_or(n);
        for (l, lc) in &self.lights {
            let ndl = n.dot(*l).max(0.0);
            if ndl <= 0.0 {
                continue;
            }
            let ndh = n.dot((*l + view).normalize_or(n)).max(0.0);
            let sp = spec * ndh.max(1e-6).powf(shin);
            for i in 0..3 {
                col[i] += (base[i] + sp) * lc[i] * ndl;
            }
        }
        pack_rgb(col)
    }
}

/// Where a full voxel's surface is, as [`Shader::surface`] found it.
#[derive(Clone, Copy, Debug)]
pub struct Surface {
    /// The surface point (world units relative to the origin), or the voxel's centre.
    pub p: DVec3,
    /// The tape's value there.
    pub v: fathom_core::Value<f64>,
    /// The distance gradient there (not normalised; zero with flat colours).
    pub g: DVec3,
    /// The voxel's plane.
    pub plane: SurfacePlane,
}

impl Surface {
    /// No surface (a packet's unused lane).
    pub(crate) const NONE: Surface = Surface {
        p: DVec3::ZERO,
        v: fathom_core::Value {
            d: f64::INFINITY,
            id: 0.0,
            id2: 0.0,
            blend: 0.0,
            trap: 0.0,
        },
        g: DVec3::ZERO,
        plane: SurfacePlane::NONE,
    };
}

/// `p` moved onto the surface by one Newton step on the distance `d` there, along its
/// gradient `g` (both already known: no evaluation), the step at most the half side `h`;
/// `p` itself where the gradient vanishes.
pub(super) fn onto_surface(p: DVec3, d: f64, g: DVec3, h: f64) -> DVec3 {
    let g2 = g.length_squared();
    if !(d.is_finite() && g2 > 0.0) {
        return p;
    }
    let step = g * (d / g2);
    let len = step.length();
    if len > h {
        p - step * (h / len)
    } else {
        p - step
    }
}

/// Occlusion samples per surface ([`AO_SAMPLES`] as a length).
const AO_N: usize = AO_SAMPLES as usize;
