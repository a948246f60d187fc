//! The explorer window: the document (scene, file, undo history), the camera, the render
//! worker and the viewport's frame scheduling, and the panels. The window owns no renderer
//! state: it sends edits and frame jobs to the worker (which owns the render session) and shows
//! what comes back, so the UI never waits on a render.
//!
//! Layout: a menu bar; on the left the scene (preset picker, the tree, the root's IFS loop,
//! lights and render settings); on the right the selected node's inspector and the renderer's
//! settings; at the bottom a status bar, and above it (when the scene has flight paths or
//! bindings, or OSC is listened for) the timeline and bindings panels ([`crate::live`]); in the
//! middle the viewport with its stats overlay.
//!
//! The document (`scene`) is what undo and save see; the render worker gets the *live scene*
//! derived from it every frame (a flight path's parameter keys, the bindings' values), sent only
//! when its numbers change.

use crate::camera::{self, CameraController, Mode};
use crate::files::{BrowseFor, FileBrowser, Watch};
use crate::history::History;
use crate::live::{self, Live, TimelineAction};
use crate::script::{FrameLog, Script};
use crate::shot::Shot;
use crate::tree::{self, NodePath, TreeAction};
use crate::viewport::{Viewport, view_key};
use crate::worker::{Reply, Stage, Worker};
use crate::{input, look};
use egui::emath::GuiRounding;
use fathom_core::presets::{self, PRESETS};
use fathom_core::{Projection, Scene, Tape, scene_file};
use fathom_render::{Backend, RenderRequest, TracerRule};
use std::net::SocketAddr;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// How the window was asked to start.
#[derive(Clone, Debug)]
pub struct ExploreOptions {
    /// The scene to open.
    pub scene: Scene,
    /// The scene file it came from (watched for changes), if any.
    pub path: Option<PathBuf>,
    /// A name for the title bar (the preset or file name).
    pub name: String,
    /// The renderer to start with (default: the GPU on a real GPU, else the CPU tracer).
    pub backend: Option<Backend>,
    /// Frame time to hold while moving, ms.
    pub target_ms: f64,
    /// Run this many frames, then exit (scripted runs and tests).
    pub frames: Option<u64>,
    /// After the last scripted frame, render the view offline to this PNG.
    pub screenshot: Option<PathBuf>,
    /// Write one JSON line per frame here.
    pub log: Option<PathBuf>,
    /// Listen for OSC here (`--osc-port`, `--osc-bind`); `None`: no listener.
    pub osc_bind: Option<SocketAddr>,
    /// Where the window leaves why a scripted run failed, for the exit code.
    pub exit_error: std::sync::Arc<std::sync::Mutex<Option<String>>>,
}

impl ExploreOptions {
    /// Options for `scene` with every default.
    pub fn new(scene: Scene, name: impl Into<String>) -> ExploreOptions {
        ExploreOptions {
            scene,
            path: None,
            name: name.into(),
            backend: None,
            target_ms: 33.0,
            frames: None,
            screenshot: None,
            log: None,
            osc_bind: None,
            exit_error: Default::default(),
        }
    }
}

/// The stereo layout shown in the viewport.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stereo {
    /// One view.
    Mono,
    /// Two views side by side, left eye on the left.
    SideBySide,
    /// Omni-directional stereo, left eye on top.
    Ods,
}

/// The renderer's settings in the window.
#[derive(Clone, Debug, PartialEq)]
pub struct ViewSettings {
    /// The renderer.
    pub backend: Backend,
    /// The CPU tracer's step rule.
    pub tracer: TracerRule,
    /// Whether the cone-marching depth prepass runs.
    pub prepass: bool,
    /// Screen-space ambient occlusion strength, [0, 4] (0: off).
    pub ssao: f32,
    /// The stereo layout.
    pub stereo: Stereo,
    /// Distance between the eyes (or the ODS circle's diameter), scene units.
    pub eye_separation: f64,
    /// Pixels an octree voxel may project to, [0.25, 16].
    pub fidelity: f64,
    /// Octree leaves wider than a pixel drawn as surfaces instead of cubes (slower).
    pub planes: bool,
    /// Octree voxels at least two pixels wide drawn smooth (each pixel the mean of a box as wide
    /// as its voxel) instead of as a mosaic of flat colours.
    pub smooth: bool,
    /// Density grid, extinction, albedo and samples of the volume renderer (the scene as a
    /// cloud).
    pub volume: fathom_render::request::VolumeSettings,
    /// Samples cap, bounces, lens and denoising of the path tracer (samples accumulate while
    /// the view holds still; moving shows the preview tracer).
    pub path: fathom_render::PathRequest,
}

/// The window's path-tracing settings: up to 1024 samples per pixel (a clean picture), so a
/// still view stops using the CPU once it is done.
fn window_path_settings() -> fathom_render::PathRequest {
    fathom_render::PathRequest {
        spp: 1024,
        ..Default::default()
    }
}

impl ViewSettings {
    /// The request the viewport's frames start from (their size is chosen per frame).
    pub fn base_request(&self) -> RenderRequest {
        let mut r = RenderRequest {
            backend: self.backend,
            tracer: self.tracer,
            prepass: self.prepass,
            ssao: self.ssao,
            projection: match self.stereo {
                Stereo::Mono => Projection::Mono,
                Stereo::SideBySide => Projection::SideBySide {
                    eye_separation: self.eye_separation,
                },
                Stereo::Ods => Projection::Ods {
                    eye_separation: self.eye_separation,
                },
            },
            ..RenderRequest::default()
        };
        r.octree.fidelity = self.fidelity;
        r.octree.planes = self.planes;
        r.octree.smooth = self.smooth;
        r.volume = self.volume.clone();
        if self.backend == Backend::Path {
            // The path tracer antialiases by its samples and has its own occlusion.
            r.ssao = 0.0;
            r.path = self.path.clone();
        }
        r
    }
}

/// What a status message is about: a newer message from the same source replaces an older
/// error (a fixed file clears the reload error it had).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum NoteSource {
    General,
    /// Opening, reloading and saving the scene file.
    File,
}

/// A message in the status bar (and in the Messages window's history).
struct Note {
    text: String,
    error: bool,
    at: Instant,
    source: NoteSource,
    /// Dismissed from the status bar (kept in the history).
    dismissed: bool,
}

/// How long an information message stays in the status bar (errors stay until dismissed or
/// followed by a newer message).
const NOTE_SECONDS: u64 = 8;

/// Messages kept in the history.
const MAX_NOTES: usize = 64;

/// The screenshot dialog's fields.
struct ShotDialog {
    open: bool,
    width: u32,
    height: u32,
    supersample: u32,
    stereo: Stereo,
    path: String,
}

