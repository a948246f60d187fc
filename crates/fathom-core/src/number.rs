//! Numbers and vectors: the [`real::Real`] trait the evaluator is generic over (f64, f32x8
//! packets), the small [`vec3::V3`], double-double numbers ([`dd`], [`dd4`]) for zooms past
//! f64 precision, [`value::Value`], a number as a scene states it, and a small seeded random
//! generator ([`rng::SplitMix64`]).

pub mod dd;
pub mod dd4;
pub mod real;
pub mod rng;
pub mod value;
pub mod vec3;
