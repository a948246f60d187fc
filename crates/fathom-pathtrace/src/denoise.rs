//! An edge-aware à-trous wavelet denoiser in the manner of SVGF (Schied et al. 2017,
//! "Spatiotemporal Variance-Guided Filtering", after Dammertz et al. 2010, "Edge-Avoiding
//! À-Trous Wavelet Transform for fast Global Illumination Filtering"), spatial part only.
//!
//! The colour is divided by the first-hit albedo (texture detail and trap colours are not
//! noise and must not be blurred), the resulting irradiance is filtered by [`ATROUS_PASSES`]
//! passes of a 5x5 B3-spline kernel with holes (step 1, 2, 4, ...), each tap weighted by
//! - normals: max(0, n_p . n_q)^sigma_n;
//! - depth: exp(-|z_p - z_q| / (sigma_z |grad z_p| |offset| + eps)) (planes at any slope
//!   pass, depth discontinuities stop the filter);
//! - luminance: exp(-|l_p - l_q| / (sigma_l sqrt(g3x3(var_p)) + eps)), where var is the
//!   variance of the pixel's mean from the accumulator, itself filtered with the squared
//!   weights each pass, so the filter relaxes as noise falls;
//!
//! and finally multiplied by the albedo again. Sky pixels (no hit) only mix with sky pixels.
//!
//! The code is plain loops over flat buffers with each weight a small function, so a WGSL
//! compute shader can follow it pass for pass.

use crate::progressive::Frame;
use crate::shared::{
    ATROUS_PASSES, DENOISE_MIN_ALBEDO, DENOISE_SIGMA_DEPTH, DENOISE_SIGMA_LUMINANCE,
    DENOISE_SIGMA_NORMAL,
};

/// The filter's knobs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DenoiseSettings {
    /// À-trous passes (step widths 1, 2, 4, ...).
    pub passes: u32,
    /// Normal-weight exponent.
    pub sigma_normal: f32,
    /// Depth-weight scale.
    pub sigma_depth: f32,
    /// Luminance-weight scale (in standard deviations).
    pub sigma_luminance: f32,
}

impl Default for DenoiseSettings {
    fn default() -> Self {
        DenoiseSettings {
            passes: ATROUS_PASSES,
            sigma_normal: DENOISE_SIGMA_NORMAL as f32,
            sigma_depth: DENOISE_SIGMA_DEPTH as f32,
            sigma_luminance: DENOISE_SIGMA_LUMINANCE as f32,
        }
    }
}

/// The B3-spline kernel's 1D taps.
const KERNEL: [f32; 5] = [1.0 / 16.0, 1.0 / 4.0, 3.0 / 8.0, 1.0 / 4.0, 1.0 / 16.0];
/// Smallest albedo divided by (black surfaces keep their colour undivided).
const MIN_ALBEDO: f32 = DENOISE_MIN_ALBEDO as f32;

fn lum(c: [f32; 3]) -> f32 {
    0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]
}

/// Normal weight.
pub fn weight_normal(np: [f32; 3], nq: [f32; 3], sigma: f32) -> f32 {
    let d = np[0] * nq[0] + np[1] * nq[1] + np[2] * nq[2];
    let zero = |n: [f32; 3]| n == [0.0; 3];
    if zero(np) && zero(nq) {
        1.0
    } else {
        d.max(0.0).powf(sigma)
    }
}

/// Depth weight; `grad` is |grad z| at p in depth per pixel, `dist` the tap's offset in
/// pixels.
pub fn weight_depth(zp: f32, zq: f32, grad: f32, dist: f32, sigma: f32) -> f32 {
    match (zp.is_finite(), zq.is_finite()) {
        (false, false) => 1.0,
        (true, true) => {
            let scale = sigma * grad * dist + 1e-3 * zp.abs() + 1e-9;
            (-(zp - zq).abs() / scale).exp()
        }
        _ => 0.0,
    }
}

/// Luminance weight; `std` is the (prefiltered) standard deviation at p.
pub fn weight_luminance(lp: f32, lq: f32, std: f32, sigma: f32) -> f32 {
    (-(lp - lq).abs() / (sigma * std + 1e-6)).exp()
}