/// The explorer window's state.
pub struct ExplorerApp {
    /// The scene being explored, as edited.
    pub scene: Scene,
    /// Bumps with every change of the scene the worker renders (document edits and live
    /// changes alike).
    pub generation: u64,
    /// Bumps with every edit of the document only (the timeline's prepared path follows it).
    doc_generation: u64,
    name: String,
    path: Option<PathBuf>,
    watch: Option<Watch>,
    /// The camera of the file as last read, to tell whether a reload moved it.
    file_camera: Option<fathom_core::Camera>,
    /// The window's own tape (distance at the eye, picking).
    tape: Tape,
    history: History,
    /// The gesture of the last edit, so a drag is one undo step.
    gesture: Option<Gesture>,
    /// Pointer presses so far (a gesture's identity).
    presses: u64,
    edit_label: String,
    /// The camera and its mode.
    pub camera: CameraController,
    /// The renderer's settings.
    pub settings: ViewSettings,
    /// The viewport's image and its dynamic render scale.
    pub viewport: Viewport,
    worker: Worker,
    /// The window's GPU (when it has one), to give a replacement worker a renderer.
    render_state: Option<egui_wgpu::RenderState>,
    /// Workers started to replace one that stopped.
    pub worker_restarts: u64,
    /// The node selected in the tree.
    pub selected: NodePath,
    notes: Vec<Note>,
    browser: FileBrowser,
    bookmarks: Vec<(String, CameraController)>,
    shot_dialog: ShotDialog,
    shots: Vec<Shot>,
    script: Script,
    /// Window frames so far.
    pub frames: u64,
    last_frame: Instant,
    ui_ms: f64,
    /// The edit whose first frame is awaited, and when it was made; the last measured latency.
    pending_edit: Option<(u64, Instant)>,
    /// From the last measured edit to its first frame on screen, ms.
    pub edit_latency_ms: Option<f64>,
    /// Recompilations the worker had done when the last frame came back.
    pub compiles: u64,
    viewport_px: (u32, u32),
    /// The viewport's rectangle in points (whole pixels), as last laid out.
    pub viewport_rect: egui::Rect,
    /// Whether the side panels are shown (F2 hides them for a full-width view).
    pub show_panels: bool,
    /// Whether the stats overlay is drawn over the viewport (F3).
    pub show_overlay: bool,
    show_help: bool,
    tree_actions: Vec<TreeAction>,
    exit_error: std::sync::Arc<std::sync::Mutex<Option<String>>>,
    /// Modulation and the timeline.
    pub live: Live,
    /// The live scene last sent to the worker, and its generation.
    live_scene: Scene,
    sent_generation: u64,
    /// The camera the bindings drive this frame (when a binding drives a camera number).
    live_camera: Option<fathom_core::Camera>,
    /// The bound values sent with each recent generation, to tell what the frame on screen
    /// shows.
    sent_values: std::collections::VecDeque<(u64, Vec<Option<f64>>)>,
    /// Whether the timeline and bindings panels are shown (F4).
    pub show_live: bool,
    /// Seconds since the previous frame.
    frame_dt: f64,
    /// The document as last opened, saved or loaded from a preset: edits since make it dirty.
    saved: Scene,
    /// The preset the document came from, if it did.
    preset: Option<&'static str>,
    /// The title last given to the window.
    title: String,
    /// The "unsaved changes" dialog is open (a close was asked for with unsaved edits).
    quit_dialog: bool,
    /// Close without asking (the user chose to discard, or a scripted run ends).
    allow_close: bool,
    /// Close once the save the dialog asked for has succeeded.
    close_after_save: bool,
    /// Whether the window's GPU is a software adapter (lavapipe, llvmpipe), and its name.
    pub software_adapter: Option<String>,
    /// The places last written to the frame log.
    logged_places: Vec<crate::script::Place>,
    show_messages: bool,
}

impl ExplorerApp {
    /// A window for `opts` (the GPU of `cc`, when it has one, renders when it is a real GPU),
    /// starting its OSC listener when `opts.osc_bind` asks for one.
    pub fn new(
        cc: &eframe::CreationContext<'_>,
        opts: ExploreOptions,
    ) -> Result<ExplorerApp, String> {
        let m = live::start_modulator(&opts.scene, opts.osc_bind).map_err(|e| e.to_string())?;
        ExplorerApp::with_modulator(cc, opts, m)
    }

    /// A window for `opts` with a modulator already started (`fathom_app::run` starts it, and
    /// its listener, before any window opens, so a port in use fails first).
    pub fn with_modulator(
        cc: &eframe::CreationContext<'_>,
        opts: ExploreOptions,
        modulator: fathom_live::Modulator,
    ) -> Result<ExplorerApp, String> {
        let ctx = cc.egui_ctx.clone();
        let tape = Tape::compile(&opts.scene).map_err(|e| e.to_string())?;
        let worker = Worker::start(opts.scene.clone(), 0, move || ctx.request_repaint())
            .map_err(|e| e.to_string())?;
        let mut backend = opts.backend.unwrap_or(Backend::Trace);
        let mut notes = Vec::new();
        let mut software_adapter = None;
        if let Some(rs) = &cc.wgpu_render_state {
            let info = rs.adapter.get_info();
            let software = info.device_type == wgpu::DeviceType::Cpu;
            if software {
                software_adapter = Some(info.name.clone());
            }
            if opts.backend.is_none() && !software {
                backend = Backend::Gpu;
            }
            // On a software adapter the GPU tracer gets a device of its own (the session
            // opens one on its first GPU frame): a frame takes seconds there, and on the
            // window's queue it would hold up every window frame (and the surface's
            // reconfiguration) until it finished.
            if backend == Backend::Gpu && !software {
                match gpu_renderer(rs) {
                    Ok(r) => worker.set_gpu(r),
                    Err(e) => {
                        backend = Backend::Trace;
                        notes.push(Note {
                            text: format!(
                                "the GPU renderer could not start ({e}); using the CPU tracer"
                            ),
                            error: true,
                            at: Instant::now(),
                            source: NoteSource::General,
                            dismissed: false,
                        });
                    }
                }
            }
        }
        let script = Script::new(opts.frames, opts.screenshot.clone(), opts.log.as_deref())?;
        let camera = CameraController::new(&opts.scene.camera);
        let watch = opts.path.clone().map(Watch::new);
        let preset = opts
            .path
            .is_none()
            .then(|| opts.name.strip_prefix("preset "))
            .flatten()
            .and_then(|n| PRESETS.iter().find(|p| p.name == n))
            .map(|p| p.name);
        Ok(ExplorerApp {
            saved: opts.scene.clone(),
            preset,
            title: String::new(),
            quit_dialog: false,
            allow_close: false,
            close_after_save: false,
            software_adapter,
            logged_places: Vec::new(),
            show_messages: false,
            file_camera: opts.path.as_ref().map(|_| opts.scene.camera.clone()),
            scene: opts.scene.clone(),
            generation: 0,
            doc_generation: 0,
            name: opts.name,
            path: opts.path,
            watch,
            tape,
            history: History::default(),
            gesture: None,
            presses: 0,
            edit_label: String::new(),
            camera,
            settings: ViewSettings {
                backend,
                tracer: TracerRule::Enhanced,
                prepass: true,
                ssao: 0.0,
                stereo: Stereo::Mono,
                eye_separation: 0.065,
                fidelity: 1.0,
                planes: false,
                smooth: true,
                volume: Default::default(),
                path: window_path_settings(),
            },
            viewport: Viewport::new(opts.target_ms),
            worker,
            render_state: cc.wgpu_render_state.clone(),
            worker_restarts: 0,
            selected: Vec::new(),
            notes,
            browser: FileBrowser::default(),
            bookmarks: Vec::new(),
            shot_dialog: ShotDialog {
                open: false,
                width: 1920,
                height: 1080,
                supersample: 2,
                stereo: Stereo::Mono,
                path: "fathom-shot.png".into(),
            },
            shots: Vec::new(),
            script,
            frames: 0,
            last_frame: Instant::now(),
            ui_ms: 0.0,
            pending_edit: None,
            edit_latency_ms: None,
            compiles: 1,
            viewport_px: (0, 0),
            viewport_rect: egui::Rect::NOTHING,
            show_panels: true,
            show_overlay: true,
            show_help: false,
            tree_actions: Vec::new(),
            exit_error: opts.exit_error,
            live: Live::new(modulator),
            live_scene: opts.scene,
            sent_generation: 0,
            live_camera: None,
            sent_values: Default::default(),
            show_live: true,
            frame_dt: 0.0,
        })
    }

    fn note(&mut self, text: impl Into<String>, error: bool) {
        self.note_from(NoteSource::General, text, error);
    }

    /// A message from `source`. A success from a source clears that source's errors: once a
    /// file reloads (or another opens), its old parse errors are gone, not stacked.
    fn note_from(&mut self, source: NoteSource, text: impl Into<String>, error: bool) {
        let text = text.into();
        if error {
            eprintln!("fathom: {text}");
        } else if source != NoteSource::General {
            self.notes.retain(|n| !(n.error && n.source == source));
        }
        self.notes.push(Note {
            text,
            error,
            at: Instant::now(),
            source,
            dismissed: false,
        });
        if self.notes.len() > MAX_NOTES {
            self.notes.remove(0);
        }
    }

    /// The message the status bar shows: the newest one, while it is an error not dismissed
    /// or an information younger than [`NOTE_SECONDS`]. An older message never comes back
    /// when a newer one expires.
    fn status_note(&self) -> Option<&Note> {
        self.notes.last().filter(|n| {
            !n.dismissed && (n.error || n.at.elapsed() < Duration::from_secs(NOTE_SECONDS))
        })
    }

    /// Whether the document has edits that were not saved.
    pub fn dirty(&self) -> bool {
        self.scene != self.saved
    }

    /// The window's title: the document's name, and `*` while it has unsaved edits.
    pub fn title(&self) -> String {
        format!(
            "fathom - {}{}",
            self.name,
            if self.dirty() { " *" } else { "" }
        )
    }

    /// The camera frames are rendered from: the flown camera, or the camera the bindings
    /// drive when a binding drives a camera number.
    pub fn view_camera(&self) -> fathom_core::Camera {
        self.live_camera
            .clone()
            .unwrap_or_else(|| self.camera.camera())
    }

