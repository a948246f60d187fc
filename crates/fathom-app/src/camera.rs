//! The window's camera: free flight (move, mouse look, roll) and orbit around a picked surface
//! point, with speeds scaled by the distance estimate at the eye, so a dive of 10^11 feels the
//! same at every depth (at distance `d` from the surface one second of full throttle covers
//! `d`). Input arrives as [`Controls`] (what the keys and mouse asked for this frame), so the
//! motion is testable without a window.
//!
//! The camera a renderer sees looks at a point `look_distance` ahead: about twice the distance
//! to the surface (so the tracer's deep-zoom switch to f64, which reads the footprint at the
//! target, engages by itself when f32 runs out, and ambient occlusion keeps the surface's
//! scale), never more than the scene's own view distance, and never less than 1e-9 of the
//! eye's distance from the origin (below that the look direction, rebuilt from the difference
//! of two f64 positions, would lose bits; deeper zooms are the octree's).

use fathom_core::eval::Evaluator;
use fathom_core::{Camera, Tape, V3};
use glam::{DQuat, DVec2, DVec3};

/// What the input asked for in one frame.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Controls {
    /// Throttle along the view direction, [-1, 1].
    pub forward: f64,
    /// Throttle to the right, [-1, 1].
    pub right: f64,
    /// Throttle up, [-1, 1].
    pub up: f64,
    /// Roll rate in [-1, 1] (positive turns the view clockwise).
    pub roll: f64,
    /// Mouse movement while looking or orbiting, in points.
    pub look: DVec2,
    /// Wheel notches (positive: in).
    pub wheel: f64,
    /// Field-of-view notches (positive: zoom in).
    pub fov: f64,
    /// Four times faster.
    pub boost: bool,
}

impl Controls {
    /// Whether anything was asked for.
    pub fn any(&self) -> bool {
        *self
            != Controls {
                boost: self.boost,
                ..Controls::default()
            }
    }
}

/// How the mouse moves the camera.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Mode {
    /// Mouse look turns the camera in place.
    Fly,
    /// Mouse drags turn the camera around the pivot; the wheel moves towards it.
    Orbit {
        /// The point orbited, world units.
        pivot: DVec3,
    },
}

/// Radians per point of mouse movement.
pub const LOOK_RATE: f64 = 0.004;
/// Radians per second of roll at full rate.
pub const ROLL_RATE: f64 = 1.2;
/// Fraction of the distance to the surface covered per second at full throttle.
pub const FLY_RATE: f64 = 1.0;

/// The camera and its mode.
#[derive(Clone, Debug, PartialEq)]
pub struct CameraController {
    /// Where the camera is, world units.
    pub eye: DVec3,
    /// Rotation from camera space (looking down -Z, up +Y) to the world.
    pub rotation: DQuat,
    /// Vertical field of view, degrees.
    pub fov: f64,
    /// Fly or orbit.
    pub mode: Mode,
    /// Distance to the point looked at.
    pub look_distance: f64,
    /// The scene's own view distance, the largest look distance.
    max_look: f64,
}

impl CameraController {
    /// A controller starting at `cam` (which must validate).
    pub fn new(cam: &Camera) -> CameraController {
        let f = cam.frame();
        // Columns: right, up, back (-forward).
        let m = glam::DMat3::from_cols(f.right, f.up, -f.forward);
        let look = (cam.target - cam.eye).length();
        CameraController {
            eye: cam.eye,
            rotation: DQuat::from_mat3(&m).normalize(),
            fov: cam.fov,
            mode: Mode::Fly,
            look_distance: look,
            max_look: look,
        }
    }

    /// The unit view direction.
    pub fn forward(&self) -> DVec3 {
        self.rotation * DVec3::NEG_Z
    }

    /// The unit up direction of the view.
    pub fn up(&self) -> DVec3 {
        self.rotation * DVec3::Y
    }

    /// The unit right direction of the view.
    pub fn right(&self) -> DVec3 {
        self.rotation * DVec3::X
    }

    /// The camera renderers use.
    pub fn camera(&self) -> Camera {
        Camera {
            eye: self.eye,
            target: self.eye + self.forward() * self.look_distance,
            up: self.up(),
            fov: self.fov,
        }
    }

