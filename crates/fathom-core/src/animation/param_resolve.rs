//! Parameter paths resolved against a scene ([`ParamPath::resolve`]): where the number a path
//! names is stored and the range it takes (from the registry for shapes and operators, from
//! [`crate::scene::fields`] for materials, lights, the camera and the render settings), and
//! reading and writing it through a [`Resolved`] path. The path syntax is
//! [`crate::param_path`], below the scene model; this sits above it.

use crate::call_serde::did_you_mean;
use crate::limits;
use crate::param_path::{ParamPath, ParamPathError, ParamRange, Seg};
use crate::registry::{Family, ParamKind};
use crate::scene::fields::{
    CAMERA_FIELDS, FieldSpec, LIGHT_FIELDS, MATERIAL_FIELDS, RENDER_FIELDS, Slot,
};
use crate::scene::{Call, Node, Scene};

/// Where a resolved path's number is stored.
#[derive(Clone, Debug, PartialEq)]
enum Loc {
    /// `Call::params[offset]` of a node's shape (`which` 0), combine (1) or operator `2 + i`,
    /// or of IFS operator `i` (`node` None).
    Call {
        node: Option<Vec<usize>>,
        which: usize,
        offset: usize,
    },
    Material {
        node: Vec<usize>,
        field: usize,
        comp: usize,
    },
    Light {
        index: usize,
        field: usize,
        comp: usize,
    },
    Camera {
        field: usize,
        comp: usize,
    },
    Render {
        field: usize,
        comp: usize,
    },
    IfsIterations,
}

/// A path checked against a scene: where its number is and what range it takes. Valid for
/// scenes of the same structure as the one it was resolved against; [`Resolved::get`] and
/// [`Resolved::set`] return `None`/`false` rather than panic on any other.
#[derive(Clone, Debug, PartialEq)]
pub struct Resolved {
    loc: Loc,
    /// The range the number takes: what [`Resolved::set`] clamps to.
    pub range: ParamRange,
}

const COMPONENTS: [&str; 3] = ["x", "y", "z"];
const COLOUR_COMPONENTS: [&str; 3] = ["r", "g", "b"];

impl ParamPath {
    /// Checks the path against `scene`: every step exists and the path ends at one number.
    pub fn resolve(&self, scene: &Scene) -> Result<Resolved, ParamPathError> {
        let missing = |msg: String| ParamPathError::Missing {
            path: self.text.clone(),
            msg,
        };
        let segs = &self.segs;
        let head = &segs[0];
        let rest = &segs[1..];
        match (head.name.as_str(), head.index) {
            ("root", None) => self.resolve_node(scene, rest),
            ("ifs", None) => {
                let ifs = scene
                    .ifs
                    .as_ref()
                    .ok_or_else(|| missing("the scene has no IFS loop (`ifs: None`)".into()))?;
                match rest.first() {
                    Some(Seg { name, index: None }) if name == "iterations" && rest.len() == 1 => {
                        Ok(Resolved {
                            loc: Loc::IfsIterations,
                            range: ParamRange {
                                bounds: Some((0.0, limits::MAX_IFS_ITERATIONS as f64)),
                                int: true,
                            },
                        })
                    }
                    Some(Seg {
                        name,
                        index: Some(i),
                    }) if name == "ops" => {
                        let op = ifs.ops.get(*i).ok_or_else(|| {
                            missing(format!("ifs.ops has {} operators", ifs.ops.len()))
                        })?;
                        let (offset, range) = self.call_param(op, &rest[1..], "ifs.ops")?;
                        Ok(Resolved {
                            loc: Loc::Call {
                                node: None,
                                which: 2 + i,
                                offset,
                            },
                            range,
                        })
                    }
                    _ => Err(missing(
                        "after `ifs` write `iterations` or `ops[N].PARAM`".into(),
                    )),
                }
            }
            ("lights", Some(index)) => {
                scene.lights.get(index).ok_or_else(|| {
                    missing(format!("the scene has {} lights", scene.lights.len()))
                })?;
                let (field, comp, range) = self.field(LIGHT_FIELDS, rest, "light")?;
                Ok(Resolved {
                    loc: Loc::Light { index, field, comp },
                    range,
                })
            }
            ("camera", None) => {
                let (field, comp, range) = self.field(CAMERA_FIELDS, rest, "camera")?;
                Ok(Resolved {
                    loc: Loc::Camera { field, comp },
                    range,
                })
            }
            ("render", None) => {
                let (field, comp, range) = self.field(RENDER_FIELDS, rest, "render")?;
                Ok(Resolved {
                    loc: Loc::Render { field, comp },
                    range,
                })
            }
            _ => Err(missing(format!(
                "a path starts with `root`, `ifs`, `lights[N]`, `camera` or `render`, not `{}`",
                seg_text(head)
            ))),
        }
    }

