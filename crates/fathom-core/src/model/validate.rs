//! Scene validation: the version, every parameter against its declaration, materials, lights,
//! render settings and the structural limits of [`crate::limits`], and (separately) the flight
//! paths and bindings against the tree, with a typed error that names the node (its path in
//! the tree) or setting that failed, so a GUI can point at it and the command line prints it
//! as text. It sits above the scene model and the animation data it checks.

use crate::binding::{Binding, BindingError, MAX_BINDINGS};
use crate::camera::CameraError;
use crate::flight_path::{
    FlightError, FlightPath, MAX_DURATION, MAX_KEY_PARAMS, MAX_KEYS, MAX_PATHS,
};
use crate::limits;
use crate::param_path::ParamPath;
use crate::registry::EntryError;
use crate::scene::fields::{LIGHT_FIELDS, MATERIAL_FIELDS, RENDER_FIELDS};
use crate::scene::{Node, SCENE_VERSION, Scene};
use thiserror::Error;

/// The first rule a scene breaks. Node paths look like `root.children[1].ops[0]`.
#[derive(Clone, Debug, PartialEq, Error)]
pub enum SceneError {
    /// The file's `version` is not the one this build reads.
    #[error("scene version {found} is not supported; this build reads version {SCENE_VERSION}")]
    Version {
        /// The version the scene gives.
        found: u32,
    },
    /// The tree has more than [`limits::MAX_NODES`] nodes.
    #[error("the scene has {nodes} nodes; the limit is {max}", max = limits::MAX_NODES)]
    TooManyNodes {
        /// How many nodes the tree has.
        nodes: usize,
    },
    /// The tree is deeper than [`limits::MAX_TREE_DEPTH`].
    #[error("the tree is {depth} levels deep; the limit is {max}", max = limits::MAX_TREE_DEPTH)]
    TooDeep {
        /// How deep the tree is.
        depth: usize,
    },
    /// The scene's IFS runs more than [`limits::MAX_IFS_ITERATIONS`] iterations.
    #[error("ifs.iterations = {iterations} is out of range [0, {max}]", max = limits::MAX_IFS_ITERATIONS)]
    IfsIterations {
        /// The iterations given.
        iterations: u32,
    },
    /// The scene's IFS has more than [`limits::MAX_OPS_PER_LIST`] operators.
    #[error("ifs has {count} operators; the limit is {max}", max = limits::MAX_OPS_PER_LIST)]
    IfsTooManyOps {
        /// How many operators it has.
        count: usize,
    },
    /// A node has more than [`limits::MAX_OPS_PER_LIST`] domain operators.
    #[error("{path}.ops: {count} operators; the limit is {max}", max = limits::MAX_OPS_PER_LIST)]
    TooManyOps {
        /// The node's path.
        path: String,
        /// How many operators it has.
        count: usize,
    },
    /// A registry call (shape, combine, operator) with a bad parameter; `path` names the call,
    /// e.g. `root.children[0].shape` or `ifs.ops[2]`.
    #[error("{path}: {error}")]
    Entry {
        /// The call's path.
        path: String,
        /// What is wrong with its parameters.
        error: EntryError,
    },
    /// A material field is outside its range.
    #[error("{path}.material.{field} = {value} is out of range [{min}, {max}]")]
    Material {
        /// The node's path.
        path: String,
        /// The material field.
        field: &'static str,
        /// The value given.
        value: f64,
        /// The field's lower bound.
        min: f64,
        /// The field's upper bound.
        max: f64,
    },
    /// The camera is invalid.
    #[error(transparent)]
    Camera(#[from] CameraError),
    /// The scene has more than [`limits::MAX_LIGHTS`] lights.
    #[error("{count} lights; the limit is {max}", max = limits::MAX_LIGHTS)]
    TooManyLights {
        /// How many lights the scene has.
        count: usize,
    },
    /// A light has a zero or non-finite direction, or a colour or intensity outside [0, 1000].
    #[error(
        "lights[{index}]: direction must be finite and non-zero, colour and intensity in [0, 1000]"
    )]
    Light {
        /// The light's index in `lights`.
        index: usize,
    },
    /// A flight path breaks a rule; `path` says where (`paths[0].keys[2].fov`).
    #[error("{path}: {error}")]
    Flight {
        /// Where in `paths` the rule is broken.
        path: String,
        /// The rule broken.
        error: FlightError,
    },
    /// A modulation binding breaks a rule; `path` says where (`bindings[1].param`).
    #[error("{path}: {error}")]
    Binding {
        /// Where in `bindings` the rule is broken.
        path: String,
        /// The rule broken.
        error: BindingError,
    },
    /// A render setting out of its range (`name` is the field of `render`).
    #[error("render.{name} = {value} is out of range [{min}, {max}]")]
    Render {
        /// The field of `render`.
        name: &'static str,
        /// The value given.
        value: f64,
        /// The field's lower bound.
        min: f64,
        /// The field's upper bound.
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

    /// Checks the flight paths and modulation bindings: the rules of [`crate::flight_path`] and
    /// [`crate::binding`], and that every parameter path they name exists in this scene.
    /// Separate from [`Scene::validate`], which is what rendering needs: an edited tree can
    /// leave a binding stale without making the scene unrenderable. Scene files check both.
    pub fn validate_animation(&self) -> Result<(), SceneError> {
        validate_paths(self).map_err(|(path, error)| SceneError::Flight { path, error })?;
        validate_bindings(self).map_err(|(path, error)| SceneError::Binding { path, error })
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

/// Checks a scene's bindings; the error names where (`bindings[1].param`).
pub fn validate_bindings(scene: &Scene) -> Result<(), (String, BindingError)> {
    if scene.bindings.len() > MAX_BINDINGS {
        return Err((
            "bindings".into(),
            BindingError::TooMany {
                count: scene.bindings.len(),
            },
        ));
    }
    for (i, b) in scene.bindings.iter().enumerate() {
        validate_binding(b, scene).map_err(|(what, e)| (format!("bindings[{i}]{what}"), e))?;
    }
    Ok(())
}

/// Checks one binding against `scene`: its own rules, then that its path names a number of
/// the scene and `to` lies in that number's range.
fn validate_binding(b: &Binding, scene: &Scene) -> Result<(), (&'static str, BindingError)> {
    b.check()?;
    let r = ParamPath::parse(&b.param)
        .and_then(|p| p.resolve(scene))
        .map_err(|e| (".param", BindingError::Param(e)))?;
    let (lo, hi) = b.to;
    if !(r.range.contains(lo) && r.range.contains(hi)) {
        return Err((
            ".to",
            BindingError::To {
                param: b.param.clone(),
                lo,
                hi,
                range: r.range.describe(),
            },
        ));
    }
    Ok(())
}

/// Checks a scene's paths; the error names where (`paths[1].keys[0].fov`).
pub fn validate_paths(scene: &Scene) -> Result<(), (String, FlightError)> {
    if scene.paths.len() > MAX_PATHS {
        return Err((
            "paths".into(),
            FlightError::TooManyPaths {
                count: scene.paths.len(),
            },
        ));
    }
    for (i, p) in scene.paths.iter().enumerate() {
        let at = |what: &str| format!("paths[{i}]{what}");
        if p.name.trim().is_empty() {
            return Err((at(".name"), FlightError::NoName));
        }
        if scene.paths[..i].iter().any(|q| q.name == p.name) {
            return Err((
                at(".name"),
                FlightError::Duplicate {
                    name: p.name.clone(),
                },
            ));
        }
        p.validate(scene)
            .map_err(|(what, e)| (format!("paths[{i}]{what}"), e))?;
    }
    Ok(())
}

impl FlightPath {
    /// Checks the path against `scene` (its parameter paths must exist there). The error's
    /// first part says where inside the path (`.keys[2].fov`).
    pub fn validate(&self, scene: &Scene) -> Result<(), (String, FlightError)> {
        let name = self.name.clone();
        let n = self.keys.len();
        if n < 2 {
            return Err((".keys".into(), FlightError::TooFewKeys { name, count: n }));
        }
        if n > MAX_KEYS {
            return Err((".keys".into(), FlightError::TooManyKeys { name, count: n }));
        }
        let d = self.duration;
        if !(d.is_finite() && d > 0.0 && d <= MAX_DURATION) {
            return Err((".duration".into(), FlightError::Duration { value: d }));
        }
        let (a, b) = (self.ease_in, self.ease_out);
        if !(a.is_finite() && b.is_finite() && a >= 0.0 && b >= 0.0 && a + b <= d) {
            return Err((
                ".ease_in".into(),
                FlightError::Ease {
                    ease_in: a,
                    ease_out: b,
                    duration: d,
                },
            ));
        }
        let mut after = 0.0;
        for (k, key) in self.keys.iter().enumerate() {
            let at = |what: &str| format!(".keys[{k}]{what}");
            key.camera()
                .validate()
                .map_err(|e| (at(""), FlightError::Camera(e)))?;
            if let Some(t) = key.time {
                if k == 0 || k + 1 == n {
                    return Err((at(".time"), FlightError::PinnedEnd { value: t }));
                }
                if !(t.is_finite() && t > after && t < d) {
                    return Err((
                        at(".time"),
                        FlightError::TimeOrder {
                            value: t,
                            after,
                            before: d,
                        },
                    ));
                }
                after = t;
            }
            if let Some(s) = key.scale
                && !(s.is_finite() && s > 0.0)
            {
                return Err((at(".scale"), FlightError::Scale { value: s }));
            }
            if key.params.len() > MAX_KEY_PARAMS {
                return Err((
                    at(".params"),
                    FlightError::TooManyParams {
                        count: key.params.len(),
                    },
                ));
            }
            for (path, &value) in &key.params {
                let r = ParamPath::parse(path)
                    .and_then(|p| p.resolve(scene))
                    .map_err(|e| (at(".params"), FlightError::Param(e)))?;
                if !r.range.contains(value) {
                    return Err((
                        at(".params"),
                        FlightError::ParamRange {
                            path: path.clone(),
                            value,
                            range: r.range.describe(),
                        },
                    ));
                }
            }
        }
        Ok(())
    }
}
