//! `fathom render --path NAME --frames N -o DIR/`: a scene's flight path to a numbered image
//! sequence (and a video when ffmpeg is on PATH). The render layer's [`FlightRender`] runs the
//! frame loop; this module loads the scene, prepares the path, names the files
//! (`fathom_trace::output::sequence_path`), drives the progress bar and calls ffmpeg.

use crate::cmd_render::RenderArgs;
use fathom_core::scene::Scene;
use fathom_live::Modulator;
use fathom_render::flight::FlightRender;
use fathom_render::{Control, Session};
use fathom_trace::output;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

/// Where frame files go: a pattern with one run of `#` (see `output::sequence_path`); a
/// directory gets `NAME-#####.EXT` in it.
pub fn frame_pattern(output: &Path, path_name: &str, ext: &str) -> PathBuf {
    let text = output.to_string_lossy();
    let is_dir =
        text.ends_with('/') || text.ends_with(std::path::MAIN_SEPARATOR) || output.is_dir();
    if is_dir {
        output.join(format!("{}-#####.{ext}", safe_name(path_name)))
    } else {
        output.to_path_buf()
    }
}

/// A path name as a file name: letters, digits, `-` and `_`; anything else becomes `_`.
fn safe_name(name: &str) -> String {
    name.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || "-_".contains(c) {
                c
            } else {
                '_'
            }
        })
        .collect()
}

/// The ffmpeg input pattern (`%05d`) for files named by [`output::sequence_path`] from
/// `pattern`.
fn ffmpeg_input(pattern: &Path) -> PathBuf {
    let text = pattern.to_string_lossy();
    match (text.find('#'), text.rfind('#')) {
        (Some(a), Some(b)) => format!("{}%0{}d{}", &text[..a], b - a + 1, &text[b + 1..]).into(),
        _ => {
            // No `#`: sequence_path appends -NNNN before the extension.
            let stem = pattern.file_stem().unwrap_or_default().to_string_lossy();
            let name = match pattern.extension() {
                Some(e) => format!("{stem}-%04d.{}", e.to_string_lossy()),
                None => format!("{stem}-%04d"),
            };
            pattern.with_file_name(name)
        }
    }
}

/// Whether `ffmpeg` runs.
pub fn ffmpeg_available() -> bool {
    Command::new("ffmpeg")
        .arg("-version")
        .output()
        .is_ok_and(|o| o.status.success())
}

/// Encodes the frames named by `pattern` into an H.264 MP4 at `fps`. ffmpeg writes a
/// temporary name beside `video` (removed on failure or interruption) that is renamed over
/// `video` once complete, as every output is.
pub fn encode_video(pattern: &Path, fps: f64, video: &Path) -> Result<(), String> {
    fathom_core::atomic_file::check_output_path(video).map_err(|e| e.to_string())?;
    let tmp = fathom_core::atomic_file::temp_path(video);
    // Registered before ffmpeg creates it, so Ctrl-C removes it too.
    let (tmp, ()) = fathom_core::cleanup::Pending::create(tmp, |_| Ok(()))
        .map_err(|e| format!("cannot write {}: {e}", video.display()))?;
    let out = Command::new("ffmpeg")
        .args(["-y", "-loglevel", "error", "-framerate"])
        .arg(format!("{fps}"))
        .arg("-i")
        .arg(ffmpeg_input(pattern))
        // yuv420p (what players expect) needs even sides.
        .args([
            "-vf",
            "pad=ceil(iw/2)*2:ceil(ih/2)*2",
            "-c:v",
            "libx264",
            "-pix_fmt",
            "yuv420p",
            "-f",
            "mp4",
        ])
        .arg(tmp.path())
        .output()
        .map_err(|e| format!("cannot run ffmpeg: {e}"))?;
    if !out.status.success() {
        return Err(format!(
            "ffmpeg failed making {}: {}",
            video.display(),
            String::from_utf8_lossy(&out.stderr).trim()
        ));
    }
    tmp.rename_to(video)
        .map_err(|(_, e)| format!("cannot write {}: {e}", video.display()))
}

