//! Assembly: every unit is verified against its receipt first (a missing or corrupt unit
//! stops it, naming the units); tiles are then decoded, checked against their rectangles and
//! stitched into the output PNG, written through a temporary name. Frames are listed in
//! order for a video encoder.

use crate::atomic;
use crate::error::FarmError;
use crate::manifest::FarmDir;
use crate::render::encode_rgb8;
use crate::work::{FRAME_PREFIX, Part, Work};
use std::path::{Path, PathBuf};

/// What an assembly produced.
#[derive(Clone, Debug)]
pub enum Assembled {
    /// The stitched still was written to this path.
    Still {
        path: PathBuf,
        width: u32,
        height: u32,
    },
    /// The verified frames, in order, and the ffmpeg input pattern that names them.
    Frames {
        files: Vec<PathBuf>,
        pattern: PathBuf,
    },
}

fn image_err(path: &Path, e: impl ToString) -> FarmError {
    FarmError::Image {
        path: path.into(),
        message: e.to_string(),
    }
}

/// Verifies every unit of `farm`, then stitches a still into `out` (frames are returned).
pub fn assemble(farm: &FarmDir, out: &Path) -> Result<Assembled, FarmError> {
    let files = farm.verified()?;
    let m = &farm.manifest;
    if !matches!(m.fingerprint.work, Work::Tiles { .. }) {
        return Ok(Assembled::Frames {
            files,
            pattern: farm.dir.join(format!("{FRAME_PREFIX}%06d.png")),
        });
    }
    let (w, h) = m.output;
    let mut canvas = vec![0u8; w as usize * h as usize * 3];
    for (unit, path) in m.units.iter().zip(&files) {
        let Part::Tile(r) = unit.part else {
            return Err(image_err(path, "a frame in a tiled job"));
        };
        let img = image::open(path).map_err(|e| image_err(path, e))?.to_rgb8();
        if img.dimensions() != (r.width, r.height) {
            return Err(image_err(
                path,
                format!(
                    "is {}x{}, its tile is {}x{}",
                    img.width(),
                    img.height(),
                    r.width,
                    r.height
                ),
            ));
        }
        let row = r.width as usize * 3;
        for y in 0..r.height as usize {
            let src = &img.as_raw()[y * row..(y + 1) * row];
            let at = ((r.y as usize + y) * w as usize + r.x as usize) * 3;
            canvas[at..at + row].copy_from_slice(src);
        }
    }
    let png = encode_rgb8(w, h, &canvas).map_err(|e| image_err(out, e))?;
    atomic::write(out, &png)?;
    Ok(Assembled::Still {
        path: out.into(),
        width: w,
        height: h,
    })
}
