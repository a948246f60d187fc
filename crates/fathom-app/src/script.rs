//! Scripted runs: `--frames N` (run N window frames and exit), `--screenshot OUT.png` (then
//! render the view offline to OUT.png) and `--log FILE.jsonl` (one JSON line per window frame:
//! frame time, render scale, renderer, refinement stage, camera, edit latency, OSC counters,
//! the bound parameters' values, the timeline's time), for tests and for measuring.

use crate::worker::Stage;
use fathom_core::Camera;
use serde::Serialize;
use std::io::Write;
use std::path::{Path, PathBuf};

/// One line of the frame log.
#[derive(Serialize)]
pub struct FrameLog<'a> {
    pub frame: u64,
    /// Time since the previous window frame, ms.
    pub frame_ms: f64,
    pub render_scale: f64,
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
    pub camera: Camera,
    /// The OSC listener's counters (packets received, rejected, ...; zero without one).
    pub osc: fathom_live::OscCounters,
    /// Every binding's parameter, source level and current value.
    pub bound: Vec<crate::live::BoundValue>,
    /// The timeline's time when a flight path drives the view.
    pub path_time: Option<f64>,
}

/// The scripted run's settings and log file.
pub struct Script {
    pub frames: Option<u64>,
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
