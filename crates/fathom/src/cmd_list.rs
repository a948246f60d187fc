//! `fathom list`: the registry (and the presets), printed from the declarations as aligned text
//! or, with `--json`, as machine-readable JSON.

use clap::{Args, ValueEnum};
use fathom_core::docgen::{self, Group};
use fathom_core::presets::{DEFAULT_PRESET, PRESETS};
use fathom_core::registry::Def;
use serde_json::{Value, json};
use std::fmt::Write;

/// What to list.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum What {
    /// Built-in scenes (`fathom scene --preset NAME` prints one).
    Presets,
    /// Primitive shapes (sphere, box, ...).
    Primitives,
    /// Fractal shapes (Mandelbulb, ...).
    Fractals,
    /// Transforms, distance modifiers and combine operators.
    Operators,
    /// Everything above.
    All,
}

/// Shown after `fathom list --help`.
const AFTER_HELP: &str = "\
Each entry shows its name, its distance quality and the first sentence of its doc, then one
line per parameter: name, kind, default, range and meaning. Names are written exactly so in
scene files; parameters left out take their defaults.

Examples:
  fathom list primitives
  fathom list operators                  transforms, distance modifiers, combines
  fathom list all --json > registry.json";

/// Arguments of `fathom list`.
#[derive(Args)]
#[command(after_help = AFTER_HELP)]
pub struct ListArgs {
    /// What to list.
    #[arg(value_enum)]
    what: What,
    /// Print JSON instead of text.
    #[arg(long)]
    json: bool,
}

/// Runs `fathom list`.
pub fn run(a: ListArgs) -> Result<(), String> {
    let out = if a.json {
        let v = list_json(a.what);
        serde_json::to_string_pretty(&v).map_err(|e| e.to_string())? + "\n"
    } else {
        list_text(a.what)
    };
    print!("{out}");
    Ok(())
}

fn groups(what: What) -> Vec<Group> {
    let mut v = Vec::new();
    match what {
        What::Presets => {}
        What::Primitives => v.push(docgen::shape_groups().into_iter().next()),
        What::Fractals => v.push(docgen::shape_groups().into_iter().nth(1)),
        What::Operators => v.extend(docgen::operator_groups().into_iter().map(Some)),
        What::All => {
            v.extend(docgen::shape_groups().into_iter().map(Some));
            v.extend(docgen::operator_groups().into_iter().map(Some));
        }
    }
    v.into_iter().flatten().collect()
}

fn wants_presets(what: What) -> bool {
    matches!(what, What::Presets | What::All)
}

/// The listing as aligned text.
pub fn list_text(what: What) -> String {
    let mut out = String::new();
    for g in groups(what) {
        let _ = writeln!(
            out,
            "{} ({}), written in {}:\n",
            g.title.to_uppercase(),
            g.defs.len(),
            g.used_in
        );
        let name_w = g.defs.iter().map(|d| d.name.len()).max().unwrap_or(0);
        for d in g.defs {
            entry_text(&mut out, d, name_w);
        }
        out.push('\n');
    }
    if wants_presets(what) {
        let _ = writeln!(
            out,
            "PRESETS ({}), default `{DEFAULT_PRESET}`:\n",
            PRESETS.len()
        );
        let w = PRESETS.iter().map(|p| p.name.len()).max().unwrap_or(0);
        for p in PRESETS {
            let _ = writeln!(out, "  {:w$}  {}", p.name, p.description);
        }
        out.push('\n');
    }
    out
}

