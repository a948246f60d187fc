//! fathom-app: the explorer window. Fly through any scene (free flight and orbit, speeds that
//! follow the distance to the surface), edit its tree, parameters, lights and settings live
//! (every edit undoable; parameter edits reach the next frame without a recompile), open, save
//! and watch scene files, take screenshots at any size, all while a render worker keeps the
//! viewport at the target frame time and refines it when the view holds still.
//!
//! - [`app`]: the window's state and panels;
//! - [`worker`]: the thread that owns the render session;
//! - [`viewport`]: which frame to render next (dynamic scale, refinement, cancellation);
//! - [`scale`]: the dynamic render-scale controller;
//! - [`camera`], [`input`]: the camera and the controls;
//! - [`params`], [`tree`], [`look`]: panels generated from the registry;
//! - [`history`]: undo and redo; [`files`]: open, save, watch; [`shot`]: screenshots;
//! - [`script`]: `--frames`, `--screenshot`, `--log`.

pub mod app;
pub mod camera;
pub mod files;
pub mod history;
pub mod input;
pub mod look;
pub mod params;
pub mod scale;
pub mod script;
pub mod shot;
pub mod tree;
pub mod viewport;
pub mod worker;

pub use app::{ExploreOptions, ExplorerApp};

/// Whether a window can be opened here (an X11 or Wayland display is set).
pub fn display_available() -> bool {
    ["DISPLAY", "WAYLAND_DISPLAY"]
        .iter()
        .any(|v| std::env::var_os(v).is_some_and(|s| !s.is_empty()))
}

/// Opens the explorer window and runs it until it is closed.
pub fn run(opts: ExploreOptions) -> Result<(), String> {
    let title = format!("fathom - {}", opts.name);
    let native = eframe::NativeOptions {
        viewport: egui::ViewportBuilder::default()
            .with_title(title)
            .with_inner_size([1280.0, 800.0])
            .with_drag_and_drop(true),
        renderer: eframe::Renderer::Wgpu,
        ..Default::default()
    };
    let failed = opts.exit_error.clone();
    eframe::run_native(
        "fathom",
        native,
        Box::new(move |cc| Ok(Box::new(ExplorerApp::new(cc, opts)?))),
    )
    .map_err(|e| format!("the window could not run: {e}"))?;
    match failed.lock().ok().and_then(|g| g.clone()) {
        Some(e) => Err(e),
        None => Ok(()),
    }
}
