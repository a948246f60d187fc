//! The pinhole camera shared by every renderer: an f64 eye (deep zooms live in the last bits of
//! the position), a look-at target, an up vector and a vertical field of view.

use glam::DVec3;
use serde::{Deserialize, Serialize};

/// A look-at pinhole camera. Pixel (0, 0) is the top-left corner of the image.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Camera {
    pub eye: DVec3,
    pub target: DVec3,
    pub up: DVec3,
    /// Vertical field of view in degrees, (0, 179].
    pub fov: f64,
}

impl Default for Camera {
    fn default() -> Self {
        Camera {
            eye: DVec3::new(0.0, 1.0, 4.0),
            target: DVec3::ZERO,
            up: DVec3::Y,
            fov: 45.0,
        }
    }
}

/// The orthonormal frame of a camera: `forward` looks at the target, `right` x `up` is `-forward`.
#[derive(Clone, Copy, Debug)]
pub struct CameraFrame {
    pub eye: DVec3,
    pub forward: DVec3,
    pub right: DVec3,
    pub up: DVec3,
    /// tan(fov / 2).
    pub tan_half_fov: f64,
}

impl Camera {
    /// Checks that the camera can form an image.
    pub fn validate(&self) -> Result<(), String> {
        if !(self.eye.is_finite() && self.target.is_finite() && self.up.is_finite()) {
            return Err("camera: eye, target and up must be finite".into());
        }
        if !(self.fov > 0.0 && self.fov <= 179.0) {
            return Err(format!(
                "camera.fov = {} is out of range (0, 179] degrees",
                self.fov
            ));
        }
        let f = self.target - self.eye;
        if f.length_squared() == 0.0 {
            return Err("camera: eye and target coincide".into());
        }
        if f.cross(self.up).length_squared()
            <= 1e-24 * f.length_squared() * self.up.length_squared()
        {
            return Err("camera: up is parallel to the view direction (or zero)".into());
        }
        Ok(())
    }

    /// The camera's orthonormal frame. Assumes [`Camera::validate`] passed.
    pub fn frame(&self) -> CameraFrame {
        let forward = (self.target - self.eye).normalize();
        let right = forward.cross(self.up).normalize();
        let up = right.cross(forward);
        CameraFrame {
            eye: self.eye,
            forward,
            right,
            up,
            tan_half_fov: (self.fov.to_radians() * 0.5).tan(),
        }
    }
}

impl CameraFrame {
    /// Unit direction through image position (`px`, `py`) in pixels (pixel centres at +0.5)
    /// of a `width` x `height` image.
    #[inline]
    pub fn ray_dir(&self, px: f64, py: f64, width: u32, height: u32) -> DVec3 {
        let h = height as f64;
        let sx = (2.0 * px - width as f64) / h * self.tan_half_fov;
        let sy = (h - 2.0 * py) / h * self.tan_half_fov;
        (self.forward + self.right * sx + self.up * sy).normalize()
    }

    /// Angular size of one pixel at the image centre (radians, small-angle): a hit at distance
    /// `t` has a footprint of about `t * pixel_angle`.
    pub fn pixel_angle(&self, height: u32) -> f64 {
        2.0 * self.tan_half_fov / height as f64
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn centre_ray_looks_at_target() {
        let c = Camera::default();
        let f = c.frame();
        let d = f.ray_dir(50.0, 50.0, 100, 100);
        assert!((d - (c.target - c.eye).normalize()).length() < 1e-12);
        // Top of the image looks up, left looks left.
        assert!(f.ray_dir(50.0, 0.0, 100, 100).dot(f.up) > 0.0);
        assert!(f.ray_dir(0.0, 50.0, 100, 100).dot(f.right) < 0.0);
    }

    #[test]
    fn bad_cameras_are_refused() {
        let mut c = Camera {
            fov: 0.0,
            ..Camera::default()
        };
        assert!(c.validate().is_err());
        c.fov = 45.0;
        c.target = c.eye;
        assert!(c.validate().is_err());
        c.target = DVec3::ZERO;
        c.up = c.eye;
        assert!(c.validate().is_err());
        c.up = DVec3::Y;
        c.eye.x = f64::NAN;
        assert!(c.validate().is_err());
    }
}
