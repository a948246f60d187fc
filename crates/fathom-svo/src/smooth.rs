//! Wide voxels drawn smooth: each pixel whose voxel is at least two pixels wide takes the
//! mean colour of a box about as wide as that voxel on screen.
//!
//! While detail arrives a zoom shows leaves tens of pixels wide, each one flat colour, so the
//! frame is a mosaic whose block edges are structure the surface does not have. A box filter
//! as wide as a block, run over an image of such blocks, interpolates linearly between the
//! blocks' centres (bilinearly in two dimensions): the colours the leaves were shaded with,
//! joined smoothly instead of stepped. Pixels whose voxel is narrower than two pixels keep
//! their colour, so a frame settled to pixel-sized voxels is unchanged. The widths vary per pixel, so the boxes are
//! summed from a summed-area table (Crow 1984) in constant time whatever their size. Written
//! here rather than taken from an image crate: the filter's width comes from the octree's
//! traversal, per pixel, and the table is a few lines.
//!
//! Memory: the table takes 16 bytes a pixel (4.9 MB at 640x480, 133 MB at 3840x2160), kept
//! between frames and not counted in the octree's memory budget; it is allocated on the first
//! frame that shows a voxel two pixels wide.

use rayon::prelude::*;

/// A pixel's box half-width for a voxel `px` pixels wide on screen: 0 (keep the pixel) below 2
/// pixels, else `px / 2` rounded down, so the box is `2 r + 1` wide, within a pixel of the
/// voxel's width; at most [`MAX_HALF_WIDTH`].
pub fn half_width(px: f64) -> u8 {
    if px < MIN_WIDE_PX {
        0
    } else {
        (px * 0.5).min(MAX_HALF_WIDTH as f64) as u8
    }
}

/// How wide on screen, in pixels, a voxel must be to be smoothed.
pub const MIN_WIDE_PX: f64 = 2.0;

/// The widest box's half-width in pixels: voxels wider than 511 pixels are smoothed as if they
/// were that wide (on a 640x480 frame only the first frames of a cold start show such voxels).
pub const MAX_HALF_WIDTH: u8 = 255;

/// Bands the summed-area table is built in, in parallel: each band sums its own rows, then
/// every band but the first adds the sums of the rows above it.
const BANDS: usize = 8;

/// Four channels' sums (RGBA; alpha is summed too, and ignored).
type Sums = [u32; 4];

/// `a + b` per lane, wrapping.
#[inline]
fn add(a: Sums, b: Sums) -> Sums {
    std::array::from_fn(|k| a[k].wrapping_add(b[k]))
}

/// `a - b` per lane, wrapping.
#[inline]
fn sub(a: Sums, b: Sums) -> Sums {
    std::array::from_fn(|k| a[k].wrapping_sub(b[k]))
}

/// An RGBA8 colour's channels as lanes.
#[inline]
fn lanes(c: u32) -> Sums {
    c.to_le_bytes().map(u32::from)
}

/// `v` rounded to the nearest integer, for `v` in [0, 2^22): adding 1.5 x 2^23 leaves the
/// integer in the float's low mantissa bits. Cheaper than `as u32`, which saturates (the
/// filter took about a fifth less time); the sums convert with `as i32 as f32` for the same
/// reason (they are below 2^31).
#[inline]
fn round_small(v: f32) -> u32 {
    const MAGIC: f32 = 12_582_912.0;
    (v + MAGIC).to_bits().wrapping_sub(MAGIC.to_bits())
}

/// Smooths frames of wide voxels, keeping its summed-area table between frames (so a frame
/// does not allocate and fault in a few megabytes of it; frames may change size).
#[derive(Default)]
pub struct Smoother {
    /// `table[(y + 1) * (width + 1) + x + 1]`: the per-channel sums of the pixels above and
    /// left of (x, y), inclusive, modulo 2^32; a zero row and column in front.
    table: Vec<Sums>,
}

