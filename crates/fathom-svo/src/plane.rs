//! The surface plane of a full leaf: where, inside its cube, a ray larger voxels would stop
//! at the cube's face meets the surface instead.
//!
//! During a zoom most visible leaves are wider than a pixel (detail arrives a few hundred
//! subdivisions a frame), and drawn as cubes they turn a smooth surface into a staircase of
//! faces with a cube's silhouette. Each full leaf therefore keeps, next to its colour, the
//! plane through the surface point its colour was shaded at, with the distance gradient there
//! as its normal (both already computed for the colour: no extra evaluation); a leaf whose
//! line of sight passed it and met the surface behind keeps a plane clear of its cube
//! ([`SurfacePlane::behind`]). A ray that ends
//! on a leaf wider than its pixel stops where it crosses that plane inside the cube, or at the
//! entry point when it enters the cube on the plane's inner side; when it crosses the cube on
//! the outer side it passes on to the next leaf. The cube cut by the plane is the leaf's solid
//! part, like the contours of Laine and Karras's efficient sparse voxel octrees (2010), from a
//! distance field instead of from geometry. Leaves a pixel wide or smaller draw as before.
//!
//! Stored in 32 bits: a valid bit, the normal in octahedral form (two 10-bit coordinates) and
//! the offset of the plane from the cube's centre along the normal in half sides (11 bits over
//! `[-OFFSET_RANGE, OFFSET_RANGE]`). Our own code: a dozen lines of encoding that the traversal
//! reads in its inner loop.

use crate::octree::BoxU;
use crate::traverse::Ray;
use glam::DVec3;

/// Offsets are clamped to this many half sides: past the cube's support (`sqrt(3)` at most)
/// the plane misses the cube, and the cube is either all solid or all passed through.
pub const OFFSET_RANGE: f64 = 2.0;

const VALID: u32 = 1 << 31;
const NORMAL_BITS: u32 = 10;
const OFFSET_BITS: u32 = 11;

/// A full leaf's surface plane (see the module documentation), or none (`SurfacePlane(0)`):
/// the leaf is drawn as its cube.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SurfacePlane(pub u32);

fn quantise(x: f64, bits: u32, range: f64) -> u32 {
    let max = ((1u32 << bits) - 1) as f64;
    (((x / range).clamp(-1.0, 1.0) * 0.5 + 0.5) * max + 0.5) as u32
}

/// `q` back to `[-range, range]`: a multiply and an add (the decode runs for every pixel that
/// shows a wide leaf, where divisions and a square root were 20 % of the render).
#[inline(always)]
fn dequantise(q: u32, bits: u32, range: f64) -> f64 {
    let max = ((1u32 << bits) - 1) as f64;
    q as f64 * (2.0 * range / max) - range
}

impl SurfacePlane {
    /// No plane: the leaf is drawn as its cube.
    pub const NONE: SurfacePlane = SurfacePlane(0);

    /// The plane through `p` with normal `n` (any length; none when it is zero or not
    /// finite) of the cube with centre `c` and half side `h`, all in one frame (world or
    /// root units alike: the plane is stored relative to the cube).
    ///
    /// Stored as `m . (x - c) = k h` with `m` the normal scaled to `|m_x| + |m_y| + |m_z| = 1`
    /// (the octahedral map's own vector, so decoding needs no square root) and `k` the
    /// offset in those units.
    pub fn new(n: DVec3, p: DVec3, c: DVec3, h: f64) -> SurfacePlane {
        let l1 = n.x.abs() + n.y.abs() + n.z.abs();
        if !(l1.is_finite() && l1 > 0.0 && h.is_finite() && h > 0.0) {
            return SurfacePlane::NONE;
        }
        let m = n / l1;
        let k = m.dot(p - c) / h;
        if !k.is_finite() {
            return SurfacePlane::NONE;
        }
        // Octahedral map: fold the lower half outwards.
        let (u, v) = if m.z >= 0.0 {
            (m.x, m.y)
        } else {
            (
                (1.0 - m.y.abs()) * m.x.signum(),
                (1.0 - m.x.abs()) * m.y.signum(),
            )
        };
        let qu = quantise(u, NORMAL_BITS, 1.0);
        let qv = quantise(v, NORMAL_BITS, 1.0);
        let qk = quantise(k, OFFSET_BITS, OFFSET_RANGE);
        SurfacePlane(VALID | qu | qv << NORMAL_BITS | qk << (2 * NORMAL_BITS))
    }