    /// The scene the render worker was last sent: the document with the timeline's parameter
    /// keys and the bindings' values written in.
    pub fn live_scene(&self) -> &Scene {
        &self.live_scene
    }

    /// The bound values (in the order of `scene.bindings`) of the scene generation on screen.
    pub fn shown_values(&self) -> Option<&[Option<f64>]> {
        let g = self.viewport.shown.as_ref()?.generation;
        self.sent_values
            .iter()
            .find(|(s, _)| *s == g)
            .map(|(_, v)| v.as_slice())
    }

    /// One frame of the live layer: derives the live scene (timeline, bindings) from the
    /// document and sends it to the worker when its numbers changed (a new generation when
    /// the document did not change: the view is new, the tape is the same).
    fn sync_live(&mut self) {
        let view = self.camera.camera();
        let (scene, path_camera, bound_camera) = self.live.derive(
            &self.scene,
            self.doc_generation,
            &self.tape,
            &view,
            self.frame_dt,
        );
        if let Some(c) = path_camera {
            self.camera = CameraController::new(&c);
        }
        self.live_camera = bound_camera;
        if scene == self.live_scene && self.sent_generation == self.generation {
            return;
        }
        if self.sent_generation == self.generation {
            self.generation += 1;
        }
        if scene != self.live_scene {
            let _ = self.tape.update_params(&scene);
        }
        self.worker.set_scene(self.generation, scene.clone());
        self.live_scene = scene;
        self.sent_generation = self.generation;
        let values = self.live.modulator.live().iter().map(|v| v.value).collect();
        self.sent_values.push_back((self.generation, values));
        while self.sent_values.len() > 32 {
            self.sent_values.pop_front();
        }
    }

    /// The key of the view on screen now.
    pub fn current_key(&self) -> u64 {
        view_key(
            &self.view_camera(),
            self.generation,
            &self.settings.base_request(),
        )
    }

    /// Whether the viewport shows the final refinement of the current view.
    pub fn settled(&self) -> bool {
        self.viewport.settled(self.current_key())
    }

    /// Replaces the document's scene (an open, a reload, an undo), sending it to the worker.
    fn replace_scene(&mut self, scene: Scene, label: Option<&str>) {
        if let Some(l) = label {
            self.history.record(l, self.scene.clone());
        }
        self.scene = scene;
        self.scene_changed();
    }

    /// After any change of `self.scene`: new generation, the window's tape, the worker.
    fn scene_changed(&mut self) {
        self.generation += 1;
        self.doc_generation += 1;
        if self.tape.update_params(&self.scene).is_err() {
            match Tape::compile(&self.scene) {
                Ok(t) => self.tape = t,
                Err(e) => self.note(e.to_string(), true),
            }
        }
        if tree::node_at(&self.scene.root, &self.selected).is_none() {
            self.selected.clear();
        }
        if let Some(e) = self.live.rebind(&self.scene) {
            self.note(e, true);
        }
        // The live scene (with the bindings' values) goes to the worker after the panels.
        self.pending_edit = Some((self.generation, Instant::now()));
    }

    /// Keeps an edit made by the panels this frame (or refuses it), recording one undo step
    /// per gesture.
    fn commit(&mut self, ctx: &egui::Context, before: Scene) {
        // A gesture is one press of the pointer on one parameter (a slider jumps to the press
        // on its first frame, before egui calls it a drag, and frames may carry the press and
        // the first moves together), or the keyboard's edits of one field: edits with the
        // same description within one press, or one focus, are one undo step.
        let (pressed, pointer) = ctx.input(|i| {
            (
                i.pointer.any_pressed(),
                i.pointer.any_down() || i.pointer.any_released(),
            )
        });
        if pressed {
            self.presses += 1;
        }
        let label = std::mem::take(&mut self.edit_label);
        if self.scene == before {
            if !pointer {
                self.gesture = None;
            }
            return;
        }
        if let Err(e) = self.scene.validate() {
            self.note(format!("edit refused: {e}"), true);
            self.scene = before;
            return;
        }
        let label = if label.is_empty() {
            "edit".to_string()
        } else {
            label
        };
        let gesture = Gesture {
            by: if pointer {
                GestureBy::Press(self.presses)
            } else {
                GestureBy::Focus(ctx.memory(|m| m.focused()))
            },
            label: label.clone(),
        };
        if self.gesture.as_ref() != Some(&gesture) {
            self.history.record(label, before);
        }
        self.gesture = Some(gesture);
        self.scene_changed();
    }

    fn undo(&mut self) {
        if let Some((label, s)) = self.history.undo(&self.scene) {
            self.scene = s;
            self.scene_changed();
            self.note(format!("undid {label}"), false);
        }
    }

    fn redo(&mut self) {
        if let Some((label, s)) = self.history.redo(&self.scene) {
            self.scene = s;
            self.scene_changed();
            self.note(format!("redid {label}"), false);
        }
    }

    /// Opens a scene file; a bad file is reported with its position and changes nothing.
    pub fn open(&mut self, path: &Path) {
        match scene_file::load(path) {
            Ok(s) => {
                self.camera = CameraController::new(&s.camera);
                self.file_camera = Some(s.camera.clone());
                self.saved = s.clone();
                self.replace_scene(s, Some("open file"));
                self.path = Some(path.to_path_buf());
                self.watch = Some(Watch::new(path.to_path_buf()));
                self.name = path.display().to_string();
                self.preset = None;
                self.note_from(
                    NoteSource::File,
                    format!("opened {}", path.display()),
                    false,
                );
            }
            Err(e) => self.note_from(NoteSource::File, format!("{e} (the scene was kept)"), true),
        }
    }

    /// Writes the scene (with the current view as its camera) to `path`.
    fn save(&mut self, path: &Path) {
        let mut s = self.scene.clone();
        s.camera = self.view_camera();
        match scene_file::save(path, &s) {
            Ok(()) => {
                self.path = Some(path.to_path_buf());
                let mut w = Watch::new(path.to_path_buf());
                w.touch();
                self.watch = Some(w);
                self.file_camera = Some(s.camera.clone());
                self.name = path.display().to_string();
                self.preset = None;
                self.saved = self.scene.clone();
                self.note_from(NoteSource::File, format!("saved {}", path.display()), false);
                if self.close_after_save {
                    self.allow_close = true;
                }
            }
            Err(e) => {
                self.close_after_save = false;
                self.note_from(NoteSource::File, e.to_string(), true)
            }
        }
    }

    fn load_preset(&mut self, name: &'static str) {
        match presets::load(name) {
            Ok(s) => {
                self.camera = CameraController::new(&s.camera);
                self.saved = s.clone();
                self.replace_scene(s, Some(&format!("load preset {name}")));
                self.name = format!("preset {name}");
                self.preset = Some(name);
                self.path = None;
                self.watch = None;
                // Errors about the file left behind are moot now.
                self.note_from(NoteSource::File, format!("loaded preset {name}"), false);
            }
            Err(e) => self.note(e.to_string(), true),
        }
    }

    /// Replies from the worker: frames to upload, edits applied or refused.
    fn poll_worker(&mut self, ctx: &egui::Context) {
        for reply in self.worker.poll() {
            match reply {
                Reply::Frame(done) => {
                    self.compiles = done.counters.compiles;
                    let generation = done.generation;
                    let note = done.result.as_ref().ok().and_then(|p| p.stats.note.clone());
                    if let Some(image) = self.viewport.accept(*done) {
                        match &mut self.viewport.texture {
                            Some(t) => t.set(image, egui::TextureOptions::LINEAR),
                            None => {
                                self.viewport.texture = Some(ctx.load_texture(
                                    "fathom viewport",
                                    image,
                                    egui::TextureOptions::LINEAR,
                                ))
                            }
                        }
                        if let Some((g, t)) = self.pending_edit
                            && generation >= g
                        {
                            self.edit_latency_ms = Some(t.elapsed().as_secs_f64() * 1e3);
                            self.pending_edit = None;
                        }
                        if let Some(n) = note
                            && !self.notes.iter().any(|x| x.text == n)
                        {
                            self.note(n, false);
                        }
                    }
                    if let Some(e) = self.viewport.error.take() {
                        self.note(e, true);
                    }
                }
                Reply::Scene(applied) => {
                    if let Err(e) = applied.result {
                        self.note(format!("the renderer refused the edit: {e}"), true);
                    }
                }
                Reply::Stopped(why) => {
                    self.replace_worker(ctx, &why);
                    return;
                }
            }
        }
    }