fn entry_text(out: &mut String, d: &Def, name_w: usize) {
    let _ = writeln!(
        out,
        "  {:name_w$}  [{}]  {}",
        d.name,
        d.quality,
        docgen::summary(d.doc)
    );
    let rows: Vec<[String; 5]> = d
        .params
        .iter()
        .map(|p| {
            [
                p.name.to_string(),
                docgen::kind_name(p.kind).to_string(),
                format!("= {}", docgen::fmt_default(p)),
                docgen::fmt_range(p),
                p.doc.to_string(),
            ]
        })
        .collect();
    let mut widths = [0usize; 5];
    for r in &rows {
        for (w, c) in widths.iter_mut().zip(r) {
            *w = (*w).max(c.chars().count());
        }
    }
    for r in rows {
        let _ = writeln!(
            out,
            "      {:w0$}  {:w1$}  {:w2$}  {:w3$}  {}",
            r[0],
            r[1],
            r[2],
            r[3],
            r[4],
            w0 = widths[0],
            w1 = widths[1],
            w2 = widths[2],
            w3 = widths[3]
        );
    }
}

fn def_json(d: &Def) -> Value {
    json!({
        "name": d.name,
        "doc": docgen::paragraph(d.doc),
        "summary": docgen::summary(d.doc),
        "quality": format!("{:?}", d.quality).to_lowercase(),
        "example": docgen::example_call(d),
        "params": d.params.iter().map(|p| json!({
            "name": p.name,
            "kind": docgen::kind_name(p.kind),
            "default": p.default_values(),
            "min": p.min,
            "max": p.max,
            "doc": p.doc,
        })).collect::<Vec<_>>(),
    })
}

/// The listing as JSON: an object keyed by group (`primitives`, `fractals`, `transforms`,
/// `modifiers`, `combines`, `presets`), each an array in registry (opcode) order.
pub fn list_json(what: What) -> Value {
    let mut m = serde_json::Map::new();
    for g in groups(what) {
        m.insert(
            g.key.to_string(),
            Value::Array(g.defs.iter().map(def_json).collect()),
        );
    }
    if wants_presets(what) {
        m.insert(
            "presets".into(),
            Value::Array(
                PRESETS
                    .iter()
                    .map(|p| {
                        json!({
                            "name": p.name,
                            "description": p.description,
                            "default": p.name == DEFAULT_PRESET,
                        })
                    })
                    .collect(),
            ),
        );
    }
    Value::Object(m)
}

#[cfg(test)]
mod tests {
    use super::*;
    use fathom_core::primitives::PRIMITIVES;

    #[test]
    fn text_lists_every_primitive_with_params_and_ranges() {
        let t = list_text(What::Primitives);
        for d in PRIMITIVES {
            assert!(t.contains(d.name), "{}", d.name);
            for p in d.params {
                assert!(t.contains(&docgen::fmt_range(p)), "{t}");
            }
        }
        assert!(t.contains("radius  scalar  = 1"), "{t}");
        assert!(!t.contains("PRESETS"));
    }

    #[test]
    fn operators_are_grouped() {
        let t = list_text(What::Operators);
        let a = t.find("TRANSFORMS").unwrap();
        let b = t.find("DISTANCE MODIFIERS").unwrap();
        let c = t.find("COMBINE OPERATORS").unwrap();
        assert!(a < b && b < c, "{t}");
    }

    #[test]
    fn json_has_every_group_and_entry() {
        let v = list_json(What::All);
        for key in [
            "primitives",
            "fractals",
            "transforms",
            "modifiers",
            "combines",
            "presets",
        ] {
            assert!(v[key].as_array().is_some_and(|a| !a.is_empty()), "{key}");
        }
        assert_eq!(v["primitives"].as_array().unwrap().len(), PRIMITIVES.len());
        let sphere = v["primitives"]
            .as_array()
            .unwrap()
            .iter()
            .find(|e| e["name"] == "Sphere")
            .unwrap();
        assert_eq!(sphere["params"][0]["name"], "radius");
        assert_eq!(sphere["params"][0]["default"][0], 1.0);
        assert_eq!(sphere["quality"], "exact");
        let presets = v["presets"].as_array().unwrap();
        assert_eq!(presets.iter().filter(|p| p["default"] == true).count(), 1);
    }
}
