//! Proptest strategies for random scenes, built from the registry tables, for fuzzing the scene
//! parser and tape compiler and for property tests that compare evaluators.
//!
//! Available to this crate's tests and, with the `testing` feature, to other crates' tests.
//!
//! - [`Mode::Valid`] scenes pass [`Scene::validate`]: every parameter lies in its declared
//!   range (near the "interesting" part of wide ranges, so evaluations stay finite), trees stay
//!   within [`limits`].
//! - [`Mode::Wild`] scenes mix in out-of-range, fractional, huge and non-finite parameters,
//!   over-long operator lists, IFS loops past the iteration limit and trees deeper than the
//!   limit, to check that bad input is refused cleanly.

use crate::combine::Combine;
use crate::limits;
use crate::registry::{Family, ParamKind, ParamSpec};
use crate::scene::{Call, DomainOp, Ifs, Material, Node, Scene, Shape};
use crate::transforms::Transform;
use proptest::prelude::*;
use std::path::{Path, PathBuf};

/// Whether generated scenes must be valid.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mode {
    /// Everything in range and within the limits.
    Valid,
    /// Anything, including values and shapes that must be refused.
    Wild,
}

/// The sub-range valid values are drawn from: the declared range, narrowed to about [-4, 4]
/// (or 4 wide from the nearer bound) when it is wider, so random scenes stay numerically tame.
pub fn tame_range(spec: &ParamSpec) -> (f64, f64) {
    let (lo, hi) = (spec.min, spec.max);
    let (a, b) = (lo.max(-4.0), hi.min(4.0));
    if a <= b {
        (a, b)
    } else if lo > 4.0 {
        (lo, hi.min(lo + 4.0))
    } else {
        (lo.max(hi - 4.0), hi)
    }
}

/// One valid value of a parameter component (whole numbers for `Int`, capped 8 above the
/// minimum so iteration counts stay cheap).
fn valid_component(spec: &'static ParamSpec) -> BoxedStrategy<f64> {
    let (lo, hi) = tame_range(spec);
    match spec.kind {
        ParamKind::Int => {
            let lo = lo.ceil();
            let hi = hi.floor().min(lo + 8.0).max(lo);
            (lo as i64..=hi as i64).prop_map(|i| i as f64).boxed()
        }
        _ if lo == hi => Just(lo).boxed(),
        _ => prop_oneof![
            1 => Just(lo),
            1 => Just(hi),
            8 => lo..=hi,
        ]
        .boxed(),
    }
}

/// A component that is usually valid and sometimes not.
fn wild_component(spec: &'static ParamSpec) -> BoxedStrategy<f64> {
    let (min, max) = (spec.min, spec.max);
    prop_oneof![
        6 => valid_component(spec),
        1 => Just(min - 1.0),
        1 => Just(max + 1.0),
        1 => Just(min + 0.5),
        1 => prop_oneof![
            Just(f64::NAN),
            Just(f64::INFINITY),
            Just(f64::NEG_INFINITY),
            Just(1e300),
            Just(-1e300),
            Just(f64::MIN_POSITIVE),
            Just(-0.0),
        ],
        1 => any::<f64>(),
    ]
    .boxed()
}

/// Random parameter values (flat) for one declaration.
fn params_for(params: &'static [ParamSpec], mode: Mode) -> BoxedStrategy<Vec<f64>> {
    let parts: Vec<BoxedStrategy<f64>> = params
        .iter()
        .flat_map(|p| {
            (0..p.kind.width()).map(move |_| match mode {
                Mode::Valid => valid_component(p),
                Mode::Wild => wild_component(p),
            })
        })
        .collect();
    parts.boxed()
}

/// A random call of any member of family `K`.
pub fn arb_call<K: Family>(mode: Mode) -> BoxedStrategy<Call<K>> {
    let all = K::all();
    (0..all.len())
        .prop_flat_map(move |i| {
            let kind = all[i];
            params_for(kind.def().params, mode).prop_map(move |params| Call { kind, params })
        })
        .boxed()
}

