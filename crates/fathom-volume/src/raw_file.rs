//! fathom's raw grid format: a 48-byte header and the voxels, for what `.vol` cannot hold
//! exactly (the simulation's u32 trail counts) and for grids that keep their world box.
//!
//! Layout (little-endian): bytes 0-7 `FVOLRAW1`, u32 voxel kind (1 = f32 density, 2 = u32
//! count), u32 res x, y, z, six f32 of the world box (min xyz, max xyz), then the voxels, x
//! fastest, then y, then z.

use crate::error::VolumeError;
use crate::file_io::{self, Fields, format_err};
use crate::grid::{DensityGrid, Grid, TrailGrid, WorldBox, check_size};
use glam::Vec3;
use std::path::Path;

/// Header length in bytes.
pub const HEADER_LEN: usize = 48;
const MAGIC: &[u8; 8] = b"FVOLRAW1";

/// A grid in the raw format: densities or trail counts.
#[derive(Clone, Debug, PartialEq)]
pub enum RawGrid {
    Density(DensityGrid),
    Trail(TrailGrid),
}

fn parse_header(
    path: &Path,
    h: &[u8],
    limit: u64,
) -> Result<(u32, [u32; 3], WorldBox, u64), VolumeError> {
    let mut f = Fields {
        path,
        bytes: h,
        at: 0,
    };
    let magic = f.take(8, "the magic bytes `FVOLRAW1`")?;
    if magic != MAGIC {
        return Err(format_err(
            path,
            0,
            "not a fathom raw grid: expected the magic bytes `FVOLRAW1`",
        ));
    }
    let kind = f.u32("the voxel kind")?;
    if kind != 1 && kind != 2 {
        return Err(format_err(
            path,
            8,
            format!("voxel kind {kind} is unknown (valid: 1 = f32 density, 2 = u32 count)"),
        ));
    }
    let mut res = [0u32; 3];
    for (a, name) in ["x", "y", "z"].iter().enumerate() {
        res[a] = f.u32(&format!("the {name} resolution"))?;
    }
    let b = f.f32s::<6>("the world box")?;
    let bbox = WorldBox::new(Vec3::new(b[0], b[1], b[2]), Vec3::new(b[3], b[4], b[5]))
        .map_err(|e| format_err(path, 24, e.to_string()))?;
    let n = check_size(&path.display().to_string(), res.map(u64::from), 4, limit)?;
    Ok((kind, res, bbox, (HEADER_LEN + 4 * n) as u64))
}

fn finish(
    path: &Path,
    bytes: &[u8],
    kind: u32,
    res: [u32; 3],
    bbox: WorldBox,
) -> Result<RawGrid, VolumeError> {
    let body = &bytes[HEADER_LEN..];
    if kind == 1 {
        let g = Grid::from_data(res, file_io::words(body, f32::from_le_bytes), bbox)?;
        g.validate_densities(&path.display().to_string())?;
        Ok(RawGrid::Density(g))
    } else {
        Ok(RawGrid::Trail(Grid::from_data(
            res,
            file_io::words(body, u32::from_le_bytes),
            bbox,
        )?))
    }
}

/// Parses a raw grid held in memory; `path` names it in errors.
pub fn parse(bytes: &[u8], path: &Path, limit: u64) -> Result<RawGrid, VolumeError> {
    let (kind, res, bbox, total) =
        parse_header(path, &bytes[..bytes.len().min(HEADER_LEN)], limit)?;
    file_io::check_length(path, bytes.len() as u64, total)?;
    finish(path, bytes, kind, res, bbox)
}

/// Reads a raw grid, checking the header, length and memory limit before the voxels.
pub fn read(path: &Path, limit: u64) -> Result<RawGrid, VolumeError> {
    let mut hdr = None;
    let bytes = file_io::read_checked(path, HEADER_LEN, |h, _| {
        let (kind, res, bbox, total) = parse_header(path, h, limit)?;
        hdr = Some((kind, res, bbox));
        Ok(total)
    })?;
    let (kind, res, bbox) = hdr.expect("the header was parsed");
    finish(path, &bytes, kind, res, bbox)
}

fn header<T: Copy + Default>(kind: u32, g: &Grid<T>) -> Vec<u8> {
    let mut h = Vec::with_capacity(HEADER_LEN);
    h.extend_from_slice(MAGIC);
    h.extend_from_slice(&kind.to_le_bytes());
    for r in g.res() {
        h.extend_from_slice(&r.to_le_bytes());
    }
    file_io::push_box(&mut h, &g.bbox);
    h
}

