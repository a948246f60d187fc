//! [`Session`]: the scene, its compiled tape and every backend's long-lived state (worker
//! threads, the GPU renderer and device, the octree explorer), behind one `render` call.
//!
//! - [`Session::set_scene`] takes an edited scene and decides what it costs: nothing (the same
//!   scene), nothing for the tape (only the scene's camera, lights or render settings moved),
//!   a parameter-buffer update (same structure, new values: no compilation, and on the GPU a
//!   buffer write), or a recompile (new structure). It says which it did, and counts.
//! - [`Session::render`] draws a frame from any camera: the camera is an argument, not part of
//!   the scene, so a window flies without editing the scene. Post effects run in
//!   `fathom_trace::post::finish_view` for every backend; stereo views are finished eye by
//!   eye; a region comes back as just its pixels.

use crate::backend::gpu::GpuBackend;
use crate::backend::octree::OctreeBackend;
use crate::backend::path::PathBackend;
use crate::backend::volume::VolumeBackend;
use crate::backend::{Counters, Rendered};
use crate::control::Control;
use crate::error::RenderError;
use crate::request::{Backend, RenderRequest};
use crate::stats::Stats;
use fathom_core::frame::Frame;
use fathom_core::scene::Scene;
use fathom_core::tape::CompileError;
use fathom_core::{Camera, Tape};
use fathom_svo::FrameStats;
use serde::Serialize;
use std::borrow::Cow;
use std::time::Instant;

/// What [`Session::set_scene`] had to do.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum SceneChange {
    /// The scene is the one the session has.
    Unchanged,
    /// Only the scene's own camera differs (renders take their camera as an argument).
    Camera,
    /// Lights or render settings changed; the tape is untouched.
    Settings,
    /// Parameters or materials changed: the parameter buffer was re-baked, nothing compiled.
    Params,
    /// The structure changed: the tape was compiled anew.
    Recompiled,
}

/// The scene, its tape and the backends' state. See the module documentation.
pub struct Session {
    scene: Scene,
    tape: Tape,
    /// Bumps whenever the tape changes (parameters or structure).
    tape_generation: u64,
    /// Bumps whenever anything an octree is built from changes (tape, lights, settings).
    shading_generation: u64,
    counters: Counters,
    pool: Option<(usize, rayon::ThreadPool)>,
    gpu: Option<GpuBackend>,
    octree: Option<OctreeBackend>,
    volume: Option<VolumeBackend>,
    path: Option<PathBackend>,
}

impl Session {
    /// A session of `scene`: validates and compiles it.
    pub fn new(scene: Scene) -> Result<Session, RenderError> {
        scene.validate()?;
        let tape = Tape::compile(&scene)?;
        Ok(Session {
            scene,
            tape,
            tape_generation: 0,
            shading_generation: 0,
            counters: Counters {
                compiles: 1,
                ..Counters::default()
            },
            pool: None,
            gpu: None,
            octree: None,
            volume: None,
            path: None,
        })
    }

    /// The current scene.
    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    /// The current compiled tape.
    pub fn tape(&self) -> &Tape {
        &self.tape
    }

    /// Compilations and updates so far.
    pub fn counters(&self) -> Counters {
        self.counters
    }

    /// Replaces the scene, doing as little as the edit allows (see [`SceneChange`]). A scene
    /// that does not validate or compile is refused and the session keeps the one it had.
    pub fn set_scene(&mut self, scene: Scene) -> Result<SceneChange, RenderError> {
        if scene == self.scene {
            return Ok(SceneChange::Unchanged);
        }
        let old = &self.scene;
        // Each branch validates the scene once (the tape's update and compile validate it).
        let change = if scene.root == old.root && scene.ifs == old.ifs {
            scene.validate()?;
            if scene.lights == old.lights && scene.render == old.render {
                SceneChange::Camera
            } else {
                SceneChange::Settings
            }
        } else {
            match self.tape.update_params(&scene) {
                Ok(()) => {
                    self.counters.param_updates += 1;
                    SceneChange::Params
                }
                Err(CompileError::StructureChanged) => {
                    self.tape = Tape::compile(&scene)?;
                    self.counters.compiles += 1;
                    SceneChange::Recompiled
                }
                Err(CompileError::Invalid(e)) => return Err(e.into()),
                Err(e) => return Err(e.into()),
            }
        };
        if matches!(change, SceneChange::Params | SceneChange::Recompiled) {
            self.tape_generation += 1;
        }
        if change != SceneChange::Camera {
            self.shading_generation += 1;
        }
        self.scene = scene;
        Ok(change)
    }

    /// Gives the session a GPU renderer to use for [`Backend::Gpu`] (a window passes one on
    /// the device it presents with). Without one, the first GPU request opens a headless
    /// device.
    pub fn set_gpu(&mut self, renderer: fathom_gpu::Renderer) {
        self.gpu = Some(GpuBackend::new(renderer));
    }

    /// Takes the GPU renderer out of the session (to hand the device to another session).
    pub fn take_gpu(&mut self) -> Option<fathom_gpu::Renderer> {
        self.gpu.take().map(GpuBackend::into_renderer)
    }

