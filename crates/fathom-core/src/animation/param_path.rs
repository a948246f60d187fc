//! Parameter paths: the text address of one number of a scene, as modulation bindings and
//! flight-path keys write it, with the range it may take (from the registry for shapes and
//! operators, from [`crate::scene::fields`] for materials, lights, the camera and the render
//! settings).
//!
//! ```text
//! root.shape.power                   a node's shape parameter
//! root.children[1].ops[0].angle      a parameter of a node's operator
//! root.children[0].combine.k         the combine on the edge to the parent
//! root.ops[0].offset.y               one component of a vector (.x .y .z, or [0] [1] [2])
//! root.children[2].material.albedo.g a material field (.r .g .b for colours)
//! ifs.iterations, ifs.ops[3].angle   the IFS loop
//! lights[0].intensity                a light
//! camera.fov, camera.eye.x           the camera
//! render.fog, render.palette[5]      a render setting (palette component 3 row + column)
//! ```
//!
//! A path is parsed once ([`ParamPath::parse`]) and resolved against a scene each time it is
//! used ([`ParamPath::resolve`]), so an edited tree makes a stale path an error, never a panic.

use thiserror::Error;

/// Why a parameter path does not name a number of a scene.
#[derive(Clone, Debug, PartialEq, Error)]
pub enum ParamPathError {
    /// The text is not a path.
    #[error("`{path}` is not a parameter path: {msg}")]
    Syntax {
        /// The text given.
        path: String,
        /// What is wrong with it.
        msg: String,
    },
    /// A step names something the scene does not have.
    #[error("`{path}`: {msg}")]
    Missing {
        /// The path given.
        path: String,
        /// Which step is missing and what there is instead.
        msg: String,
    },
    /// The path names a vector or colour: it needs a component.
    #[error("`{path}` is a {width}-component value; name one component, e.g. `{path}.{first}`")]
    NeedsComponent {
        /// The path given.
        path: String,
        /// How many components the value has.
        width: usize,
        /// The name of its first component (`x`, `r` or `0`).
        first: String,
    },
}

/// A parsed parameter path (not yet checked against a scene).
#[derive(Clone, Debug, PartialEq)]
pub struct ParamPath {
    pub(crate) text: String,
    pub(crate) segs: Vec<Seg>,
}

/// One `name` or `name[i]` step.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Seg {
    pub(crate) name: String,
    pub(crate) index: Option<usize>,
}

/// The declared range of the number a path names.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ParamRange {
    /// Closed range, or `None` when any finite value is allowed.
    pub bounds: Option<(f64, f64)>,
    /// Whether the number is whole (iterations, step counts).
    pub int: bool,
}

impl ParamRange {
    /// `x` clamped into the range (rounded when whole), or `None` when `x` is not finite.
    pub fn clamp(&self, x: f64) -> Option<f64> {
        if !x.is_finite() {
            return None;
        }
        let x = match self.bounds {
            Some((lo, hi)) => x.clamp(lo, hi),
            None => x,
        };
        Some(if self.int { x.round() } else { x })
    }

    /// Whether `x` lies in the range (and is whole when it must be).
    pub fn contains(&self, x: f64) -> bool {
        x.is_finite()
            && self.bounds.is_none_or(|(lo, hi)| (lo..=hi).contains(&x))
            && (!self.int || x.fract() == 0.0)
    }

    /// `[lo, hi]` or `any finite value`, for messages.
    pub fn describe(&self) -> String {
        match self.bounds {
            Some((lo, hi)) => format!(
                "[{}, {}]",
                crate::registry::fmt_num(lo),
                crate::registry::fmt_num(hi)
            ),
            None => "any finite value".into(),
        }
    }
}

impl ParamPath {
    /// Parses the text of a path (`root.children[0].shape.radius`); the names are checked when
    /// it is resolved against a scene.
    pub fn parse(text: &str) -> Result<ParamPath, ParamPathError> {
        let syntax = |msg: String| ParamPathError::Syntax {
            path: text.into(),
            msg,
        };
        if text.len() > 512 {
            return Err(syntax("longer than 512 characters".into()));
        }
        if text.is_empty() {
            return Err(syntax(
                "it is empty; write e.g. `root.shape.radius` or `camera.fov`".into(),
            ));
        }
        let mut segs = Vec::new();
        for part in text.split('.') {
            let (name, rest) = part.split_at(part.find('[').unwrap_or(part.len()));
            let name_ok = !name.is_empty()
                && name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
                && !name.starts_with(|c: char| c.is_ascii_digit());
            if !name_ok {
                return Err(syntax(format!(
                    "expected a name (letters, digits, `_`) at `{part}`"
                )));
            }
            let mut index = None;
            let mut rest = rest;
            while let Some(r) = rest.strip_prefix('[') {
                let close = r
                    .find(']')
                    .ok_or_else(|| syntax(format!("`[` without `]` in `{part}`")))?;
                let n: usize = r[..close].parse().map_err(|_| {
                    syntax(format!("expected a whole number inside `[]` in `{part}`"))
                })?;
                if index.is_some() {
                    // `name[i][j]`: a further index selects a component; keep it as its own step.
                    segs.push(Seg {
                        name: name.into(),
                        index,
                    });
                    segs.push(Seg {
                        name: String::new(),
                        index: Some(n),
                    });
                    index = None;
                    rest = &r[close + 1..];
                    if !rest.is_empty() {
                        return Err(syntax(format!("too many `[]` in `{part}`")));
                    }
                    continue;
                }
                index = Some(n);
                rest = &r[close + 1..];
            }
            if !rest.is_empty() {
                return Err(syntax(format!("unexpected `{rest}` in `{part}`")));
            }
            if !(segs.last().is_some_and(|s: &Seg| s.name.is_empty())) {
                segs.push(Seg {
                    name: name.into(),
                    index,
                });
            }
        }
        Ok(ParamPath {
            text: text.into(),
            segs,
        })
    }

    /// The path as written.
    pub fn as_str(&self) -> &str {
        &self.text
    }
}
