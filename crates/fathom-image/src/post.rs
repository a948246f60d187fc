//! Post effects on a [`Frame`]: distance fog, screen-space ambient occlusion, supersampling
//! reduction, NaN scrubbing and tonemapping to 8-bit sRGB. They read only the frame, so every
//! renderer that fills one (the octree and GPU renderers too) shares them, and
//! [`finish_view`] is the one place that says which run, in what order, on each eye's view.

use fathom_core::frame::{Frame, NO_ID, Rect};

/// How far (in samples) SSAO looks from a pixel: a region render traces this much more so
/// its border pixels see the same neighbours as in the whole image.
pub const SSAO_REACH: u32 = 6;

/// The post effects of one view.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PostParams {
    /// SSAO strength (0: none; callers pass 0 for ODS and geometry-only renders).
    pub ssao: f32,
    /// Angular size of a sample at the view's centre (radians), for SSAO.
    pub pixel_angle: f32,
    /// Fog density per world unit (0: none).
    pub fog: f32,
    /// Fog colour, linear RGB.
    pub fog_colour: [f32; 3],
    /// Samples per pixel along each axis.
    pub supersample: u32,
}

/// Finishes one eye's view: `frame` holds the samples of `traced` (a rectangle of the view's
/// sample grid), of which the pixels of `keep` (inside `traced`, a multiple of the supersampling
/// on every side) are wanted. Runs SSAO, then fog (so fog veils the occlusion, as in the
/// air), crops to `keep`, averages the supersamples and scrubs NaNs. Every renderer's frames go
/// through here.
pub fn finish_view(mut frame: Frame, traced: Rect, keep: Rect, p: &PostParams) -> Frame {
    if p.ssao > 0.0 {
        ssao(&mut frame, p.ssao, p.pixel_angle);
    }
    if p.fog > 0.0 {
        fog(&mut frame, p.fog, p.fog_colour);
    }
    let mut f = if keep == traced {
        frame
    } else {
        frame.crop(keep.relative_to(traced.x, traced.y))
    };
    if p.supersample > 1 {
        f = downsample(&f, p.supersample);
    }
    sanitize(&mut f);
    f
}

/// Exponential distance fog towards `colour` (linear RGB), `density` per world unit. Misses
/// keep their sky.
pub fn fog(frame: &mut Frame, density: f32, colour: [f32; 3]) {
    for (c, &d) in frame.colour.iter_mut().zip(&frame.depth) {
        if d.is_finite() {
            let f = 1.0 - (-density * d).exp();
            for i in 0..3 {
                c[i] += (colour[i] - c[i]) * f;
            }
        }
    }
}

/// Screen-space ambient occlusion: darkens a hit by how many of its neighbours (8 directions,
/// two radii) stand in front of its tangent plane, weighted by `strength`. `pixel_angle` turns
/// pixel offsets into world distances at the hit's depth.
pub fn ssao(frame: &mut Frame, strength: f32, pixel_angle: f32) {
    let (w, h) = (frame.width as i64, frame.height as i64);
    let dirs = [
        (1, 0),
        (1, 1),
        (0, 1),
        (-1, 1),
        (-1, 0),
        (-1, -1),
        (0, -1),
        (1, -1),
    ];
    let mut factor = vec![1f32; frame.len()];
    for y in 0..h {
        for x in 0..w {
            let i = (y * w + x) as usize;
            let d = frame.depth[i];
            if !d.is_finite() {
                continue;
            }
            let mut occ = 0f32;
            let mut n = 0f32;
            for r in [2i64, SSAO_REACH as i64] {
                for (dx, dy) in dirs {
                    let (sx, sy) = (x + dx * r, y + dy * r);
                    if sx < 0 || sy < 0 || sx >= w || sy >= h {
                        continue;
                    }
                    let ds = frame.depth[(sy * w + sx) as usize];
                    n += 1.0;
                    // Closer neighbours within a few footprints of radius occlude.
                    let gap = d - ds;
                    let reach = r as f32 * pixel_angle * d * 4.0;
                    if ds.is_finite() && gap > 0.0 && gap < reach {
                        occ += gap / reach;
                    }
                }
            }
            if n > 0.0 {
                factor[i] = (1.0 - strength * occ / n).clamp(0.0, 1.0);
            }
        }
    }
    for (c, f) in frame.colour.iter_mut().zip(factor) {
        for v in c.iter_mut() {
            *v *= f;
        }
    }
}

