//! A flight path rendered frame by frame: the loop of `fathom render --path` and
//! `fathom bench live`. Frame `i` of `n` is the path's pose at `i / (n - 1)` of its duration:
//! the scene takes the pose (camera and the keys' parameter values), then the caller's
//! modulation (LFO bindings at the frame's time), then the session takes the scene (parameters
//! re-baked, never recompiled: the structure does not change along a path) and renders it.

use crate::backend::Rendered;
use crate::control::Control;
use crate::error::RenderError;
use crate::request::RenderRequest;
use crate::session::{SceneChange, Session};
use fathom_core::flight::{Flight, Pose};
use fathom_core::scene::Scene;
use serde::Serialize;
use std::time::Instant;

/// Most frames one path render may have.
pub const MAX_FRAMES: usize = 1_000_000;

/// A path render to run.
#[derive(Clone, Debug)]
pub struct FlightRender {
    /// Frames, [1, 1e6]; the first at the path's start, the last at its end.
    pub frames: usize,
    /// What each frame renders; each frame looks through the path's camera at its time.
    pub request: RenderRequest,
}

/// Why a path render stopped.
#[derive(Debug, thiserror::Error)]
pub enum FlightRenderError {
    /// The frame count (given) is outside [1, [`MAX_FRAMES`]].
    #[error("--frames {0} is out of range 1..={MAX_FRAMES}")]
    Frames(usize),
    /// A frame failed to render.
    #[error(transparent)]
    Render(#[from] RenderError),
    /// The frame callback failed (writing a frame, say).
    #[error("{0}")]
    Output(String),
}

/// One finished frame, as the callback sees it.
pub struct FlightFrame<'a> {
    /// The frame's index, from 0.
    pub index: usize,
    /// Seconds from the path's start.
    pub time: f64,
    /// The path's state at this frame's time.
    pub pose: &'a Pose,
    /// The frame and its stats.
    pub rendered: &'a Rendered,
    /// What the session had to do for this frame's scene.
    pub change: SceneChange,
}

/// What a path render did.
#[derive(Clone, Debug, Default, Serialize)]
pub struct FlightReport {
    /// Frames rendered.
    pub frames: usize,
    /// Wall time per frame (scene update and render), ms.
    pub frame_ms: Vec<f64>,
    /// Frames whose scene needed a parameter-buffer update.
    pub param_updates: usize,
    /// Frames whose scene needed a recompile.
    pub recompiles: usize,
}

/// The time of frame `i` of `frames` spread over a path of `duration` seconds: the first at
/// its start, the last at its end.
pub fn frame_time(i: usize, frames: usize, duration: f64) -> f64 {
    if frames > 1 {
        duration * i as f64 / (frames - 1) as f64
    } else {
        0.0
    }
}

impl FlightRender {
    /// Checks the frame count and the request.
    pub fn validate(&self) -> Result<(), FlightRenderError> {
        if self.frames == 0 || self.frames > MAX_FRAMES {
            return Err(FlightRenderError::Frames(self.frames));
        }
        self.request.validate().map_err(RenderError::from)?;
        Ok(())
    }

    /// The time of frame `i` on a path of `duration` seconds.
    pub fn time(&self, i: usize, duration: f64) -> f64 {
        frame_time(i, self.frames, duration)
    }