    fn resolve_node(&self, scene: &Scene, segs: &[Seg]) -> Result<Resolved, ParamPathError> {
        let missing = |msg: String| ParamPathError::Missing {
            path: self.text.clone(),
            msg,
        };
        let mut node: &Node = &scene.root;
        let mut trail = Vec::new();
        let mut where_ = String::from("root");
        let mut k = 0;
        while let Some(Seg {
            name,
            index: Some(i),
        }) = segs.get(k)
        {
            if name != "children" {
                break;
            }
            node = node
                .children
                .get(*i)
                .ok_or_else(|| missing(format!("{where_} has {} children", node.children.len())))?;
            trail.push(*i);
            where_ = format!("{where_}.children[{i}]");
            k += 1;
        }
        let rest = &segs[k..];
        let part = rest.first().ok_or_else(|| {
            missing(format!(
                "{where_} is a node; continue with `.shape.PARAM`, `.combine.PARAM`, \
                 `.ops[N].PARAM` or `.material.FIELD`"
            ))
        })?;
        let call_loc = |which: usize, offset: usize, range| Resolved {
            loc: Loc::Call {
                node: Some(trail.clone()),
                which,
                offset,
            },
            range,
        };
        match (part.name.as_str(), part.index) {
            ("shape", None) => {
                let (offset, range) = self.call_param(&node.shape, &rest[1..], &where_)?;
                Ok(call_loc(0, offset, range))
            }
            ("combine", None) => {
                let (offset, range) = self.call_param(&node.combine, &rest[1..], &where_)?;
                Ok(call_loc(1, offset, range))
            }
            ("ops", Some(i)) => {
                let op = node.ops.get(i).ok_or_else(|| {
                    missing(format!("{where_}.ops has {} operators", node.ops.len()))
                })?;
                let (offset, range) = self.call_param(op, &rest[1..], &where_)?;
                Ok(call_loc(2 + i, offset, range))
            }
            ("material", None) => {
                let (field, comp, range) = self.field(MATERIAL_FIELDS, &rest[1..], "material")?;
                Ok(Resolved {
                    loc: Loc::Material {
                        node: trail,
                        field,
                        comp,
                    },
                    range,
                })
            }
            _ => Err(missing(format!(
                "after a node write `children[N]`, `shape`, `combine`, `ops[N]` or `material`, \
                 not `{}`",
                seg_text(part)
            ))),
        }
    }

    /// The flat offset and range of the parameter `segs` names in a registry call.
    fn call_param<K: Family>(
        &self,
        call: &Call<K>,
        segs: &[Seg],
        owner: &str,
    ) -> Result<(usize, ParamRange), ParamPathError> {
        let def = call.kind.def();
        let missing = |msg: String| ParamPathError::Missing {
            path: self.text.clone(),
            msg,
        };
        let valid = || def.params.iter().map(|p| p.name);
        let Some(first) = segs.first() else {
            return Err(missing(if def.params.is_empty() {
                format!("`{}` in {owner} has no parameters", def.name)
            } else {
                format!(
                    "name a parameter of `{}`: {}",
                    def.name,
                    valid().collect::<Vec<_>>().join(", ")
                )
            }));
        };
        let (offset, spec) = def.param(&first.name).ok_or_else(|| {
            missing(if def.params.is_empty() {
                format!("`{}` has no parameters", def.name)
            } else {
                format!(
                    "`{}` has no parameter `{}`; {}",
                    def.name,
                    first.name,
                    did_you_mean(&first.name, valid())
                )
            })
        })?;
        let comp = self.component(spec.kind.width(), first, &segs[1..], false)?;
        Ok((
            offset + comp,
            ParamRange {
                bounds: Some((spec.min, spec.max)),
                int: spec.kind == ParamKind::Int,
            },
        ))
    }

