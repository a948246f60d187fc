//! The pinhole camera shared by every renderer: an f64 eye (deep zooms live in the last bits of
//! the position), a look-at target, an up vector and a vertical field of view; and the
//! [`Projection`]s (mono, side-by-side stereo, omni-directional stereo) whose ray generation
//! every renderer uses, defined here once in f64 (the WGSL of fathom-gpu mirrors it).

use glam::DVec3;
use serde::{Deserialize, Serialize};

/// A look-at pinhole camera. Pixel (0, 0) is the top-left corner of the image.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Camera {
    /// Where the camera is, world units.
    pub eye: DVec3,
    /// The point looked at; the centre of the image.
    pub target: DVec3,
    /// Which way is up in the image (need not be orthogonal to the view direction).
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

/// Why a camera cannot form an image.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum CameraError {
    /// The eye, the target or the up vector has a NaN or infinite component.
    #[error("camera: eye, target and up must be finite")]
    NotFinite,
    /// The field of view is outside (0, 179] degrees.
    #[error("camera.fov = {fov} is out of range (0, 179] degrees")]
    Fov {
        /// The field of view given, degrees.
        fov: f64,
    },
    /// The eye and the target are the same point, so there is no view direction.
    #[error("camera: eye and target coincide")]
    Coincide,
    /// The up vector is zero or parallel to the view direction, so there is no right axis.
    #[error("camera: up is parallel to the view direction (or zero)")]
    UpParallel,
    /// A coordinate so large that the view direction's length overflows f64.
    #[error(
        "camera: {what} = ({x:e}, {y:e}, {z:e}) is too large: coordinates are limited to \
         {MAX_COORDINATE:e} (the view direction's length would overflow)"
    )]
    TooLarge {
        /// Which vector: `eye`, `target` or `up`.
        what: &'static str,
        /// Its x component.
        x: f64,
        /// Its y component.
        y: f64,
        /// Its z component.
        z: f64,
    },
}

/// Largest magnitude of a camera coordinate (eye, target, up): the squared length of a
/// difference of two such points is still finite.
pub const MAX_COORDINATE: f64 = 1e150;

/// Why a projection cannot be used.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ProjectionError {
    /// The eye separation is negative, not finite or above [`MAX_EYE_SEPARATION`].
    #[error("eye separation = {value} is out of range [0, {MAX_EYE_SEPARATION}] (scene units)")]
    EyeSeparation {
        /// The separation given, scene units.
        value: f64,
    },
}

/// The orthonormal frame of a camera: `forward` looks at the target, `right` x `up` is `-forward`.
#[derive(Clone, Copy, Debug)]
pub struct CameraFrame {
    /// Where the rays start, world units.
    pub eye: DVec3,
    /// Unit vector from the eye towards the target.
    pub forward: DVec3,
    /// Unit vector to the image's right.
    pub right: DVec3,
    /// Unit vector to the image's top, orthogonal to `forward` and `right`.
    pub up: DVec3,
    /// tan(fov / 2).
    pub tan_half_fov: f64,
}