    /// The plane of a leaf whose line of sight passes it and meets the surface behind it:
    /// normal `n` (towards the eye; any length), offset at the far end of the range on the
    /// outer side, so it is [`SurfacePlane::is_clear`] whatever the direction (a plane through
    /// the surface point itself decodes to an offset just above -1 when that point is barely
    /// past the cube's bounding sphere along a diagonal). Rays pass the leaf, as the line of
    /// sight did; it says that line met no surface in the cube, not that none crosses it.
    pub fn behind(n: DVec3) -> SurfacePlane {
        SurfacePlane::new(n, -n.normalize_or_zero() * 4.0, DVec3::ZERO, 1.0)
    }

    /// True when the leaf has a plane.
    #[inline(always)]
    pub fn is_some(self) -> bool {
        self.0 & VALID != 0
    }

    /// The normal scaled to unit L1 length and the offset from the cube's centre in half
    /// sides of it (see [`SurfacePlane::new`]).
    #[inline(always)]
    fn decode_l1(self) -> (DVec3, f64) {
        let mask = (1 << NORMAL_BITS) - 1;
        let u = dequantise(self.0 & mask, NORMAL_BITS, 1.0);
        let v = dequantise(self.0 >> NORMAL_BITS & mask, NORMAL_BITS, 1.0);
        let w = 1.0 - u.abs() - v.abs();
        let (x, y) = if w >= 0.0 {
            (u, v)
        } else {
            ((1.0 - v.abs()).copysign(u), (1.0 - u.abs()).copysign(v))
        };
        let k = self.0 >> (2 * NORMAL_BITS) & ((1 << OFFSET_BITS) - 1);
        (
            DVec3::new(x, y, w),
            dequantise(k, OFFSET_BITS, OFFSET_RANGE),
        )
    }

    /// True when the plane lies clear of the cube on its outer side: the leaf's surface point
    /// is outside it, so rays pass the whole leaf.
    pub fn is_clear(self) -> bool {
        self.is_some() && self.decode_l1().1 <= -1.0
    }

    /// The unit normal and the offset of the plane from the cube's centre along it, in half
    /// sides.
    pub fn decode(self) -> (DVec3, f64) {
        let (m, k) = self.decode_l1();
        let len = m.length();
        (m / len, k / len)
    }

