//! Turning linear radiance into pictures: exposure, the same soft highlight shoulder and sRGB
//! curve as fathom-trace's PNGs (so path-traced and Blinn-Phong images of a scene compare
//! directly), 8-bit PNG writing, and the error measure the tests and benchmarks use.

use std::path::Path;

/// The soft highlight shoulder and the sRGB curve of every fathom picture (fathom-image's).
pub use fathom_image::post::{srgb, tonemap};

/// Tonemapped, gamma-encoded 8-bit RGB of `colour` scaled by `exposure`.
pub fn to_rgb8(colour: &[[f32; 3]], exposure: f32) -> Vec<u8> {
    colour
        .iter()
        .flat_map(|c| c.map(|v| (srgb(tonemap(v * exposure)) * 255.0 + 0.5) as u8))
        .collect()
}

/// Writes an 8-bit sRGB PNG.
pub fn write_png(
    path: &Path,
    width: u32,
    height: u32,
    colour: &[[f32; 3]],
    exposure: f32,
) -> Result<(), image::ImageError> {
    let img =
        image::RgbImage::from_raw(width, height, to_rgb8(colour, exposure)).ok_or_else(|| {
            image::ImageError::Parameter(image::error::ParameterError::from_kind(
                image::error::ParameterErrorKind::DimensionMismatch,
            ))
        })?;
    img.save(path)
}

/// Root-mean-square error of `a` against `reference` over all channels, relative to the
/// reference's mean (so 0.02 is "2 % RMSE").
pub fn relative_rmse(a: &[[f32; 3]], reference: &[[f32; 3]]) -> f64 {
    let n = (a.len() * 3).max(1) as f64;
    let mut se = 0.0;
    let mut mean = 0.0;
    for (p, r) in a.iter().zip(reference) {
        for c in 0..3 {
            let d = p[c] as f64 - r[c] as f64;
            se += d * d;
            mean += r[c] as f64;
        }
    }
    let mean = mean / n;
    if mean > 0.0 {
        (se / n).sqrt() / mean
    } else {
        (se / n).sqrt()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tonemap_is_fathom_traces_and_bounded() {
        assert_eq!(tonemap(0.5), 0.5);
        assert!(tonemap(100.0) <= 1.0 && tonemap(f32::NAN) == 0.0);
        assert_eq!(to_rgb8(&[[1.0, 0.0, f32::INFINITY]], 1.0)[1..], [0, 0]);
        assert_eq!(relative_rmse(&[[1.0; 3]], &[[1.0; 3]]), 0.0);
        assert!((relative_rmse(&[[1.1; 3]], &[[1.0; 3]]) - 0.1).abs() < 1e-6);
    }
}
