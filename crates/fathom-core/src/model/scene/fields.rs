//! The scalar fields of a material, a light, the camera and the render settings, each declared
//! once with its range (the registry declares the shapes' and operators' parameters): scene
//! validation, parameter paths (modulation bindings, flight-path keys) and GUIs read the same
//! tables.

use super::{Light, Material, RenderSettings};
use crate::camera::Camera;
use crate::limits;

/// Where a field's numbers live in its structure.
pub enum Slot<'a> {
    /// Real numbers (one, or the components of a vector or colour).
    Reals(&'a mut [f64]),
    /// A whole number.
    Count(&'a mut u32),
}

/// One declared field of a settings structure `T`.
pub struct FieldSpec<T> {
    /// The field's name in scene files and parameter paths.
    pub name: &'static str,
    /// Number of components (1, 3 for vectors and colours, 12 for the palette).
    pub width: usize,
    /// The closed range every component must lie in; `None` when any finite value will do.
    pub range: Option<(f64, f64)>,
    /// Whether the field holds a whole number.
    pub int: bool,
    /// One line on what the field does, for the docs and tooltips.
    pub doc: &'static str,
    /// The field's storage in a value of `T`.
    pub slot: for<'a> fn(&'a mut T) -> Slot<'a>,
}

impl<T: Clone> FieldSpec<T> {
    /// The field's components in `value`.
    pub fn read(&self, value: &T) -> Vec<f64> {
        let mut copy = value.clone();
        match (self.slot)(&mut copy) {
            Slot::Reals(r) => r.to_vec(),
            Slot::Count(c) => vec![*c as f64],
        }
    }

    /// Whether `x` is an acceptable value of one component.
    pub fn accepts(&self, x: f64) -> bool {
        x.is_finite() && self.range.is_none_or(|(lo, hi)| (lo..=hi).contains(&x))
    }
}

