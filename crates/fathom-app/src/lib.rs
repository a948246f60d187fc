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
//! - [`live`]: live modulation (bindings, OSC) and the flight-path timeline;
//! - [`history`]: undo and redo; [`files`]: open, save, watch; [`shot`]: screenshots;
//! - [`script`]: `--frames`, `--screenshot`, `--log`;
//! - [`bench`]: the explorer's numbers without a window (`fathom bench explore`).
//!
//! A first use: open the window on a preset (needs a display; `fathom explore` does this).
//!
//! ```no_run
//! let scene = fathom_core::presets::load("mandelbulb")?;
//! let mut options = fathom_app::ExploreOptions::new(scene, "mandelbulb");
//! options.target_ms = 16.0;
//! fathom_app::run(options)?;
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! The pieces below the window run without one; the camera controller, for instance, turns a
//! scene's camera into the state the controls move and back:
//!
//! ```
//! use fathom_app::camera::CameraController;
//!
//! let scene = fathom_core::presets::load("mandelbulb")?;
//! let controller = CameraController::new(&scene.camera);
//! let camera = controller.camera();
//! assert_eq!(camera.eye, scene.camera.eye);
//! assert!((controller.forward().length() - 1.0).abs() < 1e-12);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

#![warn(missing_docs)]

pub mod app;
pub mod bench;
pub mod camera;
pub mod files;
pub mod history;
pub mod input;
pub mod live;
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

/// Why the window did not run.
#[derive(Debug, thiserror::Error)]
pub enum WindowError {
    /// No window could be opened here (no display server answered, or no graphics device
    /// could draw into it); nothing was shown.
    #[error("no window could be opened: {0}")]
    Unavailable(String),
    /// The window opened (or was about to) and then failed, or a scripted run failed.
    #[error("{0}")]
    Failed(String),
    /// The OSC listener could not start (a port in use); nothing was opened.
    #[error(
        "{0} (is another program, or another fathom, using it? choose another with --osc-port)"
    )]
    Osc(#[source] fathom_live::LiveError),
}

/// Opens the explorer window and runs it until it is closed.
pub fn run(opts: ExploreOptions) -> Result<(), WindowError> {
    // Bindings and the OSC listener first: a port in use fails before any window opens.
    let modulator = live::start_modulator(&opts.scene, opts.osc_bind).map_err(WindowError::Osc)?;
    if !display_available() {
        return Err(WindowError::Unavailable(
            "no display: set DISPLAY (X11) or WAYLAND_DISPLAY, or run under `xvfb-run`; \
             `fathom render` draws to a file without one"
                .into(),
        ));
    }
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
    // Set once eframe has a window and a device and asks for the app.
    let opened = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    let opened_in = opened.clone();
    let r = eframe::run_native(
        "fathom",
        native,
        Box::new(move |cc| {
            opened_in.store(true, std::sync::atomic::Ordering::SeqCst);
            Ok(Box::new(ExplorerApp::with_modulator(cc, opts, modulator)?))
        }),
    );
    if let Err(e) = r {
        return Err(if opened.load(std::sync::atomic::Ordering::SeqCst) {
            WindowError::Failed(format!("the window could not run: {e}"))
        } else {
            WindowError::Unavailable(e.to_string())
        });
    }
    match failed.lock().ok().and_then(|g| g.clone()) {
        Some(e) => Err(WindowError::Failed(e)),
        None => Ok(()),
    }
}
