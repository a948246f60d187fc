//! Colouring: the material of a surface point from its node's [`PbrMaterial`], the orbit trap,
//! its position and its normal.
//!
//! A [`Look`] is one node's material plus an ordered list of [`Layer`]s; each layer reads one
//! scalar of the hit ([`Input`]), maps it through a [`Gradient`] of N stops and mixes the
//! result into one property ([`Target`]): base colour, roughness, metallic, or emission (added,
//! for glowing veins). Today's `trap_colour` is the layer "orbit trap through the scene's
//! cosine palette into the base colour, weight trap_colour", exactly what the Blinn-Phong
//! shader does, so fractal presets keep their colours.
//!
//! Everything is plain data and a few arithmetic functions, so the same tables can be
//! uploaded to a shader.

use crate::material::{MaterialError, PbrMaterial};
use glam::DVec3;

/// What a surface point offers to colour it by.
#[derive(Clone, Copy, Debug)]
pub struct HitInfo {
    /// World position.
    pub position: DVec3,
    /// Unit outward normal.
    pub normal: DVec3,
    /// Orbit trap (`Value::trap`): smallest |z| of the fractal's or IFS loop's iteration.
    pub trap: f64,
}

/// The scalar a layer reads.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Input {
    /// The orbit trap, clamped to [0, 4] as the Blinn-Phong shader does.
    Trap,
    /// World height (y).
    Height,
    /// Distance from the world origin.
    Radius,
    /// The normal's y component, -1 (facing down) to 1 (facing up).
    NormalUp,
}

/// The property a layer writes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Target {
    /// Mixed into the base colour.
    BaseColour,
    /// Mixed into the roughness (the gradient's luminance).
    Roughness,
    /// Mixed into metallic (the gradient's luminance).
    Metallic,
    /// Added to the emitted radiance (gradient colour x weight).
    Emission,
}

/// How a scalar becomes a colour.
#[derive(Clone, Debug, PartialEq)]
pub enum Gradient {
    /// Stops (position, linear RGB) with ascending positions; smoothstep between stops,
    /// constant outside.
    Stops(Vec<(f64, [f64; 3])>),
    /// Iñigo Quilez's cosine palette `a + b cos(2 pi (c t + d))` (rows a, b, c, d), clamped
    /// to [0, 1]: `RenderSettings::palette`.
    Cosine([[f64; 3]; 4]),
}

/// Why a colouring was refused.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum LookError {
    /// The node's material.
    #[error(transparent)]
    Material(#[from] MaterialError),
    /// A gradient without stops, with unsorted or non-finite positions, or colours outside
    /// [0, 1].
    #[error("layer {layer}: gradient stops must be finite, ascending, with colours in [0, 1]")]
    Stops {
        /// Index of the layer.
        layer: usize,
    },
    /// A layer's input range or weight is not finite, or the weight is negative.
    #[error("layer {layer}: input range and weight must be finite, weight >= 0")]
    Layer {
        /// Index of the layer.
        layer: usize,
    },
}

impl Gradient {
    /// The colour at `t`.
    pub fn at(&self, t: f64) -> DVec3 {
        match self {
            Gradient::Stops(stops) => {
                let Some(first) = stops.first() else {
                    return DVec3::ZERO;
                };
                if t <= first.0 {
                    return first.1.into();
                }
                for w in stops.windows(2) {
                    let ((t0, c0), (t1, c1)) = (w[0], w[1]);
                    if t <= t1 {
                        let x = if t1 > t0 { (t - t0) / (t1 - t0) } else { 1.0 };
                        let s = x * x * (3.0 - 2.0 * x);
                        return DVec3::from(c0).lerp(DVec3::from(c1), s);
                    }
                }
                stops[stops.len() - 1].1.into()
            }
            Gradient::Cosine(p) => {
                let [a, b, c, d] = p.map(DVec3::from);
                let x = (c * t + d) * std::f64::consts::TAU;
                (a + b * DVec3::new(x.x.cos(), x.y.cos(), x.z.cos())).clamp(DVec3::ZERO, DVec3::ONE)
            }
        }
    }