    /// The GPU renderer, if one is open.
    pub fn gpu(&self) -> Option<&fathom_gpu::Renderer> {
        self.gpu.as_ref().map(GpuBackend::renderer)
    }

    /// Renders a frame (or the request's region of it) from `camera`.
    pub fn render(
        &mut self,
        camera: &Camera,
        req: &RenderRequest,
    ) -> Result<Rendered, RenderError> {
        self.render_with(camera, req, &Control::default())
    }

    /// [`Session::render`] with cancellation and progress. A cancelled frame returns
    /// [`RenderError::Cancelled`] and leaves the session as it was.
    pub fn render_with(
        &mut self,
        camera: &Camera,
        req: &RenderRequest,
        control: &Control,
    ) -> Result<Rendered, RenderError> {
        let start = Instant::now();
        req.validate()?;
        camera.validate()?;
        let scene = scene_for(&self.scene, req);
        let mut out = match req.backend {
            Backend::Trace => {
                let pool = pool(&mut self.pool, req.threads)?;
                trace(&self.tape, &scene, camera, req, control, pool)?
            }
            Backend::Gpu => {
                if self.gpu.is_none() {
                    self.gpu = Some(GpuBackend::new(fathom_gpu::Renderer::headless()?));
                }
                let gpu = self.gpu.as_mut().expect("opened above");
                match gpu.render(
                    &scene,
                    &self.tape,
                    self.tape_generation,
                    camera,
                    req,
                    control,
                    &mut self.counters,
                ) {
                    Err(fathom_gpu::GpuError::Cancelled) => return Err(RenderError::Cancelled),
                    Err(fathom_gpu::GpuError::TooDeep { .. }) => {
                        let pool = pool(&mut self.pool, req.threads)?;
                        let mut r = trace(&self.tape, &scene, camera, req, control, pool)?;
                        r.stats.note = Some(
                            "the view is zoomed past f32 precision; rendered on the CPU (f64)"
                                .into(),
                        );
                        r
                    }
                    // A tape or an image this device cannot hold: the CPU tracer has no such
                    // limits, so the frame is rendered there and the note says why.
                    Err(
                        e @ (fathom_gpu::GpuError::BufferTooLarge { .. }
                        | fathom_gpu::GpuError::ImageTooLarge { .. }),
                    ) => {
                        let pool = pool(&mut self.pool, req.threads)?;
                        let mut r = trace(&self.tape, &scene, camera, req, control, pool)?;
                        r.stats.note = Some(format!(
                            "this scene does not fit the GPU's limits ({e}); rendered on the CPU"
                        ));
                        r
                    }
                    r => r?,
                }
            }
            Backend::Octree => {
                let key = self.shading_generation;
                let ob =
                    OctreeBackend::get(&mut self.octree, &scene, key, req, &mut self.counters)?;
                ob.render(&scene, camera, req, control)?
            }
            Backend::Volume => {
                let key = self.shading_generation;
                let vb = VolumeBackend::get(
                    &mut self.volume,
                    &scene,
                    &self.tape,
                    key,
                    req,
                    &mut self.counters,
                )?;
                let pool = pool(&mut self.pool, req.threads)?;
                vb.render(camera, req, control, pool)?
            }
            Backend::Path if req.path.gpu => {
                if self.gpu.is_none() {
                    self.gpu = Some(GpuBackend::new(fathom_gpu::Renderer::headless()?));
                }
                PathBackend::render_gpu(
                    &mut self.path,
                    self.gpu.as_mut().expect("opened above"),
                    &scene,
                    &self.tape,
                    self.tape_generation,
                    self.shading_generation,
                    camera,
                    req,
                    control,
                    &mut self.counters,
                )?
            }
            Backend::Path => {
                let key = self.shading_generation;
                let pb = PathBackend::get(
                    &mut self.path,
                    &scene,
                    &self.tape,
                    key,
                    camera,
                    req,
                    &mut self.counters,
                )?;
                let pool = pool(&mut self.pool, req.threads)?;
                pb.render(req, control, pool)?
            }
        };
        out.stats.ms.total = start.elapsed().as_secs_f64() * 1e3;
        Ok(out)
    }

    /// Renders with the GPU and leaves the image on the device (no readback): the returned
    /// texture (8-bit sRGB, the output size) is what a window samples to present. Fog is
    /// applied in the shader; SSAO and supersampling need the frame on the CPU and are not
    /// applied. Views past f32 precision are refused with [`fathom_gpu::GpuError::TooDeep`]
    /// (render them with [`Session::render`], which falls back to the CPU).
    pub fn render_to_texture(
        &mut self,
        camera: &Camera,
        req: &RenderRequest,
    ) -> Result<&wgpu::Texture, RenderError> {
        req.validate()?;
        camera.validate()?;
        if self.gpu.is_none() {
            self.gpu = Some(GpuBackend::new(fathom_gpu::Renderer::headless()?));
        }
        let scene = scene_for(&self.scene, req);
        let gpu = self.gpu.as_mut().expect("opened above");
        Ok(gpu.render_to_texture(
            &scene,
            &self.tape,
            self.tape_generation,
            camera,
            req,
            &mut self.counters,
        )?)
    }

