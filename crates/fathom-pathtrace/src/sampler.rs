//! Per-pixel low-discrepancy samples: Owen-scrambled Sobol points, seeded by (pixel, sample
//! index, dimension) only.
//!
//! Why Sobol with Owen scrambling: the first two Sobol dimensions form a (0,2)-sequence, so
//! every power-of-two prefix of a pixel's samples is stratified in every elementary interval;
//! a progressive renderer that stops at any power of two gets that stratification for free,
//! and Owen scrambling keeps it while decorrelating pixels and removing the structured
//! artefacts of an unscrambled sequence (Owen 1995; the hashing form is Burley 2020,
//! "Practical Hash-based Owen Scrambling", JCGT 9(4)). Blue-noise masks or the R2 sequence
//! would need a precomputed texture or give no stratification guarantee per prefix.
//!
//! Each 2D request of a path (pixel position, lens, light, BSDF ...) is its own "padded"
//! dimension pair: the same two Sobol dimensions, with the sample index shuffled and the
//! coordinates scrambled by seeds hashed from (pixel, dimension). Nothing depends on thread,
//! tile or call order, so images are identical for any number of threads.
//!
//! Every function here is integer arithmetic on `u32`, ready for WGSL.

/// A mixing hash of one 32-bit word (an avalanche finaliser in the manner of MurmurHash3's
/// `fmix32`, with constants chosen by Wellons' "hash prospector" search).
#[inline]
pub fn hash(mut x: u32) -> u32 {
    x ^= x >> 16;
    x = x.wrapping_mul(0x7feb_352d);
    x ^= x >> 15;
    x = x.wrapping_mul(0x846c_a68b);
    x ^= x >> 16;
    x
}

/// Hashes two words into one (not symmetric).
#[inline]
pub fn hash2(a: u32, b: u32) -> u32 {
    hash(a ^ hash(b).wrapping_add(0x9e37_79b9))
}

/// The Laine-Karras style permutation of Burley 2020: each output bit depends only on the input
/// bits below it, so applied to a bit-reversed number it is a nested uniform (Owen) scramble.
#[inline]
fn lk_permute(mut x: u32, seed: u32) -> u32 {
    x = x.wrapping_add(seed);
    x ^= x.wrapping_mul(0x6c50_b47c);
    x ^= x.wrapping_mul(0xb82f_1e52);
    x ^= x.wrapping_mul(0xc7af_e638);
    x ^= x.wrapping_mul(0x8d22_f6e6);
    x
}

/// Owen scrambling of a 32-bit binary fraction `x` (most significant bit first).
#[inline]
pub fn owen_scramble(x: u32, seed: u32) -> u32 {
    lk_permute(x.reverse_bits(), seed).reverse_bits()
}

/// Sobol dimension 0 (van der Corput): the index's bits reversed.
#[inline]
pub fn sobol0(i: u32) -> u32 {
    i.reverse_bits()
}

/// Sobol dimension 1: generator matrix = the Pascal matrix mod 2 (column k is the previous
/// column xor itself shifted right by one).
#[inline]
pub fn sobol1(mut i: u32) -> u32 {
    let mut v = 1u32 << 31;
    let mut x = 0u32;
    while i != 0 {
        if i & 1 != 0 {
            x ^= v;
        }
        i >>= 1;
        v ^= v >> 1;
    }
    x
}

/// A 32-bit fraction to a float in [0, 1).
#[inline]
pub fn to_unit(x: u32) -> f64 {
    x as f64 * (1.0 / 4_294_967_296.0)
}

/// The samples of one path: pixel (`x`, `y`), sample `index`, dimensions handed out in order.
#[derive(Clone, Debug)]
pub struct PixelSampler {
    pixel_seed: u32,
    index: u32,
    dimension: u32,
}

impl PixelSampler {
    /// The sampler of sample `index` of pixel (`x`, `y`), with a scene-wide `seed`.
    pub fn new(x: u32, y: u32, index: u32, seed: u32) -> Self {
        PixelSampler {
            pixel_seed: hash2(hash2(x, y), seed),
            index,
            dimension: 0,
        }
    }

