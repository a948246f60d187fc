//! Files on disk: every output written under a temporary name and renamed once whole
//! ([`atomic_file`]), temporary files removed on every exit path ([`cleanup`]), and inputs
//! read only when regular files under a size limit ([`input_file`]).

pub mod atomic_file;
pub mod cleanup;
pub mod input_file;
