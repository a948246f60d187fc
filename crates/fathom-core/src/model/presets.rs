//! The built-in presets: scene files shipped inside the binary, each with a good default camera
//! and lighting. `fathom scene --preset NAME` prints one to start editing from.

use crate::scene::Scene;
use crate::scene_file::{self, SceneFileError};

/// A built-in scene.
pub struct Preset {
    /// The name `--preset` takes.
    pub name: &'static str,
    /// One line on what the scene shows, for `fathom list presets`.
    pub description: &'static str,
    /// The scene-file text.
    pub text: &'static str,
}

/// Every preset, in the order `fathom list presets` shows them.
pub static PRESETS: &[Preset] = &[
    Preset {
        name: "mandelbulb",
        description: "The power-8 Mandelbulb, whole bulb in view",
        text: include_str!("../../presets/mandelbulb.ron"),
    },
    Preset {
        name: "menger",
        description: "The Menger sponge, level 5, seen from a corner",
        text: include_str!("../../presets/menger.ron"),
    },
    Preset {
        name: "sierpinski",
        description: "The Sierpinski tetrahedron, 10 levels",
        text: include_str!("../../presets/sierpinski.ron"),
    },
    Preset {
        name: "koch",
        description: "The Koch snowflake as a wire, each generation slightly twisted",
        text: include_str!("../../presets/koch.ron"),
    },
    Preset {
        name: "mandelbox",
        description: "The scale-2 Mandelbox from outside a corner",
        text: include_str!("../../presets/mandelbox.ron"),
    },
    Preset {
        name: "kifs-octahedron",
        description: "Kaleidoscopic IFS with octahedral symmetry and a twist per level",
        text: include_str!("../../presets/kifs-octahedron.ron"),
    },
    Preset {
        name: "kifs-icosahedron",
        description: "Kaleidoscopic IFS with icosahedral symmetry",
        text: include_str!("../../presets/kifs-icosahedron.ron"),
    },
    Preset {
        name: "model-tree",
        description: "A CSG model tree: rounded cube, sphere, carved cross, torus, box frame (the seed paper's Fig. 2)",
        text: include_str!("../../presets/model-tree.ron"),
    },
    Preset {
        name: "psychedelic-tile",
        description: "A colourful CSG tile folded by an IFS loop of folds, rotations and scalings (Fig. 5)",
        text: include_str!("../../presets/psychedelic-tile.ron"),
    },
];

/// The preset the README's first command renders: the most striking one that is cheap to
/// render.
pub const DEFAULT_PRESET: &str = "mandelbulb";

/// Why a preset could not be loaded.
#[derive(Debug, thiserror::Error)]
pub enum PresetError {
    /// No preset has this name; `hint` names the nearest valid ones.
    #[error("unknown preset `{name}`; {hint}")]
    Unknown {
        /// The name given.
        name: String,
        /// The nearest valid names.
        hint: String,
    },
    /// The shipped text does not parse (a bug, caught by the tests).
    #[error(transparent)]
    File(#[from] SceneFileError),
}

/// Finds a preset by name; unknown names list the valid ones, nearest first.
pub fn find(name: &str) -> Result<&'static Preset, PresetError> {
    PRESETS
        .iter()
        .find(|p| p.name == name)
        .ok_or_else(|| PresetError::Unknown {
            name: name.into(),
            hint: crate::call_serde::did_you_mean(name, PRESETS.iter().map(|p| p.name)),
        })
}

/// Parses a preset into a scene.
pub fn load(name: &str) -> Result<Scene, PresetError> {
    let p = find(name)?;
    Ok(scene_file::parse(p.text, &format!("<preset:{}>", p.name))?)
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

    /// Sphere-traces one ray through the tape; the hit distance, if any.
    fn trace(tape: &Tape, eye: glam::DVec3, dir: glam::DVec3, max: f64) -> Option<f64> {
        let mut t = 0.0;
        for _ in 0..2000 {
            let p = eye + dir * t;
            let d = tape.eval_f64([p.x, p.y, p.z]).d;
            if d < 1e-4 * (1.0 + t) {
                return Some(t);
            }
            t += d.max(1e-5);
            if t > max {
                return None;
            }
        }
        Some(t)
    }

    /// A preset frames its object: the camera is outside it, the middle of the image hits it,
    /// and the top corners see sky (the object does not overflow the frame).
    #[test]
    fn every_preset_frames_its_object() {
        for p in PRESETS {
            let s = load(p.name).unwrap();
            let tape = Tape::compile(&s).unwrap();
            let c = &s.camera;
            let eye_d = tape.eval_f64([c.eye.x, c.eye.y, c.eye.z]).d;
            assert!(eye_d > 0.0, "{}: the camera is inside the object", p.name);
            let f = c.frame();
            let (w, h) = (160, 90);
            let max = s.render.max_distance;
            // Fractals have holes and wires are thin: some ray along the horizontal or vertical
            // centre line, over the middle 60% of the image, must hit.
            let n = 400;
            let centre_hits = (0..n).any(|i| {
                let u = 0.2 + 0.6 * i as f64 / n as f64;
                let across = f.ray_dir(u * w as f64, 45.0, w, h);
                let down = f.ray_dir(80.0, u * h as f64, w, h);
                trace(&tape, f.eye, across, max).is_some()
                    || trace(&tape, f.eye, down, max).is_some()
            });
            assert!(centre_hits, "{}: the middle of the image misses", p.name);
            for (x, y) in [(0.5, 0.5), (159.5, 0.5)] {
                let corner = trace(&tape, f.eye, f.ray_dir(x, y, w, h), max);
                assert!(
                    corner.is_none(),
                    "{}: the object fills the top corners",
                    p.name
                );
            }
        }
    }

    #[test]
    fn default_preset_exists_and_names_are_unique() {
        assert!(find(DEFAULT_PRESET).is_ok());
        let mut names: Vec<_> = PRESETS.iter().map(|p| p.name).collect();
        names.sort();
        names.dedup();
        assert_eq!(names.len(), PRESETS.len());
    }

    #[test]
    fn unknown_preset_lists_nearest_first() {
        let e = find("mandelbub").err().unwrap();
        assert!(matches!(&e, PresetError::Unknown { name, .. } if name == "mandelbub"));
        assert!(e.to_string().contains("did you mean `mandelbulb`"), "{e}");
    }
}
