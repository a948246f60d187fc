//! The registry: how each primitive, fractal, domain operator and combine operator is declared
//! once and read by everything else.
//!
//! [`declare_family!`] turns one table of entries (name, doc, parameters with defaults and ranges,
//! a bound-quality tag, and the distance code generic over [`crate::Real`]) into an enum, a static
//! table of [`Def`]s, and a dispatch function. The scene parser, `fathom list`, the docs, the GUI,
//! the tape compiler, the CPU interpreter and the tests iterate over those tables; nothing else
//! names a primitive. The WGSL interpreter is checked against the same tables.

use std::fmt;

/// How a parameter is stored: one number, an integer count, or a 3-vector.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ParamKind {
    /// A real number.
    Scalar,
    /// A whole number (iterations, counts); stored as a float in the parameter buffer.
    Int,
    /// Three real numbers, written `(x, y, z)` in scene files.
    Vec3,
}

impl ParamKind {
    /// How many parameter-buffer slots a value of this kind takes.
    pub const fn width(self) -> usize {
        match self {
            ParamKind::Scalar | ParamKind::Int => 1,
            ParamKind::Vec3 => 3,
        }
    }
}

/// One declared parameter: name, kind, default, the closed range every component must lie in
/// (the *hard* range: what is valid), and the *soft* range inside it that sliders cover (what
/// artists use: a torus tube is valid up to 1e6 but interesting below 1).
#[derive(Clone, Copy, Debug)]
pub struct ParamSpec {
    /// The name used in scene files, paths and the GUI.
    pub name: &'static str,
    /// Scalar, integer or 3-vector.
    pub kind: ParamKind,
    /// Default value; only the first `kind.width()` components are meaningful.
    pub default: [f64; 3],
    /// The hard range's lower end, per component.
    pub min: f64,
    /// The hard range's upper end, per component.
    pub max: f64,
    /// The slider range's lower end: the slider covers `[soft_min, soft_max]`, inside
    /// `[min, max]`; typed values may go to the hard range.
    pub soft_min: f64,
    /// The slider range's upper end.
    pub soft_max: f64,
    /// One line on what the parameter does, for `fathom list`, the docs and tooltips.
    pub doc: &'static str,
}

impl ParamSpec {
    /// The default as a flat slice of `kind.width()` numbers.
    pub fn default_values(&self) -> &[f64] {
        &self.default[..self.kind.width()]
    }

    /// Whether a slider over the soft range should be logarithmic: the range spans two
    /// decades or more of positive numbers.
    pub fn soft_is_logarithmic(&self) -> bool {
        self.soft_min > 0.0 && self.soft_max / self.soft_min >= 100.0
    }

    /// Checks one value (all of its components) against the declared kind and range.
    pub fn check(&self, v: &[f64]) -> Result<(), ParamError> {
        let param = self.name;
        if v.len() != self.kind.width() {
            return Err(ParamError::Width {
                param,
                expected: self.kind.width(),
                got: v.len(),
            });
        }
        for &value in v {
            if !value.is_finite() {
                return Err(ParamError::NotFinite { param, value });
            }
            if value < self.min || value > self.max {
                return Err(ParamError::OutOfRange {
                    param,
                    value,
                    min: self.min,
                    max: self.max,
                });
            }
            if self.kind == ParamKind::Int && value.fract() != 0.0 {
                return Err(ParamError::NotWhole { param, value });
            }
        }
        Ok(())
    }

    /// `v` clamped into the declared range (non-finite components become the default, whole
    /// numbers are rounded): what a slider or a modulation source may write.
    pub fn clamp(&self, v: &[f64]) -> Vec<f64> {
        v.iter()
            .zip(self.default_values())
            .map(|(&x, &d)| {
                let x = if x.is_finite() { x } else { d };
                let x = x.clamp(self.min, self.max);
                if self.kind == ParamKind::Int {
                    x.round()
                } else {
                    x
                }
            })
            .collect()
    }
}

