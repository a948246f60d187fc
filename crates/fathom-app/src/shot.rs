//! Screenshots: the current view rendered by the offline renderer (a session of its own on a
//! thread of its own, so the viewport stays interactive) at any size, supersampled, mono or
//! stereo, and written as PNG with a progress figure for the status bar.

use fathom_core::{Camera, Scene};
use fathom_render::{Control, Progress, RenderRequest, Session};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::thread::JoinHandle;

/// A screenshot being rendered.
pub struct Shot {
    /// The PNG being written.
    pub path: PathBuf,
    /// Tiles done (high 32 bits: total).
    progress: Arc<AtomicU64>,
    handle: Option<JoinHandle<Result<(), String>>>,
}

impl Shot {
    /// Starts rendering `camera`'s view of `scene` with `req` into `path` (PNG).
    pub fn start(scene: Scene, camera: Camera, req: RenderRequest, path: PathBuf) -> Shot {
        let progress = Arc::new(AtomicU64::new(0));
        let p = progress.clone();
        let out = path.clone();
        let handle = std::thread::Builder::new()
            .name("fathom screenshot".into())
            .spawn(move || {
                let report = |pr: Progress| {
                    p.store(
                        ((pr.total as u64) << 32) | pr.done as u64,
                        Ordering::Relaxed,
                    );
                };
                render(scene, &camera, &req, &out, &report)
            })
            .ok();
        Shot {
            path,
            progress,
            handle,
        }
    }

    /// Fraction done, [0, 1].
    pub fn fraction(&self) -> f32 {
        let v = self.progress.load(Ordering::Relaxed);
        let (total, done) = (v >> 32, v & 0xffff_ffff);
        if total == 0 {
            0.0
        } else {
            done as f32 / total as f32
        }
    }

    /// The result once the render has finished (`None` while it runs).
    pub fn poll(&mut self) -> Option<Result<(), String>> {
        if self.handle.as_ref().is_some_and(|h| h.is_finished()) {
            let h = self.handle.take().expect("checked");
            return Some(
                h.join()
                    .unwrap_or_else(|_| Err("the screenshot thread failed".into())),
            );
        }
        if self.handle.is_none() {
            return Some(Err("could not start the screenshot thread".into()));
        }
        None
    }
}

/// Renders and writes one screenshot now.
pub fn render(
    scene: Scene,
    camera: &Camera,
    req: &RenderRequest,
    path: &Path,
    progress: &(dyn Fn(Progress) + Sync),
) -> Result<(), String> {
    // Open the file first, so a bad path fails before the render.
    let file = fathom_image::output::open_output(path).map_err(|e| e.to_string())?;
    let mut s = Session::new(scene).map_err(|e| e.to_string())?;
    let control = Control {
        cancel: None,
        progress: Some(progress),
    };
    let r = s
        .render_with(camera, req, &control)
        .map_err(|e| e.to_string())?;
    fathom_image::output::save_colour(&r.frame, file, path).map_err(|e| e.to_string())
}
