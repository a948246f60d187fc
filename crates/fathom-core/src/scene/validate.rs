//! Scene validation: the version, every parameter against its declaration, materials, lights,
//! render settings and the structural limits of [`crate::limits`], with a typed error that
//! names the node (its path in the tree) or setting that failed, so a GUI can point at it and
//! the command line prints it as text.

use super::{Node, SCENE_VERSION, Scene};
use crate::camera::CameraError;
use crate::limits;
use crate::registry::EntryError;
use thiserror::Error;

/// The first rule a scene breaks. Node paths look like `root.children[1].ops[0]`.
#[derive(Clone, Debug, PartialEq, Error)]
pub enum SceneError {
    #[error("scene version {found} is not supported; this build reads version {SCENE_VERSION}")]
    Version { found: u32 },
    #[error("the scene has {nodes} nodes; the limit is {max}", max = limits::MAX_NODES)]
    TooManyNodes { nodes: usize },
    #[error("the tree is {depth} levels deep; the limit is {max}", max = limits::MAX_TREE_DEPTH)]
    TooDeep { depth: usize },
    #[error("ifs.iterations = {iterations} is out of range [0, {max}]", max = limits::MAX_IFS_ITERATIONS)]
    IfsIterations { iterations: u32 },
    #[error("ifs has {count} operators; the limit is {max}", max = limits::MAX_OPS_PER_LIST)]
    IfsTooManyOps { count: usize },
    #[error("{path}.ops: {count} operators; the limit is {max}", max = limits::MAX_OPS_PER_LIST)]
    TooManyOps { path: String, count: usize },
    /// A registry call (shape, combine, operator) with a bad parameter; `path` names the call,
    /// e.g. `root.children[0].shape` or `ifs.ops[2]`.
    #[error("{path}: {error}")]
    Entry { path: String, error: EntryError },
    #[error(
        "{path}.material: albedo and specular must lie in [0, 1], shininess in [1, 4096], trap_colour in [0, 1]"
    )]
    Material { path: String },
    #[error(transparent)]
    Camera(#[from] CameraError),
    #[error("{count} lights; the limit is {max}", max = limits::MAX_LIGHTS)]
    TooManyLights { count: usize },
    #[error(
        "lights[{index}]: direction must be finite and non-zero, colour and intensity in [0, 1000]"
    )]
    Light { index: usize },
    /// A render setting out of its range (`name` is the field of `render`).
    #[error("render.{name} = {value} is out of range [{min}, {max}]")]
    Render {
        name: &'static str,
        value: f64,
        min: f64,
        max: f64,
    },
}

impl SceneError {
    /// The path of the node or call the error is in (`root.children[1].shape`), if any.
    pub fn path(&self) -> Option<&str> {
        match self {
            SceneError::TooManyOps { path, .. }
            | SceneError::Entry { path, .. }
            | SceneError::Material { path } => Some(path),
            _ => None,
        }
    }
}

impl Scene {
    /// Checks the version, every parameter, and the structural limits of [`crate::limits`].
    /// Returns the first problem with the path of the node it is in.
    pub fn validate(&self) -> Result<(), SceneError> {
        if self.version != SCENE_VERSION {
            return Err(SceneError::Version {
                found: self.version,
            });
        }
        let nodes = self.root.count();
        if nodes > limits::MAX_NODES {
            return Err(SceneError::TooManyNodes { nodes });
        }
        let depth = self.root.depth();
        if depth > limits::MAX_TREE_DEPTH {
            return Err(SceneError::TooDeep { depth });
        }
        if let Some(ifs) = &self.ifs {
            if ifs.iterations > limits::MAX_IFS_ITERATIONS {
                return Err(SceneError::IfsIterations {
                    iterations: ifs.iterations,
                });
            }
            if ifs.ops.len() > limits::MAX_OPS_PER_LIST {
                return Err(SceneError::IfsTooManyOps {
                    count: ifs.ops.len(),
                });
            }
            for (i, op) in ifs.ops.iter().enumerate() {
                op.check().map_err(|error| SceneError::Entry {
                    path: format!("ifs.ops[{i}]"),
                    error,
                })?;
            }
        }
        validate_node(&self.root, "root")?;
        self.camera.validate()?;
        if self.lights.len() > limits::MAX_LIGHTS {
            return Err(SceneError::TooManyLights {
                count: self.lights.len(),
            });
        }
        for (index, l) in self.lights.iter().enumerate() {
            let ok = l.direction.is_finite()
                && l.direction.length_squared() > 0.0
                && l.intensity.is_finite()
                && (0.0..=1e3).contains(&l.intensity)
                && l.colour
                    .iter()
                    .all(|c| c.is_finite() && (0.0..=1e3).contains(c));
            if !ok {
                return Err(SceneError::Light { index });
            }
        }
        self.validate_render()
    }

    fn validate_render(&self) -> Result<(), SceneError> {
        let r = &self.render;
        let ranged = |name: &'static str, value: f64, min: f64, max: f64| {
            if value.is_finite() && (min..=max).contains(&value) {
                Ok(())
            } else {
                Err(SceneError::Render {
                    name,
                    value,
                    min,
                    max,
                })
            }
        };
        for (name, c) in [("sky_top", r.sky_top), ("sky_bottom", r.sky_bottom)] {
            for v in c {
                ranged(name, v, 0.0, 1e3)?;
            }
        }
        for row in r.palette {
            for v in row {
                ranged("palette", v, -1e3, 1e3)?;
            }
        }
        ranged("ambient", r.ambient, 0.0, 1.0)?;
        ranged("ao", r.ao, 0.0, 4.0)?;
        ranged("shadow_softness", r.shadow_softness, 1.0, 256.0)?;
        ranged("fog", r.fog, 0.0, 1e6)?;
        ranged(
            "max_steps",
            r.max_steps as f64,
            1.0,
            limits::MAX_STEPS as f64,
        )?;
        ranged("max_distance", r.max_distance, 1e-9, 1e12)?;
        ranged("pixel_epsilon", r.pixel_epsilon, 0.01, 16.0)?;
        Ok(())
    }
}

fn validate_node(n: &Node, path: &str) -> Result<(), SceneError> {
    let entry = |what: &str, error| SceneError::Entry {
        path: format!("{path}.{what}"),
        error,
    };
    n.combine.check().map_err(|e| entry("combine", e))?;
    n.shape.check().map_err(|e| entry("shape", e))?;
    if n.ops.len() > limits::MAX_OPS_PER_LIST {
        return Err(SceneError::TooManyOps {
            path: path.into(),
            count: n.ops.len(),
        });
    }
    for (i, op) in n.ops.iter().enumerate() {
        op.check().map_err(|e| entry(&format!("ops[{i}]"), e))?;
    }
    let m = &n.material;
    let mat_ok = m
        .albedo
        .iter()
        .all(|c| c.is_finite() && (0.0..=1.0).contains(c))
        && m.specular.is_finite()
        && (0.0..=1.0).contains(&m.specular)
        && m.shininess.is_finite()
        && (1.0..=4096.0).contains(&m.shininess)
        && m.trap_colour.is_finite()
        && (0.0..=1.0).contains(&m.trap_colour);
    if !mat_ok {
        return Err(SceneError::Material { path: path.into() });
    }
    for (i, c) in n.children.iter().enumerate() {
        validate_node(c, &format!("{path}.children[{i}]"))?;
    }
    Ok(())
}
