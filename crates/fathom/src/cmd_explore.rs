//! `fathom explore`: the explorer window on a scene file or preset. Parses the flags into the
//! window's options and opens it (fathom-app); scripted runs (`--frames`, `--screenshot`,
//! `--log`) make it usable from tests and scripts.

use clap::{Args, ValueEnum};
use fathom_app::ExploreOptions;
use fathom_core::{presets, scene_file};
use fathom_render::Backend;
use std::net::SocketAddr;
use std::path::PathBuf;

/// Renderer choice for the window.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum ExploreRenderer {
    /// The GPU tracer on a real GPU, the CPU tracer otherwise (on a software adapter such as
    /// llvmpipe the CPU tracer is faster).
    Auto,
    /// The CPU sphere tracer.
    Trace,
    /// The GPU tracer (wgpu).
    Gpu,
    /// The sparse voxel octree.
    Svo,
    /// The path tracer: the preview while the view moves, samples accumulating while it is
    /// still (docs/pathtrace.md).
    Path,
}

/// Open the explorer window: fly through a scene and edit it live.
///
/// Fly with W A S D (Q / E down and up, Z / C roll, Shift faster), drag to look around, click
/// the surface to orbit around that point, wheel to move in, Ctrl+wheel for the field of view.
/// Edit the tree and every parameter in the side panels (Ctrl+Z undoes); the open file reloads
/// when it changes on disk. F12 renders a screenshot at any size.
///
/// Examples:
///   fathom explore --preset mandelbulb
///   fathom explore my.ron                       (edit my.ron in a text editor and watch)
///   fathom explore --preset menger --renderer svo
///   fathom explore --preset menger --frames 60 --screenshot shot.png --log frames.jsonl
///   fathom explore docs/examples/mandelbulb-dive.ron --osc-port 9000
#[derive(Args, Debug)]
#[command(verbatim_doc_comment)]
pub struct ExploreArgs {
    /// Scene file (.ron); omit to use --preset or the default preset.
    pub scene: Option<PathBuf>,
    /// Built-in preset (see `fathom list presets`).
    #[arg(long, conflicts_with = "scene")]
    pub preset: Option<String>,
    /// Renderer to start with.
    #[arg(long, value_enum, default_value = "auto")]
    pub renderer: ExploreRenderer,
    /// Frame time to hold while the view moves, in ms, [1, 1000].
    #[arg(long, default_value_t = 33.0)]
    pub target_ms: f64,
    /// Run this many frames, then exit.
    #[arg(long)]
    pub frames: Option<u64>,
    /// With --frames: render the final view offline to this PNG before exiting.
    #[arg(long, requires = "frames")]
    pub screenshot: Option<PathBuf>,
    /// Write one JSON line per frame (frame ms, render scale, renderer, camera, OSC counters,
    /// bound values) to this file.
    #[arg(long)]
    pub log: Option<PathBuf>,
    /// Listen for OSC on this UDP port of 127.0.0.1 (this machine only), driving the scene's
    /// OSC bindings.
    #[arg(long, conflicts_with = "osc_bind")]
    pub osc_port: Option<u16>,
    /// Listen for OSC on HOST:PORT; 0.0.0.0 accepts packets from other machines, so anyone
    /// who can reach the port drives the bound parameters (see docs/live.md).
    #[arg(long)]
    pub osc_bind: Option<SocketAddr>,
}

impl ExploreArgs {
    /// The window's options for these flags (the scene loaded and checked).
    pub fn options(&self) -> Result<ExploreOptions, String> {
        if !(self.target_ms.is_finite() && (1.0..=1000.0).contains(&self.target_ms)) {
            return Err(format!(
                "--target-ms {} is out of range [1, 1000]",
                self.target_ms
            ));
        }
        if self.frames == Some(0) {
            return Err("--frames must be at least 1".into());
        }
        let (scene, name, path) = match (&self.scene, &self.preset) {
            (Some(p), _) => (
                scene_file::load(p).map_err(|e| e.to_string())?,
                p.display().to_string(),
                Some(p.clone()),
            ),
            (None, preset) => {
                let n = preset.as_deref().unwrap_or(presets::DEFAULT_PRESET);
                (
                    presets::load(n).map_err(|e| e.to_string())?,
                    format!("preset {n}"),
                    None,
                )
            }
        };
        let mut o = ExploreOptions::new(scene, name);
        o.path = path;
        o.backend = match self.renderer {
            ExploreRenderer::Auto => None,
            ExploreRenderer::Trace => Some(Backend::Trace),
            ExploreRenderer::Gpu => Some(Backend::Gpu),
            ExploreRenderer::Svo => Some(Backend::Octree),
            ExploreRenderer::Path => Some(Backend::Path),
        };
        o.target_ms = self.target_ms;
        o.frames = self.frames;
        o.screenshot = self.screenshot.clone();
        o.log = self.log.clone();
        o.osc_bind = match (self.osc_port, self.osc_bind) {
            (Some(port), _) => Some(SocketAddr::from(([127, 0, 0, 1], port))),
            (None, bind) => bind,
        };
        Ok(o)
    }
}

pub fn run(a: ExploreArgs) -> Result<(), String> {
    let opts = a.options()?;
    // Starts the OSC listener first (a port in use is refused before any window), then
    // checks for a display.
    fathom_app::run(opts).map_err(|e| e.to_string())
}

/// `fathom` with no arguments: the explorer window on the default preset when a display is
/// present and a window opens there; otherwise the default preset rendered to fathom.png, with
/// the reason the window did not open.
pub fn run_without_arguments() -> Result<(), String> {
    if !fathom_app::display_available() {
        return crate::cmd_render::run_default(Some(
            "no display (DISPLAY and WAYLAND_DISPLAY are unset)",
        ));
    }
    match fathom_app::run(crate::clap_defaults::<ExploreArgs>().options()?) {
        Ok(()) => Ok(()),
        Err(fathom_app::WindowError::Unavailable(why)) => {
            crate::cmd_render::run_default(Some(&format!("no window could be opened: {why}")))
        }
        Err(e) => Err(e.to_string()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bad_flags_and_files_are_refused_before_a_window_opens() {
        let mut a: ExploreArgs = crate::clap_defaults();
        a.target_ms = 0.0;
        assert!(a.options().unwrap_err().contains("--target-ms"));
        a.target_ms = 33.0;
        a.preset = Some("mandelbub".into());
        assert!(a.options().unwrap_err().contains("mandelbulb"));
        a.preset = None;
        a.scene = Some("/nonexistent/x.ron".into());
        assert!(a.options().unwrap_err().contains("/nonexistent/x.ron"));
        a.scene = None;
        let o = a.options().unwrap();
        assert_eq!(o.name, "preset mandelbulb");
        assert_eq!(o.osc_bind, None);
        a.osc_port = Some(9123);
        assert_eq!(
            a.options().unwrap().osc_bind,
            Some("127.0.0.1:9123".parse().unwrap()),
            "--osc-port listens on this machine only"
        );
    }

    #[test]
    fn an_osc_port_in_use_is_a_clear_error_naming_the_port() {
        let taken = std::net::UdpSocket::bind("127.0.0.1:0").unwrap();
        let port = taken.local_addr().unwrap().port();
        let mut a: ExploreArgs = crate::clap_defaults();
        a.preset = Some("sierpinski".into());
        a.osc_port = Some(port);
        let e = run(a).unwrap_err();
        assert!(
            e.contains(&format!("127.0.0.1:{port}")) && e.contains("--osc-port"),
            "{e}"
        );
    }
}