/// Finds a field by name.
pub fn find<T>(table: &'static [FieldSpec<T>], name: &str) -> Option<&'static FieldSpec<T>> {
    table.iter().find(|f| f.name == name)
}

/// The fields of [`Material`].
pub static MATERIAL_FIELDS: &[FieldSpec<Material>] = &[
    FieldSpec {
        name: "albedo",
        width: 3,
        range: Some((0.0, 1.0)),
        int: false,
        doc: "diffuse colour, linear RGB",
        slot: |m| Slot::Reals(&mut m.albedo),
    },
    FieldSpec {
        name: "specular",
        width: 1,
        range: Some((0.0, 1.0)),
        int: false,
        doc: "specular strength",
        slot: |m| Slot::Reals(std::slice::from_mut(&mut m.specular)),
    },
    FieldSpec {
        name: "shininess",
        width: 1,
        range: Some((1.0, 4096.0)),
        int: false,
        doc: "Blinn-Phong exponent",
        slot: |m| Slot::Reals(std::slice::from_mut(&mut m.shininess)),
    },
    FieldSpec {
        name: "trap_colour",
        width: 1,
        range: Some((0.0, 1.0)),
        int: false,
        doc: "how much the orbit-trap palette replaces the albedo",
        slot: |m| Slot::Reals(std::slice::from_mut(&mut m.trap_colour)),
    },
    FieldSpec {
        name: "metallic",
        width: 1,
        range: Some((0.0, 1.0)),
        int: false,
        doc: "path tracer: 0 dielectric, 1 metal (the albedo is its reflectance)",
        slot: |m| Slot::Reals(std::slice::from_mut(&mut m.metallic)),
    },
    FieldSpec {
        name: "emission",
        width: 3,
        range: Some((0.0, 1.0)),
        int: false,
        doc: "path tracer: colour of emitted light, linear RGB",
        slot: |m| Slot::Reals(&mut m.emission),
    },
    FieldSpec {
        name: "emission_strength",
        width: 1,
        range: Some((0.0, 1e6)),
        int: false,
        doc: "path tracer: emitted radiance is emission x this (0: not a light)",
        slot: |m| Slot::Reals(std::slice::from_mut(&mut m.emission_strength)),
    },
    FieldSpec {
        name: "transmission",
        width: 1,
        range: Some((0.0, 1.0)),
        int: false,
        doc: "path tracer: 0 opaque, 1 glass refracting through the interior",
        slot: |m| Slot::Reals(std::slice::from_mut(&mut m.transmission)),
    },
    FieldSpec {
        name: "ior",
        width: 1,
        range: Some((1.0, 3.0)),
        int: false,
        doc: "path tracer: index of refraction of a transmissive material",
        slot: |m| Slot::Reals(std::slice::from_mut(&mut m.ior)),
    },
];

/// The fields of [`Light`] (its `shadows` switch is not a number).
pub static LIGHT_FIELDS: &[FieldSpec<Light>] = &[
    FieldSpec {
        name: "direction",
        width: 3,
        range: None,
        int: false,
        doc: "direction towards the light (finite, not zero)",
        slot: |l| Slot::Reals(l.direction.as_mut()),
    },
    FieldSpec {
        name: "colour",
        width: 3,
        range: Some((0.0, 1e3)),
        int: false,
        doc: "linear RGB colour",
        slot: |l| Slot::Reals(&mut l.colour),
    },
    FieldSpec {
        name: "intensity",
        width: 1,
        range: Some((0.0, 1e3)),
        int: false,
        doc: "brightness",
        slot: |l| Slot::Reals(std::slice::from_mut(&mut l.intensity)),
    },
];

/// The fields of [`Camera`]. The camera's own validation ([`Camera::validate`]) also refuses
/// an eye on its target and an up vector along the view.
pub static CAMERA_FIELDS: &[FieldSpec<Camera>] = &[
    FieldSpec {
        name: "eye",
        width: 3,
        range: None,
        int: false,
        doc: "camera position",
        slot: |c| Slot::Reals(c.eye.as_mut()),
    },
    FieldSpec {
        name: "target",
        width: 3,
        range: None,
        int: false,
        doc: "point looked at",
        slot: |c| Slot::Reals(c.target.as_mut()),
    },
    FieldSpec {
        name: "up",
        width: 3,
        range: None,
        int: false,
        doc: "up direction",
        slot: |c| Slot::Reals(c.up.as_mut()),
    },
    FieldSpec {
        name: "fov",
        width: 1,
        range: Some((0.01, 179.0)),
        int: false,
        doc: "vertical field of view, degrees",
        slot: |c| Slot::Reals(std::slice::from_mut(&mut c.fov)),
    },
];

/// The fields of [`RenderSettings`].
pub static RENDER_FIELDS: &[FieldSpec<RenderSettings>] = &[
    FieldSpec {
        name: "sky_top",
        width: 3,
        range: Some((0.0, 1e3)),
        int: false,
        doc: "sky colour straight up",
        slot: |r| Slot::Reals(&mut r.sky_top),
    },
    FieldSpec {
        name: "sky_bottom",
        width: 3,
        range: Some((0.0, 1e3)),
        int: false,
        doc: "sky colour at the horizon",
        slot: |r| Slot::Reals(&mut r.sky_bottom),
    },
    FieldSpec {
        name: "palette",
        width: 12,
        range: Some((-1e3, 1e3)),
        int: false,
        doc: "cosine palette rows a, b, c, d (component 3 r + c)",
        slot: |r| Slot::Reals(r.palette.as_flattened_mut()),
    },
    FieldSpec {
        name: "ambient",
        width: 1,
        range: Some((0.0, 1.0)),
        int: false,
        doc: "ambient light level",
        slot: |r| Slot::Reals(std::slice::from_mut(&mut r.ambient)),
    },
    FieldSpec {
        name: "ao",
        width: 1,
        range: Some((0.0, 4.0)),
        int: false,
        doc: "distance-field ambient occlusion strength",
        slot: |r| Slot::Reals(std::slice::from_mut(&mut r.ao)),
    },
    FieldSpec {
        name: "shadow_softness",
        width: 1,
        range: Some((1.0, 256.0)),
        int: false,
        doc: "penumbra sharpness",
        slot: |r| Slot::Reals(std::slice::from_mut(&mut r.shadow_softness)),
    },
    FieldSpec {
        name: "fog",
        width: 1,
        range: Some((0.0, 1e6)),
        int: false,
        doc: "fog density per unit",
        slot: |r| Slot::Reals(std::slice::from_mut(&mut r.fog)),
    },
    FieldSpec {
        name: "max_steps",
        width: 1,
        range: Some((1.0, limits::MAX_STEPS as f64)),
        int: true,
        doc: "sphere-tracing step limit",
        slot: |r| Slot::Count(&mut r.max_steps),
    },
    FieldSpec {
        name: "max_distance",
        width: 1,
        range: Some((1e-9, 1e12)),
        int: false,
        doc: "rays stop beyond this distance",
        slot: |r| Slot::Reals(std::slice::from_mut(&mut r.max_distance)),
    },
    FieldSpec {
        name: "pixel_epsilon",
        width: 1,
        range: Some((0.01, 16.0)),
        int: false,
        doc: "hit threshold in pixel footprints",
        slot: |r| Slot::Reals(std::slice::from_mut(&mut r.pixel_epsilon)),
    },
];
