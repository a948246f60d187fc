//! Equirectangular environment maps: reading Radiance `.hdr` (RGBE) and OpenEXR files, looking
//! up radiance by direction, and importance sampling by luminance.
//!
//! Sampling follows pbrt-v4's image infinite light: a [`Distribution2D`] over the pixels
//! weighted by luminance x sin(theta) (the equirectangular map stretches rows near the poles),
//! so a small bright sun in a map is found by light sampling instead of by luck.
//!
//! Input is untrusted: the image size is read from the header and refused beyond
//! [`MAX_ENV_PIXELS`] before any pixel memory is allocated, and every error names the file.
//! The RGBE reader is ours (the format is a short header and run-length-coded scanlines), so
//! the size check happens before decoding and a truncated file is reported as truncated.

use crate::distribution::Distribution2D;
use crate::sampling::luminance;
use glam::DVec3;
use std::f64::consts::PI;
use std::io::{BufRead, BufReader, Read};
use std::path::{Path, PathBuf};

/// Widest or tallest map accepted.
pub const MAX_ENV_SIDE: usize = 16384;
/// Most pixels accepted (8192 x 4096). A map costs about 28 bytes per pixel (f32 RGB plus the
/// sampling tables), so this bounds one map near 1 GB.
pub const MAX_ENV_PIXELS: usize = 1 << 25;

/// Why an environment map could not be used.
#[derive(Debug, thiserror::Error)]
pub enum EnvMapError {
    /// The file could not be opened or read.
    #[error("environment map {path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// What the system said.
        source: std::io::Error,
    },
    /// The header declares an image beyond the limits.
    #[error(
        "environment map {path}: {width}x{height} exceeds the limit of {MAX_ENV_SIDE} pixels per side and {MAX_ENV_PIXELS} pixels in all"
    )]
    TooLarge {
        /// The file.
        path: PathBuf,
        /// Declared width.
        width: usize,
        /// Declared height.
        height: usize,
    },
    /// The file ends before its pixels do.
    #[error("environment map {path}: truncated ({what})")]
    Truncated {
        /// The file.
        path: PathBuf,
        /// Where it ended.
        what: String,
    },
    /// The file is not a valid map.
    #[error("environment map {path}: {why}")]
    Malformed {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        why: String,
    },
}

/// An equirectangular map: longitude across (u = 0.5 looks down -z), latitude down (v = 0 is
/// straight up, +y).
#[derive(Clone, Debug)]
pub struct EnvMap {
    width: usize,
    height: usize,
    pixels: Vec<[f32; 3]>,
    dist: Distribution2D,
}

impl EnvMap {
    /// Reads a `.hdr` or `.exr` file (by extension).
    pub fn load(path: &Path) -> Result<EnvMap, EnvMapError> {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        match ext.as_deref() {
            Some("hdr") | Some("pic") => read_rgbe(path),
            Some("exr") => read_exr(path),
            _ => Err(EnvMapError::Malformed {
                path: path.into(),
                why: "unknown extension (expected .hdr or .exr)".into(),
            }),
        }
    }

    /// A map from linear RGB pixels, row-major. Negative or non-finite values become 0.
    pub fn from_pixels(
        width: usize,
        height: usize,
        mut pixels: Vec<[f32; 3]>,
    ) -> Result<EnvMap, EnvMapError> {
        check_size(Path::new("<memory>"), width, height)?;
        if pixels.len() != width * height {
            return Err(EnvMapError::Malformed {
                path: "<memory>".into(),
                why: format!("{} pixels for {width}x{height}", pixels.len()),
            });
        }
        for p in &mut pixels {
            for c in p.iter_mut() {
                if !(c.is_finite() && *c > 0.0) {
                    *c = 0.0;
                }
            }
        }
        let mut f = vec![0.0; width * height];
        for y in 0..height {
            let sin_t = (PI * (y as f64 + 0.5) / height as f64).sin();
            for x in 0..width {
                let p = pixels[y * width + x];
                f[y * width + x] =
                    luminance(DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64)) * sin_t;
            }
        }
        Ok(EnvMap {
            dist: Distribution2D::new(&f, width, height),
            width,
            height,
            pixels,
        })
    }

    /// Size in pixels.
    pub fn size(&self) -> (usize, usize) {
        (self.width, self.height)
    }

    /// Radiance arriving from direction `d` (unit, world).
    pub fn radiance(&self, d: DVec3) -> DVec3 {
        let [u, v] = dir_to_uv(d);
        let x = ((u * self.width as f64) as usize).min(self.width - 1);
        let y = ((v * self.height as f64) as usize).min(self.height - 1);
        let p = self.pixels[y * self.width + x];
        DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64)
    }

    /// A direction drawn by luminance: (direction, radiance, density per steradian).
    pub fn sample(&self, u: [f64; 2]) -> (DVec3, DVec3, f64) {
        let (uv, p) = self.dist.sample(u);
        let d = uv_to_dir(uv);
        let sin_t = (PI * uv[1]).sin();
        let pdf = if sin_t > 0.0 {
            p / (2.0 * PI * PI * sin_t)
        } else {
            0.0
        };
        (d, self.radiance(d), pdf)
    }

    /// Density of [`EnvMap::sample`] drawing `d`.
    pub fn pdf(&self, d: DVec3) -> f64 {
        let uv = dir_to_uv(d);
        let sin_t = (PI * uv[1]).sin();
        if sin_t <= 0.0 {
            return 0.0;
        }
        self.dist.pdf(uv) / (2.0 * PI * PI * sin_t)
    }
}

