//! Random numbers and the small sampling routines the tracer and the simulation share.
//!
//! Every camera sample draws from its own PCG32 stream keyed by (seed, pixel, sample index), and
//! every agent owns a stream keyed by (seed, agent index): what a path or an agent does never
//! depends on which thread ran it or in what order, so images and simulations are the same
//! bytes on any thread count.

use glam::Vec3;
use rand_core::Rng;
use rand_pcg::Pcg32;

/// A random stream.
#[derive(Clone, Debug)]
pub struct Stream(Pcg32);

/// SplitMix64's finaliser: spreads a key over all 64 bits.
#[inline]
pub fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

impl Stream {
    /// The stream of sample `sample` of pixel `pixel` (or of agent `pixel`, `sample` 0).
    #[inline]
    pub fn new(seed: u64, pixel: u64, sample: u64) -> Self {
        let state = mix64(seed ^ mix64(pixel.wrapping_add(0x9e37_79b9_7f4a_7c15)));
        Stream(Pcg32::new(state, mix64(sample ^ seed.rotate_left(32))))
    }

    /// Uniform in [0, 1).
    #[inline(always)]
    pub fn f32(&mut self) -> f32 {
        (self.0.next_u32() >> 8) as f32 * (1.0 / (1u32 << 24) as f32)
    }

    /// Uniform in 0..n (n > 0), by multiply-shift (bias below 2^-32 n).
    #[inline(always)]
    pub fn below(&mut self, n: u32) -> u32 {
        ((self.0.next_u32() as u64 * n as u64) >> 32) as u32
    }

    /// An exponentially distributed optical depth (rate 1).
    #[inline(always)]
    pub fn exp1(&mut self) -> f32 {
        -(1.0 - self.f32()).ln()
    }
}

/// A uniformly distributed unit vector.
#[inline]
pub fn uniform_sphere(u1: f32, u2: f32) -> Vec3 {
    let z = 1.0 - 2.0 * u1;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let (s, c) = (std::f32::consts::TAU * u2).sin_cos();
    Vec3::new(r * c, r * s, z)
}

/// Two unit vectors completing `n` (unit) to an orthonormal basis (Duff et al. 2017).
#[inline]
pub fn basis(n: Vec3) -> (Vec3, Vec3) {
    let s = 1.0f32.copysign(n.z);
    let a = -1.0 / (s + n.z);
    let b = n.x * n.y * a;
    (
        Vec3::new(1.0 + s * n.x * n.x * a, s * b, -s * n.x),
        Vec3::new(b, s + n.y * n.y * a, -n.y),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn streams_differ_by_pixel_and_sample_and_repeat_exactly() {
        let draw = |p, s| {
            let mut r = Stream::new(7, p, s);
            (0..4).map(|_| r.f32().to_bits()).collect::<Vec<_>>()
        };
        assert_eq!(draw(3, 5), draw(3, 5));
        assert_ne!(draw(3, 5), draw(3, 6));
        assert_ne!(draw(3, 5), draw(4, 5));
        let mut r = Stream::new(1, 2, 3);
        let mean = (0..100_000).map(|_| r.f32() as f64).sum::<f64>() / 1e5;
        assert!((mean - 0.5).abs() < 0.005, "{mean}");
    }

    #[test]
    fn basis_is_orthonormal() {
        let mut r = Stream::new(0, 0, 0);
        for _ in 0..1000 {
            let n = uniform_sphere(r.f32(), r.f32());
            let (t, b) = basis(n);
            for (x, y) in [(n, t), (n, b), (t, b)] {
                assert!(x.dot(y).abs() < 1e-5);
            }
            assert!((t.length() - 1.0).abs() < 1e-5 && (b.length() - 1.0).abs() < 1e-5);
        }
    }
}
