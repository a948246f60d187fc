//! Diffusion and decay of the trail grid, one step: each voxel moves `diffusion` of the way to
//! the mean of its 3x3x3 neighbourhood, then keeps `decay` of the result (truncated, so faint
//! trails die out). The box filter is separable: each z range is processed by one task that
//! keeps three x-y-filtered planes in a ring, so the grid is read and written once per step.
//! Every voxel's arithmetic is the same whichever task computes it: the result does not depend
//! on the thread count.

use super::params::Boundary;
use rayon::prelude::*;

/// Trail voxels are capped here after diffusion (see [`super::params::MAX_STEP_DEPOSIT`]).
pub const CELL_MAX: u32 = (1 << 31) - 1;

/// The neighbour index of `i - 1` and `i + 1` along an axis of `n` cells.
#[inline(always)]
fn neighbours(i: usize, n: usize, b: Boundary) -> (usize, usize) {
    match b {
        Boundary::Wrap => ((i + n - 1) % n, (i + 1) % n),
        Boundary::Walls => (i.saturating_sub(1), (i + 1).min(n - 1)),
    }
}

/// Work buffers of one task: a row as f32, the x sums of a plane, and the ring of three x-y
/// sums (planes z - 1, z, z + 1 at slots `z % 3`).
struct Buffers {
    row: Vec<f32>,
    xsum: Vec<f32>,
    ring: [Vec<f32>; 3],
}

/// The x-y 3x3 box sum of `plane` (`rx` x `ry`) into `out`.
fn plane_sum(
    plane: &[u32],
    rx: usize,
    ry: usize,
    b: Boundary,
    row: &mut [f32],
    xsum: &mut [f32],
    out: &mut [f32],
) {
    for (src, t) in plane.chunks_exact(rx).zip(xsum.chunks_exact_mut(rx)) {
        for (f, &v) in row.iter_mut().zip(src) {
            *f = v as f32;
        }
        if rx >= 3 {
            for (o, w) in t[1..rx - 1].iter_mut().zip(row.windows(3)) {
                *o = w[0] + w[1] + w[2];
            }
        }
        for x in [0, rx - 1] {
            let (a, c) = neighbours(x, rx, b);
            t[x] = row[a] + row[x] + row[c];
        }
    }
    for (y, o) in out.chunks_exact_mut(rx).enumerate() {
        let (a, c) = neighbours(y, ry, b);
        let (ta, tb, tc) = (
            &xsum[a * rx..][..rx],
            &xsum[y * rx..][..rx],
            &xsum[c * rx..][..rx],
        );
        for (((o, &p), &q), &r) in o.iter_mut().zip(ta).zip(tb).zip(tc) {
            *o = p + q + r;
        }
    }
}