    /// Starts a fresh worker on the current scene after the last one stopped. The view it was
    /// rendering is marked failed (so a frame that panics every time is not retried in a
    /// loop); any other view renders as usual.
    fn replace_worker(&mut self, ctx: &egui::Context, why: &str) {
        self.viewport.worker_lost();
        let wake = ctx.clone();
        match Worker::start(self.live_scene.clone(), self.sent_generation, move || {
            wake.request_repaint()
        }) {
            Ok(w) => {
                self.worker = w;
                self.worker_restarts += 1;
                self.pending_edit = None;
                self.note(format!("{why}; started a new render worker"), true);
                if self.settings.backend == Backend::Gpu
                    && self.software_adapter.is_none()
                    && let Some(rs) = &self.render_state
                {
                    match gpu_renderer(rs) {
                        Ok(r) => self.worker.set_gpu(r),
                        Err(e) => {
                            self.settings.backend = Backend::Trace;
                            self.note(
                                format!(
                                    "the GPU renderer could not start ({e}); using the CPU tracer"
                                ),
                                true,
                            );
                        }
                    }
                }
            }
            Err(e) => self.note(
                format!("{why}; a new render worker could not start: {e}"),
                true,
            ),
        }
    }

    /// Makes the render worker panic, as a renderer bug would (for the fault tests).
    #[doc(hidden)]
    pub fn inject_worker_panic(&self) {
        self.worker.inject_panic();
    }

    /// The status bar's messages, oldest first, with whether each is an error.
    pub fn notes(&self) -> Vec<(String, bool)> {
        self.notes
            .iter()
            .map(|n| (n.text.clone(), n.error))
            .collect()
    }

    /// The watched file, dropped files, finished screenshots.
    fn poll_files(&mut self, ctx: &egui::Context) {
        if let Some(w) = &mut self.watch
            && w.changed()
        {
            let path = w.path.clone();
            match scene_file::load(&path) {
                Ok(s) => {
                    if self.file_camera.as_ref() != Some(&s.camera) {
                        self.camera = CameraController::new(&s.camera);
                        self.file_camera = Some(s.camera.clone());
                    }
                    self.saved = s.clone();
                    if s != self.scene {
                        self.replace_scene(s, Some("reload from disk"));
                    }
                    self.note_from(
                        NoteSource::File,
                        format!("reloaded {}", path.display()),
                        false,
                    );
                }
                Err(e) => self.note_from(
                    NoteSource::File,
                    format!("{e} (the scene on screen was kept)"),
                    true,
                ),
            }
        }
        let dropped: Vec<PathBuf> = ctx.input(|i| {
            i.raw
                .dropped_files
                .iter()
                .map(|f| f.path().to_path_buf())
                .collect()
        });
        if let Some(p) = dropped.last() {
            self.open(p);
        }
        let mut done = Vec::new();
        for (i, s) in self.shots.iter_mut().enumerate() {
            if let Some(r) = s.poll() {
                done.push((i, r, s.path.clone()));
            }
        }
        for (i, r, p) in done.into_iter().rev() {
            self.shots.remove(i);
            match r {
                Ok(()) => self.note(format!("wrote {}", p.display()), false),
                Err(e) => self.note(e, true),
            }
        }
    }

    fn shortcuts(&mut self, ctx: &egui::Context) {
        use egui::{Key, KeyboardShortcut, Modifiers};
        let sc = |m, k| KeyboardShortcut::new(m, k);
        let (undo, redo, redo2, save, open, quit, shot_dialog) = ctx.input_mut(|i| {
            (
                i.consume_shortcut(&sc(Modifiers::COMMAND, Key::Z)),
                i.consume_shortcut(&sc(Modifiers::COMMAND | Modifiers::SHIFT, Key::Z)),
                i.consume_shortcut(&sc(Modifiers::COMMAND, Key::Y)),
                i.consume_shortcut(&sc(Modifiers::COMMAND, Key::S)),
                i.consume_shortcut(&sc(Modifiers::COMMAND, Key::O)),
                i.consume_shortcut(&sc(Modifiers::COMMAND, Key::Q)),
                i.consume_shortcut(&sc(Modifiers::COMMAND, Key::F12)),
            )
        });
        if quit {
            // Through the window's close request, so the unsaved-changes check sees it.
            ctx.send_viewport_cmd(egui::ViewportCommand::Close);
        }
        if shot_dialog {
            self.shot_dialog.open = true;
        }
        if undo {
            self.undo();
        }
        if redo || redo2 {
            self.redo();
        }
        if save {
            match self.path.clone() {
                Some(p) => self.save(&p),
                None => self.browser.open(BrowseFor::Save, None),
            }
        }
        if open {
            self.browser.open(BrowseFor::Open, self.path.as_deref());
        }
        if ctx.egui_wants_keyboard_input() {
            return;
        }
        let (f2, f3, f4) = ctx.input(|i| {
            (
                i.key_pressed(Key::F2),
                i.key_pressed(Key::F3),
                i.key_pressed(Key::F4),
            )
        });
        if f2 {
            self.show_panels = !self.show_panels;
        }
        if f4 {
            self.show_live = !self.show_live;
        }
        if f3 {
            self.show_overlay = !self.show_overlay;
        }
        let (f12, digits, ctrl) = ctx.input(|i| {
            let digits: Vec<usize> = (1..=9)
                .filter(|d| {
                    let k = Key::from_name(&d.to_string()).expect("digit keys exist");
                    i.key_pressed(k)
                })
                .collect();
            (i.key_pressed(Key::F12), digits, i.modifiers.command)
        });
        if f12 {
            self.quick_shot();
        }
        for d in digits {
            if ctrl {
                while self.bookmarks.len() < d {
                    self.bookmarks.push((
                        format!("view {}", self.bookmarks.len() + 1),
                        self.camera.clone(),
                    ));
                }
                self.bookmarks[d - 1].1 = self.camera.clone();
                self.note(format!("stored bookmark {d}"), false);
            } else if let Some((_, c)) = self.bookmarks.get(d - 1) {
                self.camera = c.clone();
            }
        }
    }

    fn menu_bar(&mut self, ui: &mut egui::Ui) {
        egui::Panel::top("menu").show(ui, |ui| {
            egui::MenuBar::new().ui(ui, |ui| {
                ui.menu_button("File", |ui| {
                    if ui.button("Open... (Ctrl+O)").clicked() {
                        self.browser.open(BrowseFor::Open, self.path.as_deref());
                        ui.close();
                    }
                    if ui.button("Save (Ctrl+S)").clicked() {
                        match self.path.clone() {
                            Some(p) => self.save(&p),
                            None => self.browser.open(BrowseFor::Save, None),
                        }
                        ui.close();
                    }
                    if ui.button("Save as...").clicked() {
                        self.browser.open(BrowseFor::Save, self.path.as_deref());
                        ui.close();
                    }
                    if ui.button("Screenshot of the view (F12)").clicked() {
                        self.quick_shot();
                        ui.close();
                    }
                    if ui.button("Screenshot... (Ctrl+F12)").clicked() {
                        self.shot_dialog.open = true;
                        ui.close();
                    }
                    if ui.button("Quit (Ctrl+Q)").clicked() {
                        ui.ctx().send_viewport_cmd(egui::ViewportCommand::Close);
                        ui.close();
                    }
                });
                ui.menu_button("Edit", |ui| {
                    let u = self.history.next_undo().map(|l| format!("Undo {l}"));
                    if ui
                        .add_enabled(
                            u.is_some(),
                            egui::Button::new(u.as_deref().unwrap_or("Undo")),
                        )
                        .clicked()
                    {
                        self.undo();
                        ui.close();
                    }
                    let r = self.history.next_redo().map(|l| format!("Redo {l}"));
                    if ui
                        .add_enabled(
                            r.is_some(),
                            egui::Button::new(r.as_deref().unwrap_or("Redo")),
                        )
                        .clicked()
                    {
                        self.redo();
                        ui.close();
                    }
                });
                ui.menu_button("View", |ui| {
                    if ui.button("Store bookmark").clicked() {
                        let n = self.bookmarks.len() + 1;
                        self.bookmarks
                            .push((format!("view {n}"), self.camera.clone()));
                        ui.close();
                    }
                    let mut go = None;
                    for (i, (name, _)) in self.bookmarks.iter().enumerate() {
                        if ui.button(format!("{} ({})", name, i + 1)).clicked() {
                            go = Some(i);
                            ui.close();
                        }
                    }
                    if let Some(i) = go {
                        self.camera = self.bookmarks[i].1.clone();
                    }
                    ui.checkbox(&mut self.show_panels, "Side panels (F2)");
                    ui.checkbox(&mut self.show_overlay, "Stats overlay (F3)");
                    ui.checkbox(&mut self.show_live, "Timeline and bindings (F4)");
                    ui.checkbox(&mut self.show_messages, "Messages");
                    if ui.button("Fly (leave orbit)").clicked() {
                        self.camera.mode = Mode::Fly;
                        ui.close();
                    }
                    if ui.button("Reset view to the scene's camera").clicked() {
                        self.camera = CameraController::new(&self.scene.camera);
                        ui.close();
                    }
                });
                ui.menu_button("Help", |ui| {
                    if ui.button("Keys and mouse").clicked() {
                        self.show_help = true;
                        ui.close();
                    }
                });
            });
        });
    }

