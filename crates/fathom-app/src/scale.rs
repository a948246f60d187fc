//! The dynamic render scale: while the camera or a parameter moves, each frame is rendered at
//! a fraction of the viewport's resolution chosen to hold a target frame time. A frame's cost
//! grows with its pixel count, the square of the scale, so the next scale is the last one times
//! the square root of (target / measured), damped in log space against timing noise and never
//! grown by more than half per frame (a cheap frame of empty sky must not make the next one,
//! full of fractal, take seconds).

/// The scale controller.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderScale {
    target_ms: f64,
    scale: f64,
    min: f64,
    max: f64,
}

/// Smallest scale (a 1280-pixel viewport never drops below 96 pixels across).
pub const MIN_SCALE: f64 = 0.075;

impl RenderScale {
    /// A controller holding frames to `target_ms`, starting at half resolution.
    pub fn new(target_ms: f64) -> RenderScale {
        RenderScale {
            target_ms: target_ms.clamp(1.0, 1000.0),
            scale: 0.5,
            min: MIN_SCALE,
            max: 1.0,
        }
    }

    /// The frame-time target in ms.
    pub fn target_ms(&self) -> f64 {
        self.target_ms
    }

    /// Changes the target (clamped to [1, 1000] ms).
    pub fn set_target_ms(&mut self, ms: f64) {
        if ms.is_finite() {
            self.target_ms = ms.clamp(1.0, 1000.0);
        }
    }

    /// The scale for the next interactive frame.
    pub fn scale(&self) -> f64 {
        self.scale
    }

    /// Feeds the time (`ms`) a frame rendered at scale `used` took; returns the next scale.
    pub fn update(&mut self, used: f64, ms: f64) -> f64 {
        if !(ms.is_finite() && ms > 0.0 && used.is_finite() && used > 0.0) {
            return self.scale;
        }
        let ideal = used * (self.target_ms / ms).sqrt();
        let damped = (0.5 * self.scale.ln() + 0.5 * ideal.ln()).exp();
        self.scale = damped.min(self.scale * 1.5).clamp(self.min, self.max);
        self.scale
    }

    /// The pixel size of a frame at `scale` of a `w` x `h` viewport (at least 8 x 8).
    pub fn size(w: u32, h: u32, scale: f64) -> (u32, u32) {
        let s = |v: u32| ((v as f64 * scale).round() as u32).clamp(8.min(v.max(1)), v.max(1));
        (s(w), s(h))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_scale_settles_where_frames_take_the_target_time() {
        // A renderer whose frame time is proportional to its pixel count: 120 ms at full size.
        let cost = |s: f64| 120.0 * s * s;
        let mut r = RenderScale::new(33.0);
        let mut s = r.scale();
        for _ in 0..40 {
            s = r.update(s, cost(s));
        }
        assert!(
            (cost(s) - 33.0).abs() < 1.0,
            "settled at {s}: {} ms",
            cost(s)
        );
        // A cheap scene lets it climb to full resolution, but not in one jump.
        let mut r = RenderScale::new(33.0);
        let s1 = r.update(0.5, 1.0);
        assert!(s1 <= 0.75 + 1e-12, "{s1}");
        for _ in 0..20 {
            r.update(r.scale(), 1.0);
        }
        assert_eq!(r.scale(), 1.0);
        // Garbage timings change nothing; the floor holds.
        assert_eq!(r.update(1.0, f64::NAN), 1.0);
        for _ in 0..50 {
            r.update(r.scale(), 1e6);
        }
        assert_eq!(r.scale(), MIN_SCALE);
        assert_eq!(RenderScale::size(1280, 720, 0.5), (640, 360));
        assert_eq!(RenderScale::size(1280, 720, 0.001), (8, 8));
        assert_eq!(RenderScale::size(4, 4, 0.1), (4, 4));
    }
}