impl Smoother {
    /// Replaces each pixel with `half[i] > 0` by the mean RGB of the `(2 half + 1)`-wide
    /// square about it (clipped to the image) of `colour` (RGBA8, linear; alpha set to 255).
    /// Pixels with `half[i] == 0` are left as they are. Sums are kept in wrapping `u32`: a
    /// box's sum is the table's four corners combined, exact modulo 2^32 whatever the
    /// image's size, and a box holds at most 511^2 x 255 < 2^31. Runs on the current rayon
    /// pool.
    pub fn smooth(&mut self, colour: &mut [u32], half: &[u8], width: usize, height: usize) {
        assert_eq!(colour.len(), width * height);
        assert_eq!(half.len(), width * height);
        if width == 0 || height == 0 {
            return;
        }
        let tw = width + 1;
        self.table.resize(tw * (height + 1), [0; 4]);
        let table = &mut self.table;
        // The zero row in front (a table kept from a narrower frame has sums there).
        table[..tw].fill([0; 4]);
        // Each band of rows: running sums along its rows, plus the band's rows above.
        let band = height.div_ceil(BANDS);
        table[tw..]
            .par_chunks_mut(band * tw)
            .zip(colour.par_chunks(band * width))
            .for_each(|(rows, src)| {
                for (j, src) in src.chunks(width).enumerate() {
                    let (above, rows) = rows.split_at_mut(j * tw);
                    let row = &mut rows[..tw];
                    let mut run = [0u32; 4];
                    row[0] = run;
                    if j == 0 {
                        for (cell, &c) in row[1..].iter_mut().zip(src) {
                            run = add(run, lanes(c));
                            *cell = run;
                        }
                    } else {
                        let above = &above[(j - 1) * tw + 1..];
                        for ((cell, &c), &a) in row[1..].iter_mut().zip(src).zip(above) {
                            run = add(run, lanes(c));
                            *cell = add(run, a);
                        }
                    }
                }
            });
        // The sums of all rows above each band (its last row's sums carried down), then added.
        let bands = height.div_ceil(band);
        let mut carry = vec![[0u32; 4]; tw * bands];
        for b in 1..bands {
            let last = &table[(b * band) * tw..(b * band + 1) * tw];
            let (done, next) = carry.split_at_mut(b * tw);
            for ((n, &p), &l) in next[..tw].iter_mut().zip(&done[(b - 1) * tw..]).zip(last) {
                *n = add(p, l);
            }
        }
        table[tw..]
            .par_chunks_mut(band * tw)
            .zip(carry.par_chunks(tw))
            .skip(1)
            .for_each(|(rows, carried)| {
                for row in rows.chunks_mut(tw) {
                    for (cell, &a) in row.iter_mut().zip(carried) {
                        *cell = add(*cell, a);
                    }
                }
            });
        let table = &self.table;
        colour
            .par_chunks_mut(width)
            .zip(half.par_chunks(width))
            .enumerate()
            .for_each(|(y, (row, hrow))| {
                for (x, (c, &r)) in row.iter_mut().zip(hrow).enumerate() {
                    if r == 0 {
                        continue;
                    }
                    let r = r as usize;
                    let (x0, x1) = (x.saturating_sub(r), (x + r + 1).min(width));
                    let (y0, y1) = (y.saturating_sub(r), (y + r + 1).min(height));
                    let inv = 1.0 / ((x1 - x0) * (y1 - y0)) as i32 as f32;
                    let (top, bottom) = (&table[y0 * tw..][..tw], &table[y1 * tw..][..tw]);
                    let sum = add(sub(bottom[x1], bottom[x0]), sub(top[x0], top[x1]));
                    let mean = sum.map(|s| round_small(s as i32 as f32 * inv));
                    *c = u32::from_le_bytes(mean.map(|m| m as u8)) | 255 << 24;
                }
            });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rgb(r: u32, g: u32, b: u32) -> u32 {
        255 << 24 | b << 16 | g << 8 | r
    }

    /// The mean by brute force, for comparison.
    fn box_mean(colour: &[u32], w: usize, h: usize, x: usize, y: usize, r: usize) -> u32 {
        let mut sum = [0u32; 3];
        let mut n = 0;
        for yy in y.saturating_sub(r)..(y + r + 1).min(h) {
            for xx in x.saturating_sub(r)..(x + r + 1).min(w) {
                for (k, s) in sum.iter_mut().enumerate() {
                    *s += (colour[yy * w + xx] >> (8 * k)) & 255;
                }
                n += 1;
            }
        }
        rgb(
            (sum[0] + n / 2) / n,
            (sum[1] + n / 2) / n,
            (sum[2] + n / 2) / n,
        )
    }

    #[test]
    fn boxes_from_the_table_are_the_brute_force_means() {
        let (w, h) = (37, 23);
        let colour: Vec<u32> = (0..w * h)
            .map(|i| {
                rgb(
                    (i * 37 % 256) as u32,
                    (i * 11 % 256) as u32,
                    (i * 101 % 256) as u32,
                )
            })
            .collect();
        let half: Vec<u8> = (0..w * h).map(|i| (i * 7 % 13) as u8).collect();
        let mut out = colour.clone();
        Smoother::default().smooth(&mut out, &half, w, h);
        for y in 0..h {
            for x in 0..w {
                let i = y * w + x;
                let want = match half[i] {
                    0 => colour[i],
                    r => box_mean(&colour, w, h, x, y, r as usize),
                };
                // The mean is rounded in f32: within one of the integer rounding.
                for k in 0..4 {
                    let (o, w) = ((out[i] >> (8 * k)) & 255, (want >> (8 * k)) & 255);
                    assert!(
                        o.abs_diff(w) <= 1,
                        "pixel ({x}, {y}), half-width {}",
                        half[i]
                    );
                }
            }
        }
    }

    #[test]
    fn one_smoother_serves_frames_of_any_size_and_shape() {
        // Narrow then wide (the kept table's first row must not leak into the wide frame's
        // top boxes), then shapes with fewer rows than bands, one row and one column: each
        // against a fresh smoother's result, which the brute-force test checks.
        let mut kept = Smoother::default();
        for (w, h) in [(5, 4), (40, 9), (3, 2), (1, 1), (17, 1), (1, 13), (40, 9)] {
            let colour: Vec<u32> = (0..w * h)
                .map(|i| {
                    rgb(
                        (i * 53 % 256) as u32,
                        (i * 29 % 256) as u32,
                        255 - (i % 256) as u32,
                    )
                })
                .collect();
            let half: Vec<u8> = (0..w * h).map(|i| (i % 5) as u8).collect();
            let (mut a, mut b) = (colour.clone(), colour.clone());
            kept.smooth(&mut a, &half, w, h);
            Smoother::default().smooth(&mut b, &half, w, h);
            assert_eq!(a, b, "{w}x{h}");
            for (i, (&o, &c)) in a.iter().zip(&colour).enumerate() {
                if half[i] > 0 {
                    let want = box_mean(&colour, w, h, i % w, i / w, half[i] as usize);
                    assert!(
                        (0..3)
                            .all(|k| ((o >> (8 * k)) & 255).abs_diff((want >> (8 * k)) & 255) <= 1)
                    );
                } else {
                    assert_eq!(o, c);
                }
            }
        }
    }

    #[test]
    fn a_mosaic_of_blocks_becomes_a_ramp_between_their_centres() {
        // Blocks 8 pixels wide along x, each a step brighter: filtered with boxes as wide as
        // a block, the pixels between two centres climb one step, not all at once.
        let (w, h, block) = (64, 8, 8);
        let colour: Vec<u32> = (0..w * h)
            .map(|i| {
                let v = ((i % w) / block * 30) as u32;
                rgb(v, v, v)
            })
            .collect();
        let half = vec![half_width(block as f64); w * h];
        assert_eq!(half[0], 4);
        let mut out = colour.clone();
        Smoother::default().smooth(&mut out, &half, w, h);
        let row: Vec<u32> = out[3 * w..4 * w].iter().map(|c| c & 255).collect();
        // Between the centres of blocks 2 and 3 (x = 20 and 28), every pixel steps by at
        // most a third of the blocks' difference, and the ramp rises monotonically.
        for x in 20..28 {
            assert!(row[x + 1] >= row[x] && row[x + 1] - row[x] <= 10, "{row:?}");
        }
        assert!(row[20] <= 65 && row[28] >= 85, "{row:?}");
    }

    #[test]
    fn narrow_voxels_and_sky_keep_their_colours() {
        assert_eq!(half_width(0.0), 0);
        assert_eq!(half_width(1.99), 0);
        assert_eq!(half_width(2.0), 1);
        assert_eq!(half_width(5.9), 2);
        assert_eq!(half_width(1e9), MAX_HALF_WIDTH);
        let (w, h) = (16, 16);
        let colour: Vec<u32> = (0..w * h).map(|i| rgb(i as u32 % 256, 7, 200)).collect();
        let mut out = colour.clone();
        Smoother::default().smooth(&mut out, &vec![0; w * h], w, h);
        assert_eq!(out, colour);
    }
}
