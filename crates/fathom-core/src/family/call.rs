//! One use of a registry entry with its parameter values ([`Call`]), and the two unions of
//! families a scene node uses: its shape ([`Shape`]: primitive or fractal) and the entries of
//! its operator list ([`DomainOp`]: point operator or distance modifier). They sit with the
//! registry, below the scene, so that everything reading calls (serialisation, parameter
//! paths, the tape) need not import the scene model.

use crate::combine::Combine;
use crate::fractals::Fractal;
use crate::modifiers::Modifier;
use crate::primitives::Primitive;
use crate::registry::{Def, EntryError, Family};
use crate::transforms::Transform;
use std::sync::LazyLock;

/// A node's shape: a primitive or a fractal.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Shape {
    /// A primitive shape.
    Primitive(Primitive),
    /// A fractal.
    Fractal(Fractal),
}

static SHAPES: LazyLock<Vec<Shape>> = LazyLock::new(|| {
    Primitive::ALL
        .iter()
        .map(|&p| Shape::Primitive(p))
        .chain(Fractal::ALL.iter().map(|&f| Shape::Fractal(f)))
        .collect()
});

impl Family for Shape {
    const NOUN: &'static str = "shape";
    fn all() -> &'static [Self] {
        &SHAPES
    }
    fn def(self) -> &'static Def {
        match self {
            Shape::Primitive(p) => p.def(),
            Shape::Fractal(f) => f.def(),
        }
    }
    fn index(self) -> usize {
        match self {
            Shape::Primitive(p) => p.index(),
            Shape::Fractal(f) => Primitive::ALL.len() + f.index(),
        }
    }
}

/// An entry of a node's operator list: a point operator or a distance modifier.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum DomainOp {
    /// A point operator (moves, folds, repeats the point before the shape sees it).
    Transform(Transform),
    /// A distance modifier (changes the distance the shape returns).
    Modifier(Modifier),
}

static DOMAIN_OPS: LazyLock<Vec<DomainOp>> = LazyLock::new(|| {
    Transform::ALL
        .iter()
        .map(|&t| DomainOp::Transform(t))
        .chain(Modifier::ALL.iter().map(|&m| DomainOp::Modifier(m)))
        .collect()
});

impl Family for DomainOp {
    const NOUN: &'static str = "domain operator";
    fn all() -> &'static [Self] {
        &DOMAIN_OPS
    }
    fn def(self) -> &'static Def {
        match self {
            DomainOp::Transform(t) => t.def(),
            DomainOp::Modifier(m) => m.def(),
        }
    }
    fn index(self) -> usize {
        match self {
            DomainOp::Transform(t) => t.index(),
            DomainOp::Modifier(m) => Transform::ALL.len() + m.index(),
        }
    }
}

/// One use of a registry entry with its parameter values (flat, in declaration order).
#[derive(Clone, Debug, PartialEq)]
pub struct Call<K> {
    /// Which entry is used.
    pub kind: K,
    /// Its parameter values, flat, in declaration order.
    pub params: Vec<f64>,
}

impl<K: Family> Call<K> {
    /// The entry with all parameters at their defaults.
    pub fn new(kind: K) -> Self {
        Call {
            kind,
            params: kind.def().defaults(),
        }
    }

    /// Sets a parameter by name, checking it against its declared range.
    pub fn set(&mut self, name: &str, values: &[f64]) -> Result<(), EntryError> {
        let def = self.kind.def();
        let (off, spec) = def.param(name).ok_or_else(|| EntryError::NoSuchParam {
            entry: def.name,
            name: name.into(),
            valid: def.params.iter().map(|p| p.name).collect(),
        })?;
        spec.check(values).map_err(|error| EntryError::Param {
            entry: def.name,
            error,
        })?;
        self.params[off..off + values.len()].copy_from_slice(values);
        Ok(())
    }

    /// Builder form of [`Call::set`]; panics on a bad name or value, for code-built scenes.
    #[track_caller]
    pub fn with(mut self, name: &str, values: &[f64]) -> Self {
        if let Err(e) = self.set(name, values) {
            panic!("{e}");
        }
        self
    }

    /// A parameter's values by name.
    pub fn get(&self, name: &str) -> Option<&[f64]> {
        let (off, spec) = self.kind.def().param(name)?;
        Some(&self.params[off..off + spec.kind.width()])
    }

    /// Checks every parameter against its declaration.
    pub fn check(&self) -> Result<(), EntryError> {
        self.kind.def().check(&self.params)
    }
}

macro_rules! into_call {
    ($K:ty => $W:ident :: $V:ident) => {
        impl From<$K> for Call<$W> {
            fn from(k: $K) -> Self {
                Call::new($W::$V(k))
            }
        }
        impl From<Call<$K>> for Call<$W> {
            fn from(c: Call<$K>) -> Self {
                Call {
                    kind: $W::$V(c.kind),
                    params: c.params,
                }
            }
        }
    };
}
into_call!(Primitive => Shape::Primitive);
into_call!(Fractal => Shape::Fractal);
into_call!(Transform => DomainOp::Transform);
into_call!(Modifier => DomainOp::Modifier);

impl From<Combine> for Call<Combine> {
    fn from(c: Combine) -> Self {
        Call::new(c)
    }
}
