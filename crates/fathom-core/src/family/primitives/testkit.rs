//! Shared helpers for the registry-family tests (primitives, transforms, modifiers,
//! combines): a seeded RNG, parameter sets to test with, baking, and packet conversion.

use crate::real::{F32x8, Real};
use crate::registry::{Def, ParamKind};
use crate::vec3::V3;

/// A tiny xorshift64* generator, seeded, so failures reproduce.
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Self {
        Rng(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1)
    }
    pub fn next_u64(&mut self) -> u64 {
        let mut x = self.0;
        x ^= x >> 12;
        x ^= x << 25;
        x ^= x >> 27;
        self.0 = x;
        x.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }
    /// Uniform in [0, 1).
    pub fn unit(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }
    /// Uniform in [lo, hi).
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.unit()
    }
    /// Uniform in the cube [-r, r]^3.
    pub fn cube(&mut self, r: f64) -> [f64; 3] {
        [self.range(-r, r), self.range(-r, r), self.range(-r, r)]
    }
    /// A random direction scaled to length `len`.
    pub fn dir(&mut self, len: f64) -> [f64; 3] {
        loop {
            let v = self.cube(1.0);
            let l = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
            if l > 1e-3 && l <= 1.0 {
                return [v[0] * len / l, v[1] * len / l, v[2] * len / l];
            }
        }
    }
}

/// The parameter sets every entry is tested with: its defaults, and `extra` random variations
/// of them (scalars scaled by 0.6..1.4, or shifted by ±0.3 when the default is 0 or the range
/// is signed; clamped to the declared range; `Int` parameters kept).
pub fn param_sets(def: &Def, rng: &mut Rng, extra: usize) -> Vec<Vec<f64>> {
    let mut sets = vec![def.defaults()];
    for _ in 0..extra {
        let mut v = Vec::new();
        for spec in def.params {
            for &d in spec.default_values() {
                let x = match spec.kind {
                    ParamKind::Int => d,
                    _ if spec.min >= 0.0 && d > 0.0 => d * rng.range(0.6, 1.4),
                    _ => d + rng.range(-0.3, 0.3),
                };
                v.push(x.clamp(spec.min, spec.max));
            }
        }
        def.check(&v)
            .unwrap_or_else(|e| panic!("{}: generated params invalid: {e}", def.name));
        sets.push(v);
    }
    sets
}

/// The parameter-buffer slots for user values.
pub fn baked(def: &Def, user: &[f64]) -> Vec<f64> {
    let mut out = Vec::new();
    def.bake_into(user, &mut out);
    out
}

pub fn v3(p: [f64; 3]) -> V3<f64> {
    V3::new(p[0], p[1], p[2])
}

pub fn dist(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

/// Eight points as a packet.
pub fn pack(ps: &[[f64; 3]; 8]) -> V3<F32x8> {
    let c = |i: usize| F32x8::from_lanes(&ps.iter().map(|p| p[i]).collect::<Vec<_>>());
    V3::new(c(0), c(1), c(2))
}

/// Lane `i` of a packet as f64.
pub fn lane(v: F32x8, i: usize) -> f64 {
    <F32x8 as Real>::lane(v, i)
}

/// Parameters drawn over a wide box: sizes in [0, 2], signed values in [-2, 2], angles over
/// their whole declared range.
pub fn wide_params(def: &Def, rng: &mut Rng) -> Vec<f64> {
    let user: Vec<f64> = def
        .params
        .iter()
        .flat_map(|s| {
            let (lo, hi) = if s.max <= 180.0 && s.max > 2.0 {
                (s.min, s.max)
            } else {
                (s.min.max(-2.0), s.max.min(2.0))
            };
            (0..s.kind.width())
                .map(|_| rng.range(lo, hi))
                .collect::<Vec<_>>()
        })
        .collect();
    def.check(&user).unwrap();
    user
}