    fn status_bar(&mut self, ui: &mut egui::Ui) {
        egui::Panel::bottom("status").show(ui, |ui| {
            ui.horizontal_wrapped(|ui| {
                let shown = self.status_note().map(|n| (n.text.clone(), n.error));
                match &shown {
                    Some((text, true)) => {
                        ui.colored_label(egui::Color32::from_rgb(255, 120, 110), text);
                    }
                    Some((text, false)) => {
                        ui.label(text);
                    }
                    None => {
                        ui.label(self.title());
                    }
                }
                if shown.is_some_and(|(_, error)| error)
                    && ui.small_button("dismiss").clicked()
                    && let Some(n) = self.notes.last_mut()
                {
                    n.dismissed = true;
                }
                if self.notes.len() > 1 && ui.small_button("messages").clicked() {
                    self.show_messages = true;
                }
                for s in &self.shots {
                    ui.add(
                        egui::ProgressBar::new(s.fraction())
                            .desired_width(120.0)
                            .text(format!("{}", s.path.display())),
                    );
                }
            });
        });
    }

    /// Whether the live panels have anything to show.
    fn has_live(&self) -> bool {
        !self.scene.paths.is_empty()
            || !self.scene.bindings.is_empty()
            || self.live.modulator.osc_addr().is_some()
    }

    /// The timeline and the bindings, above the status bar.
    fn live_panel(&mut self, ui: &mut egui::Ui) {
        let mut action = None;
        egui::Panel::bottom("live")
            .resizable(true)
            .default_size(160.0)
            .show(ui, |ui| {
                // Side by side: the timeline on the left, the bindings on the right.
                ui.columns(2, |cols| {
                    egui::ScrollArea::both()
                        .id_salt("timeline scroll")
                        .show(&mut cols[0], |ui| {
                            ui.strong("Timeline");
                            action = live::timeline_ui(
                                ui,
                                &mut self.live,
                                &self.scene,
                                self.doc_generation,
                                &self.tape,
                            );
                        });
                    egui::ScrollArea::both()
                        .id_salt("bindings scroll")
                        .show(&mut cols[1], |ui| {
                            ui.strong("Bindings");
                            live::bindings_ui(ui, &self.live, &self.scene);
                        });
                });
            });
        match action {
            Some(TimelineAction::AddKey) => self.add_key(),
            Some(TimelineAction::Retime(d)) => {
                let i = self.live.timeline.path;
                if let Some(p) = self.scene.paths.get_mut(i) {
                    p.retime(d);
                    self.edit_label = format!("retime path {}", p.name);
                }
            }
            None => {}
        }
    }

    /// Adds a keyframe at the current view to the timeline's path at its time (a document
    /// edit, undoable).
    pub fn add_key(&mut self) {
        let t = self.live.timeline.t;
        let i = self.live.timeline.path;
        let flight = match self
            .live
            .flight(&self.scene, self.doc_generation, &self.tape)
        {
            Some(Ok(f)) => f.clone(),
            Some(Err(e)) => {
                let e = e.clone();
                self.note(format!("add key: {e}"), true);
                return;
            }
            None => return,
        };
        let cam = self.view_camera();
        let (at, note) = live::add_key(&mut self.scene, i, &flight, t, &cam);
        self.edit_label = format!("add key {at} to path {}", self.scene.paths[i].name);
        self.note(
            note.unwrap_or_else(|| format!("added key {at} at {t:.2} s")),
            false,
        );
    }

    fn left_panel(&mut self, ui: &mut egui::Ui) {
        let mut actions: Vec<TreeAction> = Vec::new();
        let width = ui.ctx().content_rect().width();
        egui::Panel::left("scene")
            .resizable(true)
            .default_size((0.22 * width).clamp(140.0, 280.0))
            .show(ui, |ui| {
                egui::ScrollArea::vertical().show(ui, |ui| {
                    ui.heading("Scene");
                    let mut pick = None;
                    egui::ComboBox::new("preset", "preset")
                        .selected_text(self.preset.unwrap_or("choose..."))
                        .show_ui(ui, |ui| {
                            for p in PRESETS {
                                if ui
                                    .selectable_label(self.preset == Some(p.name), p.name)
                                    .on_hover_text(p.description)
                                    .clicked()
                                {
                                    pick = Some(p.name);
                                }
                            }
                        });
                    if let Some(p) = pick {
                        self.load_preset(p);
                    }
                    ui.separator();
                    ui.strong("Tree");
                    actions.extend(tree::tree_ui(ui, &self.scene.root, &self.selected));
                    actions.extend(tree::node_buttons(ui, &self.selected));
                    ui.separator();
                    let mut notes = Vec::new();
                    ui.collapsing("IFS loop", |ui| {
                        if let Some(what) = tree::ifs_editor(ui, &mut self.scene.ifs, &mut notes) {
                            self.edit_label = format!("IFS loop: {what}");
                        }
                    });
                    ui.collapsing("Lights", |ui| {
                        if look::lights_editor(ui, &mut self.scene.lights) {
                            self.edit_label = "edit lights".into();
                        }
                    });
                    ui.collapsing("Sky, shading and tracing", |ui| {
                        if look::render_settings_editor(ui, &mut self.scene.render) {
                            self.edit_label = "edit render settings".into();
                        }
                    });
                    for n in notes {
                        self.note(n, false);
                    }
                });
            });
        self.tree_actions.extend(actions);
    }

    /// Applies the tree edits the panels asked for (after the panels' own edits are kept).
    fn apply_tree_actions(&mut self) {
        for a in std::mem::take(&mut self.tree_actions) {
            let before = self.scene.clone();
            match tree::apply(&mut self.scene, &a, &mut self.selected) {
                Ok(()) if self.scene != before => {
                    if let Err(e) = self.scene.validate() {
                        self.note(format!("{}: {e}", a.label()), true);
                        self.scene = before;
                    } else {
                        self.history.record(a.label(), before);
                        self.scene_changed();
                    }
                }
                Ok(()) => {}
                Err(e) => self.note(format!("{}: {e}", a.label()), true),
            }
        }
    }

    fn right_panel(&mut self, ui: &mut egui::Ui) {
        let width = ui.ctx().content_rect().width();
        egui::Panel::right("inspector")
            .resizable(true)
            .default_size((0.24 * width).clamp(150.0, 300.0))
            .show(ui, |ui| {
                egui::ScrollArea::vertical().show(ui, |ui| {
                    ui.heading("Node");
                    let mut notes = Vec::new();
                    let path = self.selected.clone();
                    if let Some(n) = tree::node_at_mut(&mut self.scene.root, &path) {
                        let label = tree::node_label(n, path.is_empty());
                        ui.label(format!("{label} at {}", tree::path_text(&path)));
                        if let Some(what) = tree::node_inspector(ui, n, &path, &mut notes) {
                            self.edit_label = format!("{label}: {what}");
                        }
                    }
                    for n in notes {
                        self.note(n, false);
                    }
                    ui.separator();
                    ui.heading("Renderer");
                    self.renderer_settings(ui);
                });
            });
    }

