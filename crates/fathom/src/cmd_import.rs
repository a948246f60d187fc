//! `fathom import`: a Mandelbulber2 settings file (.fract) to a fathom scene file, with every
//! setting fathom cannot honour listed as a warning.

use clap::Args;
use fathom_core::scene_file::{self, fract};
use std::path::PathBuf;

/// Import a Mandelbulber2 .fract settings file as a fathom scene.
///
/// The formulas fathom has are mapped with Mandelbulber's conventions (its z-up world turned
/// to fathom's y-up, its camera through pixel corners, its angle offsets): Mandelbulb (1, 2),
/// Menger sponge (7), Mandelbox (8). Camera, target, up, field of view, image size (printed
/// as a comment), iterations, bailout and formula parameters are taken over; every other key
/// is listed on standard error, never dropped silently. `fathom render FILE.fract` reads the
/// file directly.
///
/// Examples:
///   fathom import mandelbox001.fract > box.ron
///   fathom import /usr/share/mandelbulber2/examples/mandelbulb001.fract -o bulb.ron
///   fathom render mandelbox001.fract -o box.png
#[derive(Args, Debug)]
#[command(verbatim_doc_comment)]
pub struct ImportArgs {
    /// The .fract file.
    pub file: PathBuf,
    /// Write the scene here instead of standard output.
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// Do not list the warnings.
    #[arg(long, short)]
    pub quiet: bool,
}

pub fn run(a: ImportArgs) -> Result<(), String> {
    let imported = fract::load(&a.file).map_err(|e| e.to_string())?;
    if !a.quiet {
        for w in &imported.warnings {
            eprintln!("fathom: warning: {w}");
        }
    }
    let mut text = format!(
        "// Imported from {} (Mandelbulber image size {}x{}).\n",
        a.file.display(),
        imported.image_size.0,
        imported.image_size.1
    );
    text += &scene_file::to_string(&imported.scene);
    text.push('\n');
    match &a.output {
        Some(p) => std::fs::write(p, text).map_err(|e| format!("{}: {e}", p.display())),
        None => {
            print!("{text}");
            Ok(())
        }
    }
}
