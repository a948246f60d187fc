//! Scale-adaptive generation: the conservative full test, the parallel evaluation of the 8
//! children of requested leaves, linking the results into the tree, and recombination of
//! all-empty children upward.
//!
//! Full test: a voxel is full when the distance bound at its centre is below half its diagonal
//! times `1 + margin`, plus a few ulps of the centre's coordinates. With a distance *bound*
//! (never larger than the true distance) a voxel the surface crosses always tests full: no
//! false negatives. The margin absorbs floating-point error in the estimator (the
//! dissertation's Menger holes came from testing without one).
//!
//! Estimates that are not bounds (the scene uses an operator of quality `Safety`: the
//! Mandelbulb, the Mandelbox, twists) get a second test: a voxel is also full when one of its
//! 8 corners is inside (distance <= 0). The Mandelbulb's estimate used to be 0 inside the set
//! of points that do not escape in its 12 iterations but about 7e-7 just outside it, so below
//! that size a voxel the set's boundary crosses tested empty whenever its centre was outside;
//! it is now first-order at that boundary but can still overestimate it many times where the
//! running derivative underestimates the map's stretch (`fathom_core` fractals tests). Where
//! the boundary is locally a plane, a voxel it crosses has a corner on each side, so the
//! corner test catches it. The corners of the 8 children are the parent's 3x3x3 lattice.
//!
//! A conservative test keeps a shell of full voxels the surface does not cross in front of an
//! underestimated surface. A new child whose line of sight passes it without meeting the
//! surface, or whose surface point lies outside its cube (its plane is clear of it), and that
//! is still wider than the footprint of the ray that asked for the split is therefore tested
//! one level down at once, and dropped when none of its own children is
//! full ([`eval_children`]): the decision its split would have made a frame or more later,
//! after being drawn as a cube in front of the surface and walked through by rays.

use crate::evict::{free_children, mark_visited};
use crate::geometry::BoxU;
use crate::node::{EMPTY, NONE, REQUESTED, VISITED, pack_rgb};
use crate::octree::Octree;
use crate::plane::SurfacePlane;
use fathom_core::dd::Dd;
use fathom_core::dd4::Dd4;
use fathom_core::eval::Evaluator;
use fathom_core::real::{F64x4, Real};
use fathom_core::registry::{Family, Quality};
use fathom_core::scene::Scene;
use fathom_core::shared::AO_SAMPLES;
use fathom_core::tape::CompileError;
use fathom_core::{Tape, V3};
use glam::DVec3;

/// Default relative margin of the full test.
pub const DEFAULT_MARGIN: f64 = 0.01;

/// Where the voxels being coloured are seen from: the eye (world units relative to the
/// shader's [`Origin`]) and the view's scale (the distance from the eye to the camera's target,
/// which sets the reach of ambient occlusion as in the sphere tracer). Set by the octree view
/// before each frame's subdivision.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct View {
    /// Eye position, world units relative to the origin.
    pub eye: DVec3,
    /// Distance from the eye to the camera's target, world units.
    pub scale: f64,
}

/// The world point the shader's positions are measured from: the octree anchor's world
/// position, `hi + lo` (double-double). While the anchor is the root's corner (`deep` false)
/// the scene is evaluated in f64 at `hi + q`, exactly as in absolute coordinates; deeper, at
/// `hi + lo + q` in double-double, so voxels far below an f64 ulp of a world coordinate are
/// told apart (the cost of that is measured by `fathom bench eval`).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Origin {
    /// Leading part.
    pub hi: DVec3,
    /// Trailing part (below an ulp of `hi`).
    pub lo: DVec3,
    /// Evaluate in double-double.
    pub deep: bool,
}

/// The evaluators one worker needs: f64 for shallow frames, double-double for deep ones,
/// each for one point or four at once.
#[derive(Default)]
pub struct Probe {
    f64: Evaluator<f64>,
    x4: Evaluator<F64x4>,
    dd: Evaluator<Dd>,
    dd4: Evaluator<Dd4>,
}

impl Probe {
    /// Fresh evaluators.
    pub fn new() -> Probe {
        Probe::default()
    }
}

/// A double-double value rounded to f64 (what shading and the full test use).
fn to_f64(v: fathom_core::Value<Dd>) -> fathom_core::Value<f64> {
    fathom_core::Value {
        d: v.d.hi,
        id: v.id.hi,
        id2: v.id2.hi,
        blend: v.blend.hi,
        trap: v.trap.hi,
    }
}

/// Everything needed to decide and colour voxels: the tape plus shading constants.
pub struct Shader {
    /// The compiled scene.
    pub tape: Tape,
    /// Relative margin of the full test.
    pub margin: f64,
    /// Lights: unit direction, colour premultiplied by intensity.
    lights: Vec<(DVec3, [f64; 3])>,
    ambient: f64,
    ao: f64,
    palette: [[f64; 3]; 4],
    /// Colour voxels with the sphere tracer's lighting at the voxel's surface point (normal
    /// from the distance gradient there); when false, the flat material colour.
    pub gradient_shading: bool,
    /// The distance is an estimate, not a bound: voxels with a corner inside are full too.
    pub corner_test: bool,
    /// The view the voxels being coloured now are seen from.
    pub view: View,
    /// What positions given to the shader are relative to.
    pub origin: Origin,
}

/// True when every shape, operator and combination of `scene` declares an exact distance or a
/// bound (no `Safety` estimates).
pub fn is_bound(scene: &Scene) -> bool {
    fn ok<K: Family>(c: &fathom_core::Call<K>) -> bool {
        c.kind.def().quality != Quality::Safety
    }
    fn node(n: &fathom_core::Node) -> bool {
        ok(&n.shape) && ok(&n.combine) && n.ops.iter().all(ok) && n.children.iter().all(node)
    }
    node(&scene.root) && scene.ifs.as_ref().is_none_or(|i| i.ops.iter().all(ok))
}

impl Shader {
    /// Compiles `scene` into a shader.
    pub fn new(scene: &Scene, margin: f64) -> Result<Shader, CompileError> {
        let tape = Tape::compile(scene)?;
        let lights = scene
            .lights
            .iter()
            .map(|l| {
                (
                    l.direction.normalize_or(DVec3::Y),
                    l.colour.map(|c| c * l.intensity),
                )
            })
            .collect();
        let cam = &scene.camera;
        Ok(Shader {
            tape,
            margin,
            lights,
            ambient: scene.render.ambient,
            ao: scene.render.ao,
            palette: scene.render.palette,
            gradient_shading: true,
            corner_test: !is_bound(scene),
            view: View {
                eye: cam.eye,
                scale: (cam.target - cam.eye).length().max(1e-300),
            },
            origin: Origin::default(),
        })
    }

    /// The double-double world point `origin + q`.
    #[inline]
    fn deep_point(&self, q: DVec3) -> V3<Dd> {
        let o = &self.origin;
        V3::new(
            Dd::new(o.hi.x, o.lo.x) + Dd::from(q.x),
            Dd::new(o.hi.y, o.lo.y) + Dd::from(q.y),
            Dd::new(o.hi.z, o.lo.z) + Dd::from(q.z),
        )
    }

    /// The scene's value at `q` (world units relative to [`Shader::origin`]).
    #[inline]
    pub fn eval(&self, pr: &mut Probe, q: DVec3) -> fathom_core::Value<f64> {
        let o = &self.origin;
        if o.deep {
            to_f64(pr.dd.eval(&self.tape, self.deep_point(q)))
        } else {
            let p = o.hi + q;
            pr.f64.eval(&self.tape, V3::new(p.x, p.y, p.z))
        }
    }