    fn valid(&self) -> bool {
        match self {
            Gradient::Stops(s) => {
                !s.is_empty()
                    && s.iter().all(|(t, c)| {
                        t.is_finite() && c.iter().all(|v| v.is_finite() && (0.0..=1.0).contains(v))
                    })
                    && s.windows(2).all(|w| w[0].0 <= w[1].0)
            }
            Gradient::Cosine(p) => p.iter().flatten().all(|v| v.is_finite()),
        }
    }
}

/// One colouring rule.
#[derive(Clone, Debug, PartialEq)]
pub struct Layer {
    /// What it reads.
    pub input: Input,
    /// The input values that map to gradient positions 0 and 1.
    pub range: [f64; 2],
    /// The colours.
    pub gradient: Gradient,
    /// What it writes.
    pub target: Target,
    /// Mix weight in [0, 1] for base colour, roughness and metallic; radiance scale for
    /// emission.
    pub weight: f64,
}

/// A node's appearance: its material and colouring layers, applied in order.
#[derive(Clone, Debug, PartialEq)]
pub struct Look {
    /// The material before colouring.
    pub material: PbrMaterial,
    /// Colouring rules.
    pub layers: Vec<Layer>,
}

impl Look {
    /// What today's material means: [`PbrMaterial::from_legacy`] plus, when `trap_colour` > 0,
    /// the orbit trap through `palette` into the base colour with that weight.
    pub fn from_legacy(m: &fathom_core::Material, palette: [[f64; 3]; 4]) -> Look {
        let mut layers = Vec::new();
        if m.trap_colour > 0.0 {
            layers.push(Layer {
                input: Input::Trap,
                range: [0.0, 1.0],
                gradient: Gradient::Cosine(palette),
                target: Target::BaseColour,
                weight: m.trap_colour.clamp(0.0, 1.0),
            });
        }
        Look {
            material: PbrMaterial::from_legacy(m),
            layers,
        }
    }

    /// Checks the material and every layer.
    pub fn validate(&self) -> Result<(), LookError> {
        self.material.validate()?;
        for (layer, l) in self.layers.iter().enumerate() {
            if !l.gradient.valid() {
                return Err(LookError::Stops { layer });
            }
            if !(l.range.iter().all(|v| v.is_finite()) && l.weight.is_finite() && l.weight >= 0.0) {
                return Err(LookError::Layer { layer });
            }
        }
        Ok(())
    }

