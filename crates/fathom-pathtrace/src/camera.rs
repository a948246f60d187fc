//! A thin-lens camera on top of [`fathom_core::Camera`]: the same frame, field of view and
//! pixel convention as every other renderer, plus an aperture and a focus distance for depth
//! of field (pbrt-v4's `PerspectiveCamera` lens model).
//!
//! The pinhole ray through a pixel meets the plane of focus (perpendicular to the view
//! direction, `focus` away from the eye) at a point; the thin-lens ray leaves a point of the
//! lens disk and goes through that same point, so everything on the plane of focus stays
//! sharp and a point at distance z is blurred into a circle of confusion of diameter
//! `2 aperture |z - focus| / z` on the focus plane (the test checks this).

use fathom_core::CameraFrame;
use glam::DVec3;
use std::f64::consts::FRAC_PI_4;

/// A thin-lens camera.
#[derive(Clone, Copy, Debug)]
pub struct ThinLens {
    /// The camera's frame.
    pub frame: CameraFrame,
    /// Lens radius in world units (0: pinhole).
    pub aperture: f64,
    /// Distance from the eye to the plane of focus along the view direction, > 0.
    pub focus: f64,
}

impl ThinLens {
    /// A ray through image position (`px`, `py`) (pixel centres at +0.5) of a `w` x `h` image,
    /// through lens position `u` in [0, 1)^2: (origin, unit direction).
    pub fn ray(&self, px: f64, py: f64, w: u32, h: u32, u: [f64; 2]) -> (DVec3, DVec3) {
        let d = self.frame.ray_dir(px, py, w, h);
        if self.aperture <= 0.0 {
            return (self.frame.eye, d);
        }
        let focus_point = self.frame.eye + d * (self.focus / d.dot(self.frame.forward));
        let [lx, ly] = concentric_disk(u);
        let origin = self.frame.eye + (self.frame.right * lx + self.frame.up * ly) * self.aperture;
        (origin, (focus_point - origin).normalize())
    }
}

/// Shirley and Chiu's concentric map of the unit square onto the unit disk (area-preserving,
/// low distortion, so stratified lens samples stay stratified).
pub fn concentric_disk(u: [f64; 2]) -> [f64; 2] {
    let a = 2.0 * u[0] - 1.0;
    let b = 2.0 * u[1] - 1.0;
    if a == 0.0 && b == 0.0 {
        return [0.0, 0.0];
    }
    let (r, theta) = if a.abs() > b.abs() {
        (a, FRAC_PI_4 * (b / a))
    } else {
        (b, 2.0 * FRAC_PI_4 - FRAC_PI_4 * (a / b))
    };
    [r * theta.cos(), r * theta.sin()]
}

#[cfg(test)]
mod tests {
    use super::*;
    use fathom_core::Camera;

    fn lens(aperture: f64, focus: f64) -> ThinLens {
        let cam = Camera {
            eye: DVec3::new(0.0, 0.0, 5.0),
            target: DVec3::ZERO,
            up: DVec3::Y,
            fov: 40.0,
        };
        ThinLens {
            frame: cam.frame(),
            aperture,
            focus,
        }
    }

    /// Where a ray meets the plane z = `z`.
    fn at_plane(o: DVec3, d: DVec3, z: f64) -> DVec3 {
        o + d * ((z - o.z) / d.z)
    }

    #[test]
    fn the_focus_plane_is_sharp() {
        let l = lens(0.2, 5.0);
        for (px, py) in [(50.5, 40.5), (3.5, 90.5)] {
            let pin = at_plane(l.frame.eye, l.frame.ray_dir(px, py, 128, 96), 0.0);
            for k in 0..64 {
                let u = [(k % 8) as f64 / 8.0 + 0.06, (k / 8) as f64 / 8.0 + 0.03];
                let (o, d) = l.ray(px, py, 128, 96, u);
                assert!((at_plane(o, d, 0.0) - pin).length() < 1e-12);
            }
        }
    }

    #[test]
    fn blur_matches_the_circle_of_confusion() {
        // A point 3 units from the eye (z = 2) while focused at 5: the rays through one pixel
        // centre spread, at the point's depth, over a disk; mapped back to the focus plane
        // (scale focus / z) it is the circle of confusion 2 A |z - focus| / z.
        let (aperture, focus) = (0.15, 5.0);
        let l = lens(aperture, focus);
        let zdist = 3.0;
        let plane = 5.0 - zdist;
        let centre = at_plane(l.frame.eye, l.frame.ray_dir(64.0, 48.0, 128, 96), plane);
        let mut max_r: f64 = 0.0;
        for k in 0..4096 {
            let u = [
                (k % 64) as f64 / 64.0 + 0.007,
                (k / 64) as f64 / 64.0 + 0.003,
            ];
            let (o, d) = l.ray(64.0, 48.0, 128, 96, u);
            max_r = max_r.max((at_plane(o, d, plane) - centre).length());
        }
        let diameter_on_focus_plane = 2.0 * max_r * focus / zdist;
        let coc = 2.0 * aperture * (zdist - focus).abs() / zdist;
        assert!(
            (diameter_on_focus_plane - coc).abs() < 0.02 * coc,
            "blur {diameter_on_focus_plane} vs circle of confusion {coc}"
        );
        // Pinhole: no blur.
        let p = lens(0.0, focus);
        let (o, d) = p.ray(64.0, 48.0, 128, 96, [0.9, 0.1]);
        assert!((at_plane(o, d, plane) - centre).length() < 1e-12);
    }

    #[test]
    fn concentric_map_stays_in_the_disk_and_covers_it() {
        let mut area = 0;
        let n = 100;
        for i in 0..n {
            for j in 0..n {
                let [x, y] =
                    concentric_disk([(i as f64 + 0.5) / n as f64, (j as f64 + 0.5) / n as f64]);
                assert!(x * x + y * y <= 1.0 + 1e-12);
                if x * x + y * y < 0.25 {
                    area += 1;
                }
            }
        }
        // Area-preserving: a quarter of the samples fall inside radius 1/2.
        assert!((area as f64 / (n * n) as f64 - 0.25).abs() < 0.01);
    }
}