/// A random material (in range for `Valid`).
pub fn arb_material(mode: Mode) -> BoxedStrategy<Material> {
    let unit = || match mode {
        Mode::Valid => (0.0..=1.0f64).boxed(),
        Mode::Wild => prop_oneof![4 => 0.0..=1.0f64, 1 => Just(-1.0), 1 => Just(f64::NAN)].boxed(),
    };
    ([unit(), unit(), unit()], unit(), 1.0..=256.0f64, unit())
        .prop_map(|(albedo, specular, shininess, trap_colour)| Material {
            albedo,
            specular,
            shininess,
            trap_colour,
            ..Material::default()
        })
        .boxed()
}

/// A node without children.
fn arb_leaf(mode: Mode) -> BoxedStrategy<Node> {
    let max_ops = match mode {
        Mode::Valid => 4,
        Mode::Wild => 6,
    };
    (
        arb_call::<Combine>(mode),
        arb_call::<Shape>(mode),
        prop::collection::vec(arb_call::<DomainOp>(mode), 0..max_ops),
        arb_material(mode),
    )
        .prop_map(|(combine, shape, ops, material)| Node {
            combine,
            shape,
            ops,
            material,
            children: Vec::new(),
        })
        .boxed()
}

/// A random tree of up to `depth` levels (a lone node has depth 1) and about `size` nodes.
pub fn arb_node(mode: Mode, depth: u32, size: u32) -> BoxedStrategy<Node> {
    arb_leaf(mode)
        .prop_recursive(depth.saturating_sub(1), size, 3, move |inner| {
            (arb_leaf(mode), prop::collection::vec(inner, 0..4)).prop_map(|(mut n, children)| {
                n.children = children;
                n
            })
        })
        .boxed()
}

/// A chain of `len` nodes, each the only child of the one before: the deepest tree for its
/// size, for probing the depth limit.
pub fn arb_chain(mode: Mode, len: std::ops::RangeInclusive<usize>) -> BoxedStrategy<Node> {
    prop::collection::vec(arb_leaf(mode), len)
        .prop_map(|nodes| {
            nodes
                .into_iter()
                .rev()
                .reduce(|child, mut parent| {
                    parent.children.push(child);
                    parent
                })
                .expect("at least one node")
        })
        .boxed()
}

/// An optional IFS loop over random transforms.
pub fn arb_ifs(mode: Mode) -> BoxedStrategy<Option<Ifs>> {
    let iterations = match mode {
        Mode::Valid => (0..=6u32).boxed(),
        Mode::Wild => prop_oneof![
            4 => 0..=6u32,
            1 => Just(limits::MAX_IFS_ITERATIONS),
            1 => Just(limits::MAX_IFS_ITERATIONS + 1),
            1 => Just(u32::MAX),
        ]
        .boxed(),
    };
    let ops_len = match mode {
        Mode::Valid => 0..6usize,
        Mode::Wild => 0..(limits::MAX_OPS_PER_LIST + 3),
    };
    prop::option::weighted(
        0.4,
        (
            iterations,
            prop::collection::vec(arb_call::<Transform>(mode), ops_len),
        )
            .prop_map(|(iterations, ops)| Ifs { iterations, ops }),
    )
    .boxed()
}

/// A random scene (default camera, lights and render settings).
pub fn arb_scene(mode: Mode) -> BoxedStrategy<Scene> {
    let root = match mode {
        Mode::Valid => prop_oneof![
            4 => arb_node(mode, 4, 12),
            1 => arb_chain(mode, 1..=limits::MAX_TREE_DEPTH),
        ]
        .boxed(),
        Mode::Wild => prop_oneof![
            4 => arb_node(mode, 5, 24),
            1 => arb_chain(mode, 1..=limits::MAX_TREE_DEPTH + 4),
        ]
        .boxed(),
    };
    (root, arb_ifs(mode))
        .prop_map(|(root, ifs)| Scene {
            ifs,
            ..Scene::new(root)
        })
        .boxed()
}

/// The seeded generator tests draw numbers from, so failures reproduce from the seed.
pub use crate::rng::SplitMix64;

/// An empty scratch directory for a test: `fathom-NAME-PID` in the system's temporary
/// directory, emptied if an earlier run left it.
pub fn scratch_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("fathom-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// The names of the entries of `dir`, sorted.
pub fn file_names(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}
