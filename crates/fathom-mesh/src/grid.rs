//! The sampling grid: bounds, voxel size, the documented limits, and the memory estimate that is
//! printed (and checked against `--max-memory`) before anything large is allocated.

use crate::IsoMeshError;
use glam::DVec3;

/// Most cells along the longest side of the bounds.
pub const MAX_RESOLUTION: u32 = 1 << 16;
/// Fewest cells along the longest side.
pub const MIN_RESOLUTION: u32 = 4;
/// Largest bounds coordinate accepted (scene units).
pub const MAX_COORD: f64 = 1e6;
/// Cells per side of a brick, the unit of culling, sampling and streaming.
pub const BRICK: usize = 8;

/// A regular grid of cubic cells over an axis-aligned box. Corner `(i, j, k)` sits at
/// `origin + h (i, j, k)`; corners on or beyond the box's faces count as outside, so the mesh
/// of an object cut by the bounds is closed off there.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Grid {
    pub origin: DVec3,
    /// Cell side.
    pub h: f64,
    /// Cells per axis.
    pub cells: [u32; 3],
}

impl Grid {
    /// The grid of `resolution` cells along the longest side of `lo..hi`, checked against the
    /// limits.
    pub fn new(lo: DVec3, hi: DVec3, resolution: u32) -> Result<Grid, IsoMeshError> {
        if !(MIN_RESOLUTION..=MAX_RESOLUTION).contains(&resolution) {
            return Err(IsoMeshError::Resolution(resolution));
        }
        let ok = |v: DVec3| v.is_finite() && v.abs().max_element() <= MAX_COORD;
        if !(ok(lo) && ok(hi)) || (hi - lo).min_element() <= 0.0 {
            return Err(IsoMeshError::Bounds(format!(
                "bounds {lo} .. {hi} must be finite, within +-{MAX_COORD}, with max > min on every axis"
            )));
        }
        let size = hi - lo;
        let h = size.max_element() / resolution as f64;
        let cells = size
            .to_array()
            .map(|s| ((s / h).ceil() as u32).clamp(1, resolution));
        Ok(Grid {
            origin: lo,
            h,
            cells,
        })
    }

    /// Position of corner `c` (global corner indices).
    #[inline]
    pub fn corner(&self, c: [i64; 3]) -> DVec3 {
        self.origin + DVec3::new(c[0] as f64, c[1] as f64, c[2] as f64) * self.h
    }

    /// Whether corner `c` lies on or outside the grid's faces (forced outside).
    #[inline]
    pub fn is_boundary(&self, c: [i64; 3]) -> bool {
        (0..3).any(|a| c[a] <= 0 || c[a] >= self.cells[a] as i64)
    }

    /// Bricks per axis.
    pub fn bricks(&self) -> [u32; 3] {
        self.cells.map(|n| n.div_ceil(BRICK as u32))
    }

    /// Total cells (the dense N^3 a naive mesher would sample).
    pub fn total_cells(&self) -> u64 {
        self.cells.iter().map(|&n| n as u64).product()
    }
}

/// Bytes one active brick holds while its layer is in flight: cell cases and vertex offsets,
/// about two vertices and four triangles per surface cell for a surface crossing the brick,
/// and the sample buffer of the thread that processes it.
pub const BYTES_PER_BRICK: u64 =
    (BRICK * BRICK * BRICK) as u64 * 5 + (BRICK * BRICK) as u64 * 3 * (16 + 2 * 12);

/// A memory estimate: the fixed part and the part that grows with the surface.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MemoryEstimate {
    /// Upper estimate of bricks active in one layer (from a coarse culling pass).
    pub bricks_per_layer: u64,
    /// Bytes for the per-layer brick index and the culling lists.
    pub fixed: u64,
    /// Bytes for two layers of active bricks.
    pub surface: u64,
    /// What a dense sampling of every corner would take (f32 per corner), for comparison.
    pub dense: u64,
}

impl MemoryEstimate {
    pub fn total(&self) -> u64 {
        self.fixed + self.surface
    }
}

impl std::fmt::Display for MemoryEstimate {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "about {} ({} bricks per layer at most; a dense grid would need {})",
            human_bytes(self.total()),
            self.bricks_per_layer,
            human_bytes(self.dense)
        )
    }
}

/// `1536` -> `1.5 KiB`.
pub fn human_bytes(b: u64) -> String {
    let units = ["B", "KiB", "MiB", "GiB", "TiB", "PiB"];
    let mut v = b as f64;
    let mut u = 0;
    while v >= 1024.0 && u + 1 < units.len() {
        v /= 1024.0;
        u += 1;
    }
    if u == 0 {
        format!("{b} B")
    } else {
        format!("{v:.1} {}", units[u])
    }
}

/// Parses `512M`, `2G`, `2GiB`, `1.5g`, `1000000` (bytes).
pub fn parse_bytes(s: &str) -> Result<u64, String> {
    let t = s.trim();
    let split = t.find(|c: char| c.is_ascii_alphabetic()).unwrap_or(t.len());
    let (num, unit) = t.split_at(split);
    let v: f64 = num
        .trim()
        .parse()
        .map_err(|_| format!("`{s}` is not a size (examples: 512M, 2G, 1000000)"))?;
    let mul = match unit.trim().to_ascii_lowercase().as_str() {
        "" | "b" => 1u64,
        "k" | "kb" | "kib" => 1 << 10,
        "m" | "mb" | "mib" => 1 << 20,
        "g" | "gb" | "gib" => 1 << 30,
        "t" | "tb" | "tib" => 1 << 40,
        u => return Err(format!("`{s}`: unknown unit `{u}` (valid: B, K, M, G, T)")),
    };
    let bytes = v * mul as f64;
    if !(bytes.is_finite() && (1.0..1.8e19).contains(&bytes)) {
        return Err(format!("`{s}` is out of range [1 B, 16 EiB]"));
    }
    Ok(bytes as u64)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grids_take_the_longest_side_and_refuse_bad_input() {
        let g = Grid::new(DVec3::splat(-1.0), DVec3::new(1.0, 0.5, 1.0), 64).unwrap();
        assert_eq!(g.cells, [64, 48, 64]);
        assert_eq!(g.h, 2.0 / 64.0);
        assert!(matches!(
            Grid::new(DVec3::ZERO, DVec3::ONE, MAX_RESOLUTION + 1),
            Err(IsoMeshError::Resolution(_))
        ));
        assert!(Grid::new(DVec3::ZERO, DVec3::ONE, 2).is_err());
        assert!(Grid::new(DVec3::ONE, DVec3::ZERO, 64).is_err());
        assert!(Grid::new(DVec3::ZERO, DVec3::splat(f64::NAN), 64).is_err());
        assert!(g.is_boundary([0, 3, 3]) && g.is_boundary([3, 48, 3]) && !g.is_boundary([1, 1, 1]));
    }

    #[test]
    fn sizes_parse_with_units() {
        assert_eq!(parse_bytes("2G"), Ok(2 << 30));
        assert_eq!(parse_bytes("512MiB"), Ok(512 << 20));
        assert_eq!(parse_bytes("1000"), Ok(1000));
        assert!(parse_bytes("2X").is_err());
        assert!(parse_bytes("-1G").is_err());
        assert_eq!(human_bytes(1536), "1.5 KiB");
    }
}