    /// Orbit around `pivot` from now on.
    pub fn orbit_around(&mut self, pivot: DVec3) {
        self.mode = Mode::Orbit { pivot };
        let d = (pivot - self.eye).length();
        if d > 0.0 {
            // Turn to face the pivot, keeping the up direction as far as possible.
            let fwd = (pivot - self.eye) / d;
            let right = fwd.cross(self.up()).normalize_or(self.right());
            let up = right.cross(fwd);
            self.rotation = DQuat::from_mat3(&glam::DMat3::from_cols(right, up, -fwd)).normalize();
            self.look_distance = d;
        }
    }

    /// Moves the camera for one frame of `dt` seconds; `d_eye` is the distance bound at the
    /// eye (its scale sets the speeds). Returns whether the camera changed.
    pub fn step(&mut self, c: &Controls, dt: f64, d_eye: f64) -> bool {
        if !c.any() {
            return false;
        }
        let before = self.clone();
        let dt = dt.clamp(0.0, 0.25);
        let scale = if d_eye.is_finite() && d_eye > 0.0 {
            d_eye
        } else {
            1e-9 * self.eye.length().max(1.0)
        };
        let speed = FLY_RATE * scale * if c.boost { 4.0 } else { 1.0 };
        let (yaw, pitch) = (-c.look.x * LOOK_RATE, -c.look.y * LOOK_RATE);
        match self.mode {
            Mode::Fly => {
                self.rotation =
                    (self.rotation * DQuat::from_rotation_y(yaw) * DQuat::from_rotation_x(pitch))
                        .normalize();
                // A wheel notch moves a tenth of the way to the surface.
                let forward = c.forward * speed * dt + 0.1 * c.wheel * scale;
                self.eye += self.forward() * forward
                    + self.right() * (c.right * speed * dt)
                    + self.up() * (c.up * speed * dt);
            }
            Mode::Orbit { pivot } => {
                // Turn the eye and the view together about the pivot.
                let turn = DQuat::from_axis_angle(self.up(), yaw)
                    * DQuat::from_axis_angle(self.right(), pitch);
                let offset = turn * (self.eye - pivot);
                self.rotation = (turn * self.rotation).normalize();
                let dist = offset.length() * 0.9f64.powf(c.wheel);
                self.eye = pivot + offset.normalize_or(-self.forward()) * dist;
                self.eye += self.forward() * (c.forward * speed * dt)
                    + self.right() * (c.right * speed * dt)
                    + self.up() * (c.up * speed * dt);
            }
        }
        if c.roll != 0.0 {
            self.rotation =
                (self.rotation * DQuat::from_rotation_z(-c.roll * ROLL_RATE * dt)).normalize();
        }
        if c.fov != 0.0 {
            self.fov = (self.fov * 0.9f64.powf(c.fov)).clamp(1.0, 150.0);
        }
        self.update_look(d_eye);
        *self != before
    }

    /// Sets the look distance from the distance bound at the eye (see the module doc).
    pub fn update_look(&mut self, d_eye: f64) {
        let floor = 1e-9 * self.eye.length().max(1.0);
        self.look_distance = match self.mode {
            Mode::Orbit { pivot } => (pivot - self.eye).length().max(floor),
            Mode::Fly if d_eye.is_finite() && d_eye > 0.0 => {
                (2.0 * d_eye).clamp(floor, self.max_look.max(floor))
            }
            Mode::Fly => self.look_distance,
        };
    }
}

/// The distance bound of `tape` at `p` (f64).
pub fn distance_at(tape: &Tape, p: DVec3) -> f64 {
    Evaluator::<f64>::new().distance(tape, V3::new(p.x, p.y, p.z))
}

