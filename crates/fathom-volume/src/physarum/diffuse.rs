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

/// The x-y 3x3 box sum of plane `z` of `src` into `out` (`tmp` holds the x sums).
fn plane_sum(src: &[u32], res: [usize; 3], z: usize, b: Boundary, tmp: &mut [f32], out: &mut [f32]) {
    let [rx, ry, _] = res;
    let plane = &src[z * rx * ry..(z + 1) * rx * ry];
    for y in 0..ry {
        let row = &plane[y * rx..(y + 1) * rx];
        let t = &mut tmp[y * rx..(y + 1) * rx];
        for x in 1..rx.saturating_sub(1) {
            t[x] = row[x - 1] as f32 + row[x] as f32 + row[x + 1] as f32;
        }
        for x in [0, rx - 1] {
            let (a, c) = neighbours(x, rx, b);
            t[x] = row[a] as f32 + row[x] as f32 + row[c] as f32;
        }
    }
    for y in 0..ry {
        let (a, c) = neighbours(y, ry, b);
        let (ta, tb, tc) = (&tmp[a * rx..(a + 1) * rx], &tmp[y * rx..(y + 1) * rx], &tmp[c * rx..(c + 1) * rx]);
        for (((o, &p), &q), &r) in out[y * rx..(y + 1) * rx].iter_mut().zip(ta).zip(tb).zip(tc) {
            *o = p + q + r;
        }
    }
}

/// `dst = decay * ((1 - diffusion) src + diffusion * box3(src))`, capped at [`CELL_MAX`].
pub fn diffuse(src: &[u32], dst: &mut [u32], res: [u32; 3], diffusion: f32, decay: f32, b: Boundary) {
    let res = res.map(|r| r as usize);
    let [rx, ry, rz] = res;
    let plane = rx * ry;
    let keep = decay * (1.0 - diffusion);
    let spread = decay * diffusion / 27.0;
    // z planes per task: enough tasks to balance, few enough that the two extra planes each
    // task filters stay cheap.
    let per_task = rz.div_ceil(4 * rayon::current_num_threads()).max(4);
    dst.par_chunks_mut(plane * per_task)
        .enumerate()
        .for_each(|(task, out)| {
            let z0 = task * per_task;
            let z1 = (z0 + per_task).min(rz);
            let mut tmp = vec![0.0f32; plane];
            let mut ring: [Vec<f32>; 3] = std::array::from_fn(|_| vec![0.0f32; plane]);
            let slot = |z: usize| z % 3;
            let (below, _) = neighbours(z0, rz, b);
            plane_sum(src, res, below, b, &mut tmp, &mut ring[slot(z0 + 2)]);
            plane_sum(src, res, z0, b, &mut tmp, &mut ring[slot(z0)]);
            for z in z0..z1 {
                let (_, above) = neighbours(z, rz, b);
                plane_sum(src, res, above, b, &mut tmp, &mut ring[slot(z + 1)]);
                let (pa, pb, pc) = (&ring[slot(z + 2)], &ring[slot(z)], &ring[slot(z + 1)]);
                let s = &src[z * plane..(z + 1) * plane];
                let o = &mut out[(z - z0) * plane..(z - z0 + 1) * plane];
                for i in 0..plane {
                    let v = keep * s[i] as f32 + spread * (pa[i] + pb[i] + pc[i]);
                    o[i] = (v as u32).min(CELL_MAX);
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
                    let (xs, ys, zs) = (neighbours(x, rx, b), neighbours(y, ry, b), neighbours(z, rz, b));
                    for zz in [zs.0, z, zs.1] {
                        for yy in [ys.0, y, ys.1] {
                            for xx in [xs.0, x, xs.1] {
                                sum += at(xx, yy, zz) as f64;
                            }
                        }
                    }
                    let v = decay as f64 * ((1.0 - diffusion as f64) * at(x, y, z) as f64 + diffusion as f64 * sum / 27.0);
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
