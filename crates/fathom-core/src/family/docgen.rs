//! The registry as documentation: the groups `fathom list` prints, the formatting of kinds,
//! defaults and ranges they share, and `docs/scene-reference.md`, generated from the
//! declarations so the reference cannot drift from the code (a test compares the committed
//! file with a fresh rendering; `FATHOM_BLESS=1` rewrites it).

use crate::combine::COMBINES;
use crate::fractals::FRACTALS;
use crate::modifiers::MODIFIERS;
use crate::presets::{DEFAULT_PRESET, PRESETS};
use crate::primitives::PRIMITIVES;
use crate::registry::{Def, ParamKind, ParamSpec, fmt_num};
use crate::transforms::TRANSFORMS;
use std::fmt::Write;

/// One registry table with how it is presented.
pub struct Group {
    /// Machine name (`primitives`, `transforms`, ...), used as the JSON key.
    pub key: &'static str,
    /// Heading.
    pub title: &'static str,
    /// Where in a scene file its entries are written.
    pub used_in: &'static str,
    /// The table's entries.
    pub defs: &'static [Def],
}

/// Shapes: what a node can be.
pub fn shape_groups() -> [Group; 2] {
    [
        Group {
            key: "primitives",
            title: "Primitives",
            used_in: "a node's `shape`",
            defs: PRIMITIVES,
        },
        Group {
            key: "fractals",
            title: "Fractals",
            used_in: "a node's `shape`",
            defs: FRACTALS,
        },
    ]
}

/// Operators: transforms (point maps, also usable in the IFS loop), distance modifiers and
/// combines.
pub fn operator_groups() -> [Group; 3] {
    [
        Group {
            key: "transforms",
            title: "Transforms",
            used_in: "a node's `ops` list and the `ifs` loop's `ops`",
            defs: TRANSFORMS,
        },
        Group {
            key: "modifiers",
            title: "Distance modifiers",
            used_in: "a node's `ops` list",
            defs: MODIFIERS,
        },
        Group {
            key: "combines",
            title: "Combine operators",
            used_in: "a child node's `combine`",
            defs: COMBINES,
        },
    ]
}

/// The kind as written in listings.
pub fn kind_name(kind: ParamKind) -> &'static str {
    match kind {
        ParamKind::Scalar => "scalar",
        ParamKind::Int => "int",
        ParamKind::Vec3 => "vec3",
    }
}

/// One number as a scene file would show it (whole numbers without a fraction, exponents for
/// very large or small magnitudes).
pub fn fmt_value(x: f64) -> String {
    if x != 0.0 && x.abs() < 1e-3 {
        format!("{x:e}")
    } else {
        fmt_num(x)
    }
}

/// The default as written in a scene file: `1`, `(0, 1, 0)`.
pub fn fmt_default(spec: &ParamSpec) -> String {
    let v = spec.default_values();
    if spec.kind == ParamKind::Vec3 {
        format!(
            "({}, {}, {})",
            fmt_value(v[0]),
            fmt_value(v[1]),
            fmt_value(v[2])
        )
    } else {
        fmt_value(v[0])
    }
}

/// The closed range, `[min, max]` (for vectors it applies to each component).
pub fn fmt_range(spec: &ParamSpec) -> String {
    format!("[{}, {}]", fmt_value(spec.min), fmt_value(spec.max))
}

/// The slider's range, `[lo, hi]`, with `log` when the slider is logarithmic.
pub fn fmt_soft_range(spec: &ParamSpec) -> String {
    format!(
        "[{}, {}]{}",
        fmt_value(spec.soft_min),
        fmt_value(spec.soft_max),
        if spec.soft_is_logarithmic() {
            " log"
        } else {
            ""
        }
    )
}

/// The first line of an entry's doc.
pub fn first_line(doc: &str) -> &str {
    doc.lines().next().unwrap_or("").trim()
}

/// The first sentence of an entry's doc (up to the first `. `), for one-line listings.
pub fn summary(doc: &str) -> String {
    let p = paragraph(doc);
    // The first `. ` outside inline code.
    let mut in_code = false;
    let bytes = p.as_bytes();
    for (i, &b) in bytes.iter().enumerate() {
        match b {
            b'`' => in_code = !in_code,
            b'.' if !in_code && bytes.get(i + 1) == Some(&b' ') => return p[..=i].to_string(),
            _ => {}
        }
    }
    p
}

/// The doc as one paragraph.
pub fn paragraph(doc: &str) -> String {
    doc.split_whitespace().collect::<Vec<_>>().join(" ")
}

/// How the entry is written with every parameter at its default: `Torus(major: 1, minor: 0.25)`,
/// or `FoldAbs` for entries without parameters.
pub fn example_call(def: &Def) -> String {
    if def.params.is_empty() {
        return def.name.to_string();
    }
    let args: Vec<String> = def
        .params
        .iter()
        .map(|p| format!("{}: {}", p.name, fmt_default(p)))
        .collect();
    format!("{}({})", def.name, args.join(", "))
}