    /// The scene's distances at four points (relative to the origin): one evaluation of four
    /// lanes, f64 ([`F64x4`]) on shallow frames and double-double ([`Dd4`]) on deep ones.
    /// Measured by `fathom-core`'s `packet64` example near the zoom targets, four lanes cost
    /// what 1.2-1.3 scalar f64 evaluations do (3.0-3.2x the Mandelbulb's rate, 4.1-4.3x the
    /// Menger's) and what 1.4-1.5 scalar double-double ones do (2.6x and 2.8x); lanes are
    /// within a few ulps of the scalar paths (their transcendental functions are `wide`'s).
    #[inline]
    pub fn distance4(&self, pr: &mut Probe, q: [DVec3; 4]) -> [f64; 4] {
        if self.origin.deep {
            let d = pr.dd4.distance(&self.tape, self.deep_packet(q));
            return std::array::from_fn(|i| d.lane(i));
        }
        let d = pr.x4.distance(&self.tape, self.packet(q));
        std::array::from_fn(|i| d.lane(i))
    }

    /// Four points (relative to the origin) as one f64 packet of world coordinates.
    #[inline]
    fn packet(&self, q: [DVec3; 4]) -> V3<F64x4> {
        let p = q.map(|q| self.origin.hi + q);
        let lanes = |f: fn(&DVec3) -> f64| F64x4::from(p.each_ref().map(f));
        V3::new(lanes(|v| v.x), lanes(|v| v.y), lanes(|v| v.z))
    }

    /// Four points (relative to the origin) as one double-double packet of world coordinates.
    #[inline]
    fn deep_packet(&self, q: [DVec3; 4]) -> V3<Dd4> {
        Dd4::pack(&q.map(|q| self.deep_point(q)))
    }

    /// The scene's values (distance, materials, orbit trap) at four points (relative to the
    /// origin): [`Shader::distance4`] with the rest of the value, rounded to f64 per lane.
    pub fn eval4(&self, pr: &mut Probe, q: [DVec3; 4]) -> [fathom_core::Value<f64>; 4] {
        fn lanes<S: Real>(v: fathom_core::Value<S>) -> [fathom_core::Value<f64>; 4] {
            std::array::from_fn(|i| fathom_core::Value {
                d: v.d.lane(i),
                id: v.id.lane(i),
                id2: v.id2.lane(i),
                blend: v.blend.lane(i),
                trap: v.trap.lane(i),
            })
        }
        if self.origin.deep {
            return lanes(pr.dd4.eval(&self.tape, self.deep_packet(q)));
        }
        lanes(pr.x4.eval(&self.tape, self.packet(q)))
    }

    /// The scene's distances at `N` points (relative to the origin), four at a time
    /// ([`Shader::distance4`]; the last packet padded by repeating its last point).
    pub fn distances<const N: usize>(&self, pr: &mut Probe, q: &[DVec3; N]) -> [f64; N] {
        let mut out = [0f64; N];
        self.distances_into(pr, q, &mut out);
        out
    }

    /// [`Shader::distances`] of the points `q` into `out` (as long as `q`).
    fn distances_into(&self, pr: &mut Probe, q: &[DVec3], out: &mut [f64]) {
        let n = q.len();
        for (j, chunk) in out.chunks_mut(4).enumerate() {
            let four = std::array::from_fn(|k| q[(4 * j + k).min(n - 1)]);
            let d = self.distance4(pr, four);
            chunk.copy_from_slice(&d[..chunk.len()]);
        }
    }

    /// The scene's distance at `q` (relative to the origin).
    #[inline]
    pub fn distance(&self, pr: &mut Probe, q: DVec3) -> f64 {
        let o = &self.origin;
        if o.deep {
            pr.dd.distance(&self.tape, self.deep_point(q)).hi
        } else {
            let p = o.hi + q;
            pr.f64.distance(&self.tape, V3::new(p.x, p.y, p.z))
        }
    }

    /// The full test at centre `c` (relative to the origin) of a voxel with world
    /// half-diagonal `hd`; returns the evaluated value when full.
    #[inline]
    pub fn full(&self, ev: &mut Probe, c: DVec3, hd: f64) -> Option<fathom_core::Value<f64>> {
        let v = self.eval(ev, c);
        if self.full_distance(v.d, c, hd) {
            Some(v)
        } else {
            None
        }
    }

    /// The corner test of estimate scenes: whether any corner of the cube `centre +
    /// [-half, half]^3` is inside (or NaN, never a false negative). Always false for scenes
    /// whose distance is a bound, where the centre test alone is conservative.
    pub fn corner_inside(&self, ev: &mut Probe, centre: DVec3, half: f64) -> bool {
        self.corner_test
            && (0..8).any(|k| {
                let sign = |bit: i32| if k & bit == 0 { -half } else { half };
                self.inside(ev, centre + DVec3::new(sign(1), sign(2), sign(4)))
            })
    }

    /// Whether point `p` (relative to the origin) is inside the surface, or its distance is
    /// NaN (never a false negative): the corner test's question.
    #[inline]
    pub fn inside(&self, ev: &mut Probe, p: DVec3) -> bool {
        let d = self.distance(ev, p);
        d <= 0.0 || d.is_nan()
    }

    /// The full test on the distance `d` at centre `c` (relative to the origin,
    /// half-diagonal `hd`). The slack is a few units of the last place of the centre's
    /// coordinates: f64 ones, or double-double ones (2^-104 of the origin) on deep frames.
    #[inline]
    pub fn full_distance(&self, d: f64, c: DVec3, hd: f64) -> bool {
        let o = &self.origin;
        let slack = if o.deep {
            8.0 * f64::EPSILON * c.abs().max_element()
                + 8.0 * 2f64.powi(-104) * o.hi.abs().max_element().max(1.0)
        } else {
            8.0 * f64::EPSILON * (o.hi + c).abs().max_element().max(1.0)
        };
        // NaN counts as full: never a false negative.
        d.is_nan() || d < hd * (1.0 + self.margin) + slack
    }

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
    fn traces(&self, d: f64) -> bool {
        self.gradient_shading && d.is_finite()
    }