    /// Renders every frame of `flight` over `base` (the scene the path belongs to), calling
    /// `modulate(scene, t)` on each frame's scene before the session takes it and
    /// `on_frame` with each finished frame. `control` applies to every frame (its progress is
    /// per frame's tiles; the caller counts frames).
    pub fn run(
        &self,
        session: &mut Session,
        base: &Scene,
        flight: &Flight,
        modulate: &mut dyn FnMut(&mut Scene, f64),
        control: &Control,
        on_frame: &mut dyn FnMut(FlightFrame<'_>) -> Result<(), String>,
    ) -> Result<FlightReport, FlightRenderError> {
        self.validate()?;
        let mut report = FlightReport {
            frames: self.frames,
            ..FlightReport::default()
        };
        for i in 0..self.frames {
            let start = Instant::now();
            let time = self.time(i, flight.duration());
            let mut scene = base.clone();
            let pose = flight.apply(time, &mut scene);
            modulate(&mut scene, time);
            let camera = scene.camera.clone();
            let change = session.set_scene(scene)?;
            match change {
                SceneChange::Params => report.param_updates += 1,
                SceneChange::Recompiled => report.recompiles += 1,
                _ => {}
            }
            let rendered = session.render_with(&camera, &self.request, control)?;
            report.frame_ms.push(start.elapsed().as_secs_f64() * 1e3);
            on_frame(FlightFrame {
                index: i,
                time,
                pose: &pose,
                rendered: &rendered,
                change,
            })
            .map_err(FlightRenderError::Output)?;
        }
        Ok(report)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use fathom_core::flight::{FlightPath, Keyframe};
    use glam::DVec3;

    fn scene_with_path() -> Scene {
        let mut s = fathom_core::presets::load("mandelbulb").unwrap();
        let mut a = Keyframe::from_camera(&s.camera);
        let mut b = Keyframe::from_camera(&fathom_core::Camera {
            eye: DVec3::new(1.4, 0.9, -1.2),
            ..s.camera.clone()
        });
        a.params.insert("root.shape.power".into(), 8.0);
        b.params.insert("root.shape.power".into(), 6.0);
        b.fov = 50.0;
        s.paths.push(FlightPath::new("orbit", 2.0, vec![a, b]));
        s.validate_animation().unwrap();
        s
    }

    fn render(threads: usize) -> (Vec<Vec<[f32; 3]>>, FlightReport) {
        let scene = scene_with_path();
        let flight = scene.paths[0].prepare(&scene, None).unwrap();
        let mut session = Session::new(scene.clone()).unwrap();
        let job = FlightRender {
            frames: 4,
            request: RenderRequest {
                width: 40,
                height: 30,
                threads: Some(threads),
                ..RenderRequest::default()
            },
        };
        let mut frames = Vec::new();
        let report = job
            .run(
                &mut session,
                &scene,
                &flight,
                &mut |_, _| {},
                &Control::default(),
                &mut |f| {
                    assert_eq!(f.index, frames.len());
                    frames.push(f.rendered.frame.colour.clone());
                    Ok(())
                },
            )
            .unwrap();
        (frames, report)
    }

    #[test]
    fn a_path_rendered_to_a_sequence_gives_the_same_frames_with_1_and_2_threads() {
        let (one, report) = render(1);
        let (two, _) = render(2);
        assert_eq!(one.len(), 4);
        assert_eq!(one, two);
        // The frames differ from each other (the camera and the power move), and the keys'
        // parameter values re-bake the parameter buffer without recompiling.
        assert_ne!(one[0], one[3]);
        assert_eq!(report.recompiles, 0);
        assert_eq!(report.param_updates, 3);
    }

    #[test]
    fn bad_frame_counts_and_failing_outputs_stop_the_run() {
        let scene = scene_with_path();
        let flight = scene.paths[0].prepare(&scene, None).unwrap();
        let mut session = Session::new(scene.clone()).unwrap();
        let mut job = FlightRender {
            frames: 0,
            request: RenderRequest {
                width: 8,
                height: 8,
                threads: Some(1),
                ..RenderRequest::default()
            },
        };
        let mut none = |_: &mut Scene, _: f64| {};
        let e = job
            .run(
                &mut session,
                &scene,
                &flight,
                &mut none,
                &Control::default(),
                &mut |_| Ok(()),
            )
            .unwrap_err();
        assert!(e.to_string().contains("--frames 0"), "{e}");
        job.frames = 3;
        let e = job
            .run(
                &mut session,
                &scene,
                &flight,
                &mut none,
                &Control::default(),
                &mut |f| {
                    if f.index == 1 {
                        Err("disk full".into())
                    } else {
                        Ok(())
                    }
                },
            )
            .unwrap_err();
        assert_eq!(e.to_string(), "disk full");
    }
}
