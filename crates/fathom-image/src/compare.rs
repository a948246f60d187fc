//! How alike two pictures of the same view are: the one place the renderers' comparisons
//! live (the octree against the sphere tracer, the double-double reference against the f64
//! tracer, an octree frame against itself zoomed by three).
//!
//! - **SSIM on luminance** ([`ssim`], [`luminance`]): the structural similarity index (Wang et
//!   al. 2004) of the display luminance (tonemapped, sRGB-encoded, Rec. 709 weights), over 8x8
//!   windows placed every 4 pixels (uniform weights, `C1 = 0.01^2`, `C2 = 0.03^2`), averaged;
//! - **silhouette IoU** ([`Overlap`], [`silhouette_iou`]): hit pixels of both over hit pixels
//!   of either (1 when neither hits anything);
//! - **colour error** ([`agreement`]): over pixels both hit, the mean absolute difference of
//!   the display colour per channel (0..1) and the fraction of pixels within [`COLOUR_TOL`] on
//!   every channel; [`packed_similarity`] does the same for 8-bit packed colours;
//! - **block reduction** ([`reduce`], [`covers`]): a frame made smaller so that it can be
//!   compared with a point-sampled reference of fewer pixels.

use crate::post::{srgb, tonemap};
use fathom_core::frame::Frame;
use serde::Serialize;

/// Per-channel display-colour difference (0..1) within which a pixel counts as matching.
pub const COLOUR_TOL: f64 = 0.1;

/// Window side and stride of the SSIM.
const WIN: usize = 8;
const STRIDE: usize = 4;

/// How close two frames of the same size are.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct Agreement {
    /// SSIM of the display luminance, in [-1, 1] (1: identical).
    pub ssim: f64,
    /// Silhouette intersection over union (1 when neither frame hits anything).
    pub iou: f64,
    /// Mean absolute display-colour difference per channel over pixels both frames hit.
    pub colour_error: f64,
    /// Fraction of the pixels both frames hit whose display colours are within
    /// [`COLOUR_TOL`] on every channel (1 when there are none).
    pub colour_within: f64,
}

/// Counts of hit pixels of two silhouettes of the same size, `a` and `b`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Overlap {
    /// Pixels both hit.
    pub both: usize,
    /// Pixels either hits.
    pub either: usize,
    /// Pixels `b` hits and `a` misses (`a`'s false negatives when `b` is the reference).
    pub only_b: usize,
}

impl Overlap {
    /// The overlap of two silhouettes given pixel by pixel (true: hit).
    pub fn of(a: impl IntoIterator<Item = bool>, b: impl IntoIterator<Item = bool>) -> Overlap {
        let mut o = Overlap::default();
        for (x, y) in a.into_iter().zip(b) {
            o.add(x, y);
        }
        o
    }

    /// Counts one pixel that `a` hits or not, and `b` hits or not.
    pub fn add(&mut self, a: bool, b: bool) {
        self.both += (a && b) as usize;
        self.either += (a || b) as usize;
        self.only_b += (!a && b) as usize;
    }

    /// Intersection over union: [`Overlap::both`] over [`Overlap::either`], 1 when neither
    /// silhouette hits anything (nothing to disagree about).
    pub fn iou(&self) -> f64 {
        if self.either == 0 {
            1.0
        } else {
            self.both as f64 / self.either as f64
        }
    }
}

/// Silhouette intersection over union of two depth images of the same size (`Some`: a hit):
/// pixels both hit over pixels either hits (1 when neither hits anything).
pub fn silhouette_iou(a: &[Option<f64>], b: &[Option<f64>]) -> f64 {
    assert_eq!(a.len(), b.len(), "depth images differ in size");
    Overlap::of(a.iter().map(Option::is_some), b.iter().map(Option::is_some)).iou()
}

/// Display value of a linear channel: tonemapped and sRGB-encoded, in [0, 1].
fn display(x: f32) -> f64 {
    srgb(tonemap(x)) as f64
}

/// Display luminance (Rec. 709 weights on the encoded channels) of every pixel.
pub fn luminance(f: &Frame) -> Vec<f64> {
    f.colour
        .iter()
        .map(|c| 0.2126 * display(c[0]) + 0.7152 * display(c[1]) + 0.0722 * display(c[2]))
        .collect()
}

