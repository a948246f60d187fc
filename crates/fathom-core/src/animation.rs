//! Animation: named flight paths through a scene ([`flight`]), zooms and tours over frames
//! ([`camera_path`]), a number of a scene named by its path ([`param_path`]), and parameters
//! driven by LFOs or OSC ([`binding`]).

pub mod binding;
pub mod camera_path;
pub mod flight;
pub mod flight_path;
pub mod param_path;
pub mod param_resolve;
