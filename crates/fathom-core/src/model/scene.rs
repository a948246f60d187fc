//! The scene model: a tree of nodes in which every node is a shape (primitive or fractal), the
//! edge to its parent is a combine operator, and each node carries its own ordered list of
//! domain operators and a material. The root may carry an IFS loop. A scene also holds the
//! camera, the lights and the render settings, and for animation its flight paths and
//! modulation bindings.
//!
//! Semantics (the tape compiler and the reference evaluator both follow them):
//! - a node's point operators (`Transform`s) apply, in list order, to the node's shape and to
//!   its whole subtree, like transforms in a scene graph;
//! - the node's shape is evaluated, then each child in order is combined into it with the
//!   child's `combine` operator (the root's `combine` is ignored);
//! - the node's distance modifiers (`Modifier`s) then apply, in list order, to the combined
//!   value of the subtree;
//! - the IFS loop runs `iterations` times over its operators before the root is evaluated.

use crate::binding::Binding;
use crate::camera::Camera;
use crate::combine::Combine;
use crate::flight_path::FlightPath;
use crate::transforms::Transform;
use glam::DVec3;
use serde::{Deserialize, Serialize};

pub use crate::call::{Call, DomainOp, Shape};

/// The scene-file format version this build reads and writes.
pub const SCENE_VERSION: u32 = 1;

/// Surface appearance. `albedo`, `specular`, `shininess` and `trap_colour` drive every
/// renderer (Blinn-Phong in the preview tracers); `metallic`, `emission`, `transmission` and
/// `ior` are the path tracer's physically based extras (the preview ignores them), whose
/// defaults change nothing, so files without them mean what they always meant. The path
/// tracer's GGX roughness is `shininess` mapped by Walter et al.'s correspondence
/// (docs/pathtrace.md); the fields and their ranges are declared once in
/// [`fields::MATERIAL_FIELDS`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Material {
    /// Diffuse colour, linear RGB in [0, 1].
    pub albedo: [f64; 3],
    /// Specular strength in [0, 1].
    pub specular: f64,
    /// Blinn-Phong exponent, [1, 4096].
    pub shininess: f64,
    /// How much the orbit-trap palette replaces the albedo, [0, 1].
    pub trap_colour: f64,
    /// Path tracer: 0 a dielectric (paint, stone), 1 a metal whose albedo is its
    /// reflectance, [0, 1].
    #[serde(skip_serializing_if = "is_zero")]
    pub metallic: f64,
    /// Path tracer: colour of emitted light, linear RGB in [0, 1].
    #[serde(skip_serializing_if = "is_white")]
    pub emission: [f64; 3],
    /// Path tracer: emitted radiance = emission x this, [0, 1e6] (0: not a light).
    #[serde(skip_serializing_if = "is_zero")]
    pub emission_strength: f64,
    /// Path tracer: 0 opaque, 1 glass (light refracts through the shape's interior), [0, 1].
    #[serde(skip_serializing_if = "is_zero")]
    pub transmission: f64,
    /// Path tracer: index of refraction of a transmissive material, [1, 3].
    #[serde(skip_serializing_if = "is_default_ior")]
    pub ior: f64,
}

/// The index of refraction of glass, the default.
pub const DEFAULT_IOR: f64 = 1.5;

fn is_zero(x: &f64) -> bool {
    *x == 0.0
}

fn is_white(c: &[f64; 3]) -> bool {
    *c == [1.0; 3]
}

fn is_default_ior(x: &f64) -> bool {
    *x == DEFAULT_IOR
}

impl Default for Material {
    fn default() -> Self {
        Material {
            albedo: [0.75, 0.75, 0.75],
            specular: 0.3,
            shininess: 32.0,
            trap_colour: 0.0,
            metallic: 0.0,
            emission: [1.0; 3],
            emission_strength: 0.0,
            transmission: 0.0,
            ior: DEFAULT_IOR,
        }
    }
}

/// A node of the scene tree.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Node {
    /// How this node joins its parent (ignored at the root).
    #[serde(default = "default_combine")]
    pub combine: Call<Combine>,
    /// The node's own shape.
    pub shape: Call<Shape>,
    /// Domain operators (point transforms and distance modifiers), in order.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub ops: Vec<Call<DomainOp>>,
    /// How the node's surface looks.
    #[serde(default)]
    pub material: Material,
    /// Subtrees joined to this node, each by its own `combine`.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub children: Vec<Node>,
}

fn default_combine() -> Call<Combine> {
    Call::new(Combine::Union)
}