/// Mean SSIM of two luminance images of `w` x `h` (see the module comment); images smaller
/// than one window are compared as one window.
pub fn ssim(a: &[f64], b: &[f64], w: usize, h: usize) -> f64 {
    const C1: f64 = 0.01 * 0.01;
    const C2: f64 = 0.03 * 0.03;
    let (ww, wh) = (WIN.min(w), WIN.min(h));
    let starts = |len: usize, win: usize| {
        let mut v: Vec<usize> = (0..=len.saturating_sub(win)).step_by(STRIDE).collect();
        if v.last() != Some(&(len.saturating_sub(win))) {
            v.push(len.saturating_sub(win));
        }
        v
    };
    let (xs, ys) = (starts(w, ww), starts(h, wh));
    let mut sum = 0.0;
    let mut n = 0usize;
    for &y0 in &ys {
        for &x0 in &xs {
            let (mut sa, mut sb, mut saa, mut sbb, mut sab) = (0.0, 0.0, 0.0, 0.0, 0.0);
            for y in y0..y0 + wh {
                for x in x0..x0 + ww {
                    let (p, q) = (a[y * w + x], b[y * w + x]);
                    sa += p;
                    sb += q;
                    saa += p * p;
                    sbb += q * q;
                    sab += p * q;
                }
            }
            let k = (ww * wh) as f64;
            let (ma, mb) = (sa / k, sb / k);
            let va = (saa / k - ma * ma).max(0.0);
            let vb = (sbb / k - mb * mb).max(0.0);
            let cov = sab / k - ma * mb;
            sum += ((2.0 * ma * mb + C1) * (2.0 * cov + C2))
                / ((ma * ma + mb * mb + C1) * (va + vb + C2));
            n += 1;
        }
    }
    if n == 0 { 1.0 } else { sum / n as f64 }
}

/// Compares frame `a` with frame `b` (same size; e.g. an octree frame and the tracer's): a hit
/// is a finite depth.
pub fn agreement(a: &Frame, b: &Frame) -> Agreement {
    assert_eq!(
        (a.width, a.height),
        (b.width, b.height),
        "frames differ in size"
    );
    let (w, h) = (a.width as usize, a.height as usize);
    let ssim = ssim(&luminance(a), &luminance(b), w, h);
    let mut overlap = Overlap::default();
    let (mut err, mut within) = (0.0, 0usize);
    for i in 0..w * h {
        let (ha, hb) = (a.depth[i].is_finite(), b.depth[i].is_finite());
        overlap.add(ha, hb);
        if ha && hb {
            let d: [f64; 3] =
                std::array::from_fn(|k| (display(a.colour[i][k]) - display(b.colour[i][k])).abs());
            err += d.iter().sum::<f64>() / 3.0;
            within += d.iter().all(|&x| x <= COLOUR_TOL) as usize;
        }
    }
    let inter = overlap.both;
    Agreement {
        ssim,
        iou: overlap.iou(),
        colour_error: if inter == 0 { 0.0 } else { err / inter as f64 },
        colour_within: if inter == 0 {
            1.0
        } else {
            within as f64 / inter as f64
        },
    }
}

/// Fractions of pixels that are identical, and whose colours differ by at most `tol` (0..1)
/// on every channel, between two images of the same size in 8-bit channels packed into a
/// `u32` (red in the low byte).
pub fn packed_similarity(a: &[u32], b: &[u32], tol: f64) -> (f64, f64) {
    let n = a.len().max(1) as f64;
    let mut same = 0usize;
    let mut close = 0usize;
    for (&x, &y) in a.iter().zip(b) {
        if x == y {
            same += 1;
        }
        let ok = (0..3).all(|i| {
            let (u, v) = ((x >> (8 * i)) & 255, (y >> (8 * i)) & 255);
            (u as f64 - v as f64).abs() <= tol * 255.0
        });
        if ok {
            close += 1;
        }
    }
    (same as f64 / n, close as f64 / n)
}

/// Whether a pixel made of `samples` rays (or, reduced, of `samples` pixels) of which `hits`
/// hit counts as a hit: at least half of them. A point-sampled reference's pixels and the
/// blocks of [`reduce`] follow the same rule.
pub fn covers(hits: u32, samples: u32) -> bool {
    2 * hits >= samples
}

