//! What evaluating a distance field returns at a point: the distance and what the renderer needs
//! to shade a hit there (material ids with a blend weight, and the orbit trap).

use crate::real::Real;

/// The result of evaluating a scene (or a subtree) at a point or a packet of points.
///
/// Material ids are node indices carried as floats (exact up to 2^24). The material at the
/// point is `lerp(material[id], material[id2], blend)`: hard combines set `blend = 0`; smooth
/// combines keep the two strongest contributors.
#[derive(Clone, Copy, Debug)]
pub struct Value<S> {
    /// Signed distance bound in world units.
    pub d: S,
    /// Material id of the node that won the combine.
    pub id: S,
    /// Second material id, blended in with weight `blend`.
    pub id2: S,
    /// Weight of `id2`, in [0, 0.5].
    pub blend: S,
    /// Orbit trap: the smallest `|z|` reached by a fractal's or an IFS loop's iteration.
    pub trap: S,
}

impl<S: Real> Value<S> {
    /// A value with one material and no blend.
    #[inline(always)]
    pub fn solid(d: S, id: S, trap: S) -> Self {
        Value {
            d,
            id,
            id2: id,
            blend: S::zero(),
            trap,
        }
    }

    /// Per lane: `m ? a : b`.
    #[inline(always)]
    pub fn select(m: S::Mask, a: Self, b: Self) -> Self {
        Value {
            d: S::select(m, a.d, b.d),
            id: S::select(m, a.id, b.id),
            id2: S::select(m, a.id2, b.id2),
            blend: S::select(m, a.blend, b.blend),
            trap: S::select(m, a.trap, b.trap),
        }
    }

    /// Blends `a` (weight `w`) with `b` (weight `1 - w`) at distance `d`, keeping the stronger
    /// contributor's material as primary.
    #[inline(always)]
    pub fn blend(d: S, a: Self, b: Self, w: S) -> Self {
        let a_wins = w.ge(S::splat(0.5));
        Value {
            d,
            id: S::select(a_wins, a.id, b.id),
            id2: S::select(a_wins, b.id, a.id),
            blend: w.min(S::one() - w),
            trap: S::lerp(b.trap, a.trap, w),
        }
    }
}
