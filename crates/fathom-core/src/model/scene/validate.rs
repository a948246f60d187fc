//! Scene validation: the version, every parameter against its declaration, materials, lights,
//! render settings and the structural limits of [`crate::limits`], with a typed error that
//! names the node (its path in the tree) or setting that failed, so a GUI can point at it and
//! the command line prints it as text.

use super::fields::{LIGHT_FIELDS, MATERIAL_FIELDS, RENDER_FIELDS};
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
    #[error("{path}.material.{field} = {value} is out of range [{min}, {max}]")]
    Material {
        path: String,
        field: &'static str,
        value: f64,
        min: f64,
        max: f64,
    },
    #[error(transparent)]
    Camera(#[from] CameraError),
    #[error("{count} lights; the limit is {max}", max = limits::MAX_LIGHTS)]
    TooManyLights { count: usize },
    #[error(
        "lights[{index}]: direction must be finite and non-zero, colour and intensity in [0, 1000]"
    )]
    Light { index: usize },
    /// A flight path breaks a rule; `path` says where (`paths[0].keys[2].fov`).
    #[error("{path}: {error}")]
    Flight {
        path: String,
        error: crate::flight::FlightError,
    },
    /// A modulation binding breaks a rule; `path` says where (`bindings[1].param`).
    #[error("{path}: {error}")]
    Binding {
        path: String,
        error: crate::binding::BindingError,
    },
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
            | SceneError::Material { path, .. }
            | SceneError::Flight { path, .. }
            | SceneError::Binding { path, .. } => Some(path),
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
            let ok = l.direction.length_squared() > 0.0
                && LIGHT_FIELDS
                    .iter()
                    .all(|f| f.read(l).iter().all(|&x| f.accepts(x)));
            if !ok {
                return Err(SceneError::Light { index });
            }
        }
        self.validate_render()
    }

    /// Checks the flight paths and modulation bindings: the rules of [`crate::flight`] and
    /// [`crate::binding`], and that every parameter path they name exists in this scene.
    /// Separate from [`Scene::validate`], which is what rendering needs: an edited tree can
    /// leave a binding stale without making the scene unrenderable. Scene files check both.
    pub fn validate_animation(&self) -> Result<(), SceneError> {
        crate::flight::validate_paths(self)
            .map_err(|(path, error)| SceneError::Flight { path, error })?;
        crate::binding::validate_bindings(self)
            .map_err(|(path, error)| SceneError::Binding { path, error })
    }

    fn validate_render(&self) -> Result<(), SceneError> {
        for f in RENDER_FIELDS {
            let (min, max) = f.range.unwrap_or((f64::MIN, f64::MAX));
            if let Some(&value) = f.read(&self.render).iter().find(|&&x| !f.accepts(x)) {
                return Err(SceneError::Render {
                    name: f.name,
                    value,
                    min,
                    max,
                });
            }
        }
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
    for f in MATERIAL_FIELDS {
        if let Some(&value) = f.read(&n.material).iter().find(|&&x| !f.accepts(x)) {
            let (min, max) = f.range.unwrap_or((f64::MIN, f64::MAX));
            return Err(SceneError::Material {
                path: path.into(),
                field: f.name,
                value,
                min,
                max,
            });
        }
    }
    for (i, c) in n.children.iter().enumerate() {
        validate_node(c, &format!("{path}.children[{i}]"))?;
    }
    Ok(())
}