/// `frame` reduced by `f` (dividing both sides): each `f` x `f` block becomes a pixel whose
/// colour is the block's mean, which is a hit (at the block's nearest depth) when the block
/// [`covers`] it. A point-sampled reference pixel is then compared with what the block shows
/// on the whole.
pub fn reduce(frame: &Frame, f: u32) -> Frame {
    if f == 1 {
        return frame.clone();
    }
    let (w, h) = (frame.width / f, frame.height / f);
    let mut out = Frame::new(w, h);
    let n = (f * f) as f32;
    for y in 0..h {
        for x in 0..w {
            let o = out.index(x, y);
            let (mut c, mut hits, mut near) = ([0f32; 3], 0u32, f32::INFINITY);
            for sy in 0..f {
                for sx in 0..f {
                    let i = frame.index(x * f + sx, y * f + sy);
                    for (acc, v) in c.iter_mut().zip(frame.colour[i]) {
                        *acc += v;
                    }
                    if frame.depth[i].is_finite() {
                        hits += 1;
                        near = near.min(frame.depth[i]);
                    }
                }
            }
            out.colour[o] = c.map(|v| v / n);
            if covers(hits, f * f) {
                out.depth[o] = near;
            }
        }
    }
    out
}

/// `left` and `right` side by side on black, `gap` pixels apart (a comparison image).
pub fn side_by_side(left: &Frame, right: &Frame, gap: u32) -> Frame {
    let mut f = Frame::new(
        left.width + gap + right.width,
        left.height.max(right.height),
    );
    f.paste(left, 0, 0);
    f.paste(right, left.width + gap, 0);
    f
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame(w: u32, h: u32, f: impl Fn(u32, u32) -> Option<f32>) -> Frame {
        let mut fr = Frame::new(w, h);
        for y in 0..h {
            for x in 0..w {
                if let Some(v) = f(x, y) {
                    let i = (y * w + x) as usize;
                    fr.colour[i] = [v; 3];
                    fr.depth[i] = 1.0;
                }
            }
        }
        fr
    }

    #[test]
    fn reduction_averages_colour_and_hits_where_half_the_block_does() {
        let f = frame(4, 2, |x, _| (x == 0 || x == 3).then_some(1.0));
        let r = reduce(&f, 2);
        assert_eq!((r.width, r.height), (2, 1));
        assert!(r.depth[0].is_finite() && r.depth[1].is_finite());
        assert_eq!(r.colour[0], [0.5; 3]);
        let g = frame(4, 2, |x, y| (x == 0 && y == 0).then_some(1.0));
        assert!(!reduce(&g, 2).depth[0].is_finite());
    }

    #[test]
    fn identical_frames_agree_fully_and_different_ones_do_not() {
        let a = frame(32, 24, |x, y| {
            (x > 4).then_some(((x * 7 + y * 3) % 11) as f32 / 11.0)
        });
        let same = agreement(&a, &a);
        assert!((same.ssim - 1.0).abs() < 1e-9, "{same:?}");
        assert_eq!(
            (same.iou, same.colour_error, same.colour_within),
            (1.0, 0.0, 1.0)
        );
        // Flat colour where `a` has texture: silhouettes agree, structure does not.
        let flat = frame(32, 24, |x, _| (x > 4).then_some(0.45));
        let d = agreement(&a, &flat);
        assert_eq!(d.iou, 1.0);
        assert!(d.ssim < 0.5, "{d:?}");
        assert!(d.colour_error > 0.05 && d.colour_within < 1.0, "{d:?}");
        // Half the silhouette missing.
        let half = frame(32, 24, |x, y| (x > 4 && y < 12).then_some(0.45));
        assert!((agreement(&a, &half).iou - 0.5).abs() < 1e-9);
    }

    #[test]
    fn overlaps_count_both_either_and_misses() {
        let o = Overlap::of([true, true, false, false], [true, false, true, false]);
        assert_eq!((o.both, o.either, o.only_b), (1, 3, 1));
        assert!((o.iou() - 1.0 / 3.0).abs() < 1e-12);
        assert_eq!(Overlap::default().iou(), 1.0);
        assert_eq!(
            silhouette_iou(&[None, Some(1.0)], &[Some(2.0), Some(1.0)]),
            0.5
        );
    }

    #[test]
    fn packed_colours_within_the_tolerance_are_close() {
        let (same, close) = packed_similarity(
            &[0x00_10_20_30, 0x00_00_00_00],
            &[0x00_10_20_30, 0x00_00_00_40],
            0.1,
        );
        assert_eq!((same, close), (0.5, 0.5));
        let (_, close) = packed_similarity(&[0], &[0x00_00_00_19], 0.1);
        assert_eq!(close, 1.0);
    }
}