/// The first surface point along the ray from `eye` in unit direction `dir`, by sphere tracing
/// in f64 with a hit threshold of `eps` times the distance travelled, or `None` within
/// `max_t` and 1000 steps.
pub fn pick(tape: &Tape, eye: DVec3, dir: DVec3, eps: f64, max_t: f64) -> Option<DVec3> {
    let mut ev = Evaluator::<f64>::new();
    let mut t = 0.0;
    for _ in 0..1000 {
        let p = eye + dir * t;
        let d = ev.distance(tape, V3::new(p.x, p.y, p.z));
        if !d.is_finite() {
            return None;
        }
        if d < eps * t.max(1e-300) {
            return Some(p);
        }
        t += d;
        if t > max_t {
            return None;
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cam() -> Camera {
        Camera {
            eye: DVec3::new(0.0, 0.0, 5.0),
            target: DVec3::ZERO,
            up: DVec3::Y,
            fov: 45.0,
        }
    }

    #[test]
    fn the_controller_reproduces_the_camera_it_starts_from() {
        let c = CameraController::new(&cam());
        let out = c.camera();
        assert!((out.eye - cam().eye).length() < 1e-12);
        assert!((out.target - cam().target).length() < 1e-9);
        assert!((out.up - DVec3::Y).length() < 1e-12);
        let tilted = Camera {
            eye: DVec3::new(4.3, 3.05, 5.5),
            target: DVec3::new(0.0, -0.2, 0.0),
            ..cam()
        };
        let out = CameraController::new(&tilted).camera();
        assert!(
            (out.target - tilted.target).length() < 1e-9,
            "{:?}",
            out.target
        );
        out.validate().unwrap();
    }

    #[test]
    fn flying_speed_follows_the_distance_to_the_surface_at_every_depth() {
        // One second of full throttle covers the distance bound, whatever its size: a dive
        // past 1e-9 feels like one at 1.
        for d in [1.0, 1e-3, 1e-9] {
            let mut c = CameraController::new(&cam());
            let moved = c.step(
                &Controls {
                    forward: 1.0,
                    ..Controls::default()
                },
                0.1,
                d,
            );
            assert!(moved);
            let travelled = 5.0 - c.eye.z;
            assert!(
                (travelled / (0.1 * d) - 1.0).abs() < 1e-6,
                "{d}: {travelled}"
            );
            // The look point follows the surface's scale.
            assert!(
                (c.look_distance - 2.0 * d).abs() <= 1e-9 * 5.0 + 1e-15,
                "{}",
                c.look_distance
            );
        }
        // No input, no change.
        let mut c = CameraController::new(&cam());
        assert!(!c.step(&Controls::default(), 0.1, 1.0));
    }

    #[test]
    fn looking_rolling_and_orbiting_keep_a_valid_camera() {
        let mut c = CameraController::new(&cam());
        c.step(
            &Controls {
                look: DVec2::new(100.0, -40.0),
                roll: 1.0,
                ..Controls::default()
            },
            0.1,
            1.0,
        );
        c.camera().validate().unwrap();
        assert!(c.forward().z > -1.0 + 1e-3, "the view turned");
        // Orbit around the origin: the distance to the pivot stays, the view faces it.
        let mut c = CameraController::new(&cam());
        c.orbit_around(DVec3::ZERO);
        c.step(
            &Controls {
                look: DVec2::new(300.0, 0.0),
                ..Controls::default()
            },
            0.1,
            1.0,
        );
        assert!((c.eye.length() - 5.0).abs() < 1e-9, "{}", c.eye.length());
        assert!(c.forward().dot(-c.eye.normalize()) > 1.0 - 1e-9);
        assert!(c.eye.x.abs() > 1.0, "it went round: {:?}", c.eye);
        // The wheel moves towards the pivot.
        c.step(
            &Controls {
                wheel: 2.0,
                ..Controls::default()
            },
            0.1,
            1.0,
        );
        assert!((c.eye.length() - 5.0 * 0.81).abs() < 1e-9);
    }

    /// A click on the surface orbits it and makes it the camera's target, which is where the
    /// path tracer focuses when its focus distance is left to the camera; the wheel moves
    /// towards it and the focus follows.
    #[test]
    fn the_point_clicked_becomes_the_target_and_the_focus() {
        let mut c = CameraController::new(&cam());
        let p = DVec3::new(0.3, -0.2, 0.4);
        c.orbit_around(p);
        let focus = |c: &CameraController| {
            let cam = c.camera();
            (cam.target - cam.eye).length()
        };
        assert!((c.camera().target - p).length() < 1e-9);
        let before = focus(&c);
        c.step(
            &Controls {
                wheel: 1.0,
                ..Controls::default()
            },
            1.0 / 60.0,
            1.0,
        );
        let after = focus(&c);
        assert!(
            after < before,
            "the wheel moved towards the pivot: {before} -> {after}"
        );
        assert!((c.camera().target - p).length() < 1e-6 * before);
    }

    #[test]
    fn picking_finds_the_surface_of_a_sphere() {
        let tape = Tape::compile(&fathom_core::scenes::sphere(1.0)).unwrap();
        let p = pick(&tape, DVec3::new(0.0, 0.0, 5.0), DVec3::NEG_Z, 1e-6, 100.0).unwrap();
        assert!((p.z - 1.0).abs() < 1e-5, "{p:?}");
        assert!(pick(&tape, DVec3::new(0.0, 3.0, 5.0), DVec3::NEG_Z, 1e-6, 100.0).is_none());
        assert!((distance_at(&tape, DVec3::new(0.0, 0.0, 3.0)) - 2.0).abs() < 1e-12);
    }
}
