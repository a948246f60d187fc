//! The compiled scene evaluated where the octree needs it: at points relative to the
//! anchor ([`Origin`]), in f64 or double-double, one point or four at once, with the
//! distance gradient. Colouring a voxel ([`Shader::colour`], `shading.rs`) and finding the
//! surface point its line of sight meets (`sight.rs`) are its two submodules.

mod shading;
mod sight;

#[cfg(test)]
mod tests;

pub use shading::Surface;
pub(crate) use sight::Sight;

use fathom_core::dd::Dd;
use fathom_core::dd4::Dd4;
use fathom_core::eval::Evaluator;
use fathom_core::real::{F64x4, Real};
use fathom_core::registry::{Family, Quality};
use fathom_core::scene::Scene;
use fathom_core::tape::CompileError;
use fathom_core::{Tape, V3};
use glam::DVec3;

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
}

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