    /// The field index, component and range `segs` names in a settings structure.
    fn field<T>(
        &self,
        table: &'static [FieldSpec<T>],
        segs: &[Seg],
        noun: &str,
    ) -> Result<(usize, usize, ParamRange), ParamPathError> {
        let missing = |msg: String| ParamPathError::Missing {
            path: self.text.clone(),
            msg,
        };
        let names = || table.iter().map(|f| f.name);
        let first = segs.first().ok_or_else(|| {
            missing(format!(
                "name a {noun} field: {}",
                names().collect::<Vec<_>>().join(", ")
            ))
        })?;
        let field = table
            .iter()
            .position(|f| f.name == first.name)
            .ok_or_else(|| {
                missing(format!(
                    "a {noun} has no field `{}`; {}",
                    first.name,
                    did_you_mean(&first.name, names())
                ))
            })?;
        let spec = &table[field];
        let colour =
            spec.name.contains("colour") || spec.name.starts_with("sky") || spec.name == "albedo";
        let comp = self.component(spec.width, first, &segs[1..], colour)?;
        Ok((
            field,
            comp,
            ParamRange {
                bounds: spec.range,
                int: spec.int,
            },
        ))
    }

    /// The component a value of `width` numbers is narrowed to: `name[i]`, `name.x` or (for
    /// colours) `name.r`; none needed for a single number.
    fn component(
        &self,
        width: usize,
        seg: &Seg,
        rest: &[Seg],
        colour: bool,
    ) -> Result<usize, ParamPathError> {
        let missing = |msg: String| ParamPathError::Missing {
            path: self.text.clone(),
            msg,
        };
        let comp = match (seg.index, rest) {
            (None, []) => None,
            (Some(i), []) => Some(i),
            (None, [Seg { name, index: None }]) if width == 3 => {
                let names = if colour {
                    COLOUR_COMPONENTS
                } else {
                    COMPONENTS
                };
                let i = names
                    .iter()
                    .chain(if colour {
                        &COMPONENTS
                    } else {
                        &COLOUR_COMPONENTS
                    })
                    .position(|c| c == name)
                    .map(|i| i % 3)
                    .ok_or_else(|| {
                        missing(format!(
                            "`{}` has components {}",
                            seg.name,
                            names.map(|c| format!("`.{c}`")).join(", ")
                        ))
                    })?;
                Some(i)
            }
            (
                None,
                [
                    Seg {
                        name,
                        index: Some(i),
                    },
                ],
            ) if name.is_empty() => Some(*i),
            _ => {
                let extra: Vec<String> = rest.iter().map(seg_text).collect();
                return Err(missing(format!(
                    "`{}` is a number; nothing follows it (found `.{}`)",
                    seg.name,
                    extra.join(".")
                )));
            }
        };
        match comp {
            None if width == 1 => Ok(0),
            None => Err(ParamPathError::NeedsComponent {
                path: self.text.clone(),
                width,
                first: if width == 3 {
                    if colour { "r" } else { "x" }.into()
                } else {
                    "[0]".into()
                },
            }),
            Some(i) if i < width => Ok(i),
            Some(i) => Err(missing(format!(
                "`{}` has {width} component(s); [{i}] is out of range",
                seg.name
            ))),
        }
    }
}

fn seg_text(s: &Seg) -> String {
    match s.index {
        Some(i) => format!("{}[{i}]", s.name),
        None => s.name.clone(),
    }
}

fn node_mut<'a>(root: &'a mut Node, trail: &[usize]) -> Option<&'a mut Node> {
    let mut n = root;
    for &i in trail {
        n = n.children.get_mut(i)?;
    }
    Some(n)
}