/// Writes a raw grid.
pub fn write(path: &Path, grid: &RawGrid) -> Result<(), VolumeError> {
    match grid {
        RawGrid::Density(g) => file_io::write_file(path, &header(1, g), g.data(), f32::to_le_bytes),
        RawGrid::Trail(g) => file_io::write_file(path, &header(2, g), g.data(), u32::to_le_bytes),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tmp(name: &str) -> std::path::PathBuf {
        let d = std::env::temp_dir().join(format!("fathom-volume-raw-{}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        d.join(name)
    }

    #[test]
    fn round_trips_are_exact_for_both_kinds() {
        let bbox = WorldBox::new(Vec3::splat(-1.0), Vec3::new(1.0, 2.0, 3.0)).unwrap();
        let d = RawGrid::Density(
            Grid::from_data([3, 2, 1], vec![0.0, 1.5, 1e-30, 7.0, 0.25, 3e30], bbox).unwrap(),
        );
        let t = RawGrid::Trail(
            Grid::from_data([1, 2, 3], vec![0, 1, u32::MAX, 7, 42, 1 << 31], bbox).unwrap(),
        );
        for (i, g) in [d, t].into_iter().enumerate() {
            let p = tmp(&format!("g{i}.raw"));
            write(&p, &g).unwrap();
            assert_eq!(read(&p, 1 << 20).unwrap(), g);
            let bytes = std::fs::read(&p).unwrap();
            assert_eq!(parse(&bytes, &p, 1 << 20).unwrap(), g);
            let e = parse(&bytes[..bytes.len() - 1], &p, 1 << 20)
                .unwrap_err()
                .to_string();
            assert!(e.contains("truncated"), "{e}");
        }
    }

    #[test]
    fn bad_headers_say_what_is_wrong() {
        let p = Path::new("bad.raw");
        let g = RawGrid::Trail(Grid::from_data([1, 1, 1], vec![3], WorldBox::UNIT).unwrap());
        let q = tmp("ok.raw");
        write(&q, &g).unwrap();
        let good = std::fs::read(&q).unwrap();
        let mut b = good.clone();
        b[8] = 9;
        assert!(
            parse(&b, p, 1 << 20)
                .unwrap_err()
                .to_string()
                .contains("voxel kind 9")
        );
        let mut b = good.clone();
        b[12..16].copy_from_slice(&100_000u32.to_le_bytes());
        assert!(
            parse(&b, p, 1 << 20)
                .unwrap_err()
                .to_string()
                .contains("1..=8192")
        );
        let mut b = good.clone();
        b[24..28].copy_from_slice(&f32::NAN.to_le_bytes());
        assert!(
            parse(&b, p, 1 << 20)
                .unwrap_err()
                .to_string()
                .contains("byte 24")
        );
        assert!(
            parse(&good[..10], p, 1 << 20)
                .unwrap_err()
                .to_string()
                .contains("truncated inside its header")
        );
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(256))]

        /// Any bytes: an error or a grid, never a panic.
        #[test]
        fn random_bytes_never_panic(
            bytes in proptest::collection::vec(proptest::prelude::any::<u8>(), 0..120),
        ) {
            let _ = parse(&bytes, Path::new("fuzz.raw"), 1 << 16);
        }

        /// A valid file with bytes overwritten (header fields included) or cut short: an
        /// error naming the file, or a grid of the size the header declares.
        #[test]
        fn mutated_files_parse_or_fail_naming_the_file(
            kind in 0usize..2,
            edits in proptest::collection::vec((0usize..80, proptest::prelude::any::<u8>()), 1..6),
            cut in proptest::option::of(0usize..80),
        ) {
            let bbox = WorldBox::UNIT;
            let g = if kind == 0 {
                RawGrid::Density(Grid::from_data([2, 2, 2], vec![0.5; 8], bbox).unwrap())
            } else {
                RawGrid::Trail(Grid::from_data([2, 2, 2], vec![7; 8], bbox).unwrap())
            };
            let q = tmp(&format!("mut{kind}.raw"));
            write(&q, &g).unwrap();
            let mut b = std::fs::read(&q).unwrap();
            for (at, v) in edits {
                if at < b.len() {
                    b[at] = v;
                }
            }
            if let Some(n) = cut {
                b.truncate(n);
            }
            match parse(&b, Path::new("fuzz.raw"), 1 << 16) {
                Ok(g) => {
                    let voxels = match g {
                        RawGrid::Density(g) => g.data().len(),
                        RawGrid::Trail(g) => g.data().len(),
                    };
                    proptest::prop_assert_eq!(voxels * 4 + HEADER_LEN, b.len());
                }
                Err(e) => proptest::prop_assert!(e.to_string().contains("fuzz.raw"), "{}", e),
            }
        }
    }
}