    /// [`Shader::surface`] once the line of sight's point (`sight`) is known.
    fn surface_from(
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
    const NONE: Surface = Surface {
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

impl Shader {
    /// The surface point a pixel showing the voxel at world centre `c` (half side `h`) would
    /// see: sphere tracing from where the line of sight from [`Shader::view`]'s eye through
    /// the centre enters the voxel's bounding sphere, until the distance is below a quarter
    /// of the side or the point is inside. Shading there rather than at the centre is what
    /// the sphere tracer does: voxels of a face with sub-pixel holes behind it take the
    /// face's normal, not a hole wall's.
    ///
    /// When the line passes the voxel without meeting the surface (a leaf the conservative
    /// full test keeps in front of an underestimated surface, most of the Mandelbulb zoom's
    /// visible leaves before zoom 1e6), on scenes whose distance is an estimate the trace
    /// goes on, up to [`SIGHT_REACH`] half-diagonals ([`Shader::sight_limits`]), to the
    /// surface a pixel through the centre shows behind it: while such a leaf is drawn, it
    /// shows that surface's colour, as the tracer's pixel does. `None` when the line escapes
    /// or the steps run out, and then [`Shader::surface`] takes [`Shader::newton_point`].
    fn sight_point(&self, ev: &mut Probe, c: DVec3, h: f64) -> Option<SightHit> {
        let hd = h * 3f64.sqrt();
        let (reach, steps) = self.sight_limits();
        let dir = (c - self.view.eye).normalize_or_zero();
        if dir == DVec3::ZERO {
            return None;
        }
        let reach = hd * reach;
        let mut t = -hd;
        for _ in 0..steps {
            let p = c + dir * t;
            let v = self.eval(ev, p);
            if !v.d.is_finite() {
                return None;
            }
            if v.d < 0.5 * h {
                return Some(SightHit::traced(p, v, dir, t, hd));
            }
            t += v.d;
            if t > reach {
                return None;
            }
        }
        None
    }

    /// [`Shader::sight_point`] of four voxels of half side `h` at once (lanes whose `traced`
    /// is false give `None`): [`Shader::sight_lines`] traced to the full reach by
    /// [`Shader::trace4`].
    #[cfg(test)]
    fn sight_points(
        &self,
        ev: &mut Probe,
        c: [DVec3; 4],
        traced: [bool; 4],
        h: f64,
    ) -> [Option<SightHit>; 4] {
        let reach = h * 3f64.sqrt() * self.sight_limits().0;
        let lines = self.sight_lines(c, traced, h);
        self.trace4(ev, lines, h, reach, false).map(Sight::hit)
    }

    /// [`Shader::sight_line`] of four voxels (`None` where `traced` is false).
    #[cfg(test)]
    fn sight_lines(&self, c: [DVec3; 4], traced: [bool; 4], h: f64) -> [Option<SightLine>; 4] {
        std::array::from_fn(|i| traced[i].then(|| self.sight_line(c[i], h)).flatten())
    }

    /// The line of sight of the voxel of half side `h` with centre `c`, not yet traced: from
    /// the eye through the centre, starting where the line enters the voxel's bounding sphere
    /// (`None` when the eye is at the centre).
    fn sight_line(&self, c: DVec3, h: f64) -> Option<SightLine> {
        let dir = (c - self.view.eye).normalize_or_zero();
        (dir != DVec3::ZERO).then_some(SightLine {
            c,
            dir,
            t: -h * 3f64.sqrt(),
            steps: 0,
        })
    }

    /// Traces four lines of sight of voxels of half side `h` (`None` lanes stay
    /// [`Sight::Lost`]) until each meets the surface (its distance below a quarter of the
    /// side), gets a NaN or an infinite distance, runs out of [`Shader::sight_limits`]' steps
    /// (counted over every stretch of its trace), or goes beyond `until` (world units along
    /// the line from the centre): that ends it [`Sight::Passed`] with `pass`, to be traced on
    /// by a later call, and [`Sight::Lost`] without. Each step is one four-lane evaluation
    /// ([`Shader::eval4`]); a lane that has stopped repeats the point of one still tracing, so
    /// the packet costs what its slowest line does (traced one at a time, these traces were a
    /// quarter of a Mandelbulb zoom's subdivision time). Lanes are evaluated independently, so
    /// a line reaches the same points whatever lanes and packets carry it, also when traced
    /// on in other packets than the one it began in (within a few ulps of the scalar trace,
    /// [`Shader::sight_point`]).
    fn trace4(
        &self,
        ev: &mut Probe,
        mut lines: [Option<SightLine>; 4],
        h: f64,
        until: f64,
        pass: bool,
    ) -> [Sight; 4] {
        let hd = h * 3f64.sqrt();
        let max_steps = self.sight_limits().1;
        let mut out = [Sight::Lost; 4];
        loop {
            for (line, out) in lines.iter_mut().zip(&mut out) {
                if let Some(l) = *line
                    && (l.t > until || l.steps >= max_steps)
                {
                    if l.t > until && pass {
                        *out = Sight::Passed(l);
                    }
                    *line = None;
                }
            }
            let Some(first) = lines.iter().flatten().next().copied() else {
                break;
            };
            let p: [DVec3; 4] = std::array::from_fn(|i| {
                let l = lines[i].unwrap_or(first);
                l.c + l.dir * l.t
            });
            let v = self.eval4(ev, p);
            for i in 0..4 {
                let Some(l) = &mut lines[i] else {
                    continue;
                };
                l.steps += 1;
                let d = v[i].d;
                if !d.is_finite() {
                    lines[i] = None;
                } else if d < 0.5 * h {
                    out[i] = Sight::Hit(SightHit::traced(p[i], v[i], l.dir, l.t, hd));
                    lines[i] = None;
                } else {
                    l.t += d;
                }
            }
        }
        out
    }

    /// How far lines of sight are traced, in half-diagonals, and in how many steps:
    /// [`SIGHT_REACH`] and [`SIGHT_STEPS`] where the distance is an estimate (the scenes with
    /// a shell of leaves in front of their surface), the bounding sphere and
    /// [`SIGHT_STEPS_BOUND`] where it is a bound. On the Menger sponge, tracing on changed
    /// the splits a frame by -8 % and the SSIM to the tracer by -0.02 to +0.02: no gain.
    fn sight_limits(&self) -> (f64, usize) {
        if self.corner_test {
            (SIGHT_REACH, SIGHT_STEPS)
        } else {
            (1.0, SIGHT_STEPS_BOUND)
        }
    }

    /// The surface point of a voxel whose line of sight found none: the centre `c` moved
    /// along the gradient by its distance (one Newton step, at most the half-diagonal).
    fn newton_point(&self, ev: &mut Probe, c: DVec3, h: f64) -> Option<SightHit> {
        let hd = h * 3f64.sqrt();
        let g = self.gradient(ev, c, h);
        let v = self.eval(ev, c);
        let len = g.length();
        let step = (v.d / len.max(1e-300)).clamp(-hd, hd);
        if len > 0.0 && step.is_finite() {
            let p = c - g / len * step;
            Some(SightHit {
                p,
                v: self.eval(ev, p),
                behind: None,
            })
        } else {
            None
        }
    }
}

/// A voxel's line of sight while it is traced ([`Shader::trace4`]): through centre `c` in
/// direction `dir`, at `t` along it from the centre (world units), after `steps` evaluations.
#[derive(Clone, Copy, Debug)]
struct SightLine {
    c: DVec3,
    dir: DVec3,
    t: f64,
    steps: usize,
}

/// Where a line of sight stands after a stretch of tracing ([`Shader::trace4`]).
#[derive(Clone, Copy, Debug)]
enum Sight {
    /// It met the surface.
    Hit(SightHit),
    /// It went past the end of the stretch without meeting the surface, or is not traced yet:
    /// to be traced on.
    Passed(SightLine),
    /// It escaped (went past the end of a stretch that does not pass lines on), met a NaN
    /// or an infinite distance, ran out of steps, or was never traced.
    Lost,
}

impl Sight {
    /// The surface point, if the line met the surface.
    fn hit(self) -> Option<SightHit> {
        match self {
            Sight::Hit(x) => Some(x),
            _ => None,
        }
    }
}

/// A surface point found for a voxel: by its line of sight ([`Shader::sight_point`]) or,
/// when that found none, by a Newton step from its centre ([`Shader::newton_point`]).
#[derive(Clone, Copy, Debug)]
struct SightHit {
    /// The point (world units relative to the origin).
    p: DVec3,
    /// The tape's value there.
    v: fathom_core::Value<f64>,
    /// The line of sight's direction when the point lies past the voxel's bounding sphere, on
    /// the far side from the eye: the line passed the voxel (a Newton point never does: its
    /// step is at most the half-diagonal).
    behind: Option<DVec3>,
}

impl SightHit {
    /// The hit of a line of sight in direction `dir` from the voxel's centre, `t` along it,
    /// for a voxel of half-diagonal `hd`.
    fn traced(p: DVec3, v: fathom_core::Value<f64>, dir: DVec3, t: f64, hd: f64) -> SightHit {
        SightHit {
            p,
            v,
            behind: (t > hd).then_some(dir),
        }
    }
}

/// `p` moved onto the surface by one Newton step on the distance `d` there, along its
/// gradient `g` (both already known: no evaluation), the step at most the half side `h`;
/// `p` itself where the gradient vanishes.
fn onto_surface(p: DVec3, d: f64, g: DVec3, h: f64) -> DVec3 {
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

/// Steps of a voxel's line-of-sight trace on scenes whose distance is an estimate
/// ([`Shader::sight_limits`]): 48 (24 before lines went past the voxel), so that a trace
/// that has passed the voxel can still cover a few times the voxel in the estimate's short
/// steps near a surface.
const SIGHT_STEPS: usize = 48;

/// Steps of a voxel's line-of-sight trace on scenes whose distance is a bound, where it
/// ends at the voxel's bounding sphere.
const SIGHT_STEPS_BOUND: usize = 24;

/// How far a voxel's line of sight is traced, in half-diagonals from its centre: on past
/// the voxel, to what a pixel through its centre would show behind it (see
/// [`Shader::sight_point`]). 64 gave the same pictures as 1000 on the Mandelbulb zoom.
const SIGHT_REACH: f64 = 64.0;

impl Shader {
    /// The distance gradient at `p` (relative to the origin) by the tetrahedron technique
    /// with offsets `e (±1, ±1, ±1)` (4 evaluations, the sphere tracer's normal: with `e` half a
    /// pixel footprint the two agree on pixel-sized voxels); not normalised, zero where a
    /// sample is NaN or infinite or the field is flat.
    pub fn gradient(&self, ev: &mut Probe, p: DVec3, e: f64) -> DVec3 {
        const K: [DVec3; 4] = [
            DVec3::new(1.0, -1.0, -1.0),
            DVec3::new(-1.0, -1.0, 1.0),
            DVec3::new(-1.0, 1.0, -1.0),
            DVec3::new(1.0, 1.0, 1.0),
        ];
        let d = self.distance4(ev, K.map(|k| p + k * e));
        let mut g = DVec3::ZERO;
        for (k, d) in K.into_iter().zip(d) {
            g += k * d;
        }
        // For a linear field d = n . x the sum is 4 e n.
        let g = g / (4.0 * e);
        if g.is_finite() { g } else { DVec3::ZERO }
    }
}

/// The evaluated children of one node: bit `o` of `full` set when child `o` is full.
#[derive(Clone, Copy, Debug)]
pub struct Children {
    /// Node that was evaluated.
    pub id: u32,
    /// Its box.
    pub b: BoxU,
    /// Full-child mask.
    pub full: u8,
    /// Colours of the full children.
    pub colours: [u32; 8],
    /// Surface planes of the full children.
    pub planes: [SurfacePlane; 8],
}

/// Evaluates the 8 children of the leaf `id` with box `b` (read-only; runs in parallel).
///
/// A full child wider than `final_side` (root units: the footprint of the ray that asked for
/// the split, below which the child is drawn as it is) whose line of sight passes its
/// bounding sphere without meeting the surface (on estimate scenes, before the line is traced
/// on past it), or whose surface plane lies clear of its cube (its surface point is outside
/// it, [`SurfacePlane::is_clear`]), has its own children tested at once, and is empty when
/// none of them is full: the test its subdivision would make, made before it is drawn. Such
/// a child is the conservative full test's shell in front of an underestimated surface (two
/// thirds of the Mandelbulb zoom's full leaves, three quarters of which emptied when split
/// later). Children at or below `final_side` keep the plain test, so settled trees are
/// unchanged, up to one approximation: the footprint is the asking ray's at the parent, so a
/// child within a few tenths of a percent of it can fall on either side (and with several
/// threads, which ray asks first is a race).
pub fn eval_children(
    sh: &Shader,
    tree: &Octree,
    ev: &mut Probe,
    (id, b): (u32, BoxU),
    final_side: f64,
) -> Children {
    let mut out = Children {
        id,
        b,
        full: 0,
        colours: [0; 8],
        planes: [SurfacePlane::NONE; 8],
    };
    let side = b.dim() * 0.5 * tree.root_size;
    let h = (side * 0.5).max(1e-300);
    let hd = h * 3f64.sqrt();
    let reach = sh.sight_limits().0;
    let t = full_children(sh, tree, ev, &b);
    out.full = t.full;
    let look_deeper = b.depth + 1 < tree.depth_limit() && b.dim() * 0.5 > final_side;
    let mut full = [0usize; 8];
    let mut n = 0;
    for o in (0..8).filter(|o| t.full >> o & 1 == 1) {
        full[n] = o;
        n += 1;
    }
    // The full children's lines of sight, four at a time, as far as each child's bounding
    // sphere; on estimate scenes a line that gets there is `Passed`, to be traced on.
    let mut sight: [Sight; 8] = std::array::from_fn(|o| {
        let traced = t.full >> o & 1 == 1 && sh.traces(t.d[o]);
        match traced.then(|| sh.sight_line(t.centres[o], h)).flatten() {
            Some(l) => Sight::Passed(l),
            None => Sight::Lost,
        }
    });
    trace_on(sh, ev, &mut sight, &full[..n], h, hd, reach > 1.0);
    // A wide child whose line passed it without meeting the surface is tested one level down
    // before its line is traced on: dropped, it needs neither the rest of the trace nor a
    // gradient (on the Mandelbulb zoom 70 % of the wide children with a clear plane were
    // dropped, and four fifths of the trace's steps were past the bounding sphere).
    let mut tested = 0u8;
    let mut passed = [0usize; 8];
    let mut np = 0;
    for &o in &full[..n] {
        if !matches!(sight[o], Sight::Passed(_)) {
            continue;
        }
        if look_deeper {
            tested |= 1 << o;
            if !any_child_full(sh, tree, ev, &b, o, &t) {
                out.full &= !(1 << o);
                continue;
            }
        }
        passed[np] = o;
        np += 1;
    }
    // The kept children's lines traced on, to the reach.
    trace_on(sh, ev, &mut sight, &passed[..np], h, hd * reach, false);
    // Each kept child's surface; a wide one whose plane is clear of it, not tested yet, is
    // tested one level down now.
    let mut surfaces = [Surface::NONE; 8];
    let mut kept = [0usize; 8];
    let mut m = 0;
    for &o in &full[..n] {
        if out.full >> o & 1 == 0 {
            continue;
        }
        let s = sh.surface_from(ev, t.centres[o], h, t.d[o], sight[o].hit());
        if look_deeper
            && tested >> o & 1 == 0
            && s.plane.is_clear()
            && !any_child_full(sh, tree, ev, &b, o, &t)
        {
            out.full &= !(1 << o);
            continue;
        }
        surfaces[o] = s;
        kept[m] = o;
        m += 1;
    }
    // The kept children shaded together, four at a time (`Shader::shade4`).
    for group in kept[..m].chunks(4) {
        let colours = sh.shade4(
            ev,
            std::array::from_fn(|j| &surfaces[group[j.min(group.len() - 1)]]),
            group.len(),
        );
        for (j, &o) in group.iter().enumerate() {
            (out.colours[o], out.planes[o]) = (colours[j], surfaces[o].plane);
        }
    }
    out
}

/// Traces on the lines of sight of children `which` that are [`Sight::Passed`] (the others
/// stay as they are), four at a time, with [`Shader::trace4`]'s `until` and `pass`.
fn trace_on(
    sh: &Shader,
    ev: &mut Probe,
    sight: &mut [Sight; 8],
    which: &[usize],
    h: f64,
    until: f64,
    pass: bool,
) {
    for group in which.chunks(4) {
        let lines = std::array::from_fn(|k| match group.get(k).map(|&o| sight[o]) {
            Some(Sight::Passed(l)) => Some(l),
            _ => None,
        });
        let s = sh.trace4(ev, lines, h, until, pass);
        for (k, &o) in group.iter().enumerate() {
            if matches!(sight[o], Sight::Passed(_)) {
                sight[o] = s[k];
            }
        }
    }
}

/// The full test of the children of `b`'s child `o` (`t` is `b`'s [`full_children`]): true
/// when one of them is full, as `full_children(&b.child(o)).full != 0` would say, without
/// evaluating again the points of the child's 3x3x3 lattice `t` already has: its centre and,
/// when `b`'s lattice was evaluated, its corners (26 new points instead of 35).
fn any_child_full(
    sh: &Shader,
    tree: &Octree,
    ev: &mut Probe,
    b: &BoxU,
    o: usize,
    t: &ChildTests,
) -> bool {
    let cb = b.child(o);
    if centre_test(sh, tree, ev, &cb).2 != 0 {
        return true;
    }
    if !sh.corner_test {
        return false;
    }
    // Every point of the child's lattice is a corner of one of its children: one inside
    // makes that child full. Its centre is `t.d[o]`; its corners are in `b`'s lattice.
    if inside(t.d[o]) {
        return true;
    }
    let corners = match &t.lattice {
        Some(l) => (0..8).any(|k| l[corner_index(o, k)]),
        None => {
            let pts: [DVec3; 8] = std::array::from_fn(|k| {
                lattice_point(tree, &cb, [0, 1, 2].map(|a| 2 * (k >> a & 1)))
            });
            sh.distances(ev, &pts).into_iter().any(inside)
        }
    };
    if corners {
        return true;
    }
    // The 18 others: a coordinate at the middle, not all three.
    let others: [DVec3; 18] = std::array::from_fn(|k| {
        let ijk = LATTICE_MIDDLES[k];
        lattice_point(tree, &cb, ijk)
    });
    sh.distances(ev, &others).into_iter().any(inside)
}

/// The points of a 3x3x3 lattice with one or two coordinates at the middle (neither a corner
/// nor the centre), in `lattice_ijk` order.
const LATTICE_MIDDLES: [[usize; 3]; 18] = {
    let mut out = [[0; 3]; 18];
    let (mut i, mut n) = (0, 0);
    while i < 27 {
        let ijk = lattice_ijk(i);
        let middles = (ijk[0] == 1) as u8 + (ijk[1] == 1) as u8 + (ijk[2] == 1) as u8;
        if middles == 1 || middles == 2 {
            out[n] = ijk;
            n += 1;
        }
        i += 1;
    }
    out
};

/// Point `i` of a 3x3x3 lattice as `ijk`, 0..=2 per axis (`i = i0 + 3 i1 + 9 i2`).
const fn lattice_ijk(i: usize) -> [usize; 3] {
    [i % 3, i / 3 % 3, i / 9]
}

/// The lattice index of corner `k` of child `o` in its parent's 3x3x3 lattice.
fn corner_index(o: usize, k: usize) -> usize {
    let ijk = [0, 1, 2].map(|a| (o >> a & 1) + (k >> a & 1));
    ijk[0] + 3 * ijk[1] + 9 * ijk[2]
}

/// Lattice point `ijk` of box `b` (world units relative to the origin).
fn lattice_point(tree: &Octree, b: &BoxU, ijk: [usize; 3]) -> DVec3 {
    let h = b.dim() * 0.5;
    tree.local_world([0, 1, 2].map(|a| b.min[a] + h * ijk[a] as f64))
}

/// The corner test's "inside": at or below zero, or NaN (never a false negative).
fn inside(d: f64) -> bool {
    d <= 0.0 || d.is_nan()
}

/// The centre test of the 8 children of box `b`: their centres (world units relative to the
/// origin), the distances there and the mask of those that pass.
fn centre_test(sh: &Shader, tree: &Octree, ev: &mut Probe, b: &BoxU) -> ([DVec3; 8], [f64; 8], u8) {
    let side = b.dim() * 0.5 * tree.root_size;
    let hd = side * 0.5 * 3f64.sqrt();
    let centres: [DVec3; 8] = std::array::from_fn(|o| tree.centre_local(&b.child(o)));
    let d = sh.distances(ev, &centres);
    let mut full = 0u8;
    for (o, (&c, &d)) in centres.iter().zip(&d).enumerate() {
        if sh.full_distance(d, c, hd) {
            full |= 1 << o;
        }
    }
    (centres, d, full)
}

/// The full test of the 8 children of a box ([`full_children`]).
struct ChildTests {
    /// Mask of the full children.
    full: u8,
    /// Their centres (world units relative to the origin) and the distances there.
    centres: [DVec3; 8],
    d: [f64; 8],
    /// Inside flags of the box's 3x3x3 lattice of children's corners, when it was evaluated.
    lattice: Option<[bool; 27]>,
}

/// The full test of the 8 children of box `b`: the mask of full children, their centres
/// (world units relative to the origin) and the distances there.
///
/// The children's centre distances are two four-lane evaluations, and on estimate scenes the
/// parent's 3x3x3 corner lattice is seven, all 27 points at once once any child fails the
/// centre test: seven packets cost what 9-11 scalar evaluations do, where the lattice filled
/// lazily child by child took 19 on average (Mandelbulb zoom).
fn full_children(sh: &Shader, tree: &Octree, ev: &mut Probe, b: &BoxU) -> ChildTests {
    let (centres, d, mut full) = centre_test(sh, tree, ev, b);
    let mut lattice = None;
    if full != 0xff && sh.corner_test {
        // Inside flags of the parent's 3x3x3 lattice (the children's corners).
        let pts: [DVec3; 27] = std::array::from_fn(|i| lattice_point(tree, b, lattice_ijk(i)));
        let ins = sh.distances(ev, &pts).map(inside);
        let by_centre = full;
        for o in (0..8).filter(|o| by_centre >> o & 1 == 0) {
            if (0..8).any(|k| ins[corner_index(o, k)]) {
                full |= 1 << o;
            }
        }
        lattice = Some(ins);
    }
    ChildTests {
        full,
        centres,
        d,
        lattice,
    }
}

/// What linking one evaluated node did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Outcome {
    /// 8 children were linked in.
    Split,
    /// Every child was empty: the node became an empty leaf (and maybe recombined upward).
    Emptied,
    /// The node was freed, split or emptied since it was requested: nothing done.
    Stale,
    /// The memory budget had no room for 8 children.
    NoMemory,
}

/// Links the result of [`eval_children`] into the tree (single-threaded, between frames).
pub fn apply(tree: &mut Octree, r: &Children) -> Outcome {
    let id = r.id;
    {
        let n = &tree.nodes[id as usize];
        n.clear_flags(REQUESTED);
        if n.is_free() || !n.is_leaf() || n.is_empty() || n.depth != r.b.depth {
            return Outcome::Stale;
        }
    }
    if r.full == 0 {
        tree.nodes[id as usize].set_flags(EMPTY);
        recombine_up(tree, id);
        return Outcome::Emptied;
    }
    let Some(first) = tree.alloc_block() else {
        return Outcome::NoMemory;
    };
    let depth = r.b.depth + 1;
    let brick_here = tree.is_brick_depth(depth);
    let (parent_links, parent_brick) = {
        let n = &tree.nodes[id as usize];
        (std::array::from_fn::<u32, 6, _>(|f| n.link(f)), n.brick)
    };
    let mut sum = [0u32; 3];
    let mut count = 0;
    for o in 0..8u32 {
        let cid = first + o;
        let c = &mut tree.nodes[cid as usize];
        c.children = NONE;
        c.parent = id;
        c.depth = depth;
        c.brick = if brick_here { cid } else { parent_brick };
        c.idle = 0;
        let full = r.full >> o & 1 == 1;
        c.colour = if full { r.colours[o as usize] } else { 0 };
        // Empty children's planes are `NONE` (eval_children sets only the full ones').
        c.plane = r.planes[o as usize];
        // New nodes count as visited so the next unification does not unload them unseen.
        *c.flags.get_mut() = if full { 0 } else { EMPTY } | VISITED;
        for a in 0..3 {
            let hi = o >> a & 1 == 1;
            // Face towards the sibling: exact link; face outwards: the parent's link (same
            // or coarser depth, made finer by rays on the fly).
            let (inner, outer) = if hi {
                (2 * a, 2 * a + 1)
            } else {
                (2 * a + 1, 2 * a)
            };
            *c.nb[inner].get_mut() = first + (o ^ (1 << a));
            *c.nb[outer].get_mut() = parent_links[outer];
        }
        if full {
            let rgb = r.colours[o as usize];
            for (i, s) in sum.iter_mut().enumerate() {
                *s += rgb >> (8 * i) & 255;
            }
            count += 1;
        }
    }
    // Refine the copied outer links: descend from the parent's neighbour towards each child's
    // adjacent box, as deep as the child (safe here: nothing else runs during link-in).
    // Without this, chains of full leaves subdivided level after level hand their children
    // links many levels too coarse, and every first crossing pays a long descent.
    let rc = tree.anchor.cell_of(&r.b);
    for o in 0..8u32 {
        let cb = rc.child(o as usize);
        for a in 0..3 {
            let outer = if o >> a & 1 == 1 { 2 * a + 1 } else { 2 * a };
            let l = parent_links[outer];
            if l == NONE {
                continue;
            }
            let target = cb.across(outer);
            let mut m = l;
            let mut mb = target.snapped(tree.nodes[m as usize].depth);
            while mb.depth < cb.depth {
                let mn = &tree.nodes[m as usize];
                if mn.is_leaf() {
                    break;
                }
                let oc = mb.octant_towards(&target);
                m = mn.children + oc as u32;
                mb = mb.child(oc);
            }
            if m != l {
                tree.nodes[(first + o) as usize].set_link(outer, m);
            }
        }
    }
    let n = &mut tree.nodes[id as usize];
    n.children = first;
    n.colour = sum
        .iter()
        .enumerate()
        .fold(255 << 24, |acc, (i, s)| acc | (s / count) << (8 * i));
    tree.note_inner(id, true);
    // The children are marked visited; so must be every brick above them, or the first ray
    // that reaches them stops its marking walk at their (marked) brick and the enclosing
    // bricks are unloaded at the next unification, in view (a still camera's picture then
    // fell back to 15-pixel blocks every few frames).
    mark_visited(tree, id);
    Outcome::Split
}

/// After `id` became an empty leaf: while every child of the parent is an empty leaf, free
/// them and make the parent an empty leaf.
pub fn recombine_up(tree: &mut Octree, mut id: u32) {
    loop {
        let p = tree.nodes[id as usize].parent;
        if p == NONE {
            return;
        }
        let first = tree.nodes[p as usize].children;
        if !(first..first + 8).all(|c| tree.is_empty_leaf(c)) {
            return;
        }
        let pb = tree.cell_of(p);
        free_children(tree, p, pb);
        tree.nodes[p as usize].set_flags(EMPTY);
        id = p;
    }
}

/// Evaluates the root and sets it full (with a colour) or empty.
pub fn init_root(tree: &mut Octree, sh: &Shader) {
    let mut ev = Probe::new();
    let b = tree.root_box();
    let c = tree.centre_local(&b);
    let hd = tree.root_size * 0.5 * 3f64.sqrt();
    let n = &mut tree.nodes[0];
    match sh.full(&mut ev, c, hd) {
        Some(v) => (n.colour, n.plane) = sh.colour(&mut ev, c, tree.root_size * 0.5, v.d),
        None => *n.flags.get_mut() |= EMPTY,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use fathom_core::camera_path::path_preset;

    #[test]
    fn packet_children_tests_match_point_by_point_ones() {
        // full_children decides the 8 children from two packets of centres and, on estimate
        // scenes, seven packets of the 3x3x3 corner lattice; point by point (f64), the same
        // points must give the same full children on boxes down to the zoom target. The
        // Mandelbulb's estimate is first-order at its surface and its centres alone find the
        // surface on this path, so its centre test is made a sign test (a margin of -1) to
        // make the corners decide some children.
        for (name, margin) in [("mandelbulb", -1.0), ("menger", DEFAULT_MARGIN)] {
            let p = path_preset(name).unwrap();
            let mut sh = Shader::new(&p.scene, margin).unwrap();
            sh.gradient_shading = false;
            let tree = Octree::new(DVec3::splat(-1.5), 3.0, 3, 1 << 12);
            sh.origin.hi = tree.root_min;
            let u = tree.to_u(p.path.target().unwrap());
            let mut pr = Probe::new();
            let (mut full, mut by_corner) = (0, 0);
            let mut b = BoxU::ROOT;
            for _ in 0..40 {
                let got = full_children(&sh, &tree, &mut pr, &b).full;
                let side = b.dim() * 0.5 * tree.root_size;
                let h = b.dim() * 0.5;
                let inside = |pr: &mut Probe, ijk: [usize; 3]| {
                    let q = [0, 1, 2].map(|a| b.min[a] + h * ijk[a] as f64);
                    let d = sh.distance(pr, tree.local_world(q));
                    d <= 0.0 || d.is_nan()
                };
                for o in 0..8 {
                    let c = tree.centre_local(&b.child(o));
                    let centre =
                        sh.full_distance(sh.distance(&mut pr, c), c, side * 0.75f64.sqrt());
                    let corner = sh.corner_test
                        && (0..8).any(|k| {
                            inside(&mut pr, [0, 1, 2].map(|a| (o >> a & 1) + (k >> a & 1)))
                        });
                    assert_eq!(
                        got >> o & 1 == 1,
                        centre || corner,
                        "{name} depth {} child {o}",
                        b.depth
                    );
                    full += (centre || corner) as u32;
                    by_corner += (corner && !centre) as u32;
                }
                b = b.child(b.octant_of(u));
            }
            assert!(full >= 40, "{name}: {full} full children");
            if name == "mandelbulb" {
                assert!(by_corner > 0, "the corner lattice was never needed");
            }
        }
    }

    #[test]
    fn a_clear_child_is_full_only_when_one_of_its_own_children_is() {
        // Down the Mandelbulb zoom's path, seen from its first camera: eval_children keeps the
        // full test's children except those whose own children all test empty and whose line
        // of sight passes their bounding sphere without meeting the surface or whose plane is
        // clear of their cube. Such children exist on this path (the shell in front of the
        // surface), and a clear child kept has a full child of its own. Children no wider
        // than the footprint of the ray that asked are final and keep the plain test.
        let p = path_preset("mandelbulb").unwrap();
        let mut sh = Shader::new(&p.scene, DEFAULT_MARGIN).unwrap();
        let tree = Octree::new(DVec3::splat(-1.5), 3.0, 3, 1 << 12);
        sh.origin.hi = tree.root_min;
        let target = p.path.target().unwrap();
        let cam = p.path.camera(0, 300, 1e15, 40.0);
        sh.view = View {
            eye: cam.eye - tree.root_min,
            scale: (target - cam.eye).length(),
        };
        let u = tree.to_u(target);
        let mut pr = Probe::new();
        let (mut kept_clear, mut dropped, mut passed_dropped) = (0, 0, 0);
        let mut b = BoxU::ROOT;
        for _ in 0..30 {
            // The path's box and its children: the shell lies beside the path, not on it.
            for x in std::iter::once(b).chain((0..8).map(|o| b.child(o))) {
                let plain = full_children(&sh, &tree, &mut pr, &x);
                let got = eval_children(&sh, &tree, &mut pr, (0, x), 0.0);
                // Children no wider than the asking ray's footprint keep the plain test.
                let footprint = x.dim() * 0.5;
                let fine = eval_children(&sh, &tree, &mut pr, (0, x), footprint);
                assert_eq!(fine.full, plain.full, "depth {}: final children", x.depth);
                assert_eq!(
                    got.full & !plain.full,
                    0,
                    "depth {}: a child not full",
                    x.depth
                );
                let h = x.dim() * 0.25 * tree.root_size;
                for o in (0..8).filter(|o| plain.full >> o & 1 == 1) {
                    let plane = sh.surface(&mut pr, plain.centres[o], h, plain.d[o]).plane;
                    let below = full_children(&sh, &tree, &mut pr, &x.child(o)).full;
                    let any = any_child_full(&sh, &tree, &mut pr, &x, o, &plain);
                    assert_eq!(any, below != 0, "depth {} child {o}", x.depth);
                    // Whether the line of sight passes the child's bounding sphere.
                    let c = [plain.centres[o]; 4];
                    let lines = sh.sight_lines(c, [true; 4], h);
                    let hd = h * 3f64.sqrt();
                    let near = sh.trace4(&mut pr, lines, h, hd, true)[0];
                    let passed = matches!(near, Sight::Passed(_));
                    let kept = got.full >> o & 1 == 1;
                    let want = below != 0 || !(passed || plane.is_clear());
                    assert_eq!(kept, want, "depth {} child {o}", x.depth);
                    kept_clear += (kept && plane.is_clear()) as u32;
                    dropped += !kept as u32;
                    passed_dropped += (!kept && passed) as u32;
                }
            }
            b = b.child(b.octant_of(u));
        }
        assert!(dropped > 0, "no clear child was dropped");
        assert!(
            passed_dropped > 0,
            "no child whose line passed it was dropped"
        );
        assert!(kept_clear > 0, "no clear child was kept");
    }

    #[test]
    fn a_plane_point_is_moved_onto_the_zero_of_a_linear_distance() {
        // A distance that is linear with any slope (estimates are scaled distances): one
        // Newton step lands on its zero, from either side; a step longer than the half side
        // is cut to it, and a vanishing or broken gradient leaves the point where it is.
        let n = DVec3::new(0.3, -0.5, 0.8);
        let field = |x: DVec3| 2.5 * (n.dot(x) - 0.1);
        let g = 2.5 * n;
        for p in [DVec3::new(0.2, 0.1, 0.3), DVec3::new(-0.1, 0.4, -0.2)] {
            let on = onto_surface(p, field(p), g, 1.0);
            assert!(field(on).abs() < 1e-12, "{p}: {} at {on}", field(on));
            let short = onto_surface(p, field(p), g, 0.01);
            assert!(((short - p).length() - 0.01).abs() < 1e-12, "{p}: {short}");
            assert!(
                field(short).abs() < field(p).abs(),
                "{p}: not toward the zero"
            );
            assert_eq!(onto_surface(p, field(p), DVec3::ZERO, 1.0), p);
            assert_eq!(onto_surface(p, f64::NAN, g, 1.0), p);
        }
    }

    #[test]
    fn a_leaf_plane_passes_nearer_the_surface_than_its_shading_point() {
        // Voxels of several sizes around each zoom target: where the line of sight stopped
        // (the shading point) the distance may be up to a quarter side; the plane's point
        // nearest it, after the Newton step, must be much nearer the surface.
        for name in ["mandelbulb", "menger"] {
            let p = path_preset(name).unwrap();
            let mut sh = Shader::new(&p.scene, DEFAULT_MARGIN).unwrap();
            let t = p.path.target().unwrap();
            let eye = p.path.camera(0, 300, 1e15, 40.0).eye;
            sh.view = View {
                eye,
                scale: (t - eye).length(),
            };
            let mut pr = Probe::new();
            let (mut at_point, mut at_plane) = (Vec::new(), Vec::new());
            for h in [1e-2, 1e-3, 1e-4] {
                for k in 0..64 {
                    let f = |i: u32| ((k * 7 + i * 13) % 17) as f64 / 8.0 - 1.0;
                    let c = t + DVec3::new(f(1), f(2), f(3)) * (2.0 * h);
                    let d = sh.distance(&mut pr, c);
                    let s = sh.surface(&mut pr, c, h, d);
                    if !s.plane.is_some() || s.plane.is_behind() {
                        continue;
                    }
                    let (m, off) = s.plane.decode();
                    let q = s.p - m * (m.dot(s.p - c) - off * h);
                    at_point.push(s.v.d.abs() / h);
                    at_plane.push(sh.distance(&mut pr, q).abs() / h);
                }
            }
            let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len().max(1) as f64;
            let (a, b) = (mean(&at_point), mean(&at_plane));
            eprintln!(
                "{name}: {} planes; mean |distance| / half side: point {a:.4}, plane {b:.4}",
                at_plane.len()
            );
            assert!(at_plane.len() >= 40, "{name}: {} planes", at_plane.len());
            assert!(b < 0.5 * a, "{name}: plane {b} vs point {a}");
        }
    }

    /// A zoom preset's shader, its zoom target and a deep origin at the target (double-double
    /// evaluation relative to it).
    fn at_target(name: &str) -> (Shader, DVec3, Origin) {
        let p = path_preset(name).unwrap();
        let sh = Shader::new(&p.scene, DEFAULT_MARGIN).unwrap();
        let t = p.path.target().unwrap();
        let deep = Origin {
            hi: t,
            lo: DVec3::splat(1e-20),
            deep: true,
        };
        (sh, t, deep)
    }

    #[test]
    fn four_surfaces_at_once_match_one_at_a_time() {
        // Voxels of several sizes around each zoom target, on shallow and deep frames: the
        // packet's surface points, values and colours are the scalar path's up to the
        // packet's rounding; a lane past `live` is left empty.
        for name in ["mandelbulb", "menger"] {
            let (mut sh, t, deep) = at_target(name);
            let mut pr = Probe::new();
            let mut traced = 0;
            let shallow = sh.origin;
            for h in [3e-2, 1e-3, 4e-5, 1e-6] {
                let c: [DVec3; 4] = std::array::from_fn(|k| {
                    t + DVec3::new(0.7, -0.4, 0.3) * (h * (k as f64 - 1.5))
                });
                for (origin, c) in [(shallow, c), (deep, c.map(|c| c - t))] {
                    sh.origin = origin;
                    let d = c.map(|c| sh.distance(&mut pr, c));
                    for live in [4, 3] {
                        let four = sh.surfaces4(&mut pr, c, d, live, h);
                        // Shaded together, each surface takes the colour it takes alone.
                        let together = sh.shade4(&mut pr, std::array::from_fn(|k| &four[k]), live);
                        for k in 0..4 {
                            let what = format!("{name} h {h:e} deep {} lane {k}", origin.deep);
                            if k >= live {
                                assert_eq!(four[k].plane, SurfacePlane::NONE, "{what}");
                                continue;
                            }
                            let one = sh.surface(&mut pr, c[k], h, d[k]);
                            traced += sh.sight_point(&mut pr, c[k], h).is_some() as usize;
                            let moved = (four[k].p - one.p).length();
                            assert!(moved <= 1e-9 * h, "{what}: moved {moved:e}");
                            let dd = (four[k].v.d - one.v.d).abs();
                            assert!(dd <= 1e-9 * h, "{what}: distance off by {dd:e}");
                            let dt = (four[k].v.trap - one.v.trap).abs();
                            assert!(
                                dt <= 1e-9 * one.v.trap.abs().max(1.0),
                                "{what}: trap {dt:e}"
                            );
                            let a = sh.shade(&mut pr, &four[k]);
                            assert_eq!(together[k], a, "{what}: shaded together");
                            let b = sh.shade(&mut pr, &one);
                            for ch in 0..4 {
                                let (x, y) = ((a >> (8 * ch)) & 255, (b >> (8 * ch)) & 255);
                                assert!(
                                    x.abs_diff(y) <= 1,
                                    "{what}: colour {a:08x} against {b:08x}"
                                );
                            }
                        }
                    }
                }
            }
            // Most of these voxels straddle the surface: their lines of sight find it.
            assert!(
                traced >= 40,
                "{name}: only {traced} of 56 lines of sight found it"
            );
        }
    }

    #[test]
    fn a_voxel_its_line_of_sight_passes_shows_the_surface_behind_it() {
        // Voxels in front of the Mandelbulb zoom's target, on the line from the first
        // camera's eye to it, 4 to 10 half-diagonals short of it: the line of sight passes
        // each voxel and meets the surface near the target, past the voxel's bounding sphere.
        // The surface point is there (a Newton step from the centre would stay within one
        // half-diagonal of it), the plane is clear of the cube, and the packet path finds the
        // same points. On shallow and deep frames.
        let p = path_preset("mandelbulb").unwrap();
        let (mut sh, t, deep) = at_target("mandelbulb");
        let shallow = sh.origin;
        let eye = p.path.camera(0, 300, 1e15, 40.0).eye;
        let dist = (t - eye).length();
        let dir = (t - eye) / dist;
        let mut pr = Probe::new();
        for h in [1e-3 * dist, 1e-6 * dist] {
            let hd = h * 3f64.sqrt();
            let c: [DVec3; 4] = std::array::from_fn(|k| t - dir * (hd * (4.0 + 2.0 * k as f64)));
            for (origin, at) in [(shallow, DVec3::ZERO), (deep, t)] {
                sh.origin = origin;
                sh.view = View {
                    eye: eye - at,
                    scale: dist,
                };
                let c = c.map(|c| c - at);
                let d = c.map(|c| sh.distance(&mut pr, c));
                let four = sh.surfaces4(&mut pr, c, d, 4, h);
                for k in 0..4 {
                    let what = format!("h {h:e} deep {} voxel {k}", origin.deep);
                    let s = sh.surface(&mut pr, c[k], h, d[k]);
                    let along = (s.p - c[k]).dot(dir);
                    assert!(
                        along > hd,
                        "{what}: stopped {:.2} half-diagonals on",
                        along / hd
                    );
                    // Not past the target (the first surface on the line) by more than the
                    // trace's stopping distance.
                    let past = (s.p - (t - at)).dot(dir);
                    assert!(
                        past <= 0.5 * h,
                        "{what}: {:.2} sides past the target",
                        past / h
                    );
                    assert!(s.v.d < 0.5 * h, "{what}: distance {:e} at the point", s.v.d);
                    assert!(s.plane.is_clear(), "{what}: plane {:?}", s.plane);
                    let moved = (four[k].p - s.p).length();
                    assert!(moved <= 1e-9 * h, "{what}: packet point moved {moved:e}");
                }
            }
        }
    }

    #[test]
    fn lines_of_sight_traced_in_two_stretches_reach_the_points_of_one() {
        // Lines of sight of voxels in front of the Mandelbulb zoom's target: traced to their
        // bounding spheres, then on in other lanes of another packet, they end at exactly the
        // points one trace reaches (eval_children traces on only the lines of the children it
        // keeps, regrouped four at a time).
        let p = path_preset("mandelbulb").unwrap();
        let (mut sh, t, _) = at_target("mandelbulb");
        let eye = p.path.camera(0, 300, 1e15, 40.0).eye;
        let dist = (t - eye).length();
        let dir = (t - eye) / dist;
        sh.view = View { eye, scale: dist };
        let mut pr = Probe::new();
        let h = 1e-3 * dist;
        let hd = h * 3f64.sqrt();
        let reach = hd * sh.sight_limits().0;
        let c: [DVec3; 4] = std::array::from_fn(|k| t - dir * (hd * (3.0 + 5.0 * k as f64)));
        let lines = sh.sight_lines(c, [true, true, false, true], h);
        let once = sh.trace4(&mut pr, lines, h, reach, false);
        let near = sh.trace4(&mut pr, lines, h, hd, true);
        let passed = near
            .iter()
            .filter(|s| matches!(s, Sight::Passed(_)))
            .count();
        assert!(passed >= 2, "{passed} lines passed their spheres");
        let on: [Option<SightLine>; 4] = std::array::from_fn(|k| match near[3 - k] {
            Sight::Passed(l) => Some(l),
            _ => None,
        });
        let far = sh.trace4(&mut pr, on, h, reach, false);
        for k in 0..4 {
            let two = match near[k] {
                Sight::Passed(_) => far[3 - k],
                s => s,
            };
            let (a, b) = (once[k].hit().map(|x| x.p), two.hit().map(|x| x.p));
            assert_eq!(a, b, "line {k}");
            assert_eq!(a.is_some(), k != 2, "line {k}: {:?}", once[k]);
            if let Sight::Passed(l) = near[k] {
                assert!(l.t > hd && l.steps >= 1, "line {k}: passed at {l:?}");
            }
            // The scalar trace's point, up to the packet's rounding.
            if let Some(a) = a {
                let scalar = sh.sight_point(&mut pr, c[k], h).expect("scalar trace").p;
                let moved = (scalar - a).length();
                assert!(moved <= 1e-9 * h, "line {k}: packet point moved {moved:e}");
            }
        }
    }

    #[test]
    fn four_distances_at_once_match_one_at_a_time() {
        // Four lanes at once, f64 on shallow frames and double-double on deep ones: within a
        // few ulps of the scalar paths (the packets' transcendental functions are wide's,
        // not libm's).
        for name in ["mandelbulb", "menger"] {
            let (mut sh, t, deep) = at_target(name);
            let mut pr = Probe::new();
            let q: [DVec3; 4] = std::array::from_fn(|k| {
                t + DVec3::new(1e-3 * k as f64, -7e-4 * k as f64, 3e-4) - DVec3::splat(1e-4)
            });
            for (origin, q) in [(sh.origin, q), (deep, q.map(|q| q - t))] {
                sh.origin = origin;
                let four = sh.distance4(&mut pr, q);
                for k in 0..4 {
                    let one = sh.distance(&mut pr, q[k]);
                    assert!(
                        (four[k] - one).abs() <= 1e-13 * one.abs().max(1e-3),
                        "{name} lane {k} (deep {}): {} against {one}",
                        origin.deep,
                        four[k]
                    );
                }
            }
        }
    }
}