/// `dst = decay * ((1 - diffusion) src + diffusion * box3(src))`, capped at [`CELL_MAX`].
pub fn diffuse(
    src: &[u32],
    dst: &mut [u32],
    res: [u32; 3],
    diffusion: f32,
    decay: f32,
    b: Boundary,
) {
    let [rx, ry, rz] = res.map(|r| r as usize);
    let plane = rx * ry;
    let keep = decay * (1.0 - diffusion);
    let spread = decay * diffusion / 27.0;
    let src_plane = |z: usize| &src[z * plane..(z + 1) * plane];
    // z planes per task: enough tasks to balance, few enough that the two extra planes each
    // task filters stay cheap.
    let per_task = rz.div_ceil(4 * rayon::current_num_threads()).max(4);
    dst.par_chunks_mut(plane * per_task)
        .enumerate()
        .for_each(|(task, out)| {
            let z0 = task * per_task;
            let z1 = (z0 + per_task).min(rz);
            let mut w = Buffers {
                row: vec![0.0; rx],
                xsum: vec![0.0; plane],
                ring: std::array::from_fn(|_| vec![0.0; plane]),
            };
            let slot = |z: usize| z % 3;
            let (below, _) = neighbours(z0, rz, b);
            plane_sum(
                src_plane(below),
                rx,
                ry,
                b,
                &mut w.row,
                &mut w.xsum,
                &mut w.ring[slot(z0 + 2)],
            );
            plane_sum(
                src_plane(z0),
                rx,
                ry,
                b,
                &mut w.row,
                &mut w.xsum,
                &mut w.ring[slot(z0)],
            );
            for (z, o) in (z0..z1).zip(out.chunks_exact_mut(plane)) {
                let (_, above) = neighbours(z, rz, b);
                plane_sum(
                    src_plane(above),
                    rx,
                    ry,
                    b,
                    &mut w.row,
                    &mut w.xsum,
                    &mut w.ring[slot(z + 1)],
                );
                let (pa, pb, pc) = (&w.ring[slot(z + 2)], &w.ring[slot(z)], &w.ring[slot(z + 1)]);
                for ((((o, &s), &a), &b), &c) in
                    o.iter_mut().zip(src_plane(z)).zip(pa).zip(pb).zip(pc)
                {
                    let v = keep * s as f32 + spread * (a + b + c);
                    // v >= 0; through i32, which the vector units convert to directly.
                    *o = v.min(CELL_MAX as f32) as i32 as u32;
                }
            }
        });
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The direct 27-point definition, for comparison.
    fn reference(src: &[u32], res: [u32; 3], diffusion: f32, decay: f32, b: Boundary) -> Vec<u32> {
        let [rx, ry, rz] = res.map(|r| r as usize);
        let at = |x: usize, y: usize, z: usize| src[x + rx * (y + ry * z)];
        let mut out = vec![0; src.len()];
        for z in 0..rz {
            for y in 0..ry {
                for x in 0..rx {
                    let mut sum = 0.0f64;
                    let (xs, ys, zs) = (
                        neighbours(x, rx, b),
                        neighbours(y, ry, b),
                        neighbours(z, rz, b),
                    );
                    for zz in [zs.0, z, zs.1] {
                        for yy in [ys.0, y, ys.1] {
                            for xx in [xs.0, x, xs.1] {
                                sum += at(xx, yy, zz) as f64;
                            }
                        }
                    }
                    let v = decay as f64
                        * ((1.0 - diffusion as f64) * at(x, y, z) as f64
                            + diffusion as f64 * sum / 27.0);
                    out[x + rx * (y + ry * z)] = v as u32;
                }
            }
        }
        out
    }

    #[test]
    fn separable_ring_filter_matches_the_27_point_definition() {
        let res = [7u32, 5, 9];
        let n = (res[0] * res[1] * res[2]) as usize;
        let mut s = 1u64;
        let src: Vec<u32> = (0..n)
            .map(|_| {
                s = crate::sampling::mix64(s);
                (s % 5000) as u32
            })
            .collect();
        for b in [Boundary::Wrap, Boundary::Walls] {
            let mut dst = vec![0; n];
            diffuse(&src, &mut dst, res, 0.6, 0.9, b);
            let want = reference(&src, res, 0.6, 0.9, b);
            for (i, (g, w)) in dst.iter().zip(&want).enumerate() {
                // f32 versus f64 sums: truncation may differ by one count.
                assert!(g.abs_diff(*w) <= 1, "{b:?} voxel {i}: {g} vs {w}");
            }
        }
    }

    #[test]
    fn faint_trails_die_and_big_ones_are_capped() {
        let res = [4u32, 4, 4];
        let mut src = vec![1u32; 64];
        let mut dst = vec![0; 64];
        diffuse(&src, &mut dst, res, 0.5, 0.9, Boundary::Wrap);
        assert!(dst.iter().all(|&v| v == 0));
        src.fill(u32::MAX);
        diffuse(&src, &mut dst, res, 0.5, 1.0, Boundary::Walls);
        assert!(dst.iter().all(|&v| v == CELL_MAX));
    }
}