    /// The next 2D sample in [0, 1)^2.
    pub fn next_2d(&mut self) -> [f64; 2] {
        let s = hash2(self.pixel_seed, self.dimension);
        self.dimension += 1;
        let i = owen_scramble(self.index, hash2(s, 1));
        [
            to_unit(owen_scramble(sobol0(i), hash2(s, 2))),
            to_unit(owen_scramble(sobol1(i), hash2(s, 3))),
        ]
    }

    /// The next 1D sample in [0, 1) (the first coordinate of a dimension pair).
    pub fn next_1d(&mut self) -> f64 {
        self.next_2d()[0]
    }

    /// How many dimension pairs this path has used.
    pub fn dimensions_used(&self) -> u32 {
        self.dimension
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sobol1_matches_known_direction_numbers() {
        // The first direction numbers of Sobol's second dimension (Joe and Kuo's tables):
        // 1/2, 3/4, 5/8, 15/16.
        assert_eq!(sobol1(1), 0x8000_0000);
        assert_eq!(sobol1(2), 0xc000_0000);
        assert_eq!(sobol1(4), 0xa000_0000);
        assert_eq!(sobol1(8), 0xf000_0000);
        assert_eq!(sobol1(3), 0x4000_0000);
    }

    #[test]
    fn owen_scramble_is_a_bijection_on_prefixes() {
        // A nested scramble maps the 2^k aligned intervals onto each other: the top k bits of
        // the output depend only on the top k bits of the input.
        for seed in [1u32, 0xdead_beef, 77] {
            let mut seen = [false; 256];
            for x in 0..256u32 {
                let y = owen_scramble(x << 24, seed) >> 24;
                assert!(!seen[y as usize]);
                seen[y as usize] = true;
            }
        }
    }

    /// Every power-of-two prefix of a pixel's samples is a (0,m,2)-net: one point in each
    /// elementary interval of area 1/n, for all shapes 2^a x 2^b with a + b = m.
    #[test]
    fn prefixes_are_stratified_in_every_elementary_interval() {
        for (px, py) in [(0, 0), (17, 3), (640, 479)] {
            for dim in 0..4 {
                for m in [2u32, 4, 6, 8] {
                    let n = 1u32 << m;
                    let pts: Vec<[f64; 2]> = (0..n)
                        .map(|i| {
                            let mut s = PixelSampler::new(px, py, i, 5);
                            for _ in 0..dim {
                                s.next_2d();
                            }
                            s.next_2d()
                        })
                        .collect();
                    for a in 0..=m {
                        let (nx, ny) = (1u32 << a, 1u32 << (m - a));
                        let mut count = vec![0u32; n as usize];
                        for p in &pts {
                            let cx = (p[0] * nx as f64) as u32;
                            let cy = (p[1] * ny as f64) as u32;
                            count[(cy * nx + cx) as usize] += 1;
                        }
                        assert!(
                            count.iter().all(|&c| c == 1),
                            "pixel ({px},{py}) dim {dim} n {n} intervals {nx}x{ny}"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn pixels_and_dimensions_are_decorrelated() {
        // The first sample of neighbouring pixels, and consecutive dimensions of one path,
        // should look independent: their means are near 1/2 and their correlation near 0.
        let n = 4096;
        let (mut sx, mut sxy, mut sy) = (0.0, 0.0, 0.0);
        for k in 0..n {
            let mut s = PixelSampler::new(k % 64, k / 64, 0, 9);
            let a = s.next_1d();
            let b = s.next_1d();
            sx += a;
            sy += b;
            sxy += (a - 0.5) * (b - 0.5);
        }
        let nf = n as f64;
        assert!((sx / nf - 0.5).abs() < 0.02 && (sy / nf - 0.5).abs() < 0.02);
        // Correlation of two uniforms: covariance / (1/12).
        assert!((sxy / nf * 12.0).abs() < 0.06, "{}", sxy / nf * 12.0);
    }
}
