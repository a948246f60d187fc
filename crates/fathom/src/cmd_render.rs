//! `fathom render`: a scene file or preset to an image.

use clap::Args;

#[derive(Args)]
pub struct RenderArgs {}

pub fn run(_a: RenderArgs) -> Result<(), String> {
    Err("render is not written yet".into())
}

/// What `fathom` with no arguments does: render the default preset and say where it went.
pub fn run_default() -> Result<(), String> {
    Err("render is not written yet".into())
}