/// Why a value does not fit a declared parameter.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ParamError {
    /// The value has the wrong number of components for the parameter's kind.
    #[error("parameter `{param}` takes {expected} number(s), got {got}")]
    Width {
        /// The parameter's name.
        param: &'static str,
        /// Components the kind takes.
        expected: usize,
        /// Components given.
        got: usize,
    },
    /// A component is NaN or infinite.
    #[error("parameter `{param}` must be a finite number, got {value}")]
    NotFinite {
        /// The parameter's name.
        param: &'static str,
        /// The component given.
        value: f64,
    },
    /// A component is outside the hard range `[min, max]`.
    #[error("parameter `{param}` = {value} is out of range [{}, {}]", fmt_num(*min), fmt_num(*max))]
    OutOfRange {
        /// The parameter's name.
        param: &'static str,
        /// The component given.
        value: f64,
        /// The hard range's lower end.
        min: f64,
        /// The hard range's upper end.
        max: f64,
    },
    /// An integer parameter got a fractional value.
    #[error("parameter `{param}` must be a whole number, got {value}")]
    NotWhole {
        /// The parameter's name.
        param: &'static str,
        /// The value given.
        value: f64,
    },
}

/// Why a parameter list does not fit a registry entry.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum EntryError {
    /// The list has the wrong number of values for the entry.
    #[error("`{entry}` takes {expected} parameter values, got {got}")]
    Count {
        /// The entry's name.
        entry: &'static str,
        /// Values the entry takes.
        expected: usize,
        /// Values given.
        got: usize,
    },
    /// A parameter is named that the entry does not declare.
    #[error("`{entry}` has no parameter `{name}`; it has: {}", valid.join(", "))]
    NoSuchParam {
        /// The entry's name.
        entry: &'static str,
        /// The name given.
        name: String,
        /// The entry's parameter names.
        valid: Vec<&'static str>,
    },
    /// A value does not fit its parameter.
    #[error("{entry}: {error}")]
    Param {
        /// The entry's name.
        entry: &'static str,
        /// What is wrong with the value.
        error: ParamError,
    },
}

/// Formats a range bound readably (`1e+300` rather than three hundred digits).
pub fn fmt_num(x: f64) -> String {
    if x.abs() >= 1e6 && x.is_finite() {
        format!("{x:e}")
    } else {
        format!("{x}")
    }
}

/// How far a declared distance can be trusted.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Quality {
    /// The exact Euclidean signed distance.
    Exact,
    /// A conservative bound: never more than the true distance, and 1-Lipschitz.
    Bound,
    /// The operator breaks the Lipschitz bound; it multiplies the distance by its `safety`
    /// parameter, which keeps the bound valid inside the region its doc names.
    Safety,
}

impl fmt::Display for Quality {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Quality::Exact => "exact",
            Quality::Bound => "bound",
            Quality::Safety => "bound with safety factor",
        })
    }
}

/// Converts user parameter values into the parameter-buffer layout the evaluator reads.
pub type BakeFn = fn(user: &[f64], out: &mut Vec<f64>);

/// The declaration of one registry entry.
#[derive(Debug)]
pub struct Def {
    /// The name used in scene files and on the command line.
    pub name: &'static str,
    /// What the entry is, for `fathom list`, the docs and the GUI.
    pub doc: &'static str,
    /// How far its distance can be trusted.
    pub quality: Quality,
    /// Its parameters, in scene-file order.
    pub params: &'static [ParamSpec],
    /// When set, the user's parameters are converted (e.g. axis-angle to a matrix) before they
    /// go into the parameter buffer.
    pub bake: Option<BakeFn>,
    /// Slots this entry takes in the parameter buffer.
    pub baked_len: usize,
}

impl Def {
    /// Number of user-facing parameter values (sum of widths).
    pub fn user_len(&self) -> usize {
        self.params.iter().map(|p| p.kind.width()).sum()
    }

    /// The defaults of all parameters, flat.
    pub fn defaults(&self) -> Vec<f64> {
        self.params
            .iter()
            .flat_map(|p| p.default_values().iter().copied())
            .collect()
    }

    /// Looks a parameter up by name, returning its spec and flat offset.
    pub fn param(&self, name: &str) -> Option<(usize, &'static ParamSpec)> {
        let mut off = 0;
        for p in self.params {
            if p.name == name {
                return Some((off, p));
            }
            off += p.kind.width();
        }
        None
    }

    /// Validates a full flat parameter list.
    pub fn check(&self, values: &[f64]) -> Result<(), EntryError> {
        if values.len() != self.user_len() {
            return Err(EntryError::Count {
                entry: self.name,
                expected: self.user_len(),
                got: values.len(),
            });
        }
        let mut off = 0;
        for p in self.params {
            let w = p.kind.width();
            p.check(&values[off..off + w])
                .map_err(|error| EntryError::Param {
                    entry: self.name,
                    error,
                })?;
            off += w;
        }
        Ok(())
    }

