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
        /// The PNG written.
        path: PathBuf,
        /// Its width, pixels.
        width: u32,
        /// Its height, pixels.
        height: u32,
    },
    /// The verified frames, in order, and the ffmpeg input pattern that names them.
    Frames {
        /// The frame files, in order.
        files: Vec<PathBuf>,
        /// The ffmpeg input pattern that names them (the frame prefix and `%06d.png`).
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
    refuse_inside_job(farm, out)?;
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

/// Refuses an output that would overwrite one of the job's own files (a unit, its receipt,
/// the manifest or the stored scene): the job directory is the farm's, not an output's.
pub fn refuse_inside_job(farm: &FarmDir, out: &Path) -> Result<(), FarmError> {
    let canon = |p: &Path| std::fs::canonicalize(p).ok();
    let (Some(job), Some(name)) = (canon(&farm.dir), out.file_name()) else {
        return Ok(());
    };
    let parent = match out.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let Some(dir) = canon(parent) else {
        return Ok(());
    };
    if dir.starts_with(&job) {
        let name = name.to_string_lossy();
        let owned = farm.manifest.units.iter().any(|u| u.file == name)
            || dir != job
            || [crate::manifest::MANIFEST, crate::manifest::SCENE].contains(&name.as_ref());
        if owned {
            return Err(FarmError::Work(format!(
                "{}: the output would overwrite a file of the job in {} (its units, receipts, \
                 manifest or scene); write it outside the job directory",
                out.display(),
                farm.dir.display()
            )));
        }
    }
    Ok(())
}