    /// Where ray `r`, entering the leaf with box `b` (root units) at `t`, meets its solid
    /// part: `t` when it enters on the plane's inner side, the crossing when it crosses the
    /// plane inwards before leaving the box, else `None` (it passes through the leaf).
    #[inline(always)]
    pub fn meet(self, r: &Ray, b: &BoxU, t: f64) -> Option<f64> {
        let (m, k) = self.decode_l1();
        // With `m` of unit L1 length the cube's support along it is one half side: with the
        // plane further than that behind the centre the whole cube is on the outer side (a
        // leaf the conservative full test kept whose surface point lies outside it, or
        // behind it along its line of sight), and every ray passes.
        if k <= -1.0 {
            return None;
        }
        let h = b.dim() * 0.5;
        // The entry point relative to the centre (root units near the anchor: exact enough
        // at any depth, the box's own scale).
        let x = DVec3::new(
            r.o[0] + t * r.d[0] - (b.min[0] + h),
            r.o[1] + t * r.d[1] - (b.min[1] + h),
            r.o[2] + t * r.d[2] - (b.min[2] + h),
        );
        let above = m.dot(x) - k * h;
        if above <= 0.0 {
            return Some(t);
        }
        let towards = -m.dot(DVec3::from(r.d));
        if towards <= 0.0 {
            return None;
        }
        let tc = t + above / towards;
        // Leaving the box: the traversal's own exit distance (`tc > t` here, so its floor
        // at `t` changes nothing).
        let exit = crate::traverse::exit(r, b, t).0;
        (tc <= exit).then_some(tc)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normals_and_offsets_round_trip_within_their_quantisation() {
        // Normals over the sphere (both hemispheres, the folds and the axes) come back within
        // half a degree, offsets within 0.005 half sides (a step of 4 / 2047 in units of the
        // L1-scaled normal, whose quantised length adds its own error), and out-of-range
        // offsets clamp to the range (the plane then misses the cube either way).
        let mut worst = 0f64;
        let mut k = 0;
        for i in 0..40 {
            for j in 0..80 {
                let th = std::f64::consts::PI * (i as f64 + 0.5) / 40.0;
                let ph = std::f64::consts::TAU * j as f64 / 80.0;
                let n = DVec3::new(th.sin() * ph.cos(), th.sin() * ph.sin(), th.cos());
                let off = -1.9 + 3.8 * ((k * 37) % 101) as f64 / 100.0;
                k += 1;
                let c = DVec3::new(0.3, -2.0, 5.0);
                let h = 0.125;
                let pl = SurfacePlane::new(n * 3.0, c + n * off * h, c, h);
                assert!(pl.is_some());
                let (m, o) = pl.decode();
                worst = worst.max(m.angle_between(n));
                assert!((o - off).abs() <= 0.005, "{o} vs {off}");
            }
        }
        assert!(
            worst < 0.5f64.to_radians(),
            "worst normal error {worst} rad"
        );
        // The axes (an even number of levels has no exact zero: half a step off).
        for n in [DVec3::X, DVec3::NEG_Y, DVec3::Z, DVec3::NEG_Z] {
            let (m, _) = SurfacePlane::new(n, DVec3::ZERO, DVec3::ZERO, 1.0).decode();
            assert!(m.angle_between(n) < 0.2f64.to_radians(), "{n} -> {m}");
        }
        let far = SurfacePlane::new(DVec3::Y, DVec3::Y * 9.0, DVec3::ZERO, 1.0);
        assert!((far.decode().1 - OFFSET_RANGE).abs() < 0.005);
        assert_eq!(
            SurfacePlane::new(DVec3::ZERO, DVec3::ZERO, DVec3::ZERO, 1.0),
            SurfacePlane::NONE
        );
        assert!(!SurfacePlane::NONE.is_some());
    }

    #[test]
    fn rays_stop_on_the_plane_enter_the_solid_side_or_pass() {
        // The unit-half-side cube at the origin's lattice: box [0, 1)^3 at depth 0 has half
        // side 0.5 and centre (0.5, 0.5, 0.5). Plane y = 0.5 + 0.25, normal +y.
        let b = BoxU {
            min: [0.0; 3],
            depth: 0,
        };
        let c = DVec3::splat(0.5);
        let pl = SurfacePlane::new(DVec3::Y, c + DVec3::Y * 0.25, c, 0.5);
        // Straight down from above: enters through the top face (y = 1) at t = 1, meets
        // the plane at y = 0.75.
        let down = Ray::new([0.5, 2.0, 0.5], [0.0, -1.0, 0.0], 0.0);
        let t = pl.meet(&down, &b, 1.0).unwrap();
        assert!((t - 1.25).abs() < 1e-3, "{t}");
        // Sideways below the plane: enters the solid part through the side face.
        let side = Ray::new([-1.0, 0.3, 0.5], [1.0, 0.0, 0.0], 0.0);
        assert_eq!(pl.meet(&side, &b, 1.0), Some(1.0));
        // Sideways above the plane: passes through.
        let above = Ray::new([-1.0, 0.9, 0.5], [1.0, 0.0, 0.0], 0.0);
        assert_eq!(pl.meet(&above, &b, 1.0), None);
        // Downwards at a slant that leaves through the side before reaching the plane.
        let d = DVec3::new(1.0, -0.1, 0.0).normalize();
        let graze = Ray::new([0.0, 0.95, 0.5], d.to_array(), 0.0);
        assert_eq!(pl.meet(&graze, &b, 0.0), None);
        // Upwards from inside the solid part: hit where it is.
        let up = Ray::new([0.5, 0.1, 0.5], [0.0, 1.0, 0.0], 0.0);
        assert_eq!(pl.meet(&up, &b, 0.0), Some(0.0));
        // A plane clear of the cube on its outer side (below it, normal up): every ray
        // passes, even one that starts below the plane.
        let clear = SurfacePlane::new(DVec3::Y, c - DVec3::Y * 0.6, c, 0.5);
        assert_eq!(clear.meet(&down, &b, 1.0), None);
        assert_eq!(
            clear.meet(&Ray::new([0.5, -0.3, 0.5], [0.0, 1.0, 0.0], 0.0), &b, 0.0),
            None
        );
        // A leaf whose line of sight met the surface behind it: clear for every direction,
        // the body diagonals (the largest L1 length) included.
        for n in [
            DVec3::ONE,
            DVec3::new(1.0, -1.0, 1.0),
            DVec3::NEG_Z,
            DVec3::new(0.3, 0.1, -2.0),
        ] {
            let pl = SurfacePlane::behind(n);
            assert!(pl.is_clear(), "{n}: {:?}", pl.decode());
            assert!(pl.decode().0.angle_between(n) < 0.5f64.to_radians(), "{n}");
            assert_eq!(pl.meet(&down, &b, 1.0), None);
        }
        // Clear of it on the inner side (above, normal up): solid, hit at the entry.
        let solid = SurfacePlane::new(DVec3::Y, c + DVec3::Y * 0.6, c, 0.5);
        assert_eq!(solid.meet(&side, &b, 1.0), Some(1.0));
    }
}