impl Camera {
    /// Checks that the camera can form an image.
    pub fn validate(&self) -> Result<(), CameraError> {
        if !(self.eye.is_finite() && self.target.is_finite() && self.up.is_finite()) {
            return Err(CameraError::NotFinite);
        }
        if !(self.fov > 0.0 && self.fov <= 179.0) {
            return Err(CameraError::Fov { fov: self.fov });
        }
        for (what, v) in [("eye", self.eye), ("target", self.target), ("up", self.up)] {
            if v.abs().max_element() > MAX_COORDINATE {
                return Err(CameraError::TooLarge {
                    what,
                    x: v.x,
                    y: v.y,
                    z: v.z,
                });
            }
        }
        let f = self.target - self.eye;
        if f.length_squared() == 0.0 {
            return Err(CameraError::Coincide);
        }
        if f.cross(self.up).length_squared()
            <= 1e-24 * f.length_squared() * self.up.length_squared()
        {
            return Err(CameraError::UpParallel);
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

/// How the rays leave the camera: one view, or a stereo pair laid out in one image.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum Projection {
    /// One pinhole view.
    #[default]
    Mono,
    /// Two parallel pinhole views side by side (output twice as wide), eyes `eye_separation`
    /// apart along the camera's right axis, left eye on the left.
    SideBySide {
        /// Distance between the eyes, scene units, [0, 1e6].
        eye_separation: f64,
    },
    /// Omni-directional stereo, equirectangular (longitude -180..180 degrees across, latitude
    /// 90..-90 down), left eye on top (output twice as tall). Each ray leaves from the point of
    /// the viewing circle of diameter `eye_separation` (in the camera's horizontal plane) where
    /// it is tangent to that circle; each eye's view should be 2:1.
    Ods {
        /// Diameter of the viewing circle, scene units, [0, 1e6].
        eye_separation: f64,
    },
}

/// The largest eye separation accepted, in scene units.
pub const MAX_EYE_SEPARATION: f64 = 1e6;

impl Projection {
    /// Checks the eye separation.
    pub fn validate(self) -> Result<(), ProjectionError> {
        let sep = self.separation();
        if !(sep.is_finite() && (0.0..=MAX_EYE_SEPARATION).contains(&sep)) {
            return Err(ProjectionError::EyeSeparation { value: sep });
        }
        Ok(())
    }

    /// The distance between the eyes (0 for mono).
    pub fn separation(self) -> f64 {
        match self {
            Projection::Mono => 0.0,
            Projection::SideBySide { eye_separation } | Projection::Ods { eye_separation } => {
                eye_separation
            }
        }
    }

    /// Whether screen-space post effects (SSAO) apply to each eye's view: not for ODS, whose
    /// view wraps around at the seam and stretches towards the poles.
    pub fn screen_space(self) -> bool {
        !matches!(self, Projection::Ods { .. })
    }

    /// Number of views: 1 or 2.
    pub fn eyes(self) -> u32 {
        if self == Projection::Mono { 1 } else { 2 }
    }

    /// Output size for a per-eye view of `w` x `h`. Saturates at `u32::MAX` instead of
    /// wrapping, so a huge requested size still fails the callers' size limits.
    pub fn output_size(self, w: u32, h: u32) -> (u32, u32) {
        match self {
            Projection::Mono => (w, h),
            Projection::SideBySide { .. } => (w.saturating_mul(2), h),
            Projection::Ods { .. } => (w, h.saturating_mul(2)),
        }
    }

    /// Where eye `eye`'s pixel (`x`, `y`) of a `w` x `h` view sits in the output image.
    pub fn output_pixel(self, eye: u32, x: u32, y: u32, w: u32, h: u32) -> (u32, u32) {
        match self {
            Projection::Mono => (x, y),
            Projection::SideBySide { .. } => (eye * w + x, y),
            Projection::Ods { .. } => (x, eye * h + y),
        }
    }

    /// The camera frame the rays are built from. A panorama is levelled: latitude 0 is the
    /// plane normal to the camera's up vector, longitude 0 the view direction projected onto
    /// it. Assumes [`Camera::validate`] passed.
    pub fn frame(self, camera: &Camera) -> CameraFrame {
        let mut f = camera.frame();
        if let Projection::Ods { .. } = self {
            let up = camera.up.normalize();
            let fwd = (f.forward - up * f.forward.dot(up)).normalize();
            f.right = fwd.cross(up);
            f.up = up;
            f.forward = fwd;
        }
        f
    }

    /// Angular size of the largest pixel of a `w` x `h` view (radians): a hit at distance
    /// `t` has a footprint of about `t * pixel_angle`. For ODS a pixel spans `2 pi / w` of
    /// longitude at the equator and `pi / h` of latitude.
    pub fn pixel_angle(self, frame: &CameraFrame, w: u32, h: u32) -> f64 {
        match self {
            Projection::Ods { .. } => {
                (std::f64::consts::PI / h as f64).max(std::f64::consts::TAU / w as f64)
            }
            _ => frame.pixel_angle(h),
        }
    }

    /// Radius at distance 0 of a cone that covers the rays of a `block` x `block` pixel block
    /// of a `w`-wide view: the spread of the rays' origins (0 unless the origin moves with the
    /// pixel, as in ODS, where it moves `eye_separation / 2` per radian of longitude).
    pub fn cone_base(self, block: u32, w: u32) -> f64 {
        match self {
            Projection::Ods { eye_separation } => {
                0.5 * eye_separation * block as f64 * std::f64::consts::TAU / w as f64
            }
            _ => 0.0,
        }
    }

    /// The fixed origin offset of eye `eye` (relative to the camera position), or `None` when
    /// the origin moves with the pixel (ODS).
    pub fn eye_offset(self, frame: &CameraFrame, eye: u32) -> Option<DVec3> {
        match self {
            Projection::Mono => Some(DVec3::ZERO),
            Projection::SideBySide { eye_separation } => {
                Some(frame.right * (side(eye) * 0.5 * eye_separation))
            }
            Projection::Ods { .. } => None,
        }
    }

    /// The ray of eye `eye` (0 = left) through per-eye position (`px`, `py`) in pixels (pixel
    /// centres at +0.5) of a `w` x `h` view: (origin relative to the camera position, unit
    /// direction).
    #[inline]
    pub fn ray(
        self,
        frame: &CameraFrame,
        eye: u32,
        px: f64,
        py: f64,
        w: u32,
        h: u32,
    ) -> (DVec3, DVec3) {
        use std::f64::consts::PI;
        match self {
            Projection::Mono => (DVec3::ZERO, frame.ray_dir(px, py, w, h)),
            Projection::SideBySide { .. } => (
                self.eye_offset(frame, eye).unwrap_or_default(),
                frame.ray_dir(px, py, w, h),
            ),
            Projection::Ods { eye_separation } => {
                let lon = px / w as f64 * 2.0 * PI - PI;
                let lat = 0.5 * PI - py / h as f64 * PI;
                let (sl, cl) = lon.sin_cos();
                let (sa, ca) = lat.sin_cos();
                let dir = frame.right * (sl * ca) + frame.up * sa + frame.forward * (cl * ca);
                let off =
                    (frame.right * cl - frame.forward * sl) * (side(eye) * 0.5 * eye_separation);
                (off, dir)
            }
        }
    }
}

/// -1 for the left eye (0), +1 for the right.
fn side(eye: u32) -> f64 {
    if eye == 0 { -1.0 } else { 1.0 }
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
    fn huge_coordinates_are_blamed_not_the_up_vector() {
        let c = Camera {
            eye: DVec3::new(1e308, 0.0, 0.0),
            ..Camera::default()
        };
        let e = c.validate().unwrap_err().to_string();
        assert!(e.contains("eye = (1e308") && e.contains("1e150"), "{e}");
        let c = Camera {
            eye: DVec3::new(1e150, 0.0, 0.0),
            ..Camera::default()
        };
        c.validate().unwrap();
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

    /// The two eyes' rays towards a point `dist` straight ahead, by bisection on the longitude
    /// of the equator row: the angle between their longitudes.
    fn ods_disparity(sep: f64, dist: f64) -> f64 {
        let c = Camera::default();
        let p = Projection::Ods {
            eye_separation: sep,
        };
        let f = p.frame(&c);
        let target = f.eye + f.forward * dist;
        let (w, h) = (4096u32, 2048u32);
        let lon_of = |eye: u32| {
            // The signed miss of the ray at column px, as a function of px: zero where the ray
            // passes through the target.
            let miss = |px: f64| {
                let (off, dir) = p.ray(&f, eye, px, h as f64 / 2.0, w, h);
                let to = target - (f.eye + off);
                to.cross(dir).dot(f.up)
            };
            let (mut a, mut b) = (w as f64 * 0.25, w as f64 * 0.75);
            assert!(miss(a) * miss(b) < 0.0);
            for _ in 0..100 {
                let m = 0.5 * (a + b);
                if miss(a) * miss(m) <= 0.0 {
                    b = m;
                } else {
                    a = m;
                }
            }
            (0.5 * (a + b)) / w as f64 * std::f64::consts::TAU - std::f64::consts::PI
        };
        lon_of(0) - lon_of(1)
    }

    #[test]
    fn ods_disparity_of_a_point_ahead_is_twice_asin_of_half_sep_over_distance() {
        for (sep, dist) in [(0.065, 1.0), (0.065, 0.2), (0.5, 3.0), (1.0, 0.75)] {
            let got = ods_disparity(sep, dist);
            let want = 2.0 * (sep / (2.0 * dist)).asin();
            assert!(
                (got - want).abs() < 1e-9,
                "sep {sep} dist {dist}: disparity {got}, expected {want}"
            );
        }
    }

    #[test]
    fn ods_rays_are_tangent_to_the_viewing_circle_and_cover_the_sphere() {
        let c = Camera {
            up: DVec3::new(0.1, 1.0, 0.0),
            ..Camera::default()
        };
        let p = Projection::Ods {
            eye_separation: 0.3,
        };
        let f = p.frame(&c);
        let (w, h) = (64u32, 32u32);
        for eye in 0..2 {
            for y in 0..h {
                for x in 0..w {
                    let (off, dir) = p.ray(&f, eye, x as f64 + 0.5, y as f64 + 0.5, w, h);
                    assert!((dir.length() - 1.0).abs() < 1e-12);
                    assert!((off.length() - 0.15).abs() < 1e-12);
                    assert!(
                        off.dot(f.up).abs() < 1e-12,
                        "origin in the horizontal plane"
                    );
                    assert!(off.dot(dir).abs() < 1e-12, "tangent");
                }
            }
        }
        // The centre column looks forward, the top row up, the left edge backwards; the two
        // edges of the image meet (same ray at longitude -180 and 180).
        let (_, d) = p.ray(&f, 0, w as f64 / 2.0, h as f64 / 2.0, w, h);
        assert!((d - f.forward).length() < 1e-12);
        let (_, d) = p.ray(&f, 0, 3.0, 0.0, w, h);
        assert!((d - f.up).length() < 1e-12);
        let a = p.ray(&f, 1, 0.0, 7.0, w, h);
        let b = p.ray(&f, 1, w as f64, 7.0, w, h);
        assert!((a.0 - b.0).length() < 1e-12 && (a.1 - b.1).length() < 1e-12);
        // The left eye sits to the left when looking forward.
        let (off, _) = p.ray(&f, 0, w as f64 / 2.0, h as f64 / 2.0, w, h);
        assert!(off.dot(f.right) < 0.0);
    }

    #[test]
    fn side_by_side_rays_are_mono_rays_from_shifted_eyes() {
        let c = Camera::default();
        let sbs = Projection::SideBySide {
            eye_separation: 0.2,
        };
        let f = sbs.frame(&c);
        for eye in 0..2 {
            let (off, dir) = sbs.ray(&f, eye, 3.5, 7.5, 16, 12);
            assert_eq!(dir, f.ray_dir(3.5, 7.5, 16, 12));
            assert_eq!(Some(off), sbs.eye_offset(&f, eye));
            let want = if eye == 0 { -0.1 } else { 0.1 };
            assert!((off - f.right * want).length() < 1e-15);
        }
        assert_eq!(sbs.output_size(16, 12), (32, 12));
        assert_eq!(sbs.output_pixel(1, 3, 4, 16, 12), (19, 4));
        let ods = Projection::Ods {
            eye_separation: 0.2,
        };
        assert_eq!(ods.output_size(16, 8), (16, 16));
        assert_eq!(ods.output_pixel(1, 3, 4, 16, 8), (3, 12));
    }

    #[test]
    fn bad_separations_are_refused() {
        for sep in [-0.1, f64::NAN, f64::INFINITY, 2e6] {
            let e = Projection::Ods {
                eye_separation: sep,
            }
            .validate()
            .unwrap_err();
            assert!(e.to_string().contains("eye separation"), "{e}");
            assert!(matches!(e, ProjectionError::EyeSeparation { .. }));
        }
        assert!(Projection::Mono.validate().is_ok());
    }
}
