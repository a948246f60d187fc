//! The surface plane of a full leaf: where, inside its cube, a ray larger voxels would stop
//! at the cube's face meets the surface instead.
//!
//! During a zoom most visible leaves are wider than a pixel (detail arrives a few hundred
//! subdivisions a frame), and drawn as cubes they turn a smooth surface into a staircase of
//! faces with a cube's silhouette. Each full leaf therefore keeps, next to its colour, the
//! plane whose normal is the distance gradient at the point its colour was shaded at, through
//! that point moved onto the surface by a Newton step (the line of sight that found it stops
//! up to a quarter side short; the distance and gradient there are already computed for the
//! colour: no extra evaluation); a leaf whose line of sight passed it and met the surface
//! behind keeps that surface's plane, marked so that it counts as clear of its cube
//! ([`SurfacePlane::behind`]).
//!
//! With `--planes`, a ray that ends on a leaf wider than its pixel stops where it crosses
//! that plane inside the cube, or at the entry point when it enters the cube on the plane's
//! inner side; when it crosses the cube on the outer side it passes on to the next leaf. The
//! cube cut by the plane is the leaf's solid part, like the contours of Laine and Karras's
//! efficient sparse voxel octrees (2010), from a distance field instead of from geometry.
//! Without it (the default) rays stop at the cube, but the pixel is drawn at the depth where
//! the ray reaches the plane ([`SurfacePlane::depth`]), so the screen-space occlusion sees the
//! surface rather than a staircase of cubes. Leaves a pixel wide or smaller draw as before.
//!
//! Stored in 5 bytes: a valid bit, the normal in octahedral form (two 10-bit coordinates) and
//! the offset of the plane from the cube's centre along the normal (11 bits over
//! `[-OFFSET_RANGE, OFFSET_RANGE]`) in half sides; for a plane behind the leaf, in units of as
//! many half sides as the fifth byte says. Our own code: a dozen lines of encoding that the
//! traversal reads in its inner loop.

use crate::geometry::{BoxU, Ray, exit};
use glam::DVec3;

/// Offsets are clamped to this many half sides: past the cube's support (`sqrt(3)` at most)
/// the plane misses the cube, and the cube is either all solid or all passed through.
pub const OFFSET_RANGE: f64 = 2.0;

/// How far past a leaf's entry, in sides of the leaf, [`SurfacePlane::depth`] follows a ray to
/// its plane: rays within 64 degrees of the normal reach it from anywhere in the cube (the
/// plane is at most a diagonal, `sqrt(3)` sides, from the entry); more grazing ones may be
/// drawn at this distance instead.
pub const DEPTH_REACH: f64 = 4.0;

const VALID: u32 = 1 << 31;
const NORMAL_BITS: u32 = 10;
const OFFSET_BITS: u32 = 11;

