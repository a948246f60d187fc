//! Tape and evaluation: the flat program a scene compiles to ([`tape`]), its CPU interpreter
//! ([`eval`]), the direct tree walk that defines what the tape must compute ([`reference`]),
//! and the constants the CPU renderers and the WGSL program share ([`shared`]).

pub mod eval;
pub mod reference;
pub mod shared;
pub mod tape;
#[cfg(test)]
mod tape_props;
