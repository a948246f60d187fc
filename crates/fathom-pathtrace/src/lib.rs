//! fathom-pathtrace: an unbiased, progressive path tracer for fathom's distance fields.
#![warn(missing_docs)]

pub mod bsdf;
pub mod material;
pub mod microfacet;
pub mod sampler;
pub mod sampling;
pub mod shared;