fn call_slot<'a>(
    scene: &'a mut Scene,
    node: &Option<Vec<usize>>,
    which: usize,
) -> Option<&'a mut Vec<f64>> {
    match node {
        None => Some(
            &mut scene
                .ifs
                .as_mut()?
                .ops
                .get_mut(which.checked_sub(2)?)?
                .params,
        ),
        Some(trail) => {
            let n = node_mut(&mut scene.root, trail)?;
            Some(match which {
                0 => &mut n.shape.params,
                1 => &mut n.combine.params,
                _ => &mut n.ops.get_mut(which - 2)?.params,
            })
        }
    }
}

fn field_slot<'a, T>(
    table: &'static [FieldSpec<T>],
    field: usize,
    v: &'a mut T,
    comp: usize,
) -> Option<NumMut<'a>> {
    match (table.get(field)?.slot)(v) {
        Slot::Reals(r) => r.get_mut(comp).map(NumMut::Real),
        Slot::Count(c) => (comp == 0).then_some(NumMut::Count(c)),
    }
}

enum NumMut<'a> {
    Real(&'a mut f64),
    Count(&'a mut u32),
}

impl Resolved {
    fn slot<'a>(&self, scene: &'a mut Scene) -> Option<NumMut<'a>> {
        match &self.loc {
            Loc::Call {
                node,
                which,
                offset,
            } => call_slot(scene, node, *which)?
                .get_mut(*offset)
                .map(NumMut::Real),
            Loc::Material { node, field, comp } => field_slot(
                MATERIAL_FIELDS,
                *field,
                &mut node_mut(&mut scene.root, node)?.material,
                *comp,
            ),
            Loc::Light { index, field, comp } => {
                field_slot(LIGHT_FIELDS, *field, scene.lights.get_mut(*index)?, *comp)
            }
            Loc::Camera { field, comp } => {
                field_slot(CAMERA_FIELDS, *field, &mut scene.camera, *comp)
            }
            Loc::Render { field, comp } => {
                field_slot(RENDER_FIELDS, *field, &mut scene.render, *comp)
            }
            Loc::IfsIterations => Some(NumMut::Count(&mut scene.ifs.as_mut()?.iterations)),
        }
    }

    /// The number in `scene`, or `None` when the scene no longer has it.
    pub fn get(&self, scene: &Scene) -> Option<f64> {
        // Settings structures are small; reading through a copy keeps one accessor per field.
        let mut copy = match &self.loc {
            Loc::Call { .. } | Loc::Material { .. } | Loc::IfsIterations => None,
            _ => Some(scene.clone()),
        };
        let read = |s: NumMut<'_>| match s {
            NumMut::Real(r) => *r,
            NumMut::Count(c) => *c as f64,
        };
        match &mut copy {
            Some(c) => self.slot(c).map(read),
            None => self.get_tree(scene),
        }
    }

    fn get_tree(&self, scene: &Scene) -> Option<f64> {
        let node = |trail: &[usize]| {
            let mut n = &scene.root;
            for &i in trail {
                n = n.children.get(i)?;
            }
            Some(n)
        };
        match &self.loc {
            Loc::Call {
                node: None,
                which,
                offset,
            } => scene
                .ifs
                .as_ref()?
                .ops
                .get(which.checked_sub(2)?)?
                .params
                .get(*offset)
                .copied(),
            Loc::Call {
                node: Some(trail),
                which,
                offset,
            } => {
                let n = node(trail)?;
                let params = match which {
                    0 => &n.shape.params,
                    1 => &n.combine.params,
                    _ => &n.ops.get(which - 2)?.params,
                };
                params.get(*offset).copied()
            }
            Loc::Material {
                node: trail,
                field,
                comp,
            } => MATERIAL_FIELDS
                .get(*field)?
                .read(&node(trail)?.material)
                .get(*comp)
                .copied(),
            Loc::IfsIterations => Some(scene.ifs.as_ref()?.iterations as f64),
            _ => None,
        }
    }

    /// Writes `value`, clamped into the declared range (rounded when whole). Returns the value
    /// written, or `None` (and writes nothing) when `value` is not finite or the scene no
    /// longer has this number.
    pub fn set(&self, scene: &mut Scene, value: f64) -> Option<f64> {
        let v = self.range.clamp(value)?;
        match self.slot(scene)? {
            NumMut::Real(r) => *r = v,
            NumMut::Count(c) => *c = v.clamp(0.0, u32::MAX as f64) as u32,
        }
        Some(v)
    }

    /// Whether the number is part of the camera (a window flies its own camera and needs to
    /// hear about these).
    pub fn is_camera(&self) -> bool {
        matches!(self.loc, Loc::Camera { .. })
    }
}

