//! Scripted runs: `--frames N` (run N window frames and exit), `--screenshot OUT.png` (then
//! render the view offline to OUT.png) and `--log FILE.jsonl` (one JSON line per window frame:
//! wall-clock time, frame time, render scale, renderer, refinement stage, camera, edit latency,
//! OSC counters, the bound parameters' values, the timeline's time, the selected node, the
//! title and whether the document has unsaved edits, and, whenever it changed, where the
//! viewport, the tree's rows and the parameter widgets were drawn), for tests and for measuring.
//!
//! The places let a test drive the real window with real X input (`fathom-xdrive`): click the
//! row of `root.children[1]`, drag the slider of `Torus.minor`.

use crate::worker::Stage;
use fathom_core::Camera;
use serde::Serialize;
use std::io::Write;
use std::path::{Path, PathBuf};

/// Where a widget was drawn this frame: its kind (`tree`, `param`, `button`), its name (a
/// node path, `Torus.minor`, a button's text) and its rectangle in window pixels (x, y,
/// width, height).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Place {
    /// `tree`, `param` or `button`.
    pub kind: &'static str,
    /// A node path, a parameter (`Torus.minor`) or a button's text.
    pub name: String,
    /// x, y, width and height in window pixels.
    pub rect: [f32; 4],
}

/// The places recorded in the current frame, kept in the context's temporary data.
#[derive(Clone, Default)]
struct Places(Vec<Place>);

/// Records where a widget of `kind` named `name` was drawn this frame (for the frame log).
pub fn place(kind: &'static str, name: String, r: &egui::Response) {
    let ppp = r.ctx.pixels_per_point();
    let rect = [
        r.rect.min.x * ppp,
        r.rect.min.y * ppp,
        r.rect.width() * ppp,
        r.rect.height() * ppp,
    ];
    r.ctx.data_mut(|d| {
        d.get_temp_mut_or_default::<Places>(egui::Id::NULL)
            .0
            .push(Place { kind, name, rect })
    });
}

/// The places recorded since the last call (and forgets them).
pub fn take_places(ctx: &egui::Context) -> Vec<Place> {
    ctx.data_mut(|d| std::mem::take(&mut d.get_temp_mut_or_default::<Places>(egui::Id::NULL).0))
}

/// One line of the frame log.
#[derive(Serialize)]
pub struct FrameLog<'a> {
    /// The window frame's number.
    pub frame: u64,
    /// Wall-clock time of the line, ms since the Unix epoch (to put X events and frames on
    /// one time line).
    pub t_ms: f64,
    /// The window's title (it says the document's name, and `*` for unsaved edits).
    pub title: &'a str,
    /// Whether the document has edits not saved (or, for a preset, any edits).
    pub dirty: bool,
    /// The dialog open over the window, if any (`unsaved changes`, `screenshot`, ...).
    pub dialog: Option<&'a str>,
    /// The selected node's path (`root.children[0]`).
    pub selected: String,
    /// The selected node's label in the tree.
    pub selected_label: String,
    /// The selected node's shape parameters, by name.
    pub selected_params: Vec<(&'static str, Vec<f64>)>,
    /// What Ctrl+Z would undo.
    pub undo: Option<&'a str>,
    /// The status bar's message.
    pub status: Option<&'a str>,
    /// The view key of the frame on screen; it differs from `view` while
    /// the screen lags the camera (a drag's latency is until they first differ from before).
    pub shown_view: Option<u64>,
    /// The view key asked for now.
    pub view: u64,
    /// The resolution scale of the frame on screen (1: full resolution).
    pub shown_scale: Option<f64>,
    /// The camera mode: `fly` or `orbit`.
    pub mode: &'static str,
    /// The orbit's pivot, in orbit mode.
    pub pivot: Option<[f64; 3]>,
    /// Whether the renderer runs on a software adapter (the GPU tracer on lavapipe).
    pub software_adapter: bool,
    /// Time since the previous window frame, ms.
    pub frame_ms: f64,
    /// The viewport's dynamic render scale now (1: full resolution).
    pub render_scale: f64,
    /// The renderer drawing the viewport.
    pub renderer: &'a str,
    /// The refinement stage of the frame on screen.
    pub stage: Option<Stage>,
    /// Render time of the frame on screen, ms.
    pub render_ms: Option<f64>,
    /// Its size in pixels (per eye).
    pub shown: Option<(u32, u32)>,
    /// Whether the frame on screen is the final refinement of the current view.
    pub settled: bool,
    /// From the view holding still to its first full-resolution frame, ms.
    pub full_after_still_ms: Option<f64>,
    /// From the last scene edit to the first frame that shows it, ms.
    pub edit_latency_ms: Option<f64>,
    /// Tape compilations so far (parameter edits add none).
    pub compiles: u64,
    /// The camera now.
    pub camera: Camera,
    /// The OSC listener's counters (packets received, rejected, ...; zero without one).
    pub osc: fathom_live::OscCounters,
    /// Every binding's parameter, source level and current value.
    pub bound: Vec<crate::live::BoundValue>,
    /// The timeline's time when a flight path drives the view.
    pub path_time: Option<f64>,
    /// Where the widgets were drawn, when that changed since the last line.
    pub places: Option<Vec<Place>>,
    /// Samples per pixel of the path-traced frame on screen (none for other renderers).
    pub path_spp: Option<u32>,
}

/// The scripted run's settings and log file.
pub struct Script {
    /// Frames to run before exiting, for a scripted run.
    pub frames: Option<u64>,
    /// Where the view is rendered offline after the last scripted frame.
    pub screenshot: Option<PathBuf>,
    log: Option<(PathBuf, std::io::BufWriter<std::fs::File>)>,
    /// Why the run failed (a screenshot that could not be written), for the exit code.
    pub failed: Option<String>,
    /// The window was asked to close (frames after that are not scripted).
    pub closing: bool,
}

impl Script {
    /// Opens the log now, so a bad path fails before the window opens.
    pub fn new(
        frames: Option<u64>,
        screenshot: Option<PathBuf>,
        log: Option<&Path>,
    ) -> Result<Script, String> {
        let log = match log {
            Some(p) => {
                let f = std::fs::File::create(p)
                    .map_err(|e| format!("cannot write {}: {e}", p.display()))?;
                Some((p.to_path_buf(), std::io::BufWriter::new(f)))
            }
            None => None,
        };
        Ok(Script {
            frames,
            screenshot,
            log,
            failed: None,
            closing: false,
        })
    }

    /// Appends a line to the log (if there is one).
    pub fn log(&mut self, line: &FrameLog) -> Result<(), String> {
        if let Some((p, w)) = &mut self.log {
            serde_json::to_writer(&mut *w, line)
                .map_err(|e| e.to_string())
                .and_then(|_| writeln!(w).map_err(|e| e.to_string()))
                .and_then(|_| w.flush().map_err(|e| e.to_string()))
                .map_err(|e| format!("cannot write {}: {e}", p.display()))?;
        }
        Ok(())
    }

    /// Whether the scripted number of frames has run.
    pub fn finished(&self, frames: u64) -> bool {
        self.frames.is_some_and(|n| frames >= n)
    }
}