    /// Appends this entry's parameter-buffer slots for the given user values.
    pub fn bake_into(&self, values: &[f64], out: &mut Vec<f64>) {
        let start = out.len();
        match self.bake {
            Some(f) => f(values, out),
            None => out.extend_from_slice(values),
        }
        debug_assert_eq!(
            out.len() - start,
            self.baked_len,
            "{}: bake wrote a wrong length",
            self.name
        );
    }
}

/// A registry family: one enum per family of declarations.
pub trait Family: Copy + Eq + fmt::Debug + 'static {
    /// Human name of the family ("primitive", "fractal", ...).
    const NOUN: &'static str;
    /// Every member, in opcode order.
    fn all() -> &'static [Self];
    /// The member's declaration.
    fn def(self) -> &'static Def;
    /// Index within the family (the low byte of the opcode).
    fn index(self) -> usize;
    /// Finds a member by its exact name.
    fn from_name(name: &str) -> Option<Self> {
        Self::all().iter().copied().find(|k| k.def().name == name)
    }
}

/// Reads one declared parameter from the parameter buffer as the type the code uses.
#[doc(hidden)]
pub mod read {
    use crate::real::Real;
    use crate::vec3::V3;

    #[inline(always)]
    pub fn scalar<S: Real>(a: &[f64], off: &mut usize) -> S {
        let v = S::splat(a[*off]);
        *off += 1;
        v
    }
    #[inline(always)]
    pub fn int(a: &[f64], off: &mut usize) -> usize {
        let v = a[*off] as usize;
        *off += 1;
        v
    }
    #[inline(always)]
    pub fn vec3<S: Real>(a: &[f64], off: &mut usize) -> V3<S> {
        let v = V3::c(a[*off], a[*off + 1], a[*off + 2]);
        *off += 3;
        v
    }
}

#[doc(hidden)]
#[macro_export]
macro_rules! __param_read {
    ($a:ident, $off:ident, Scalar) => {
        $crate::registry::read::scalar::<S>($a, &mut $off)
    };
    ($a:ident, $off:ident, Int) => {
        $crate::registry::read::int($a, &mut $off)
    };
    ($a:ident, $off:ident, Vec3) => {
        $crate::registry::read::vec3::<S>($a, &mut $off)
    };
}

#[doc(hidden)]
#[macro_export]
macro_rules! __param_default {
    (Vec3, $d:expr) => {
        $d
    };
    ($k:ident, $d:expr) => {
        [$d, 0.0, 0.0]
    };
}

/// Binds each parameter (or each baked slot when a bake is declared) to a local of its name.
#[doc(hidden)]
#[macro_export]
macro_rules! __param_locals {
    ($a:ident, $off:ident; ($($p:ident : $k:ident),*)) => {
        $( let $p = $crate::__param_read!($a, $off, $k); )*
    };
    ($a:ident, $off:ident; ($($p:ident : $k:ident),*) ($($b:ident : $bk:ident),*)) => {
        $( let $b = $crate::__param_read!($a, $off, $bk); )*
    };
}

#[doc(hidden)]
#[macro_export]
macro_rules! __baked_len {
    (($($k:ident),*)) => { 0 $(+ $crate::registry::ParamKind::$k.width())* };
    (($($k:ident),*) ($($bk:ident),*)) => { 0 $(+ $crate::registry::ParamKind::$bk.width())* };
}

#[doc(hidden)]
#[macro_export]
macro_rules! __bake_fn {
    () => {
        None
    };
    ($f:path) => {
        Some($f)
    };
}