/// Direction to (u, v) in [0, 1)^2.
pub fn dir_to_uv(d: DVec3) -> [f64; 2] {
    let u = 0.5 + d.x.atan2(-d.z) / (2.0 * PI);
    let v = d.y.clamp(-1.0, 1.0).acos() / PI;
    [u.rem_euclid(1.0), v.clamp(0.0, 1.0)]
}

/// (u, v) to a unit direction.
pub fn uv_to_dir(uv: [f64; 2]) -> DVec3 {
    let phi = (uv[0] - 0.5) * 2.0 * PI;
    let theta = uv[1] * PI;
    let s = theta.sin();
    DVec3::new(s * phi.sin(), theta.cos(), -s * phi.cos())
}

fn check_size(path: &Path, width: usize, height: usize) -> Result<(), EnvMapError> {
    if width == 0
        || height == 0
        || width > MAX_ENV_SIDE
        || height > MAX_ENV_SIDE
        || width.saturating_mul(height) > MAX_ENV_PIXELS
    {
        if width == 0 || height == 0 {
            return Err(EnvMapError::Malformed {
                path: path.into(),
                why: format!("empty image {width}x{height}"),
            });
        }
        return Err(EnvMapError::TooLarge {
            path: path.into(),
            width,
            height,
        });
    }
    Ok(())
}

fn io(path: &Path) -> impl Fn(std::io::Error) -> EnvMapError + '_ {
    move |source| EnvMapError::Io {
        path: path.into(),
        source,
    }
}

/// Reads a Radiance RGBE file (flat or new-style run-length scanlines, "-Y h +X w" layout).
fn read_rgbe(path: &Path) -> Result<EnvMap, EnvMapError> {
    let file = std::fs::File::open(path).map_err(io(path))?;
    let mut r = BufReader::new(file);
    let malformed = |why: &str| EnvMapError::Malformed {
        path: path.into(),
        why: why.into(),
    };
    let truncated = |what: String| EnvMapError::Truncated {
        path: path.into(),
        what,
    };
    // Header: lines up to an empty one; at most 64 KiB of it.
    let mut line = String::new();
    let mut header_bytes = 0usize;
    let mut first = true;
    loop {
        line.clear();
        let n = (&mut r)
            .take(4096)
            .read_line(&mut line)
            .map_err(|_| malformed("header is not text"))?;
        if n == 0 || !line.ends_with('\n') {
            return Err(truncated("in the header".into()));
        }
        header_bytes += n;
        if header_bytes > 65536 {
            return Err(malformed("header longer than 64 KiB"));
        }
        let l = line.trim_end();
        if first {
            if !l.starts_with("#?") {
                return Err(malformed("not a Radiance file (no #? signature)"));
            }
            first = false;
            continue;
        }
        if l.is_empty() {
            break;
        }
        if let Some(f) = l.strip_prefix("FORMAT=")
            && f != "32-bit_rle_rgbe"
        {
            return Err(malformed(&format!("unsupported format {f}")));
        }
    }
    line.clear();
    (&mut r)
        .take(256)
        .read_line(&mut line)
        .map_err(|_| malformed("bad resolution line"))?;
    let parts: Vec<&str> = line.split_whitespace().collect();
    let (height, width) = match parts.as_slice() {
        ["-Y", h, "+X", w] => (
            h.parse::<usize>()
                .map_err(|_| malformed("bad height in the resolution line"))?,
            w.parse::<usize>()
                .map_err(|_| malformed("bad width in the resolution line"))?,
        ),
        [] => return Err(truncated("before the resolution line".into())),
        _ => {
            return Err(malformed(
                "only the standard \"-Y height +X width\" orientation is supported",
            ));
        }
    };
    check_size(path, width, height)?;
    let mut pixels = vec![[0f32; 3]; width * height];
    let mut scan = vec![[0u8; 4]; width];
    for y in 0..height {
        read_scanline(&mut r, &mut scan).map_err(|e| match e {
            ScanError::Eof => truncated(format!("at scanline {y} of {height}")),
            ScanError::Bad(why) => malformed(&format!("scanline {y}: {why}")),
        })?;
        for (x, p) in scan.iter().enumerate() {
            pixels[y * width + x] = rgbe_to_rgb(*p);
        }
    }
    EnvMap::from_pixels(width, height, pixels).map_err(|e| match e {
        EnvMapError::Malformed { why, .. } => malformed(&why),
        other => other,
    })
}

