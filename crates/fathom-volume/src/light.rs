//! What lights the volume: the environment (constant or a sky gradient) seen through every
//! escaping ray, one optional directional light (the sun), and optional emission from a colour
//! map on density.

use glam::Vec3;

/// Radiance arriving from infinitely far away, by direction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Environment {
    /// The same radiance from every direction.
    Constant(Vec3),
    /// `bottom` below the horizon's far side blending linearly to `top` straight up (along
    /// `up`, a unit vector), by the cosine to `up`.
    Sky { top: Vec3, bottom: Vec3, up: Vec3 },
}

impl Environment {
    /// Radiance from direction `d` (unit, pointing away from the scene).
    #[inline]
    pub fn radiance(&self, d: Vec3) -> Vec3 {
        match *self {
            Environment::Constant(c) => c,
            Environment::Sky { top, bottom, up } => {
                let t = 0.5 * (d.dot(up) + 1.0);
                bottom + (top - bottom) * t
            }
        }
    }

    /// True when no direction gives any light (next-event estimation toward it is skipped).
    pub fn is_black(&self) -> bool {
        match *self {
            Environment::Constant(c) => c == Vec3::ZERO,
            Environment::Sky { top, bottom, .. } => top == Vec3::ZERO && bottom == Vec3::ZERO,
        }
    }
}

/// A directional light: radiance `radiance` arriving from direction `towards` (unit, from the
/// scene to the light), as irradiance on a surface facing it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sun {
    pub towards: Vec3,
    pub radiance: Vec3,
}

/// Emission from the medium: radiance `strength * map(density / reference)`, emitted where the
/// medium absorbs (scaled by 1 - albedo, as the transport equation has it).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Emission {
    pub strength: f32,
    /// The density the top of the colour map stands for (usually the grid's maximum).
    pub reference: f32,
}

/// Stops of the colour map (a dark purple to orange to pale yellow ramp, like matplotlib's
/// "inferno"), evenly spaced over [0, 1].
const MAP: [[f32; 3]; 6] = [
    [0.0, 0.0, 0.016],
    [0.259, 0.039, 0.408],
    [0.576, 0.149, 0.404],
    [0.867, 0.32, 0.227],
    [0.988, 0.647, 0.039],
    [0.988, 1.0, 0.643],
];

/// The colour map at `t` (clamped to [0, 1]).
pub fn colour_map(t: f32) -> Vec3 {
    let x = t.clamp(0.0, 1.0) * (MAP.len() - 1) as f32;
    let i = (x as usize).min(MAP.len() - 2);
    let f = x - i as f32;
    Vec3::from(MAP[i]).lerp(Vec3::from(MAP[i + 1]), f)
}

impl Emission {
    /// Emitted radiance where the density is `density`.
    #[inline]
    pub fn radiance(&self, density: f32) -> Vec3 {
        colour_map(density / self.reference) * self.strength
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sky_blends_bottom_to_top_and_map_spans_dark_to_bright() {
        let e = Environment::Sky {
            top: Vec3::ONE,
            bottom: Vec3::ZERO,
            up: Vec3::Y,
        };
        assert_eq!(e.radiance(Vec3::Y), Vec3::ONE);
        assert_eq!(e.radiance(-Vec3::Y), Vec3::ZERO);
        assert_eq!(e.radiance(Vec3::X), Vec3::splat(0.5));
        assert!(colour_map(0.0).length() < 0.05 && colour_map(1.0).min_element() > 0.6);
        assert_eq!(colour_map(7.0), colour_map(1.0));
        assert!(Environment::Constant(Vec3::ZERO).is_black());
    }
}