    fn renderer_settings(&mut self, ui: &mut egui::Ui) {
        let gpu_label = match &self.software_adapter {
            Some(_) => "GPU tracer (software adapter: slow)",
            None => "GPU tracer",
        };
        let gpu_tip = match &self.software_adapter {
            Some(name) => format!(
                "The window's graphics adapter is {name}, which runs shaders on the CPU: the \
                 GPU tracer works but is far slower than the CPU tracer here. Its frames show \
                 their progress and are cancelled as soon as you switch away."
            ),
            None => "The WGSL tape interpreter on the window's GPU.".to_string(),
        };
        let s = &mut self.settings;
        egui::ComboBox::new("backend", "renderer")
            .selected_text(match s.backend {
                Backend::Trace => "CPU tracer",
                Backend::Gpu => gpu_label,
                Backend::Octree => "octree",
                Backend::Volume => "volume (cloud)",
                Backend::Path => "path tracer",
            })
            .show_ui(ui, |ui| {
                ui.selectable_value(&mut s.backend, Backend::Trace, "CPU tracer");
                ui.selectable_value(&mut s.backend, Backend::Gpu, gpu_label)
                    .on_hover_text(gpu_tip);
                ui.selectable_value(&mut s.backend, Backend::Octree, "octree");
                ui.selectable_value(&mut s.backend, Backend::Volume, "volume (cloud)")
                    .on_hover_text(
                        "the scene's interior as a cloud, path-traced (fathom-volume); \
                         refines while the view is still",
                    );
                ui.selectable_value(&mut s.backend, Backend::Path, "path tracer")
                    .on_hover_text(
                        "global illumination, soft shadows, depth of field (CPU): samples \
                         accumulate while the view holds still; moving or editing shows the \
                         preview tracer and starts over",
                    );
            });
        ui.horizontal(|ui| {
            ui.label("step rule");
            ui.selectable_value(&mut s.tracer, TracerRule::Enhanced, "enhanced");
            ui.selectable_value(&mut s.tracer, TracerRule::Basic, "basic");
        });
        ui.checkbox(&mut s.prepass, "cone-marching prepass");
        ui.add(egui::Slider::new(&mut s.ssao, 0.0..=4.0).text("SSAO"));
        if s.backend == Backend::Octree {
            ui.add(
                egui::Slider::new(&mut s.fidelity, 0.25..=16.0)
                    .logarithmic(true)
                    .text("voxel size (px)"),
            );
            ui.checkbox(&mut s.planes, "surface planes").on_hover_text(
                "Draw voxels still wider than a pixel as the surface through them instead \
                     of as cubes: smoother while detail arrives, slower (rebuilds the tree)",
            );
            ui.checkbox(&mut s.smooth, "smooth wide voxels")
                .on_hover_text(
                    "Blend the colours of voxels two or more pixels wide across their width \
                     instead of drawing each flat: a soft picture instead of a mosaic while \
                     detail arrives (keeps the tree; views settled to voxels under two \
                     pixels look the same)",
                );
        }
        if s.backend == Backend::Volume {
            let v = &mut s.volume;
            ui.add(egui::Slider::new(&mut v.grid, 16..=256).text("density grid"));
            ui.add(
                egui::Slider::new(&mut v.density_scale, 0.1..=200.0)
                    .logarithmic(true)
                    .text("extinction"),
            );
            ui.add(egui::Slider::new(&mut v.albedo, 0.0..=1.0).text("albedo"));
            ui.add(egui::Slider::new(&mut v.g, -0.95..=0.95).text("anisotropy g"));
            ui.add(egui::Slider::new(&mut v.spp, 1..=64).text("samples per frame"));
        }
        if s.backend == Backend::Path {
            let p = &mut s.path;
            ui.add(
                egui::Slider::new(&mut p.spp, 1..=4096)
                    .logarithmic(true)
                    .text("samples per pixel"),
            )
            .on_hover_text("accumulation stops here; the noise falls as 1/sqrt(samples)");
            ui.add(egui::Slider::new(&mut p.max_bounces, 1..=32).text("bounces"));
            ui.add(
                egui::Slider::new(&mut p.aperture, 0.0..=1.0)
                    .logarithmic(true)
                    .text("aperture"),
            )
            .on_hover_text("lens radius in scene units: 0 keeps everything sharp");
            let mut focus = p.focus_distance.unwrap_or(0.0);
            if ui
                .add(
                    egui::Slider::new(&mut focus, 0.0..=100.0)
                        .logarithmic(true)
                        .text("focus distance"),
                )
                .on_hover_text(
                    "0: the camera's target is in focus; clicking the surface makes the point \
                     clicked the target (the orbit pivot), so a click focuses there",
                )
                .changed()
            {
                p.focus_distance = (focus > 0.0).then_some(focus);
            }
            ui.checkbox(&mut p.denoise, "denoise")
                .on_hover_text("edge-aware à-trous filter guided by albedo, normal and depth");
        }
        ui.horizontal(|ui| {
            ui.label("stereo");
            ui.selectable_value(&mut s.stereo, Stereo::Mono, "mono");
            ui.selectable_value(&mut s.stereo, Stereo::SideBySide, "side by side");
            ui.selectable_value(&mut s.stereo, Stereo::Ods, "360 (ODS)");
        });
        if s.stereo != Stereo::Mono {
            ui.add(
                egui::Slider::new(&mut s.eye_separation, 0.0..=1.0)
                    .logarithmic(true)
                    .text("eye separation"),
            );
        }
        if matches!(s.backend, Backend::Octree | Backend::Volume | Backend::Path)
            && s.stereo != Stereo::Mono
        {
            s.stereo = Stereo::Mono;
        }
        let mut target = self.viewport.scale.target_ms();
        if ui
            .add(egui::Slider::new(&mut target, 8.0..=200.0).text("target frame ms"))
            .changed()
        {
            self.viewport.scale.set_target_ms(target);
        }
        let mut ss = self.viewport.refine_supersample;
        ui.add(egui::Slider::new(&mut ss, 1..=4).text("refine supersampling"));
        self.viewport.refine_supersample = ss;
    }

    /// The viewport: camera input, the frame, the stats overlay. Returns its size in pixels.
    fn central(&mut self, ui: &mut egui::Ui, dt: f64) {
        egui::CentralPanel::no_frame().show(ui, |ui| {
            let ppp = ui.ctx().pixels_per_point();
            // Whole pixels, so the frame's texels land on the screen's pixels one to one.
            let rect = ui.available_rect_before_wrap().round_to_pixels(ppp);
            self.viewport_rect = rect;
            let r = ui.allocate_rect(rect, egui::Sense::click_and_drag());
            crate::script::place("viewport", "viewport".into(), &r);
            self.viewport_px = (
                (rect.width() * ppp).round().max(0.0) as u32,
                (rect.height() * ppp).round().max(0.0) as u32,
            );
            // Camera: click to orbit the surface point under the cursor, drag to look, keys.
            if r.clicked()
                && let Some(pos) = r.interact_pointer_pos()
            {
                let cam = self.view_camera();
                let f = cam.frame();
                let (px, py) = ((pos.x - rect.left()) * ppp, (pos.y - rect.top()) * ppp);
                let (w, h) = self.viewport_px;
                let d = f.ray_dir(px as f64, py as f64, w.max(1), h.max(1));
                let eps = 0.5 * f.pixel_angle(h.max(1));
                match camera::pick(&self.tape, cam.eye, d, eps, self.scene.render.max_distance) {
                    Some(p) => {
                        self.camera.orbit_around(p);
                        self.note("orbiting the picked point (click the sky to fly)", false);
                    }
                    None => self.camera.mode = Mode::Fly,
                }
            }
            let controls = input::controls(ui.ctx(), &r);
            let d_eye = camera::distance_at(&self.tape, self.camera.eye);
            self.camera.step(&controls, dt, d_eye);
            let painter = ui.painter_at(rect);
            painter.rect_filled(rect, 0.0, egui::Color32::from_gray(20));
            if let Some(t) = &self.viewport.texture {
                painter.image(
                    t.id(),
                    fit(rect, t.size_vec2()),
                    egui::Rect::from_min_max(egui::pos2(0.0, 0.0), egui::pos2(1.0, 1.0)),
                    egui::Color32::WHITE,
                );
            }
            if self.show_overlay {
                self.overlay(&painter, rect);
            }
        });
    }