impl Node {
    /// A node with the given shape, no operators, default material and no children.
    pub fn new(shape: impl Into<Call<Shape>>) -> Self {
        Node {
            combine: default_combine(),
            shape: shape.into(),
            ops: Vec::new(),
            material: Material::default(),
            children: Vec::new(),
        }
    }
    /// Sets the combine operator on the edge to the parent.
    pub fn combine(mut self, c: impl Into<Call<Combine>>) -> Self {
        self.combine = c.into();
        self
    }
    /// Appends a domain operator.
    pub fn op(mut self, op: impl Into<Call<DomainOp>>) -> Self {
        self.ops.push(op.into());
        self
    }
    /// Appends a child.
    pub fn child(mut self, n: Node) -> Self {
        self.children.push(n);
        self
    }
    /// Sets the node's material.
    pub fn material(mut self, m: Material) -> Self {
        self.material = m;
        self
    }
    /// Number of nodes in this subtree.
    pub fn count(&self) -> usize {
        1 + self.children.iter().map(Node::count).sum::<usize>()
    }
    /// Depth of this subtree (a leaf has depth 1).
    pub fn depth(&self) -> usize {
        1 + self.children.iter().map(Node::depth).max().unwrap_or(0)
    }
}

/// An iterated function system applied to the point before the root's tree is evaluated.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Ifs {
    /// How many times the operator list runs, [0, limits::MAX_IFS_ITERATIONS].
    pub iterations: u32,
    /// Folds, rotations, scalings and translations, applied in order each iteration.
    pub ops: Vec<Call<Transform>>,
}

/// A directional light.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Light {
    /// Direction towards the light (need not be unit length).
    pub direction: DVec3,
    /// Linear RGB colour.
    pub colour: [f64; 3],
    /// Brightness multiplier, [0, 1000].
    pub intensity: f64,
    /// Whether this light casts soft shadows.
    pub shadows: bool,
}

impl Default for Light {
    fn default() -> Self {
        Light {
            direction: DVec3::new(0.6, 0.8, 0.4),
            colour: [1.0, 0.97, 0.9],
            intensity: 1.0,
            shadows: true,
        }
    }
}

/// Background and lighting environment plus the tracer's quality knobs.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct RenderSettings {
    /// Sky colour straight up (linear RGB).
    pub sky_top: [f64; 3],
    /// Sky colour at and below the horizon (linear RGB).
    pub sky_bottom: [f64; 3],
    /// Ambient light level, [0, 1].
    pub ambient: f64,
    /// Strength of distance-field ambient occlusion, [0, 4].
    pub ao: f64,
    /// Penumbra sharpness of soft shadows (larger is harder), [1, 256].
    pub shadow_softness: f64,
    /// Fog density per world unit (0 disables), [0, 1e6].
    pub fog: f64,
    /// Sphere-tracing step limit per ray, [1, limits::MAX_STEPS].
    pub max_steps: u32,
    /// Rays stop beyond this distance from the camera.
    pub max_distance: f64,
    /// Hit threshold as a multiple of the pixel footprint at the hit distance, [0.01, 16].
    pub pixel_epsilon: f64,
    /// Orbit-trap cosine palette `a + b cos(2 pi (c t + d))`, rows a, b, c, d.
    pub palette: [[f64; 3]; 4],
}

impl Default for RenderSettings {
    fn default() -> Self {
        RenderSettings {
            sky_top: [0.30, 0.45, 0.75],
            sky_bottom: [0.85, 0.80, 0.75],
            ambient: 0.15,
            ao: 1.0,
            shadow_softness: 16.0,
            fog: 0.0,
            max_steps: 256,
            max_distance: 100.0,
            pixel_epsilon: 1.0,
            palette: [
                [0.5, 0.5, 0.5],
                [0.5, 0.5, 0.5],
                [1.0, 1.0, 1.0],
                [0.0, 0.10, 0.20],
            ],
        }
    }
}

/// A whole scene: the tree plus how to look at it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    /// Scene-file format version; this build reads [`SCENE_VERSION`].
    pub version: u32,
    /// The camera the scene opens with.
    #[serde(default)]
    pub camera: Camera,
    /// Directional lights; one default light when left out.
    #[serde(default = "default_lights")]
    pub lights: Vec<Light>,
    /// Render settings (steps, shading, fog, palette, ...).
    #[serde(default)]
    pub render: RenderSettings,
    /// An iterated function system run on the point before the tree, if any.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ifs: Option<Ifs>,
    /// The root of the node tree.
    pub root: Node,
    /// Named camera paths ([`crate::flight`]).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub paths: Vec<FlightPath>,
    /// Parameters driven by LFOs or OSC ([`crate::binding`]).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub bindings: Vec<Binding>,
}

fn default_lights() -> Vec<Light> {
    vec![Light::default()]
}

impl Scene {
    /// A scene of one tree with the default camera, one light and default settings.
    pub fn new(root: Node) -> Self {
        Scene {
            version: SCENE_VERSION,
            camera: Camera::default(),
            lights: default_lights(),
            render: RenderSettings::default(),
            ifs: None,
            root,
            paths: Vec::new(),
            bindings: Vec::new(),
        }
    }
}

pub mod fields;