/// Averages `ss` x `ss` blocks of colour; depth, normal and id come from the nearest sample of
/// each block, steps are the block's mean.
pub fn downsample(big: &Frame, ss: u32) -> Frame {
    let (w, h) = (big.width / ss, big.height / ss);
    let mut f = Frame::new(w, h);
    let inv = 1.0 / (ss * ss) as f32;
    for y in 0..h {
        for x in 0..w {
            let o = f.index(x, y);
            let mut c = [0f32; 3];
            let mut best = None::<usize>;
            let mut steps = 0u64;
            for sy in 0..ss {
                for sx in 0..ss {
                    let i = big.index(x * ss + sx, y * ss + sy);
                    for (acc, v) in c.iter_mut().zip(big.colour[i]) {
                        *acc += v;
                    }
                    steps += big.steps[i] as u64;
                    if best.is_none_or(|b| big.depth[i] < big.depth[b]) {
                        best = Some(i);
                    }
                }
            }
            f.colour[o] = c.map(|v| v * inv);
            let b = best.expect("ss >= 1");
            f.depth[o] = big.depth[b];
            f.normal[o] = big.normal[b];
            f.id[o] = big.id[b];
            f.steps[o] = (steps / (ss * ss) as u64) as u32;
        }
    }
    f
}

/// Replaces non-finite colours and normals by zero, and non-finite depths by a miss, so no NaN
/// or infinity reaches an output pixel.
pub fn sanitize(frame: &mut Frame) {
    for i in 0..frame.len() {
        let c = &mut frame.colour[i];
        for v in c.iter_mut() {
            if !v.is_finite() {
                *v = 0.0;
            }
        }
        if frame.depth[i].is_nan() || frame.depth[i] < 0.0 {
            frame.depth[i] = f32::INFINITY;
        }
        if !frame.depth[i].is_finite() {
            frame.id[i] = NO_ID;
        }
        if frame.normal[i].iter().any(|v| !v.is_finite()) {
            frame.normal[i] = [0.0; 3];
        }
    }
}

/// A soft shoulder above 0.8 so highlights roll off instead of clipping.
#[inline]
pub fn tonemap(x: f32) -> f32 {
    if !x.is_finite() || x <= 0.0 {
        0.0
    } else if x < 0.8 {
        x
    } else {
        0.8 + 0.2 * (1.0 - (-(x - 0.8) / 0.2).exp())
    }
}

/// Linear [0, 1] to the sRGB transfer curve.
#[inline]
pub fn srgb(x: f32) -> f32 {
    let x = x.clamp(0.0, 1.0);
    if x <= 0.003_130_8 {
        12.92 * x
    } else {
        1.055 * x.powf(1.0 / 2.4) - 0.055
    }
}

/// Tonemapped, gamma-encoded 8-bit RGB, row-major.
pub fn to_rgb8(frame: &Frame) -> Vec<u8> {
    frame
        .colour
        .iter()
        .flat_map(|c| c.map(|v| (srgb(tonemap(v)) * 255.0 + 0.5) as u8))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn non_finite_values_never_reach_pixels() {
        let mut f = Frame::new(2, 1);
        f.colour[0] = [f32::NAN, f32::INFINITY, -1.0];
        f.depth[1] = f32::NAN;
        sanitize(&mut f);
        assert_eq!(to_rgb8(&f)[..3], [0, 0, 0]);
        assert!(!f.is_hit(1));
        assert_eq!(tonemap(f32::INFINITY), 0.0);
        assert!(tonemap(100.0) <= 1.0 && tonemap(0.5) == 0.5);
    }

    #[test]
    fn fog_fades_far_hits_to_the_fog_colour() {
        let mut f = Frame::new(2, 1);
        f.depth = vec![1e6, 0.0];
        f.colour = vec![[1.0; 3], [1.0; 3]];
        fog(&mut f, 1.0, [0.0; 3]);
        assert!(f.colour[0][0] < 1e-6 && f.colour[1][0] == 1.0);
    }

    #[test]
    fn downsample_averages_colour_and_keeps_nearest_depth() {
        let mut f = Frame::new(2, 2);
        f.colour = vec![[1.0; 3], [0.0; 3], [0.0; 3], [1.0; 3]];
        f.depth = vec![f32::INFINITY, 2.0, 1.0, 3.0];
        f.id = vec![NO_ID, 7, 8, 9];
        let d = downsample(&f, 2);
        assert_eq!(d.colour[0], [0.5; 3]);
        assert_eq!((d.depth[0], d.id[0]), (1.0, 8));
    }
}
