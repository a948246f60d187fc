//! `fathom scene`: print a preset or a scene file as scene-file text.

use clap::Args;

#[derive(Args)]
pub struct SceneArgs {}

pub fn run(_a: SceneArgs) -> Result<(), String> {
    Err("scene is not written yet".into())
}