/// Renders the path named by `a.path` of the scene `a` names.
pub fn run(a: &RenderArgs, scene: Scene) -> Result<(), String> {
    let name = a.path.as_deref().unwrap_or_default();
    let frames = a.frames.unwrap_or(1);
    if !(a.fps.is_finite() && a.fps > 0.0 && a.fps <= 1000.0) {
        return Err(format!("--fps {} is out of range (0, 1000]", a.fps));
    }
    let job = FlightRender {
        frames,
        request: a.request()?,
    };
    job.validate().map_err(|e| e.to_string())?;
    let path = scene.path(name).map_err(|e| e.to_string())?;
    let mut session = Session::new(scene.clone()).map_err(|e| e.to_string())?;
    let flight = path
        .prepare(&scene, Some(session.tape()))
        .map_err(|e| format!("path `{name}`: {e}"))?;
    let mut modulator = Modulator::new(&scene).map_err(|e| e.to_string())?;
    let far = scene.render.max_distance as f32;

    let pattern = frame_pattern(&a.output, name, "png");
    let kind = output::ImageKind::for_path(&pattern, a.bit_depth).map_err(|e| e.to_string())?;
    // Check the naming and the directory before rendering anything.
    let last = output::sequence_path(&pattern, frames as u64 - 1)?;
    if let Some(dir) = last.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir)
            .map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    }
    output::open_output(&output::sequence_path(&pattern, 0)?).map_err(|e| e.to_string())?;
    if let Some(glb) = &a.camera_path {
        // The cameras come from the path alone, so they are written before any frame: an
        // unwritable file fails before the work.
        let cameras: Vec<_> = (0..frames)
            .map(|i| flight.sample(job.time(i, flight.duration())).camera)
            .collect();
        let (w, h) = job.request.output_size();
        let fov_animated = output::save_camera_path(&cameras, a.fps, w as f64 / h as f64, glb)
            .map_err(|e| format!("--camera-path: {e}"))?;
        if fov_animated {
            eprintln!(
                "note: {}: the path changes the field of view; it is animated through the \
                 glTF extension KHR_animation_pointer (readers without it keep the first \
                 frame's fov of {} degrees)",
                glb.display(),
                cameras[0].fov
            );
        }
    }

    let bar = if a.quiet {
        indicatif::ProgressBar::hidden()
    } else {
        let b = indicatif::ProgressBar::new(frames as u64);
        b.set_style(
            indicatif::ProgressStyle::with_template(
                "{spinner} path `{msg}` [{bar:40}] {pos}/{len} frames {elapsed} (eta {eta})",
            )
            .map_err(|e| e.to_string())?
            .progress_chars("=> "),
        );
        b.set_message(name.to_string());
        b
    };
    let start = Instant::now();
    let report = job
        .run(
            &mut session,
            &scene,
            &flight,
            &mut |s, t| {
                modulator.apply(s, t);
            },
            &Control::default(),
            &mut |f| {
                let file = output::sequence_path(&pattern, f.index as u64)?;
                let out = output::open_output(&file).map_err(|e| e.to_string())?;
                output::save_image(&f.rendered.frame, kind, far, out, &file)
                    .map_err(|e| e.to_string())?;
                bar.inc(1);
                Ok(())
            },
        )
        .map_err(|e| e.to_string())?;
    bar.finish_and_clear();
    let secs = start.elapsed().as_secs_f64();
    let first = output::sequence_path(&pattern, 0)?;
    if !a.quiet {
        eprintln!(
            "wrote {frames} frames of path `{name}` ({:.1} s at {} fps) to {} ... in {secs:.1} s \
             ({:.2} frames/s; {} parameter updates, {} recompiles)",
            flight.duration(),
            a.fps,
            first.display(),
            frames as f64 / secs,
            report.param_updates,
            report.recompiles
        );
    }
    if a.no_video || frames < 2 {
        return Ok(());
    }
    if kind == output::ImageKind::LayeredExr {
        if !a.quiet {
            eprintln!("fathom: note: the frames are linear EXR layers; no video was made");
        }
        return Ok(());
    }
    if !ffmpeg_available() {
        if !a.quiet {
            eprintln!(
                "fathom: note: ffmpeg is not on PATH, so no video was made (install it, e.g. \
                 `apt-get install ffmpeg`, or use --no-video to silence this)"
            );
        }
        return Ok(());
    }
    let video = first.with_file_name(format!("{}.mp4", safe_name(name)));
    encode_video(&pattern, a.fps, &video)?;
    if !a.quiet {
        eprintln!("wrote {}", video.display());
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use fathom_core::scene_file;

    fn example() -> PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../docs/examples/mandelbulb-dive.ron")
    }

    fn args(dir: &Path, path: &str, frames: usize) -> RenderArgs {
        RenderArgs {
            scene: Some(example()),
            output: PathBuf::from(format!("{}/", dir.display())),
            size: Some((32, 24)),
            threads: Some(1),
            quiet: true,
            path: Some(path.into()),
            frames: Some(frames),
            ..RenderArgs::defaults()
        }
    }

    #[test]
    fn a_path_renders_to_numbered_frames_and_a_video() {
        let dir = std::env::temp_dir().join(format!("fathom-path-{}", std::process::id()));
        crate::render(args(&dir, "dive", 4)).unwrap();
        let names: Vec<PathBuf> = (0..4)
            .map(|i| dir.join(format!("dive-0000{i}.png")))
            .collect();
        let images: Vec<_> = names
            .iter()
            .map(|n| image::open(n).unwrap().to_rgb8())
            .collect();
        assert_eq!(images[0].dimensions(), (32, 24));
        assert_ne!(images[0], images[3], "the camera moves");
        assert!(
            ffmpeg_available(),
            "ffmpeg is not on PATH; scripts/setup.sh installs it"
        );
        let video = dir.join("dive.mp4");
        let probe = Command::new("ffprobe")
            .args(["-v", "error", "-count_frames", "-select_streams", "v:0"])
            .args([
                "-show_entries",
                "stream=nb_read_frames,width,height",
                "-of",
                "csv=p=0",
            ])
            .arg(&video)
            .output()
            .unwrap();
        let text = String::from_utf8_lossy(&probe.stdout);
        assert_eq!(text.trim(), "32,24,4", "{text}");
        // Names that are not there are explained.
        let e = crate::render(args(&dir, "diev", 2)).unwrap_err();
        assert!(e.contains("did you mean `dive`"), "{e}");
        let mut plain = args(&dir, "dive", 2);
        plain.scene = None;
        plain.preset = Some("menger".into());
        let e = crate::render(plain).unwrap_err();
        assert!(e.contains("has no paths"), "{e}");
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn layered_exr_frames_and_a_gltf_camera_path() {
        let dir = std::env::temp_dir().join(format!("fathom-path-exr-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        // The example's dive widens the fov at its end: core glTF cannot animate it, so the
        // camera path carries it through KHR_animation_pointer.
        let mut a = args(&dir, "dive", 3);
        a.output = dir.join("w-##.exr");
        a.camera_path = Some(dir.join("wide.glb"));
        crate::render(a).unwrap();
        let glb = std::fs::read(dir.join("wide.glb")).unwrap();
        let text = String::from_utf8_lossy(&glb);
        assert!(
            text.contains("\"extensionsUsed\":[\"KHR_animation_pointer\"]")
                && text.contains("/cameras/0/perspective/yfov"),
            "the fov is animated"
        );
        // The same path at one fov.
        let mut scene = scene_file::load(&example()).unwrap();
        for p in &mut scene.paths {
            for k in &mut p.keys {
                k.fov = 40.0;
            }
        }
        let file = dir.join("dive.ron");
        scene_file::save(&file, &scene).unwrap();
        let mut a = args(&dir, "dive", 3);
        a.scene = Some(file);
        a.output = dir.join("f-##.exr");
        a.camera_path = Some(dir.join("cam.glb"));
        crate::render(a).unwrap();
        for i in 0..3 {
            let bytes = std::fs::read(dir.join(format!("f-0{i}.exr"))).unwrap();
            assert_eq!(
                &bytes[..4],
                &[0x76, 0x2f, 0x31, 0x01],
                "frame {i} is an EXR"
            );
        }
        assert!(!dir.join("dive.mp4").exists(), "no video of linear frames");
        let (doc, buffers, _) = gltf::import(dir.join("cam.glb")).unwrap();
        let anim = doc.animations().next().unwrap();
        let ch = anim.channels().next().unwrap();
        let r = ch.reader(|b| Some(&buffers[b.index()]));
        assert_eq!(r.read_inputs().unwrap().count(), 3, "one key per frame");
        // A bad extension fails before any work.
        let mut a = args(&dir, "dive", 2);
        a.output = dir.join("f-##.jpg");
        assert!(crate::render(a).unwrap_err().contains("`jpg`"));
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn frame_patterns_and_their_ffmpeg_form() {
        assert_eq!(
            frame_pattern(Path::new("out/"), "dive in", "png"),
            PathBuf::from("out/dive_in-#####.png")
        );
        assert_eq!(
            frame_pattern(Path::new("shots/f-####.png"), "x", "png"),
            PathBuf::from("shots/f-####.png")
        );
        assert_eq!(
            ffmpeg_input(Path::new("out/dive-#####.png")),
            PathBuf::from("out/dive-%05d.png")
        );
        assert_eq!(
            ffmpeg_input(Path::new("out/f.png")),
            PathBuf::from("out/f-%04d.png")
        );
        // The two namings agree.
        let p = Path::new("o/a-###.png");
        assert_eq!(
            output::sequence_path(p, 7).unwrap(),
            PathBuf::from("o/a-007.png")
        );
    }
}