    /// The material at a hit.
    pub fn at(&self, hit: &HitInfo) -> PbrMaterial {
        let mut m = self.material.clone();
        for l in &self.layers {
            let x = match l.input {
                Input::Trap => hit.trap.clamp(0.0, 4.0),
                Input::Height => hit.position.y,
                Input::Radius => hit.position.length(),
                Input::NormalUp => hit.normal.y,
            };
            let span = l.range[1] - l.range[0];
            let t = if span != 0.0 {
                (x - l.range[0]) / span
            } else {
                0.0
            };
            let c = l.gradient.at(t);
            let w = l.weight;
            let scalar = crate::sampling::luminance(c);
            match l.target {
                Target::BaseColour => {
                    let wc = w.min(1.0);
                    let b = DVec3::from(m.base_colour).lerp(c, wc);
                    m.base_colour = b.clamp(DVec3::ZERO, DVec3::ONE).into();
                }
                Target::Roughness => {
                    m.roughness =
                        (m.roughness + (scalar - m.roughness) * w.min(1.0)).clamp(0.0, 1.0)
                }
                Target::Metallic => {
                    m.metallic = (m.metallic + (scalar - m.metallic) * w.min(1.0)).clamp(0.0, 1.0)
                }
                Target::Emission => {
                    // Emission is colour x strength: fold the layer's radiance into both.
                    let e = m.emitted() + c * w;
                    let s = e.max_element();
                    if s > 0.0 {
                        m.emission = (e / s).into();
                        m.emission_strength = s;
                    }
                }
            }
        }
        m
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn hit(trap: f64, y: f64) -> HitInfo {
        HitInfo {
            position: DVec3::new(0.0, y, 0.0),
            normal: DVec3::Y,
            trap,
        }
    }

    #[test]
    fn stops_interpolate_smoothly_and_clamp_outside() {
        let g = Gradient::Stops(vec![
            (0.0, [0.0, 0.0, 0.0]),
            (0.5, [1.0, 0.0, 0.0]),
            (1.0, [1.0, 1.0, 1.0]),
        ]);
        assert_eq!(g.at(-1.0), DVec3::ZERO);
        assert_eq!(g.at(0.25), DVec3::new(0.5, 0.0, 0.0));
        assert_eq!(g.at(0.5), DVec3::X);
        assert_eq!(g.at(7.0), DVec3::ONE);
        // Smoothstep: flat at the stops.
        assert!(g.at(0.01).x < 0.01);
    }

    #[test]
    fn legacy_trap_colour_is_the_blinn_phong_palette_mix() {
        let palette = fathom_core::scene::RenderSettings::default().palette;
        let m = fathom_core::Material {
            albedo: [0.2, 0.2, 0.2],
            trap_colour: 0.6,
            ..Default::default()
        };
        let look = Look::from_legacy(&m, palette);
        look.validate().unwrap();
        let trap = 0.3;
        // What fathom-trace's shader computes for the same inputs.
        let want: [f64; 3] = std::array::from_fn(|c| {
            let x = std::f64::consts::TAU * (palette[2][c] * trap + palette[3][c]);
            let pc = (palette[0][c] + palette[1][c] * x.cos()).clamp(0.0, 1.0);
            0.2 + (pc - 0.2) * 0.6
        });
        let got = look.at(&hit(trap, 0.0)).base_colour;
        for c in 0..3 {
            assert!((got[c] - want[c]).abs() < 1e-12);
        }
        assert!(
            Look::from_legacy(&fathom_core::Material::default(), palette)
                .layers
                .is_empty()
        );
    }

    #[test]
    fn layers_drive_roughness_metallic_and_emission() {
        let look = Look {
            material: PbrMaterial::diffuse([0.5; 3]),
            layers: vec![
                Layer {
                    input: Input::Height,
                    range: [0.0, 1.0],
                    gradient: Gradient::Stops(vec![(0.0, [0.0; 3]), (1.0, [1.0; 3])]),
                    target: Target::Metallic,
                    weight: 1.0,
                },
                Layer {
                    input: Input::Trap,
                    range: [0.0, 0.1],
                    gradient: Gradient::Stops(vec![(0.0, [1.0, 0.5, 0.0]), (1.0, [0.0; 3])]),
                    target: Target::Emission,
                    weight: 20.0,
                },
            ],
        };
        look.validate().unwrap();
        let top = look.at(&hit(1.0, 1.0));
        assert!((top.metallic - 1.0).abs() < 1e-12 && top.emission_strength == 0.0);
        let vein = look.at(&hit(0.0, 0.0));
        assert!(vein.metallic.abs() < 1e-12);
        assert_eq!(vein.emitted(), DVec3::new(20.0, 10.0, 0.0));
        vein.validate().unwrap();
    }

    #[test]
    fn bad_layers_are_refused() {
        let mut look = Look::from_legacy(&fathom_core::Material::default(), [[0.5; 3]; 4]);
        look.layers.push(Layer {
            input: Input::Trap,
            range: [0.0, 1.0],
            gradient: Gradient::Stops(vec![(1.0, [0.0; 3]), (0.0, [1.0; 3])]),
            target: Target::BaseColour,
            weight: 1.0,
        });
        assert_eq!(look.validate(), Err(LookError::Stops { layer: 0 }));
        look.layers[0].gradient = Gradient::Stops(vec![(0.0, [0.0; 3])]);
        look.layers[0].weight = f64::NAN;
        assert_eq!(look.validate(), Err(LookError::Layer { layer: 0 }));
    }
}