/// Denoises `frame`'s colour; returns the filtered linear RGB.
pub fn denoise(frame: &Frame, s: &DenoiseSettings) -> Vec<[f32; 3]> {
    let (w, h) = (frame.width as usize, frame.height as usize);
    let n = w * h;
    let albedo: Vec<[f32; 3]> = frame
        .albedo
        .iter()
        .map(|a| a.map(|v| v.max(MIN_ALBEDO)))
        .collect();
    // Demodulate.
    let mut irr: Vec<[f32; 3]> = (0..n)
        .map(|i| std::array::from_fn(|c| frame.colour[i][c] / albedo[i][c]))
        .collect();
    let mut var: Vec<f32> = (0..n)
        .map(|i| {
            let a = lum(albedo[i]).max(MIN_ALBEDO);
            frame.variance[i] / (a * a)
        })
        .collect();
    // Depth gradient per pixel (largest one-sided difference to a finite neighbour).
    let z = &frame.depth;
    let grad: Vec<f32> = (0..n)
        .map(|i| {
            let (x, y) = (i % w, i / w);
            let mut g = 0.0f32;
            for (dx, dy) in [(1i64, 0i64), (-1, 0), (0, 1), (0, -1)] {
                let (qx, qy) = (x as i64 + dx, y as i64 + dy);
                if qx < 0 || qy < 0 || qx >= w as i64 || qy >= h as i64 {
                    continue;
                }
                let q = qy as usize * w + qx as usize;
                if z[i].is_finite() && z[q].is_finite() {
                    g = g.max((z[i] - z[q]).abs());
                }
            }
            g
        })
        .collect();
    let mut next = irr.clone();
    let mut next_var = var.clone();
    for pass in 0..s.passes {
        let step = 1i64 << pass;
        let std = prefilter_std(&var, w, h);
        for i in 0..n {
            let (x, y) = ((i % w) as i64, (i / w) as i64);
            let lp = lum(irr[i]);
            let mut sum = [0f32; 3];
            let mut wsum = 0f32;
            let mut vsum = 0f32;
            for (ky, hy) in KERNEL.iter().enumerate() {
                for (kx, hx) in KERNEL.iter().enumerate() {
                    let (dx, dy) = ((kx as i64 - 2) * step, (ky as i64 - 2) * step);
                    let (qx, qy) = (x + dx, y + dy);
                    if qx < 0 || qy < 0 || qx >= w as i64 || qy >= h as i64 {
                        continue;
                    }
                    let q = qy as usize * w + qx as usize;
                    let dist = ((dx * dx + dy * dy) as f32).sqrt();
                    let wt = hx
                        * hy
                        * weight_normal(frame.normal[i], frame.normal[q], s.sigma_normal)
                        * weight_depth(z[i], z[q], grad[i], dist, s.sigma_depth)
                        * weight_luminance(lp, lum(irr[q]), std[i], s.sigma_luminance);
                    for c in 0..3 {
                        sum[c] += wt * irr[q][c];
                    }
                    wsum += wt;
                    vsum += wt * wt * var[q];
                }
            }
            // The centre tap always has weight 3/8 * 3/8 > 0.
            next[i] = sum.map(|v| v / wsum);
            next_var[i] = vsum / (wsum * wsum);
        }
        std::mem::swap(&mut irr, &mut next);
        std::mem::swap(&mut var, &mut next_var);
    }
    // Remodulate.
    (0..n)
        .map(|i| std::array::from_fn(|c| irr[i][c] * albedo[i][c]))
        .collect()
}

/// The standard deviation after a 3x3 Gaussian blur of the variance (SVGF's prefilter).
fn prefilter_std(var: &[f32], w: usize, h: usize) -> Vec<f32> {
    const G: [f32; 3] = [0.25, 0.5, 0.25];
    (0..w * h)
        .map(|i| {
            let (x, y) = ((i % w) as i64, (i / w) as i64);
            let (mut s, mut ws) = (0f32, 0f32);
            for (ky, gy) in G.iter().enumerate() {
                for (kx, gx) in G.iter().enumerate() {
                    let (qx, qy) = (x + kx as i64 - 1, y + ky as i64 - 1);
                    if qx < 0 || qy < 0 || qx >= w as i64 || qy >= h as i64 {
                        continue;
                    }
                    s += gx * gy * var[qy as usize * w + qx as usize];
                    ws += gx * gy;
                }
            }
            (s / ws).max(0.0).sqrt()
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame(w: u32, h: u32) -> Frame {
        let n = (w * h) as usize;
        Frame {
            width: w,
            height: h,
            colour: vec![[0.5; 3]; n],
            albedo: vec![[1.0; 3]; n],
            normal: vec![[0.0, 0.0, 1.0]; n],
            depth: vec![1.0; n],
            variance: vec![0.01; n],
            id: vec![0; n],
            steps: vec![0; n],
            samples: 4,
        }
    }

    #[test]
    fn flat_noise_is_smoothed_and_the_mean_kept() {
        let mut f = frame(32, 32);
        let mut s = 1u32;
        for c in &mut f.colour {
            s = crate::sampler::hash(s);
            let v = 0.5 + (s as f32 / u32::MAX as f32 - 0.5) * 0.4;
            *c = [v; 3];
        }
        let out = denoise(&f, &DenoiseSettings::default());
        let var = |v: &[[f32; 3]]| {
            let m = v.iter().map(|c| c[0]).sum::<f32>() / v.len() as f32;
            (
                m,
                v.iter().map(|c| (c[0] - m).powi(2)).sum::<f32>() / v.len() as f32,
            )
        };
        let (m0, v0) = var(&f.colour);
        let (m1, v1) = var(&out);
        assert!((m0 - m1).abs() < 0.01, "{m0} {m1}");
        assert!(v1 < v0 / 20.0, "variance {v0} -> {v1}");
    }

    #[test]
    fn edges_albedo_and_sky_survive() {
        let mut f = frame(32, 32);
        for i in 0..f.colour.len() {
            let x = i % 32;
            if x < 16 {
                // A different surface: another normal and depth.
                f.normal[i] = [1.0, 0.0, 0.0];
                f.depth[i] = 3.0;
                f.colour[i] = [0.1; 3];
            }
            if x >= 28 {
                f.depth[i] = f32::INFINITY;
                f.normal[i] = [0.0; 3];
                f.colour[i] = [2.0, 2.0, 3.0];
            }
            // A checker albedo on the right surface: detail, not noise.
            if (16..28).contains(&x) && (i / 32 + x) % 2 == 0 {
                f.albedo[i] = [0.2; 3];
                f.colour[i] = [0.1; 3];
            }
        }
        let out = denoise(&f, &DenoiseSettings::default());
        for (i, (o, c)) in out.iter().zip(&f.colour).enumerate() {
            for k in 0..3 {
                assert!((o[k] - c[k]).abs() < 1e-3, "pixel {i}: {o:?} vs {c:?}");
            }
        }
    }
}