    /// One frame of exploration with the octree: render the tree as it is, then subdivide
    /// within the request's time budget (and unify every few frames). Returns the finished
    /// frame when `want_frame` (post effects cost time a benchmark does not want) and the
    /// octree's frame statistics. A cancel in `control` stops the subdivision at its next
    /// batch (the frame itself is rendered whole).
    pub fn step_octree(
        &mut self,
        camera: &Camera,
        req: &RenderRequest,
        want_frame: bool,
        still: bool,
        control: &Control,
    ) -> Result<(Option<Frame>, FrameStats), RenderError> {
        let deep = fathom_svo::DeepEye::of(camera);
        let (scene, ob) = self.octree_at(camera, &deep, req)?;
        Ok(ob.step(&scene, camera, &deep, req, want_frame, still, control))
    }

    /// [`Session::step_octree`] for a zoom past f64: the eye is `camera.eye + deep.eye_lo` (a
    /// double-double position), the view's scale `deep.scale` (see `fathom_svo::DeepEye`).
    pub fn step_octree_deep(
        &mut self,
        camera: &Camera,
        deep: &fathom_svo::DeepEye,
        req: &RenderRequest,
        want_frame: bool,
        control: &Control,
    ) -> Result<(Option<Frame>, FrameStats), RenderError> {
        let (scene, ob) = self.octree_at(camera, deep, req)?;
        Ok(ob.step(&scene, camera, deep, req, want_frame, false, control))
    }

    /// Builds the octree for `req` if needed and settles it at the deep camera for at most
    /// `budget_ms` (`fathom_svo::OctreeView::settle_deep`); returns the frames taken.
    pub fn warm_octree(
        &mut self,
        camera: &Camera,
        deep: &fathom_svo::DeepEye,
        req: &RenderRequest,
        budget_ms: f64,
    ) -> Result<usize, RenderError> {
        let (_, ob) = self.octree_at(camera, deep, req)?;
        Ok(ob.view.settle_deep(camera, deep, usize::MAX, budget_ms))
    }

    /// Checks the request, camera and deep eye, and returns the scene with the request's
    /// overrides and the octree for them (built when either changed).
    fn octree_at(
        &mut self,
        camera: &Camera,
        deep: &fathom_svo::DeepEye,
        req: &RenderRequest,
    ) -> Result<(Cow<'_, Scene>, &mut OctreeBackend), RenderError> {
        req.validate()?;
        camera.validate()?;
        let lo = deep.eye_lo;
        if !(lo.is_finite() && deep.scale.is_finite() && deep.scale > 0.0) {
            return Err(RenderError::DeepEye {
                x: lo.x,
                y: lo.y,
                z: lo.z,
                scale: deep.scale,
            });
        }
        let scene = scene_for(&self.scene, req);
        let key = self.shading_generation;
        let ob = OctreeBackend::get(&mut self.octree, &scene, key, req, &mut self.counters)?;
        Ok((scene, ob))
    }

    /// The octree explorer, if one is built.
    pub fn octree(&self) -> Option<&fathom_svo::OctreeView> {
        self.octree.as_ref().map(|o| &o.view)
    }
}

/// The scene with the request's overrides applied (borrowed when there are none).
fn scene_for<'a>(scene: &'a Scene, req: &RenderRequest) -> Cow<'a, Scene> {
    match req.fog {
        Some(f) if f != scene.render.fog => {
            let mut s = scene.clone();
            s.render.fog = f;
            Cow::Owned(s)
        }
        _ => Cow::Borrowed(scene),
    }
}

/// The worker pool for `threads` (the global pool when `None`), built once per count.
fn pool(
    slot: &mut Option<(usize, rayon::ThreadPool)>,
    threads: Option<usize>,
) -> Result<Option<&rayon::ThreadPool>, RenderError> {
    let Some(n) = threads else {
        return Ok(None);
    };
    if slot.as_ref().is_none_or(|(k, _)| *k != n) {
        let p = rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build()
            .map_err(|e| RenderError::Threads {
                threads: n,
                message: e.to_string(),
            })?;
        *slot = Some((n, p));
    }
    Ok(slot.as_ref().map(|(_, p)| p))
}

/// The CPU tracer's frame, on `pool` (or the global pool).
fn trace(
    tape: &Tape,
    scene: &Scene,
    camera: &Camera,
    req: &RenderRequest,
    control: &Control,
    pool: Option<&rayon::ThreadPool>,
) -> Result<Rendered, RenderError> {
    let opts = req.trace_options();
    let progress = |done: usize, total: usize| control.report(done, total);
    let hooks = fathom_trace::Hooks {
        cancel: control.cancel.map(|c| c.flag()),
        progress: &progress,
    };
    let run = || fathom_trace::render_tape(tape, scene, camera, &opts, req.region, hooks);
    let (frame, s) = match pool {
        Some(p) => p.install(run),
        None => run(),
    }?;
    Ok(Rendered {
        frame,
        stats: Stats::from_trace(&s),
    })
}