/// Parses and resolves in one step.
pub fn resolve(scene: &Scene, text: &str) -> Result<Resolved, ParamPathError> {
    ParamPath::parse(text)?.resolve(scene)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::presets;

    fn scene() -> Scene {
        presets::load("model-tree").unwrap()
    }

    #[test]
    fn paths_reach_every_kind_of_number_and_set_clamps_to_the_declared_range() {
        let mut s = presets::load("psychedelic-tile").unwrap();
        let cases = [
            "root.material.specular",
            "root.children[0].material.albedo.g",
            "lights[0].intensity",
            "lights[0].direction.y",
            "camera.fov",
            "camera.eye.x",
            "render.fog",
            "render.max_steps",
            "render.palette[5]",
            "ifs.iterations",
            "ifs.ops[1].angle",
            "ifs.ops[3].centre.z",
        ];
        for text in cases {
            let r = resolve(&s, text).unwrap_or_else(|e| panic!("{text}: {e}"));
            let before = r.get(&s).unwrap();
            let want = match r.range.bounds {
                Some((lo, hi)) => lo + 0.25 * (hi - lo).min(8.0),
                None => before + 0.5,
            };
            let want = r.range.clamp(want).unwrap();
            assert_eq!(r.set(&mut s, want), Some(want), "{text}");
            assert_eq!(r.get(&s), Some(want), "{text}");
            if let Some((lo, hi)) = r.range.bounds {
                assert_eq!(r.set(&mut s, hi + 1e9), Some(hi), "{text}");
                assert_eq!(r.set(&mut s, lo - 1e9), Some(lo), "{text}");
            }
            assert_eq!(r.set(&mut s, f64::NAN), None, "{text}");
        }
        s.validate().unwrap();
    }

    #[test]
    fn registry_parameters_and_vector_components() {
        let mut s = scene();
        // RoundBox(size: (1, 1, 1), radius: 0.08); a rotation on a grandchild.
        let r = resolve(&s, "root.shape.size.y").unwrap();
        assert_eq!(r.set(&mut s, 0.7), Some(0.7));
        assert_eq!(s.root.shape.params[..3], [1.0, 0.7, 1.0]);
        let r = resolve(&s, "root.shape.size[2]").unwrap();
        r.set(&mut s, 0.6).unwrap();
        assert_eq!(s.root.shape.params[2], 0.6);
        let r = resolve(&s, "root.children[1].children[0].ops[0].angle").unwrap();
        assert_eq!(r.get(&s), Some(90.0));
        r.set(&mut s, 45.0).unwrap();
        assert_eq!(s.root.children[1].children[0].ops[0].params[3], 45.0);
        let r = resolve(&s, "root.children[0].combine").unwrap_err();
        assert!(
            r.to_string()
                .contains("`Intersect` in root.children[0] has no parameters"),
            "{r}"
        );
        s.validate().unwrap();
    }

    #[test]
    fn bad_paths_say_what_exists() {
        let s = scene();
        let err = |t: &str| resolve(&s, t).unwrap_err().to_string();
        assert!(err("root.children[99].shape.radius").contains("children"));
        assert!(err("root.materal.specular").contains("material"));
        assert!(err("root.material.specularr").contains("did you mean `specular`"));
        assert!(err("lights[3].intensity").contains("2 lights"));
        assert!(err("camera.eye").contains("camera.eye.x"));
        assert!(err("camera.eye.w").contains(".x"));
        assert!(err("camera.fov.x").contains("nothing follows"));
        assert!(err("ifs.iterations").contains("no IFS loop"));
        assert!(err("").contains("empty"));
        assert!(err("root..shape").contains("expected a name"));
        assert!(err("root.children[x]").contains("whole number"));
        assert!(err("sky.fog").contains("starts with"));
        assert!(err("render.palette[12]").contains("out of range"));
    }

    #[test]
    fn a_stale_path_is_none_not_a_panic() {
        let mut s = scene();
        let r = resolve(&s, "root.children[1].material.specular").unwrap();
        s.root.children.clear();
        assert_eq!(r.get(&s), None);
        assert_eq!(r.set(&mut s, 0.5), None);
    }

    /// A parameter path through `scene`'s tree chosen by `picks` (each pick chooses a child,
    /// an operator, the shape, the material or the combine; indices and names are sometimes
    /// one past what exists), so that most resolve and some fail in each place.
    fn walk_path(scene: &Scene, picks: &[u32]) -> String {
        fn param<K: Family>(c: &Call<K>, pick: u32) -> String {
            let params = c.kind.def().params;
            let Some(p) = params.get(pick as usize % (params.len() + 1)) else {
                return "nope".into();
            };
            match p.kind {
                ParamKind::Vec3 => format!("{}.{}", p.name, COMPONENTS[pick as usize / 7 % 3]),
                _ => p.name.into(),
            }
        }
        let mut node = &scene.root;
        let mut path = String::from("root");
        for &pick in picks {
            let k = pick as usize / 5;
            match pick % 5 {
                0 => {
                    let i = k % (node.children.len() + 1);
                    path += &format!(".children[{i}]");
                    match node.children.get(i) {
                        Some(c) => node = c,
                        None => return path + ".shape",
                    }
                    continue;
                }
                1 => path += &format!(".shape.{}", param(&node.shape, pick / 5)),
                2 => {
                    let i = k % (node.ops.len() + 1);
                    let rest = node.ops.get(i).map_or("x".into(), |o| param(o, pick / 5));
                    path += &format!(".ops[{i}].{rest}");
                }
                3 => {
                    let f = [
                        "specular",
                        "shininess",
                        "trap_colour",
                        "albedo.r",
                        "albedo.b",
                    ];
                    path += &format!(".material.{}", f[k % f.len()]);
                }
                _ => path += &format!(".combine.{}", param(&node.combine, pick / 5)),
            }
            return path;
        }
        path
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(256))]

        /// Paths through every preset's tree (see `walk_path`), and stray text after them: a
        /// path that resolves reads and sets any number without panicking; what it sets lies
        /// in its declared range and leaves the scene valid; one that does not resolve gives
        /// an error. The camera, lights and render settings are covered by the tests above.
        #[test]
        fn paths_through_every_preset_resolve_or_fail_and_never_panic(
            preset in 0..presets::PRESETS.len(),
            picks in proptest::collection::vec(proptest::prelude::any::<u32>(), 0..6),
            tail in proptest::prop_oneof![
                3 => proptest::strategy::Just(""),
                1 => proptest::sample::select(vec![
                    ".x", "[0]", ".", " ", "..y", "[99999999999999999999]", "\u{e9}",
                ]),
            ],
            value in proptest::prop_oneof![
                proptest::num::f64::ANY,
                proptest::sample::select(vec![f64::NAN, f64::INFINITY, -1e300, 0.0, 1e300]),
            ],
        ) {
            let mut s = presets::load(presets::PRESETS[preset].name).unwrap();
            let text = walk_path(&s, &picks) + tail;
            match resolve(&s, &text) {
                Ok(r) => {
                    let _ = r.get(&s);
                    match r.set(&mut s, value) {
                        Some(v) => {
                            proptest::prop_assert_eq!(r.get(&s), Some(v));
                            if let Some((lo, hi)) = r.range.bounds {
                                proptest::prop_assert!((lo..=hi).contains(&v), "{} = {}", text, v);
                            }
                            proptest::prop_assert!(s.validate().is_ok(), "{} = {}", text, v);
                        }
                        None => {
                            proptest::prop_assert!(!value.is_finite(), "{} refused {}", text, value)
                        }
                    }
                }
                Err(e) => proptest::prop_assert!(!e.to_string().is_empty()),
            }
        }
    }
}
