//! `fathom scene`: print a preset or a scene file as scene-file text, or check a scene file.

use clap::Args;
use fathom_core::presets::{self, PRESETS};
use fathom_core::scene_file;
use fathom_core::tape::Tape;
use std::path::PathBuf;

/// Shown after `fathom scene --help`.
const AFTER_HELP: &str = "\
With --preset NAME the preset's scene file is printed as shipped, comments included: the usual
way to start a scene of your own. With a FILE the file is read, checked and printed back in
normal form (every field written out, defaults filled in); errors are reported as
FILE:LINE:COLUMN: message.

Examples:
  fathom scene --preset menger > menger.ron     start from a preset
  fathom scene my.ron                           print my.ron normalised
  fathom scene my.ron --check                   only check it (and that it compiles)
  fathom scene --list                           the preset names

The format: docs/scene-format.md; every shape and operator: docs/scene-reference.md or
`fathom list all`.";

/// Arguments of `fathom scene`.
#[derive(Args)]
#[command(after_help = AFTER_HELP)]
pub struct SceneArgs {
    /// Scene file to read.
    #[arg(conflicts_with_all = ["preset", "list"])]
    file: Option<PathBuf>,
    /// Print this built-in preset instead of a file (`fathom list presets` shows them).
    #[arg(long, short, value_name = "NAME", conflicts_with = "list")]
    preset: Option<String>,
    /// List the preset names and descriptions.
    #[arg(long)]
    list: bool,
    /// Check the scene (parse, validate, compile) and print a one-line summary instead.
    #[arg(long)]
    check: bool,
    /// Write to this file instead of standard output.
    #[arg(long, short, value_name = "FILE")]
    output: Option<PathBuf>,
}

/// Runs `fathom scene`.
pub fn run(a: SceneArgs) -> Result<(), String> {
    let text = render(&a)?;
    match &a.output {
        Some(path) => fathom_core::atomic_file::write(path, text).map_err(|e| e.to_string()),
        None => {
            print!("{text}");
            Ok(())
        }
    }
}

/// What `fathom scene` prints for these arguments.
fn render(a: &SceneArgs) -> Result<String, String> {
    if a.list {
        let w = PRESETS.iter().map(|p| p.name.len()).max().unwrap_or(0);
        return Ok(PRESETS
            .iter()
            .map(|p| format!("{:w$}  {}\n", p.name, p.description))
            .collect());
    }
    let (scene, origin, shipped) = match (&a.file, &a.preset) {
        (Some(path), _) => (
            scene_file::load(path).map_err(|e| e.to_string())?,
            path.display().to_string(),
            None,
        ),
        (None, Some(name)) => {
            let p = presets::find(name).map_err(|e| e.to_string())?;
            let scene = presets::load(name).map_err(|e| e.to_string())?;
            (scene, format!("preset {name}"), Some(p.text))
        }
        (None, None) => {
            return Err("give a scene FILE or `--preset NAME` (see `fathom scene --help`)".into());
        }
    };
    let tape = Tape::compile(&scene).map_err(|e| format!("{origin}: {e}"))?;
    if a.check {
        return Ok(format!(
            "{origin}: ok ({} nodes, depth {}, {} tape instructions, {} parameters)\n",
            scene.root.count(),
            scene.root.depth(),
            tape.instrs().len(),
            tape.params().len()
        ));
    }
    Ok(match shipped {
        Some(text) => text.to_string(),
        None => scene_file::to_string(&scene) + "\n",
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn args(file: Option<&str>, preset: Option<&str>) -> SceneArgs {
        SceneArgs {
            file: file.map(PathBuf::from),
            preset: preset.map(String::from),
            list: false,
            check: false,
            output: None,
        }
    }

    #[test]
    fn preset_prints_a_scene_that_parses_back() {
        let text = render(&args(None, Some(presets::DEFAULT_PRESET))).unwrap();
        let s = scene_file::parse(&text, "out").unwrap();
        assert_eq!(s, presets::load(presets::DEFAULT_PRESET).unwrap());
    }

    #[test]
    fn file_is_printed_normalised_and_errors_have_positions() {
        let dir = std::env::temp_dir().join(format!("fathom-cmd-scene-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let good = dir.join("good.ron");
        std::fs::write(&good, "Scene(version: 1, root: Node(shape: Torus))").unwrap();
        let out = render(&args(good.to_str(), None)).unwrap();
        assert!(
            out.contains("Torus(") && out.contains("major: 1.0"),
            "{out}"
        );
        assert!(out.contains("camera: Camera("), "{out}");
        let bad = dir.join("bad.ron");
        std::fs::write(&bad, "Scene(version: 1,\n  root: Node(shape: Tours))").unwrap();
        let e = render(&args(bad.to_str(), None)).unwrap_err();
        assert!(e.starts_with(&format!("{}:2:", bad.display())), "{e}");
        assert!(e.contains("did you mean `Torus`"), "{e}");
        let mut check = args(good.to_str(), None);
        check.check = true;
        assert!(render(&check).unwrap().contains(": ok ("));
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn unknown_preset_and_missing_input_are_errors() {
        let e = render(&args(None, Some("mandelbub"))).unwrap_err();
        assert!(e.contains("did you mean `mandelbulb`"), "{e}");
        assert!(render(&args(None, None)).unwrap_err().contains("--preset"));
    }
}