    fn overlay(&self, painter: &egui::Painter, rect: egui::Rect) {
        let mut lines = vec![format!("{:.0} fps (window)", 1e3 / self.ui_ms.max(1e-3))];
        if let Some(s) = &self.viewport.shown {
            let st = &s.stats;
            lines.push(format!(
                "{} {} {}x{}{} in {:.1} ms",
                st.renderer,
                match s.stage {
                    Stage::Interactive if s.octree_requests.is_some() => "step",
                    Stage::Full if s.octree_requests.is_some() => "still step",
                    Stage::Interactive => "interactive",
                    Stage::Full => "full",
                    Stage::Supersampled => "supersampled",
                },
                s.request.width,
                s.request.height,
                if s.request.supersample > 1 {
                    format!(" x{}", s.request.supersample)
                } else {
                    String::new()
                },
                s.ms
            ));
            lines.push(format!(
                "scale {:.2}  prepass {:.1}  trace {:.1}  post {:.1} ms",
                s.scale, st.ms.prepass, st.ms.trace_and_shade, st.ms.post
            ));
            lines.push(format!(
                "DE/px {:.2}{}",
                st.depth_de_per_pixel,
                if st.deep_f64_path { "  f64 path" } else { "" }
            ));
            if let Some(p) = &st.path {
                lines.push(format!(
                    "path {} spp, noise {:.1} %, {:.2} M paths/s{}",
                    p.samples_per_pixel,
                    p.relative_noise * 100.0,
                    p.paths_per_second / 1e6,
                    if p.denoised { ", denoised" } else { "" }
                ));
            }
            if let Some(o) = &st.octree {
                lines.push(format!(
                    "octree {} nodes, {:.1} MiB, {:.1} nodes/ray{}",
                    o.nodes,
                    o.arena_bytes as f64 / 1048576.0,
                    o.nodes_per_ray,
                    match s.octree_requests {
                        Some(0) => ", settled".to_string(),
                        Some(n) => format!(", {n} to subdivide"),
                        None => String::new(),
                    }
                ));
            }
        }
        if self.settings.backend == Backend::Gpu
            && let Some(name) = &self.software_adapter
        {
            lines.push(format!("software adapter ({name}): CPU speed"));
        }
        if let Some(p) = self.viewport.progress() {
            lines.push(format!("rendering... {:.0} %", p * 100.0));
        }
        if let Some(ms) = self.viewport.full_after_still_ms {
            lines.push(format!("full resolution {ms:.0} ms after stopping"));
        }
        if let Some(ms) = self.edit_latency_ms {
            lines.push(format!(
                "last edit on screen after {ms:.0} ms; {} compile(s)",
                self.compiles
            ));
        }
        if !self.scene.bindings.is_empty() || self.live.modulator.osc_addr().is_some() {
            let c = self.live.counters();
            lines.push(match self.live.modulator.osc_addr() {
                Some(a) => format!("OSC {a}: {} packets, {} rejected", c.packets, c.rejected),
                None => format!(
                    "{} binding(s); OSC not listening",
                    self.scene.bindings.len()
                ),
            });
        }
        let text = lines.join("\n");
        let pos = rect.left_top() + egui::vec2(8.0, 8.0);
        let galley = painter.layout_no_wrap(
            text,
            egui::FontId::monospace(11.0),
            egui::Color32::from_gray(235),
        );
        let bg = egui::Rect::from_min_size(pos, galley.size()).expand(4.0);
        painter.rect_filled(bg, 3.0, egui::Color32::from_black_alpha(150));
        painter.galley(pos, galley, egui::Color32::WHITE);
    }

    fn dialogs(&mut self, ctx: &egui::Context) {
        if let Some((purpose, p)) = self.browser.show(ctx) {
            match purpose {
                BrowseFor::Open => self.open(&p),
                BrowseFor::Save => self.save(&p),
            }
        }
        if self.show_help {
            egui::Window::new("Keys and mouse")
                .open(&mut self.show_help)
                .resizable(false)
                .show(ctx, |ui| {
                    // Never wrapped: each row of the table is one line.
                    ui.add(
                        egui::Label::new(egui::RichText::new(input::KEY_HELP).monospace()).extend(),
                    );
                });
        }
        if self.show_messages {
            let mut open = true;
            egui::Window::new("Messages")
                .open(&mut open)
                .default_width(480.0)
                .show(ctx, |ui| {
                    egui::ScrollArea::vertical().show(ui, |ui| {
                        for n in self.notes.iter().rev() {
                            if n.error {
                                ui.colored_label(egui::Color32::from_rgb(255, 120, 110), &n.text);
                            } else {
                                ui.label(&n.text);
                            }
                        }
                    });
                });
            self.show_messages = open;
        }
        if self.quit_dialog {
            self.unsaved_dialog(ctx);
        }
        let mut start = false;
        if self.shot_dialog.open {
            let d = &mut self.shot_dialog;
            egui::Window::new("Screenshot")
                .open(&mut d.open)
                .show(ctx, |ui| {
                    ui.horizontal(|ui| {
                        ui.add(egui::DragValue::new(&mut d.width).range(16..=16384));
                        ui.label("x");
                        ui.add(egui::DragValue::new(&mut d.height).range(16..=16384));
                        ui.label("pixels (per eye)");
                    });
                    ui.add(egui::Slider::new(&mut d.supersample, 1..=4).text("supersampling"));
                    ui.horizontal(|ui| {
                        ui.selectable_value(&mut d.stereo, Stereo::Mono, "mono");
                        ui.selectable_value(&mut d.stereo, Stereo::SideBySide, "side by side");
                        ui.selectable_value(&mut d.stereo, Stereo::Ods, "360 stereo (ODS)");
                    });
                    ui.horizontal(|ui| {
                        ui.label("file");
                        ui.text_edit_singleline(&mut d.path);
                    });
                    if ui.button("Render").clicked() {
                        start = true;
                    }
                });
        }
        if start {
            self.shot_dialog.open = false;
            self.start_shot();
        }
    }

    /// The dialog asking what to do with unsaved edits when the window is asked to close.
    fn unsaved_dialog(&mut self, ctx: &egui::Context) {
        let mut choice = None;
        egui::Window::new("Unsaved changes")
            .collapsible(false)
            .resizable(false)
            .anchor(egui::Align2::CENTER_CENTER, egui::vec2(0.0, 0.0))
            .show(ctx, |ui| {
                ui.label(format!(
                    "{} has edits that were not saved. Save them before closing?",
                    self.name
                ));
                ui.horizontal(|ui| {
                    for (text, c) in [
                        ("Save", QuitChoice::Save),
                        ("Discard", QuitChoice::Discard),
                        ("Cancel", QuitChoice::Cancel),
                    ] {
                        let r = ui.button(text);
                        crate::script::place("button", text.into(), &r);
                        if r.clicked() {
                            choice = Some(c);
                        }
                    }
                });
            });
        if ctx.input(|i| i.key_pressed(egui::Key::Escape)) {
            choice = Some(QuitChoice::Cancel);
        }
        match choice {
            Some(QuitChoice::Save) => {
                self.quit_dialog = false;
                self.close_after_save = true;
                match self.path.clone() {
                    Some(p) => self.save(&p),
                    None => self.browser.open(BrowseFor::Save, None),
                }
                if self.allow_close {
                    ctx.send_viewport_cmd(egui::ViewportCommand::Close);
                }
            }
            Some(QuitChoice::Discard) => {
                self.quit_dialog = false;
                self.allow_close = true;
                ctx.send_viewport_cmd(egui::ViewportCommand::Close);
            }
            Some(QuitChoice::Cancel) => {
                self.quit_dialog = false;
                self.close_after_save = false;
            }
            None => {}
        }
    }

    /// F12: the view as the viewport shows it (the live scene with the bindings' values of
    /// this moment, the flown camera, the stereo layout) at the viewport's size, written to
    /// the next free `fathom-shot-NNN.png` in the working directory.
    pub fn quick_shot(&mut self) {
        let path = (1..10000)
            .map(|i| PathBuf::from(format!("fathom-shot-{i:03}.png")))
            .find(|p| !p.exists() && !self.shots.iter().any(|s| &s.path == p))
            .unwrap_or_else(|| PathBuf::from("fathom-shot.png"));
        let (w, h) = self.viewport_px;
        let (w, h) = match self.settings.stereo {
            Stereo::Mono => (w, h),
            Stereo::SideBySide => (w / 2, h / 2),
            Stereo::Ods => (w, h / 2),
        };
        let req = self.shot_request(w.max(16), h.max(16), 1, self.settings.stereo);
        self.start_shot_of(req, path);
    }

    /// The offline request for a screenshot of the current view.
    pub fn shot_request(
        &self,
        width: u32,
        height: u32,
        supersample: u32,
        stereo: Stereo,
    ) -> RenderRequest {
        let settings = ViewSettings {
            stereo,
            backend: match self.settings.backend {
                Backend::Octree => Backend::Octree,
                Backend::Volume => Backend::Volume,
                Backend::Path => Backend::Path,
                _ => Backend::Trace,
            },
            ..self.settings.clone()
        };
        RenderRequest {
            width,
            height,
            supersample,
            ..settings.base_request()
        }
    }

    fn start_shot(&mut self) {
        let d = &self.shot_dialog;
        let req = self.shot_request(d.width, d.height, d.supersample, d.stereo);
        let path = PathBuf::from(d.path.trim());
        self.start_shot_of(req, path);
    }