/// A full leaf's surface plane (see the module documentation), or none
/// ([`SurfacePlane::NONE`]): the leaf is drawn as its cube. Packed into 5 bytes so that the
/// node keeps its 48 ([`crate::node`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[repr(C, packed)]
pub struct SurfacePlane {
    /// The valid bit, the octahedral normal and the offset.
    bits: u32,
    /// 0 for a plane through the leaf's own surface point; else the leaf's line of sight
    /// met the surface behind it ([`SurfacePlane::behind`]), and the offset is in units of
    /// this many half sides.
    behind: u8,
}

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
    pub const NONE: SurfacePlane = SurfacePlane { bits: 0, behind: 0 };

    /// The plane through `p` with normal `n` (any length; none when it is zero or not
    /// finite) of the cube with centre `c` and half side `h`, all in one frame (world or
    /// root units alike: the plane is stored relative to the cube).
    ///
    /// Stored as `m . (x - c) = k h` with `m` the normal scaled to `|m_x| + |m_y| + |m_z| = 1`
    /// (the octahedral map's own vector, so decoding needs no square root) and `k` the
    /// offset in those units.
    pub fn new(n: DVec3, p: DVec3, c: DVec3, h: f64) -> SurfacePlane {
        l1_offset(n, p, c, h).map_or(SurfacePlane::NONE, |(m, k)| SurfacePlane::encode(m, k, 0))
    }

    /// The stored form of the plane `m . (x - c) = k h` (`m` of unit L1 length; `k` in units
    /// of `behind` half sides, 0 meaning 1 for a leaf's own plane).
    fn encode(m: DVec3, k: f64, behind: u8) -> SurfacePlane {
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
        SurfacePlane {
            bits: VALID | qu | qv << NORMAL_BITS | qk << (2 * NORMAL_BITS),
            behind,
        }
    }

    /// The plane of a leaf (centre `c`, half side `h`) whose line of sight passes it and
    /// meets the surface behind it at `p`: that surface's plane there (normal `n`, any length;
    /// `toward` when `n` is zero, the line's direction back to the eye), its offset in units
    /// of as many half sides as keep it within [`OFFSET_RANGE`] (up to 255). Always
    /// [`SurfacePlane::is_clear`]: rays pass the leaf, as the line of sight did (it says that
    /// line met no surface in the cube, not that none crosses it); a ray stopped at the cube
    /// is drawn at that surface's depth ([`SurfacePlane::depth`]).
    pub fn behind(n: DVec3, toward: DVec3, p: DVec3, c: DVec3, h: f64) -> SurfacePlane {
        let n = if n.is_finite() && n != DVec3::ZERO {
            n
        } else {
            toward
        };
        match l1_offset(n, p, c, h) {
            Some((m, k)) => {
                let scale = (k.abs() / OFFSET_RANGE).ceil().clamp(1.0, 255.0);
                SurfacePlane::encode(m, k / scale, scale as u8)
            }
            // Only non-finite points: some plane well behind the cube, still marked behind.
            None => SurfacePlane::encode(DVec3::Z, -OFFSET_RANGE, 1),
        }
    }

    /// Whether rays pass the leaf because its line of sight met the surface behind it.
    #[inline(always)]
    pub fn is_behind(self) -> bool {
        self.behind != 0
    }

    /// True when the leaf has a plane.
    #[inline(always)]
    pub fn is_some(self) -> bool {
        self.bits & VALID != 0
    }

    /// The normal scaled to unit L1 length and the offset from the cube's centre in half
    /// sides of it (see [`SurfacePlane::new`]).
    #[inline(always)]
    fn decode_l1(self) -> (DVec3, f64) {
        let mask = (1 << NORMAL_BITS) - 1;
        let bits = self.bits;
        let u = dequantise(bits & mask, NORMAL_BITS, 1.0);
        let v = dequantise(bits >> NORMAL_BITS & mask, NORMAL_BITS, 1.0);
        let w = 1.0 - u.abs() - v.abs();
        let (x, y) = if w >= 0.0 {
            (u, v)
        } else {
            ((1.0 - v.abs()).copysign(u), (1.0 - u.abs()).copysign(v))
        };
        let k = bits >> (2 * NORMAL_BITS) & ((1 << OFFSET_BITS) - 1);
        (
            DVec3::new(x, y, w),
            dequantise(k, OFFSET_BITS, OFFSET_RANGE),
        )
    }

    /// True when the plane lies clear of the cube on its outer side (the leaf's surface point
    /// is outside it) or the leaf's line of sight met the surface behind it: rays pass the
    /// whole leaf.
    pub fn is_clear(self) -> bool {
        self.is_behind() || self.is_some() && self.decode_l1().1 <= -1.0
    }

    /// The unit normal and the offset of the plane from the cube's centre along it, in half
    /// sides.
    pub fn decode(self) -> (DVec3, f64) {
        let (m, k) = self.decode_l1();
        let len = m.length();
        (m / len, k * self.scale() / len)
    }

    /// Half sides per unit of the stored offset.
    #[inline(always)]
    fn scale(self) -> f64 {
        f64::from(self.behind.max(1))
    }

    /// Where ray `r`, entering the leaf with box `b` (root units) at `t`, meets its solid
    /// part: `t` when it enters on the plane's inner side, the crossing when it crosses the
    /// plane inwards before leaving the box, else `None` (it passes through the leaf).
    #[inline(always)]
    pub fn meet(self, r: &Ray, b: &BoxU, t: f64) -> Option<f64> {
        // Every ray passes a leaf whose line of sight met the surface behind it (most of the
        // wide leaves a Mandelbulb zoom's rays meet): no decoding for those.
        if self.is_behind() {
            return None;
        }
        let (m, k) = self.decode_l1();
        // With `m` of unit L1 length the cube's support along it is one half side: with the
        // plane further than that behind the centre the whole cube is on the outer side (a
        // leaf the conservative full test kept whose surface point lies outside it), and
        // every ray passes.
        if k <= -1.0 {
            return None;
        }
        let tc = reach(m, k, r, b, t)?;
        if tc <= t {
            return Some(t);
        }
        // Leaving the box: the traversal's own exit distance (`tc > t` here, so its floor
        // at `t` changes nothing).
        let exit = exit(r, b, t).0;
        (tc <= exit).then_some(tc)
    }

    /// The distance a ray stopped at the leaf's cube is drawn at when the leaf is not cut by
    /// its plane (`--planes` off, or the leaf narrower than the planes' threshold): where it
    /// reaches the plane, wherever that is past the entry `t` (at most [`DEPTH_REACH`] sides
    /// on, plus the offset's scale for a plane behind the leaf), else `t`. Clear planes
    /// count: the depth is that of the surface the leaf's colour was shaded at. Only the
    /// depth changes, not which leaf the ray stops at or its colour.
    ///
    /// A ray that enters a leaf of a smooth surface above the plane and leaves it before
    /// reaching it would meet the surface in the next leaf, near the same plane, so the
    /// crossing of this leaf's plane is the depth its surface has there. Drawn at the
    /// cube's face instead, the depth steps by up to a voxel between neighbouring leaves, and
    /// the screen-space occlusion that follows darkens every step: a smooth Mandelbulb wall
    /// became a staircase of cubes during zooms.
    #[inline(always)]
    pub fn depth(self, r: &Ray, b: &BoxU, t: f64) -> f64 {
        let (m, k) = self.decode_l1();
        let most = (DEPTH_REACH + f64::from(self.behind)) * b.dim();
        reach(m, k * self.scale(), r, b, t).map_or(t, |tc| tc.min(t + most))
    }
}

