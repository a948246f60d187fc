//! The built-in presets: scene files shipped inside the binary, each with a good default camera
//! and lighting. `fathom scene --preset NAME` prints one to start editing from.

use crate::scene::Scene;
use crate::scene_file::{self, SceneFileError};

/// A built-in scene.
pub struct Preset {
    pub name: &'static str,
    pub description: &'static str,
    /// The scene-file text.
    pub text: &'static str,
}

/// Every preset, in the order `fathom list presets` shows them.
pub static PRESETS: &[Preset] = &[Preset {
    name: "mandelbulb",
    description: "The power-8 Mandelbulb, whole bulb in view",
    text: include_str!("../presets/mandelbulb.ron"),
}];

/// The preset the README's first command renders.
pub const DEFAULT_PRESET: &str = "mandelbulb";

/// Finds a preset by name; unknown names list the valid ones, nearest first.
pub fn find(name: &str) -> Result<&'static Preset, String> {
    PRESETS.iter().find(|p| p.name == name).ok_or_else(|| {
        crate::call_serde::unknown_name("preset", name, PRESETS.iter().map(|p| p.name))
    })
}

/// Parses a preset into a scene.
pub fn load(name: &str) -> Result<Scene, String> {
    let p = find(name)?;
    scene_file::parse(p.text, &format!("<preset:{}>", p.name))
        .map_err(|e: SceneFileError| e.to_string())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tape::Tape;

    #[test]
    fn every_preset_parses_round_trips_and_compiles() {
        for p in PRESETS {
            let s = load(p.name).unwrap_or_else(|e| panic!("{e}"));
            let text = scene_file::to_string(&s);
            let back = scene_file::parse(&text, "roundtrip")
                .unwrap_or_else(|e| panic!("{}: {e}\n{text}", p.name));
            assert_eq!(back, s, "{} does not round-trip", p.name);
            Tape::compile(&s).unwrap_or_else(|e| panic!("{}: {e}", p.name));
        }
    }

    #[test]
    fn unknown_preset_lists_nearest_first() {
        let e = find("mandelbub").err().unwrap();
        assert!(e.contains("did you mean `mandelbulb`"), "{e}");
    }
}