fn group_markdown(out: &mut String, g: &Group) {
    let _ = writeln!(out, "## {}\n", g.title);
    let _ = writeln!(out, "Written in {}. {} entries.\n", g.used_in, g.defs.len());
    for def in g.defs {
        let _ = writeln!(out, "### `{}`\n", def.name);
        let _ = writeln!(out, "{}\n", paragraph(def.doc));
        let _ = writeln!(out, "- Distance quality: {}", def.quality);
        let _ = writeln!(out, "- Written: `{}`\n", example_call(def));
        if !def.params.is_empty() {
            out.push_str("| parameter | kind | default | range | slider | meaning |\n");
            out.push_str("|---|---|---|---|---|---|\n");
            for p in def.params {
                let _ = writeln!(
                    out,
                    "| `{}` | {} | `{}` | {} | {} | {} |",
                    p.name,
                    kind_name(p.kind),
                    fmt_default(p),
                    fmt_range(p),
                    fmt_soft_range(p),
                    p.doc.replace('|', "\\|")
                );
            }
            out.push('\n');
        }
    }
}

/// The fields of a node's `material`, from [`crate::scene::fields::MATERIAL_FIELDS`].
fn material_markdown(out: &mut String) {
    let defaults = crate::scene::Material::default();
    out.push_str(
        "## Materials\n\n\
         A node's `material: (...)`; fields left out take their defaults. The first four drive \
         every renderer; the rest are the path tracer's (`fathom render --integrator path`), \
         which also maps `shininess` to its GGX roughness (see docs/pathtrace.md).\n\n\
         | field | components | default | range | meaning |\n|---|---|---|---|---|\n",
    );
    for f in crate::scene::fields::MATERIAL_FIELDS {
        let d: Vec<String> = f.read(&defaults).iter().map(|v| format!("{v}")).collect();
        let range = f
            .range
            .map_or("any finite".to_string(), |(lo, hi)| format!("[{lo}, {hi}]"));
        let _ = writeln!(
            out,
            "| `{}` | {} | {} | {} | {} |",
            f.name,
            f.width,
            d.join(", "),
            range,
            f.doc.replace('|', "\\|")
        );
    }
    out.push('\n');
}

/// The whole of `docs/scene-reference.md`.
pub fn scene_reference_markdown() -> String {
    let mut out = String::new();
    out.push_str(
        "# Scene reference\n\n\
         <!-- Generated by fathom_core::docgen::scene_reference_markdown from the registry \
         declarations. Do not edit: run `FATHOM_BLESS=1 cargo test -p fathom-core docgen` \
         to regenerate. -->\n\n\
         Every shape and operator a scene file can name, with its parameters. Parameters left \
         out take their defaults; a bare name (`Sphere`) takes all defaults. Values outside a \
         range are refused with an error naming the range; vector ranges apply to each \
         component. The *slider* range is what the explorer's sliders cover (typed values may \
         go anywhere in the range). `fathom list` prints the same tables. The format itself is described in \
         [scene-format.md](scene-format.md).\n\n\
         Distance quality: **exact** is the true Euclidean distance; **bound** never exceeds \
         it (safe for sphere tracing); **bound with safety factor** means the operator \
         stretches space and multiplies distances by its `safety` parameter.\n\n",
    );
    out.push_str("## Contents\n\n");
    for g in shape_groups().iter().chain(operator_groups().iter()) {
        let names: Vec<String> = g.defs.iter().map(|d| format!("`{}`", d.name)).collect();
        let _ = writeln!(out, "- {}: {}", g.title, names.join(", "));
    }
    out.push_str("- Materials\n- Presets\n\n");
    for g in shape_groups().iter().chain(operator_groups().iter()) {
        group_markdown(&mut out, g);
    }
    material_markdown(&mut out);
    out.push_str("## Presets\n\n");
    let _ = writeln!(
        out,
        "Built-in scenes; `fathom scene --preset NAME` prints one as a scene file to start \
         from. The default is `{DEFAULT_PRESET}`.\n"
    );
    out.push_str("| name | description |\n|---|---|\n");
    for p in PRESETS {
        let _ = writeln!(out, "| `{}` | {} |", p.name, p.description);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn committed_reference_matches_the_registry() {
        let path =
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../docs/scene-reference.md");
        let fresh = scene_reference_markdown();
        if std::env::var_os("FATHOM_BLESS").is_some() {
            std::fs::write(&path, &fresh).unwrap();
            return;
        }
        let committed = std::fs::read_to_string(&path).unwrap_or_default();
        assert!(
            committed == fresh,
            "{} is out of date with the registry; run `FATHOM_BLESS=1 cargo test -p \
             fathom-core docgen` and commit it",
            path.display()
        );
    }

    #[test]
    fn reference_names_every_entry_and_parameter() {
        let md = scene_reference_markdown();
        for g in shape_groups().iter().chain(operator_groups().iter()) {
            for d in g.defs {
                assert!(md.contains(&format!("### `{}`", d.name)), "{}", d.name);
                for p in d.params {
                    assert!(md.contains(&format!("| `{}` |", p.name)), "{}", p.name);
                }
            }
        }
    }

    #[test]
    fn summary_stops_at_the_first_sentence_outside_code() {
        assert_eq!(summary("A b. C d."), "A b.");
        assert_eq!(
            summary("Keeps `n . p >= 0` and\nmore. Rest"),
            "Keeps `n . p >= 0` and more."
        );
        assert_eq!(summary("No stop"), "No stop");
    }

    #[test]
    fn example_calls_parse_as_defaults() {
        for g in shape_groups() {
            for d in g.defs {
                let text = format!("Scene(version: 1, root: Node(shape: {}))", example_call(d));
                let s = crate::scene_file::parse(&text, "example").unwrap();
                assert_eq!(s.root.shape.params, d.defaults(), "{}", d.name);
            }
        }
    }
}