/// The normal `n` scaled to unit L1 length and the offset of the plane through `p` from the
/// centre `c` along it, in half sides `h`; `None` when `n` is zero or not finite, or the
/// offset is not finite.
fn l1_offset(n: DVec3, p: DVec3, c: DVec3, h: f64) -> Option<(DVec3, f64)> {
    let l1 = n.x.abs() + n.y.abs() + n.z.abs();
    if !(l1.is_finite() && l1 > 0.0 && h.is_finite() && h > 0.0) {
        return None;
    }
    let m = n / l1;
    let k = m.dot(p - c) / h;
    k.is_finite().then_some((m, k))
}

/// Where ray `r`, entering the box `b` at `t`, reaches the inner side of the plane
/// `m . (x - centre) = k h` (`m` of unit L1 length, `h` the half side): `t` when it enters
/// there, the crossing when it heads inwards (however far past the box), `None` when it
/// heads away from it.
#[inline(always)]
fn reach(m: DVec3, k: f64, r: &Ray, b: &BoxU, t: f64) -> Option<f64> {
    let h = b.dim() * 0.5;
    // The entry point relative to the centre (root units near the anchor: exact enough at
    // any depth, the box's own scale).
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
    Some(t + above / towards)
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

    /// The unit-half-side cube at the origin's lattice (box [0, 1)^3 at depth 0: half side
    /// 0.5, centre (0.5, 0.5, 0.5)), its centre, the plane y = 0.5 + 0.25 with normal +y,
    /// and a ray straight down from above, entering through the top face (y = 1) at t = 1.
    fn cube_plane_and_ray_down() -> (BoxU, DVec3, SurfacePlane, Ray) {
        let b = BoxU {
            min: [0.0; 3],
            depth: 0,
        };
        let c = DVec3::splat(0.5);
        let pl = SurfacePlane::new(DVec3::Y, c + DVec3::Y * 0.25, c, 0.5);
        (b, c, pl, Ray::new([0.5, 2.0, 0.5], [0.0, -1.0, 0.0], 0.0))
    }

    #[test]
    fn rays_stop_on_the_plane_enter_the_solid_side_or_pass() {
        let (b, c, pl, down) = cube_plane_and_ray_down();
        // Straight down: meets the plane at y = 0.75.
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
        // A leaf whose line of sight met the surface behind it: clear for every normal and
        // offset, even one through the cube (the surface's plane behind it may cross it);
        // offsets past the range kept in a coarser unit.
        for (n, off) in [
            (DVec3::ONE, -3.0),
            (DVec3::new(1.0, -1.0, 1.0), -40.0),
            (DVec3::NEG_Z, 0.5),
            (DVec3::new(0.3, 0.1, -2.0), -300.0),
        ] {
            let p = c + n.normalize() * off * 0.5;
            let pl = SurfacePlane::behind(n, DVec3::Y, p, c, 0.5);
            assert!(pl.is_clear(), "{n}: {:?}", pl.decode());
            let (m, o) = pl.decode();
            assert!(m.angle_between(n) < 0.5f64.to_radians(), "{n}");
            assert!(
                (o - off).abs() <= 0.005 * off.abs().max(1.0),
                "{n}: {o} vs {off}"
            );
            assert_eq!(pl.meet(&down, &b, 1.0), None);
        }
        // Without a normal: the line of sight's way back to the eye.
        let pl = SurfacePlane::behind(DVec3::ZERO, DVec3::Y, c - DVec3::Y * 2.0, c, 0.5);
        assert!(pl.is_clear() && pl.decode().0.angle_between(DVec3::Y) < 1e-3);
        // Clear of it on the inner side (above, normal up): solid, hit at the entry.
        let solid = SurfacePlane::new(DVec3::Y, c + DVec3::Y * 0.6, c, 0.5);
        assert_eq!(solid.meet(&side, &b, 1.0), Some(1.0));
    }

    #[test]
    fn rays_stopped_at_the_cube_are_drawn_where_they_reach_its_plane() {
        let (b, c, pl, down) = cube_plane_and_ray_down();
        // Through the plane inside the cube: where `meet` stops it.
        assert_eq!(pl.depth(&down, &b, 1.0), pl.meet(&down, &b, 1.0).unwrap());
        // Leaving through the side above the plane (y = 0.95 - 0.1 x): reaches y = 0.75
        // at x = 2, past the cube, where the next leaf of a flat surface would stop it.
        let d = DVec3::new(1.0, -0.1, 0.0).normalize();
        let graze = Ray::new([0.0, 0.95, 0.5], d.to_array(), 0.0);
        let t = pl.depth(&graze, &b, 0.0);
        assert!((t - 2.0 * d.length() / d.x).abs() < 0.01, "{t}");
        // Nearer grazing than the reach: drawn DEPTH_REACH sides on.
        let d = DVec3::new(1.0, -0.01, 0.0).normalize();
        let flat = Ray::new([0.0, 0.95, 0.5], d.to_array(), 0.0);
        assert_eq!(pl.depth(&flat, &b, 0.0), DEPTH_REACH);
        // Entering the solid side, heading away from the plane, or a clear plane: the entry.
        let side = Ray::new([-1.0, 0.3, 0.5], [1.0, 0.0, 0.0], 0.0);
        assert_eq!(pl.depth(&side, &b, 1.0), 1.0);
        let away = Ray::new(
            [0.5, 0.9, -1.0],
            DVec3::new(0.0, 0.2, 1.0).normalize().to_array(),
            0.0,
        );
        assert_eq!(pl.depth(&away, &b, 1.0), 1.0);
        // A clear plane or one behind the leaf: drawn where the ray reaches it, past the box.
        let clear = SurfacePlane::new(DVec3::Y, c - DVec3::Y * 0.6, c, 0.5);
        assert!((clear.depth(&down, &b, 1.0) - 2.1).abs() < 1e-3);
        let behind = SurfacePlane::behind(DVec3::Y, DVec3::Y, c - DVec3::Y * 3.0, c, 0.5);
        assert!((behind.depth(&down, &b, 1.0) - 4.5).abs() < 0.02);
        // Far behind (200 half sides, kept in units of 100): reached within the offset's
        // quantisation; a grazing ray no further than the reach plus that scale.
        let far = SurfacePlane::behind(DVec3::Y, DVec3::Y, c - DVec3::Y * 100.0, c, 0.5);
        assert!((far.depth(&down, &b, 1.0) - 101.5).abs() < 0.2);
        assert_eq!(far.depth(&flat, &b, 0.0), DEPTH_REACH + 100.0);
    }
}