/// Declares a family of registry entries. See the family modules for the form; each entry is
/// (`[min, max]` the valid range, `soft [lo, hi]` the slider's range inside it)
///
/// ```text
/// /// Doc line(s).
/// Name [Exact|Bound|Safety] (param: Kind = default, [min, max], soft [lo, hi], "doc", ...)
///     [baked(bake_fn) (slot: Kind, ...)]
///     => expression using the fn arguments and the parameter (or slot) names;
/// ```
#[macro_export]
macro_rules! declare_family {
    (
        $(#[$emeta:meta])*
        family $Kind:ident, noun $noun:literal, table $DEFS:ident;
        fn $fname:ident ( $($arg:ident : $argty:ty),* ) -> $ret:ty;
        $(
            $(#[doc = $doc:literal])+
            $Var:ident [$quality:ident] (
                $($pname:ident : $pkind:ident = $pdef:expr, [$pmin:expr, $pmax:expr], soft [$smin:expr, $smax:expr], $pdoc:literal),* $(,)?
            )
            $( baked($bakefn:path) ( $($bname:ident : $bkind:ident),* $(,)? ) )?
            => $body:expr;
        )*
    ) => {
        $(#[$emeta])*
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
        #[repr(u8)]
        pub enum $Kind {
            $( $(#[doc = $doc])+ $Var ),*
        }

        /// Declarations of this family, indexed by the enum's discriminant.
        pub static $DEFS: &[$crate::registry::Def] = &[
            $(
                $crate::registry::Def {
                    name: stringify!($Var),
                    doc: concat!($($doc, "\n"),+),
                    quality: $crate::registry::Quality::$quality,
                    params: &[
                        $(
                            $crate::registry::ParamSpec {
                                name: stringify!($pname),
                                kind: $crate::registry::ParamKind::$pkind,
                                default: $crate::__param_default!($pkind, $pdef),
                                min: $pmin,
                                max: $pmax,
                                soft_min: $smin,
                                soft_max: $smax,
                                doc: $pdoc,
                            }
                        ),*
                    ],
                    bake: $crate::__bake_fn!($($bakefn)?),
                    baked_len: $crate::__baked_len!(($($pkind),*) $( ($($bkind),*) )?),
                }
            ),*
        ];

        impl $crate::registry::Family for $Kind {
            const NOUN: &'static str = $noun;
            fn all() -> &'static [Self] {
                Self::ALL
            }
            fn def(self) -> &'static $crate::registry::Def {
                &$DEFS[self as usize]
            }
            fn index(self) -> usize {
                self as usize
            }
        }

        impl $Kind {
            /// Every member, in opcode order.
            pub const ALL: &'static [$Kind] = &[$($Kind::$Var),*];

            /// Evaluates this entry reading its parameters from `a` (the parameter buffer,
            /// starting at this entry's offset).
            #[inline(always)]
            #[allow(unused_variables, unused_mut, unused_assignments, clippy::unused_unit)]
            pub fn $fname<S: $crate::real::Real>(self, $($arg: $argty,)* a: &[f64]) -> $ret {
                let mut off = 0usize;
                match self {
                    $(
                        $Kind::$Var => {
                            $crate::__param_locals!(a, off; ($($pname: $pkind),*) $( ($($bname: $bkind),*) )?);
                            $body
                        }
                    )*
                }
            }
        }
    };
}

#[cfg(test)]
mod tests {
    use crate::combine::COMBINES;
    use crate::fractals::FRACTALS;
    use crate::modifiers::MODIFIERS;
    use crate::primitives::PRIMITIVES;
    use crate::transforms::TRANSFORMS;

    /// Every parameter's slider range lies inside its valid range, holds its default, and is
    /// an artist's range: a drag across a 200-pixel slider moves a length by at most a few
    /// hundredths per pixel, an angle by at most two degrees (not the 420000 a linear slider
    /// over [0, 1e6] gave a 36-pixel drag).
    #[test]
    fn every_parameter_declares_a_soft_range_an_artist_can_drag() {
        let tables = [PRIMITIVES, FRACTALS, COMBINES, MODIFIERS, TRANSFORMS];
        let mut checked = 0;
        for def in tables.iter().flat_map(|t| t.iter()) {
            for p in def.params {
                let what = format!("{}.{}", def.name, p.name);
                assert!(p.soft_min < p.soft_max, "{what}: empty soft range");
                assert!(
                    p.min <= p.soft_min && p.soft_max <= p.max,
                    "{what}: soft range [{}, {}] outside [{}, {}]",
                    p.soft_min,
                    p.soft_max,
                    p.min,
                    p.max
                );
                for &d in p.default_values() {
                    assert!(
                        (p.soft_min..=p.soft_max).contains(&d),
                        "{what}: default {d} outside its soft range"
                    );
                }
                let per_px = (p.soft_max - p.soft_min) / 200.0;
                let limit = if p.name.contains("angle")
                    || p.name.contains("rotation")
                    || p.name.contains("offset") && p.soft_max >= 180.0
                    || p.name == "twist"
                {
                    2.0
                } else if p.soft_is_logarithmic() || p.kind == super::ParamKind::Int {
                    f64::INFINITY // a log slider's step is relative; integers step by one
                } else {
                    0.1
                };
                assert!(
                    per_px <= limit,
                    "{what}: {per_px} per pixel over [{}, {}]",
                    p.soft_min,
                    p.soft_max
                );
                checked += 1;
            }
        }
        assert!(checked > 100, "{checked}");
    }
}
