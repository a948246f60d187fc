//! Mitsuba 3's `.vol` grid format, read and written with Mitsuba's exact conventions, so the
//! same grid renders in both.
//!
//! Layout (little-endian): bytes 0-2 `VOL`, byte 3 version 3, i32 encoding (1 = float32, the
//! only one Mitsuba 3 reads), i32 res x, y, z, i32 channel count (1 here: a density), six f32
//! of a bounding box (min xyz, max xyz), then `res_x * res_y * res_z * channels` f32 with x
//! fastest, then y, then z. Mitsuba 3 ignores the bounding box: the grid spans the unit cube
//! unless its `to_world` moves it (checked against mitsuba 3.9). We write the grid's world box
//! there and report it back, but a grid read from a file sits in the unit cube, like
//! Mitsuba's; the caller may place it in the file's box ([`VolFile::file_box`]) or any other.

use crate::error::VolumeError;
use crate::file_io::{self, Fields, format_err};
use crate::grid::{DensityGrid, Grid, WorldBox, check_size};
use std::path::Path;

/// Header length in bytes.
pub const HEADER_LEN: usize = 48;

/// A grid read from a `.vol` file.
#[derive(Clone, Debug, PartialEq)]
pub struct VolFile {
    /// The densities, placed in the unit cube.
    pub grid: DensityGrid,
    /// The bounding box written in the file (min xyz, max xyz), unchecked.
    pub bbox: [f32; 6],
}

impl VolFile {
    /// The file's bounding box, if it is a valid box.
    pub fn file_box(&self) -> Result<WorldBox, VolumeError> {
        let b = self.bbox;
        WorldBox::new(
            b[..3].try_into().map(glam::Vec3::from_array).unwrap(),
            glam::Vec3::new(b[3], b[4], b[5]),
        )
    }
}

/// Parses the header; returns the resolution, the box and the total file length it implies.
fn parse_header(
    path: &Path,
    header: &[u8],
    limit: u64,
) -> Result<([u32; 3], [f32; 6], u64), VolumeError> {
    let mut f = Fields {
        path,
        bytes: header,
        at: 0,
    };
    let magic = f.take(3, "the magic bytes `VOL`")?;
    if magic != b"VOL" {
        return Err(format_err(
            path,
            0,
            format!("not a Mitsuba volume: it starts with {magic:?}, expected the bytes `VOL`"),
        ));
    }
    let version = f.take(1, "the version byte")?[0];
    if version != 3 {
        return Err(format_err(
            path,
            3,
            format!("version {version} is not supported (supported versions: 3)"),
        ));
    }
    let encoding = f.i32("the encoding")?;
    if encoding != 1 {
        return Err(format_err(
            path,
            4,
            format!(
                "encoding {encoding} is not supported (supported encodings: 1 = float32; \
                 Mitsuba 3 reads and writes only that one)"
            ),
        ));
    }
    let mut res = [0u32; 3];
    for (a, name) in ["x", "y", "z"].iter().enumerate() {
        let v = f.i32(&format!("the {name} resolution"))?;
        if v <= 0 || v as u32 > crate::grid::MAX_RES {
            return Err(format_err(
                path,
                8 + 4 * a as u64,
                format!(
                    "{name} resolution {v} is out of range 1..={}",
                    crate::grid::MAX_RES
                ),
            ));
        }
        res[a] = v as u32;
    }
    let channels = f.i32("the channel count")?;
    if channels != 1 {
        return Err(format_err(
            path,
            20,
            format!("{channels} channels: a density grid has exactly 1"),
        ));
    }
    let bbox = f.f32s::<6>("the bounding box")?;
    let n = check_size(&path.display().to_string(), res.map(u64::from), 4, limit)?;
    Ok((res, bbox, (HEADER_LEN + 4 * n) as u64))
}

/// Turns a whole, length-checked file into a grid, refusing NaN, infinite or negative values.
fn finish(
    path: &Path,
    bytes: &[u8],
    res: [u32; 3],
    bbox: [f32; 6],
) -> Result<VolFile, VolumeError> {
    let data = file_io::words(&bytes[HEADER_LEN..], f32::from_le_bytes);
    let grid = Grid::from_data(res, data, WorldBox::UNIT)?;
    grid.validate_densities(&path.display().to_string())?;
    Ok(VolFile { grid, bbox })
}

/// Parses a `.vol` file held in memory; `path` names it in errors.
pub fn parse(bytes: &[u8], path: &Path, limit: u64) -> Result<VolFile, VolumeError> {
    let (res, bbox, total) = parse_header(path, &bytes[..bytes.len().min(HEADER_LEN)], limit)?;
    file_io::check_length(path, bytes.len() as u64, total)?;
    finish(path, bytes, res, bbox)
}

/// Reads a `.vol` file, refusing it before reading the voxels if the header is bad, the
/// length disagrees with it, or the grid exceeds `limit` bytes.
pub fn read(path: &Path, limit: u64) -> Result<VolFile, VolumeError> {
    let mut hdr = None;
    let bytes = file_io::read_checked(path, HEADER_LEN, |h, _| {
        let (res, bbox, total) = parse_header(path, h, limit)?;
        hdr = Some((res, bbox));
        Ok(total)
    })?;
    let (res, bbox) = hdr.expect("the header was parsed");
    finish(path, &bytes, res, bbox)
}

/// The header of `grid` (with its world box as the bounding box).
fn header(grid: &DensityGrid) -> Vec<u8> {
    let mut h = Vec::with_capacity(HEADER_LEN);
    h.extend_from_slice(b"VOL\x03");
    h.extend_from_slice(&1i32.to_le_bytes());
    for r in grid.res() {
        h.extend_from_slice(&(r as i32).to_le_bytes());
    }
    h.extend_from_slice(&1i32.to_le_bytes());
    file_io::push_box(&mut h, &grid.bbox);
    h
}

/// Writes `grid` as a `.vol` file (its world box goes in the bounding-box field).
pub fn write(path: &Path, grid: &DensityGrid) -> Result<(), VolumeError> {
    file_io::write_file(path, &header(grid), grid.data(), f32::to_le_bytes)
}

/// The bytes of `grid` as a `.vol` file.
pub fn to_bytes(grid: &DensityGrid) -> Vec<u8> {
    let mut b = header(grid);
    b.extend(grid.data().iter().flat_map(|v| v.to_le_bytes()));
    b
}

#[cfg(test)]
mod tests;
