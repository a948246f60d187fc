//! The units rendered by a `fathom_render::Session`, exactly as the single-process commands
//! render them: a tile is the request with the tile as its region (bit-identical to the same
//! pixels of the whole image); frame `i` of a path takes the pose `fathom render --path` gives
//! it, with the scene's modulation replayed from frame 0 (smoothed bindings depend on the
//! frames before); frame `i` of a zoom is the preset's camera rendered as a settled still on
//! a fresh session (a stepped octree would depend on the frames before). Files are PNGs
//! encoded as `fathom render` encodes them.

use crate::error::FarmError;
use crate::manifest::FarmDir;
use crate::run::UnitRenderer;
use crate::work::{Part, Unit, Work};
use fathom_core::camera_path::{PathPreset, path_preset};
use fathom_core::flight::Flight;
use fathom_core::frame::Frame;
use fathom_core::scene::Scene;
use fathom_live::Modulator;
use fathom_render::flight::FlightRender;
use fathom_render::{RenderRequest, Session};

/// PNG bytes of a frame, tonemapped and encoded as `fathom render` writes its output.
pub fn encode_frame(frame: &Frame) -> Result<Vec<u8>, String> {
    encode_rgb8(
        frame.width,
        frame.height,
        &fathom_image::post::to_rgb8(frame),
    )
}

/// PNG bytes of an 8-bit RGB image (the encoder and settings of `fathom_image::output`).
pub fn encode_rgb8(width: u32, height: u32, rgb: &[u8]) -> Result<Vec<u8>, String> {
    use image::ImageEncoder;
    let mut out = Vec::new();
    image::codecs::png::PngEncoder::new(&mut out)
        .write_image(rgb, width, height, image::ExtendedColorType::Rgb8)
        .map_err(|e| e.to_string())?;
    Ok(out)
}

enum Mode {
    Tiles,
    Path(Box<PathState>),
    Zoom {
        preset: Box<PathPreset>,
        depth: f64,
        frames: usize,
    },
}

/// A path job's state: the prepared flight and the modulation so far.
struct PathState {
    flight: Flight,
    job: FlightRender,
    modulator: Modulator,
    /// The next frame whose modulation has not been applied.
    next: usize,
}

/// Renders a job's units with a session.
pub struct SessionRenderer {
    session: Session,
    base: Scene,
    request: RenderRequest,
    mode: Mode,
}

fn err(unit: &Unit, e: impl ToString) -> FarmError {
    FarmError::Render {
        unit: unit.index,
        file: unit.file.clone(),
        message: e.to_string(),
    }
}

fn setup(e: impl ToString) -> FarmError {
    FarmError::Render {
        unit: 0,
        file: "(setup)".into(),
        message: e.to_string(),
    }
}

impl SessionRenderer {
    /// The renderer of `farm`'s job, with `threads` worker threads (default: all cores).
    pub fn new(farm: &FarmDir, threads: Option<usize>) -> Result<SessionRenderer, FarmError> {
        let fp = &farm.manifest.fingerprint;
        let request = RenderRequest {
            threads,
            ..fp.request.clone()
        };
        let text = farm.scene_text()?;
        let base = fathom_core::scene_file::parse(&text, "scene.ron").map_err(setup)?;
        let session = Session::new(base.clone()).map_err(setup)?;
        let mode = match &fp.work {
            Work::Tiles { .. } => Mode::Tiles,
            Work::Path { path, frames } => {
                let p = base.path(path).map_err(setup)?;
                let flight = p
                    .prepare(&base, Some(session.tape()))
                    .map_err(|e| setup(format!("path `{path}`: {e}")))?;
                Mode::Path(Box::new(PathState {
                    flight,
                    job: FlightRender {
                        frames: *frames,
                        request: request.clone(),
                    },
                    modulator: Modulator::new(&base).map_err(setup)?,
                    next: 0,
                }))
            }
            Work::Zoom {
                preset,
                depth,
                frames,
            } => Mode::Zoom {
                preset: Box::new(path_preset(preset).map_err(setup)?),
                depth: *depth,
                frames: *frames,
            },
        };
        Ok(SessionRenderer {
            session,
            base,
            request,
            mode,
        })
    }
}

impl UnitRenderer for SessionRenderer {
    fn render(&mut self, unit: &Unit) -> Result<Vec<u8>, FarmError> {
        let frame = match (&mut self.mode, unit.part) {
            (Mode::Tiles, Part::Tile(rect)) => {
                let req = RenderRequest {
                    region: Some(rect),
                    ..self.request.clone()
                };
                let camera = self.base.camera.clone();
                self.session
                    .render(&camera, &req)
                    .map_err(|e| err(unit, e))?
                    .frame
            }
            (Mode::Path(p), Part::Frame(i)) => {
                let PathState {
                    flight,
                    job,
                    modulator,
                    next,
                } = &mut **p;
                if i < *next {
                    // Modulation only runs forwards (a rerun starts a new renderer).
                    *modulator = Modulator::new(&self.base).map_err(|e| err(unit, e))?;
                    *next = 0;
                }
                let duration = flight.duration();
                // Replay the skipped frames' modulation so smoothing sees every frame.
                for j in *next..i {
                    let t = job.time(j, duration);
                    let mut s = self.base.clone();
                    flight.apply(t, &mut s);
                    modulator.apply(&mut s, t);
                }
                let t = job.time(i, duration);
                let mut scene = self.base.clone();
                flight.apply(t, &mut scene);
                modulator.apply(&mut scene, t);
                *next = i + 1;
                let camera = scene.camera.clone();
                self.session.set_scene(scene).map_err(|e| err(unit, e))?;
                self.session
                    .render(&camera, &self.request)
                    .map_err(|e| err(unit, e))?
                    .frame
            }
            (
                Mode::Zoom {
                    preset,
                    depth,
                    frames,
                },
                Part::Frame(i),
            ) => {
                let mut req = self.request.clone();
                if preset.cube.is_some() {
                    req.octree.root = preset.cube;
                }
                let camera = preset.camera(i, *frames, *depth);
                let mut session = Session::new(preset.scene.clone()).map_err(|e| err(unit, e))?;
                session
                    .render(&camera, &req)
                    .map_err(|e| err(unit, e))?
                    .frame
            }
            _ => return Err(err(unit, "the unit does not belong to this kind of job")),
        };
        encode_frame(&frame).map_err(|e| err(unit, e))
    }
}
