//! Writing a [`Frame`] to files: the tonemapped PNG, the hit mask, the depth map (EXR) and the
//! heat map of steps per pixel.

use crate::post;
use fathom_core::frame::Frame;
use std::fs::File;
use std::io::BufWriter;
use std::path::{Path, PathBuf};

/// Why an output file could not be written.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    /// The file could not be created (missing directory, no permission, ...).
    #[error("cannot write {}: {source}", path.display())]
    Create {
        path: PathBuf,
        source: std::io::Error,
    },
    /// Encoding or writing the image failed (disk full, ...).
    #[error("cannot write {}: {message}", path.display())]
    Write { path: PathBuf, message: String },
}

fn write_error(path: &Path, e: impl std::fmt::Display) -> OutputError {
    OutputError::Write {
        path: path.into(),
        message: e.to_string(),
    }
}

/// Opens `path` for writing now, so an unwritable path fails before any rendering.
pub fn open_output(path: &Path) -> Result<File, OutputError> {
    File::create(path).map_err(|source| OutputError::Create {
        path: path.into(),
        source,
    })
}

fn write_png(file: File, path: &Path, w: u32, h: u32, rgb: &[u8]) -> Result<(), OutputError> {
    use image::ImageEncoder;
    let enc = image::codecs::png::PngEncoder::new(BufWriter::new(file));
    enc.write_image(rgb, w, h, image::ExtendedColorType::Rgb8)
        .map_err(|e| write_error(path, e))
}

/// The tonemapped, gamma-encoded colour image as PNG.
pub fn save_colour(frame: &Frame, file: File, path: &Path) -> Result<(), OutputError> {
    write_png(file, path, frame.width, frame.height, &post::to_rgb8(frame))
}

/// White where the primary ray hit, black elsewhere (PNG).
pub fn save_mask(frame: &Frame, file: File, path: &Path) -> Result<(), OutputError> {
    let rgb: Vec<u8> = (0..frame.len())
        .flat_map(|i| [if frame.is_hit(i) { 255 } else { 0 }; 3])
        .collect();
    write_png(file, path, frame.width, frame.height, &rgb)
}

/// Heat map of distance evaluations per pixel (black, red, yellow, white up to the frame's
/// maximum), PNG.
pub fn save_steps(frame: &Frame, file: File, path: &Path) -> Result<(), OutputError> {
    let max = frame.steps.iter().copied().max().unwrap_or(0).max(1) as f32;
    let rgb: Vec<u8> = frame
        .steps
        .iter()
        .flat_map(|&s| {
            let v = s as f32 / max * 3.0;
            [v, v - 1.0, v - 2.0].map(|c| (c.clamp(0.0, 1.0) * 255.0 + 0.5) as u8)
        })
        .collect();
    write_png(file, path, frame.width, frame.height, &rgb)
}

/// Ray distance per pixel as a float EXR: RGB hold the distance along the primary ray, alpha
/// the coverage (1 where the ray hit, 0 where it missed). Misses carry `far` (the scene's
/// maximum distance) in RGB so no infinity reaches the file, and alpha 0 tells a compositor
/// they are background, not a surface at `far`.
pub fn save_depth(frame: &Frame, far: f32, file: File, path: &Path) -> Result<(), OutputError> {
    let data: Vec<f32> = (0..frame.len())
        .flat_map(|i| {
            let d = frame.depth[i];
            if frame.is_hit(i) {
                [d, d, d, 1.0]
            } else {
                [far, far, far, 0.0]
            }
        })
        .collect();
    let img = image::Rgba32FImage::from_raw(frame.width, frame.height, data)
        .ok_or_else(|| write_error(path, "the depth buffer has the wrong size"))?;
    let mut w = BufWriter::new(file);
    image::DynamicImage::ImageRgba32F(img)
        .write_to(&mut w, image::ImageFormat::OpenExr)
        .map_err(|e| write_error(path, e))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn depth_exr_keeps_hits_and_marks_misses_in_alpha() {
        let mut frame = Frame::new(2, 1);
        frame.depth[0] = 2.5;
        frame.depth[1] = f32::INFINITY;
        let dir = std::env::temp_dir().join(format!("fathom-depth-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("d.exr");
        save_depth(&frame, 20.0, open_output(&path).unwrap(), &path).unwrap();
        let img = image::open(&path).unwrap().to_rgba32f();
        let _ = std::fs::remove_dir_all(&dir);
        assert_eq!(img.get_pixel(0, 0).0, [2.5, 2.5, 2.5, 1.0]);
        assert_eq!(img.get_pixel(1, 0).0, [20.0, 20.0, 20.0, 0.0]);
    }
}
