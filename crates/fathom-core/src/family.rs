//! Registry and families: how each primitive, fractal, transform, modifier and combiner is
//! declared once ([`registry`]), the declarations themselves, how a call reads and writes in
//! a scene file ([`call_serde`]), and the reference pages generated from them ([`docgen`]).

pub mod call;
pub mod call_serde;
pub mod combine;
pub mod docgen;
pub mod fractals;
pub mod modifiers;
pub mod primitives;
pub mod registry;
pub mod transforms;
