//! What a job is made of: [`Work`] (the tiles of a still, the frames of a flight path, the
//! frames of a zoom) and its [`Unit`]s, each with a fixed index, a fixed file name and what to
//! render. Units are deterministic: the same unit renders to the same bytes in any task.

use crate::error::FarmError;
use fathom_core::frame::Rect;
use serde::{Deserialize, Serialize};

/// Most units of one job.
pub const MAX_UNITS: usize = 1_000_000;

/// The kind of job and its size.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "lowercase", deny_unknown_fields)]
pub enum Work {
    /// A still cut into `cols` x `rows` tiles (regions of the output image), row by row.
    Tiles {
        /// Tiles per row.
        cols: u32,
        /// Tiles per column.
        rows: u32,
    },
    /// `frames` frames of the scene's flight path `path` (as `fathom render --path`).
    Path {
        /// The flight path's name.
        path: String,
        /// Frames over the path.
        frames: usize,
    },
    /// `frames` frames of the camera-path preset `preset` zooming by `depth` (as
    /// `fathom zoom`), each rendered as a settled still so it does not depend on the frames
    /// before it.
    Zoom {
        /// The camera-path preset's name.
        preset: String,
        /// Zoom factor from the first to the last frame, >= 1.
        depth: f64,
        /// Frames of the zoom.
        frames: usize,
    },
}

/// What one unit renders.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Part {
    /// A rectangle of the output image.
    Tile(Rect),
    /// A whole frame.
    Frame(usize),
}

/// One unit of work.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Unit {
    /// The unit's index in the job, from 0.
    pub index: usize,
    /// File name in the job directory.
    pub file: String,
    /// What it renders.
    pub part: Part,
}

impl Work {
    /// `n` tiles of a `width` x `height` image: the grid `cols` x `rows = n` whose tiles are
    /// closest to square (a prime `n` gives strips).
    pub fn tiles(n: usize, width: u32, height: u32) -> Result<Work, FarmError> {
        if n == 0 || n > MAX_UNITS {
            return Err(FarmError::Work(format!(
                "--tiles {n} is out of range 1..={MAX_UNITS}"
            )));
        }
        let mut best: Option<(f64, u32, u32)> = None;
        for cols in 1..=n {
            if !n.is_multiple_of(cols) {
                continue;
            }
            let rows = n / cols;
            if cols > width as usize || rows > height as usize {
                continue;
            }
            let (cols, rows) = (cols as u32, rows as u32);
            let aspect = (width as f64 / cols as f64) / (height as f64 / rows as f64);
            let score = aspect.ln().abs();
            if best.is_none_or(|(s, _, _)| score < s) {
                best = Some((score, cols, rows));
            }
        }
        let (_, cols, rows) = best.ok_or_else(|| {
            FarmError::Work(format!(
                "--tiles {n} cannot cut a {width}x{height} image into tiles of at least one pixel"
            ))
        })?;
        Ok(Work::Tiles { cols, rows })
    }

    /// How many units.
    pub fn len(&self) -> usize {
        match self {
            Work::Tiles { cols, rows } => *cols as usize * *rows as usize,
            Work::Path { frames, .. } | Work::Zoom { frames, .. } => *frames,
        }
    }

    /// No units.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Checks the counts (and, for tiles, against the output image size).
    pub fn validate(&self, output: (u32, u32)) -> Result<(), FarmError> {
        let n = self.len();
        if n == 0 || n > MAX_UNITS {
            return Err(FarmError::Work(format!(
                "a job has 1..={MAX_UNITS} units; this one has {n}"
            )));
        }
        match self {
            Work::Tiles { cols, rows } => {
                if *cols > output.0 || *rows > output.1 {
                    return Err(FarmError::Work(format!(
                        "{cols}x{rows} tiles do not fit a {}x{} image",
                        output.0, output.1
                    )));
                }
            }
            Work::Zoom { depth, .. } => {
                if !(depth.is_finite() && *depth >= 1.0) {
                    return Err(FarmError::Work(format!(
                        "--depth {depth} must be a finite zoom factor >= 1"
                    )));
                }
            }
            Work::Path { .. } => {}
        }
        Ok(())
    }

    /// Unit `i` of a job whose output image is `output` (`i < self.len()`).
    pub fn unit(&self, i: usize, output: (u32, u32)) -> Unit {
        match self {
            Work::Tiles { cols, rows } => {
                let (c, r) = ((i % *cols as usize) as u32, (i / *cols as usize) as u32);
                let split = |k: u32, n: u32, len: u32| (k as u64 * len as u64 / n as u64) as u32;
                let (x0, x1) = (split(c, *cols, output.0), split(c + 1, *cols, output.0));
                let (y0, y1) = (split(r, *rows, output.1), split(r + 1, *rows, output.1));
                Unit {
                    index: i,
                    file: format!("tile-{i:05}.png"),
                    part: Part::Tile(Rect {
                        x: x0,
                        y: y0,
                        width: x1 - x0,
                        height: y1 - y0,
                    }),
                }
            }
            Work::Path { .. } | Work::Zoom { .. } => Unit {
                index: i,
                file: format!("{}{i:06}.png", FRAME_PREFIX),
                part: Part::Frame(i),
            },
        }
    }

    /// Every unit, in order.
    pub fn units(&self, output: (u32, u32)) -> Vec<Unit> {
        (0..self.len()).map(|i| self.unit(i, output)).collect()
    }
}

/// Frame files are `frame-NNNNNN.png` (ffmpeg: `frame-%06d.png`).
pub const FRAME_PREFIX: &str = "frame-";

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tiles_cover_the_image_exactly_once() {
        for (n, w, h) in [
            (8, 256, 192),
            (7, 100, 30),
            (12, 33, 17),
            (1, 5, 5),
            (64, 64, 64),
        ] {
            let work = Work::tiles(n, w, h).unwrap();
            work.validate((w, h)).unwrap();
            assert_eq!(work.len(), n);
            let mut cover = vec![0u8; (w * h) as usize];
            for u in work.units((w, h)) {
                let Part::Tile(r) = u.part else { panic!() };
                assert!(!r.is_empty() && r.fits(w, h), "{r:?}");
                for y in r.y..r.bottom() {
                    for x in r.x..r.right() {
                        cover[(y * w + x) as usize] += 1;
                    }
                }
            }
            assert!(cover.iter().all(|&c| c == 1), "{n} tiles of {w}x{h}");
        }
        assert_eq!(
            Work::tiles(8, 256, 192).unwrap(),
            Work::Tiles { cols: 4, rows: 2 }
        );
        assert!(Work::tiles(0, 8, 8).is_err());
        // 11 is prime: strips, which a 4-pixel-wide, 4-pixel-tall image cannot hold.
        let e = Work::tiles(11, 4, 4).unwrap_err().to_string();
        assert!(e.contains("--tiles 11"), "{e}");
    }

    #[test]
    fn frames_have_fixed_names_and_bad_counts_are_refused() {
        let w = Work::Path {
            path: "dive".into(),
            frames: 3,
        };
        assert_eq!(w.unit(2, (8, 8)).file, "frame-000002.png");
        assert!(
            Work::Path {
                path: "dive".into(),
                frames: 0
            }
            .validate((8, 8))
            .is_err()
        );
        let z = Work::Zoom {
            preset: "menger".into(),
            depth: 0.5,
            frames: 3,
        };
        assert!(
            z.validate((8, 8))
                .unwrap_err()
                .to_string()
                .contains("--depth")
        );
        let json = serde_json::to_string(&w).unwrap();
        assert_eq!(serde_json::from_str::<Work>(&json).unwrap(), w);
    }
}