enum ScanError {
    Eof,
    Bad(&'static str),
}

fn byte(r: &mut impl Read) -> Result<u8, ScanError> {
    let mut b = [0u8; 1];
    r.read_exact(&mut b).map_err(|_| ScanError::Eof)?;
    Ok(b[0])
}

fn read_scanline(r: &mut impl Read, out: &mut [[u8; 4]]) -> Result<(), ScanError> {
    let w = out.len();
    let mut head = [0u8; 4];
    r.read_exact(&mut head).map_err(|_| ScanError::Eof)?;
    let rle = (8..32768).contains(&w) && head[0] == 2 && head[1] == 2 && head[2] & 0x80 == 0;
    if !rle {
        // Flat pixels.
        out[0] = head;
        for p in out.iter_mut().skip(1) {
            r.read_exact(p).map_err(|_| ScanError::Eof)?;
        }
        return Ok(());
    }
    if ((head[2] as usize) << 8 | head[3] as usize) != w {
        return Err(ScanError::Bad("run-length scanline width mismatch"));
    }
    for c in 0..4 {
        let mut x = 0;
        while x < w {
            let count = byte(r)? as usize;
            if count > 128 {
                let n = count - 128;
                if x + n > w {
                    return Err(ScanError::Bad("run overflows the scanline"));
                }
                let v = byte(r)?;
                for p in &mut out[x..x + n] {
                    p[c] = v;
                }
                x += n;
            } else {
                if count == 0 || x + count > w {
                    return Err(ScanError::Bad("bad literal run"));
                }
                for p in &mut out[x..x + count] {
                    p[c] = byte(r)?;
                }
                x += count;
            }
        }
    }
    Ok(())
}

fn rgbe_to_rgb(p: [u8; 4]) -> [f32; 3] {
    if p[3] == 0 {
        return [0.0; 3];
    }
    let f = 2f32.powi(p[3] as i32 - 136);
    [0, 1, 2].map(|i| (p[i] as f32 + 0.5) * f)
}

/// Reads the first RGB(A) layer of an OpenEXR file, checking its size from the header first.
fn read_exr(path: &Path) -> Result<EnvMap, EnvMapError> {
    let malformed = |e: exr::error::Error| {
        let why = e.to_string();
        if why.contains("end of file") || why.contains("UnexpectedEof") || why.contains("fill") {
            EnvMapError::Truncated {
                path: path.into(),
                what: why,
            }
        } else {
            EnvMapError::Malformed {
                path: path.into(),
                why,
            }
        }
    };
    let meta = exr::meta::MetaData::read_from_file(path, false).map_err(malformed)?;
    let header = meta.headers.first().ok_or_else(|| EnvMapError::Malformed {
        path: path.into(),
        why: "no layers".into(),
    })?;
    let (w, h) = (header.layer_size.0, header.layer_size.1);
    check_size(path, w, h)?;
    use exr::prelude::*;
    let img = read_first_rgba_layer_from_file(
        path,
        |res: Vec2<usize>, _| (res.0, vec![[0f32; 3]; res.0 * res.1]),
        |px: &mut (usize, Vec<[f32; 3]>), pos: Vec2<usize>, (r, g, b, _a): (f32, f32, f32, f32)| {
            let w = px.0;
            px.1[pos.1 * w + pos.0] = [r, g, b];
        },
    )
    .map_err(malformed)?;
    let (_, pixels) = img.layer_data.channel_data.pixels;
    EnvMap::from_pixels(w, h, pixels)
}

#[cfg(test)]
mod tests;