    /// Renders the view offline with `req` into `path`: the live scene (what the viewport
    /// shows, the bindings' values of this moment included), not the document.
    fn start_shot_of(&mut self, req: RenderRequest, path: PathBuf) {
        if let Err(e) = req.validate() {
            self.note(format!("screenshot: {e}"), true);
            return;
        }
        self.note(format!("rendering {}...", path.display()), false);
        self.shots.push(Shot::start(
            self.live_scene.clone(),
            self.view_camera(),
            req,
            path,
        ));
    }

    /// One window frame of logic after the panels: scheduling, the scripted run, the log.
    fn after_panels(&mut self, ctx: &egui::Context) {
        self.sync_live();
        let cam = self.view_camera();
        let base = self.settings.base_request();
        let key = view_key(&cam, self.generation, &base);
        self.viewport
            .schedule(&self.worker, key, &cam, &base, self.viewport_px);
        self.frames += 1;
        let title = self.title();
        if title != self.title {
            ctx.send_viewport_cmd(egui::ViewportCommand::Title(title.clone()));
            self.title = title;
        }
        let places = crate::script::take_places(ctx);
        let places = (places != self.logged_places).then(|| {
            self.logged_places = places.clone();
            places
        });
        let node = tree::node_at(&self.scene.root, &self.selected);
        let status = self.status_note().map(|n| n.text.clone());
        let line = FrameLog {
            frame: self.frames,
            t_ms: std::time::SystemTime::now()
                .duration_since(std::time::UNIX_EPOCH)
                .map_or(0.0, |d| d.as_secs_f64() * 1e3),
            title: &self.title,
            dirty: self.dirty(),
            dialog: if self.quit_dialog {
                Some("unsaved changes")
            } else if self.shot_dialog.open {
                Some("screenshot")
            } else {
                None
            },
            selected: tree::path_text(&self.selected),
            selected_label: node
                .map(|n| tree::node_label(n, self.selected.is_empty()))
                .unwrap_or_default(),
            selected_params: node
                .map(|n| {
                    let mut off = 0;
                    use fathom_core::registry::Family;
                    n.shape
                        .kind
                        .def()
                        .params
                        .iter()
                        .map(|p| {
                            let w = p.kind.width();
                            let v = n.shape.params[off..off + w].to_vec();
                            off += w;
                            (p.name, v)
                        })
                        .collect()
                })
                .unwrap_or_default(),
            undo: self.history.next_undo(),
            status: status.as_deref(),
            shown_view: self.viewport.shown.as_ref().map(|s| s.key),
            view: key,
            shown_scale: self.viewport.shown.as_ref().map(|s| s.scale),
            mode: match self.camera.mode {
                Mode::Fly => "fly",
                Mode::Orbit { .. } => "orbit",
            },
            pivot: match self.camera.mode {
                Mode::Fly => None,
                Mode::Orbit { pivot } => Some(pivot.to_array()),
            },
            software_adapter: self.settings.backend == Backend::Gpu
                && self.software_adapter.is_some(),
            places,
            path_spp: self
                .viewport
                .shown
                .as_ref()
                .and_then(|s| s.stats.path.map(|p| p.samples_per_pixel)),
            frame_ms: self.ui_ms,
            render_scale: self.viewport.scale.scale(),
            renderer: self
                .viewport
                .shown
                .as_ref()
                .map(|s| s.stats.renderer)
                .unwrap_or(""),
            stage: self.viewport.shown.as_ref().map(|s| s.stage),
            render_ms: self.viewport.shown.as_ref().map(|s| s.ms),
            shown: self
                .viewport
                .shown
                .as_ref()
                .map(|s| (s.request.width, s.request.height)),
            settled: self.viewport.settled(key),
            full_after_still_ms: self.viewport.full_after_still_ms,
            edit_latency_ms: self.edit_latency_ms,
            compiles: self.compiles,
            camera: cam.clone(),
            osc: self.live.counters(),
            bound: self.live.bound_values(&self.scene),
            path_time: self.live.timeline.engaged.then_some(self.live.timeline.t),
        };
        // Frames eframe still runs after the scripted run asked to close are not logged.
        if !self.script.closing
            && let Err(e) = self.script.log(&line)
        {
            self.note(e, true);
        }
        if self.script.finished(self.frames) && !self.script.closing {
            self.script.closing = true;
            if let Some(p) = self.script.screenshot.clone() {
                let (w, h) = self.viewport_px;
                let req = self.shot_request(w.max(16), h.max(16), 1, self.settings.stereo);
                let r = crate::shot::render(self.live_scene.clone(), &cam, &req, &p, &|_| {});
                match r {
                    Ok(()) => eprintln!("fathom: wrote {}", p.display()),
                    Err(e) => {
                        eprintln!("fathom: screenshot failed: {e}");
                        self.script.failed = Some(e);
                    }
                }
            }
            self.allow_close = true;
            ctx.send_viewport_cmd(egui::ViewportCommand::Close);
        }
        // Keep drawing while something moves or renders; otherwise the worker wakes us.
        let moving = self.viewport.busy()
            || !self.viewport.settled(key)
            || ctx.input(|i| i.pointer.is_decidedly_dragging() || !i.keys_down.is_empty())
            || self.script.frames.is_some()
            || !self.shots.is_empty()
            || !self.scene.bindings.is_empty()
            || self.live.timeline.playing;
        if moving {
            ctx.request_repaint();
        } else if self.watch.is_some() {
            ctx.request_repaint_after(Duration::from_millis(500));
        }
    }

    /// Why the scripted run failed, if it did.
    pub fn script_error(&self) -> Option<&str> {
        self.script.failed.as_deref()
    }
}

/// What makes edits one undo step: the same description, within one press of the pointer or
/// one focus of the keyboard.
#[derive(Clone, Debug, PartialEq)]
struct Gesture {
    by: GestureBy,
    label: String,
}

#[derive(Clone, Debug, PartialEq)]
enum GestureBy {
    Press(u64),
    Focus(Option<egui::Id>),
}

/// What the unsaved-changes dialog was answered.
#[derive(Clone, Copy)]
enum QuitChoice {
    Save,
    Discard,
    Cancel,
}

/// The largest rectangle of `size`'s aspect ratio centred in `rect` (a stereo pair's eyes keep
/// their shape; the rest of the viewport stays dark).
fn fit(rect: egui::Rect, size: egui::Vec2) -> egui::Rect {
    if size.x <= 0.0 || size.y <= 0.0 || rect.width() <= 0.0 || rect.height() <= 0.0 {
        return rect;
    }
    let s = (rect.width() / size.x).min(rect.height() / size.y);
    egui::Rect::from_center_size(rect.center(), size * s)
}

/// A GPU renderer on the window's device.
fn gpu_renderer(rs: &egui_wgpu::RenderState) -> Result<fathom_gpu::Renderer, fathom_gpu::GpuError> {
    let info = rs.adapter.get_info();
    let gpu = fathom_gpu::Gpu::from_device(rs.device.clone(), rs.queue.clone(), info);
    fathom_gpu::Renderer::new(gpu)
}

impl eframe::App for ExplorerApp {
    fn ui(&mut self, ui: &mut egui::Ui, _frame: &mut eframe::Frame) {
        let ctx = ui.ctx().clone();
        if ctx.input(|i| i.viewport().close_requested()) && self.dirty() && !self.allow_close {
            ctx.send_viewport_cmd(egui::ViewportCommand::CancelClose);
            self.quit_dialog = true;
        }
        let now = Instant::now();
        let dt = now.duration_since(self.last_frame).as_secs_f64();
        self.ui_ms = dt * 1e3;
        self.frame_dt = dt;
        self.last_frame = now;
        self.poll_worker(&ctx);
        self.poll_files(&ctx);
        self.shortcuts(&ctx);
        let before = self.scene.clone();
        self.menu_bar(ui);
        self.status_bar(ui);
        if self.show_live && self.has_live() {
            self.live_panel(ui);
        }
        if self.show_panels {
            self.left_panel(ui);
            self.right_panel(ui);
        }
        self.central(ui, dt);
        self.dialogs(&ctx);
        self.commit(&ctx, before);
        self.apply_tree_actions();
        self.after_panels(&ctx);
    }

    fn on_exit(&mut self) {
        if let Some(e) = &self.script.failed
            && let Ok(mut g) = self.exit_error.lock()
        {
            *g = Some(e.clone());
        }
    }
}
