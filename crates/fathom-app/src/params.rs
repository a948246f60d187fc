//! Widgets generated from the registry: a picker over any family's entries and an editor for a
//! call's parameters, with each parameter's declared range, default and documentation (as the
//! tooltip). A new primitive, fractal or operator appears here with no GUI code.
//!
//! Editing rules: sliders cover the declared *soft* range (what artists use; logarithmic when
//! it spans two decades); a typed value may go anywhere in the hard range (what is valid), and
//! one outside it is clamped into it with a note saying so; double-click (or the context menu)
//! resets a parameter to its default.

use fathom_core::registry::{Family, ParamKind, ParamSpec, fmt_num};
use fathom_core::scene::Call;

/// The tooltip of a parameter: its doc, default and range.
pub fn param_tooltip(p: &ParamSpec) -> String {
    let d = p
        .default_values()
        .iter()
        .map(|v| fmt_num(*v))
        .collect::<Vec<_>>()
        .join(", ");
    format!(
        "{}\ndefault {d}; slider [{}, {}], typed values [{}, {}]\ndouble-click resets",
        p.doc,
        fmt_num(p.soft_min),
        fmt_num(p.soft_max),
        fmt_num(p.min),
        fmt_num(p.max)
    )
}

/// A combo box choosing an entry of family `K`; says what changed (`change shape to Box`).
/// Changing the entry resets its parameters to the new entry's defaults.
pub fn entry_picker<K: Family>(
    ui: &mut egui::Ui,
    id: impl egui::AsIdSalt,
    label: &str,
    call: &mut Call<K>,
) -> Option<String> {
    let mut changed = None;
    let current = call.kind;
    egui::ComboBox::new(id, label)
        .selected_text(current.def().name)
        .show_ui(ui, |ui| {
            for &k in K::all() {
                let r = ui
                    .selectable_label(k == current, k.def().name)
                    .on_hover_text(k.def().doc);
                if r.clicked() && k != current {
                    *call = Call::new(k);
                    changed = Some(format!("change {label} to {}", k.def().name));
                }
            }
        });
    changed
}

/// Editors for every parameter of `call`. Clamped values add a line to `notes`. Says what
/// changed (`set minor`, `reset minor`).
pub fn call_params<K: Family>(
    ui: &mut egui::Ui,
    call: &mut Call<K>,
    notes: &mut Vec<String>,
) -> Option<String> {
    let def = call.kind.def();
    let mut changed = None;
    let mut off = 0;
    for p in def.params {
        let w = p.kind.width();
        let values = &mut call.params[off..off + w];
        let r = param_editor(ui, def.name, p, values);
        if r.changed {
            changed.get_or_insert_with(|| format!("set {}", p.name));
            let clamped = p.clamp(values);
            if clamped != values {
                notes.push(format!(
                    "{}.{}: {} is outside [{}, {}]; clamped to {}",
                    def.name,
                    p.name,
                    values
                        .iter()
                        .map(|v| fmt_num(*v))
                        .collect::<Vec<_>>()
                        .join(", "),
                    fmt_num(p.min),
                    fmt_num(p.max),
                    clamped
                        .iter()
                        .map(|v| fmt_num(*v))
                        .collect::<Vec<_>>()
                        .join(", ")
                ));
                values.copy_from_slice(&clamped);
            }
        }
        if r.reset {
            values.copy_from_slice(p.default_values());
            changed = Some(format!("reset {}", p.name));
        }
        off += w;
    }
    changed
}

struct Edited {
    changed: bool,
    reset: bool,
}

/// One parameter's widget(s): a slider over the declared soft range (logarithmic when it spans
/// decades), or drag values for vectors whose speed follows the soft range; typed values may
/// go anywhere in the hard range. Sliders and drag values sense drags only; double-click (and
/// the context menu) resets, so clicks are asked for here.
fn param_editor(ui: &mut egui::Ui, entry: &str, p: &ParamSpec, v: &mut [f64]) -> Edited {
    let tip = param_tooltip(p);
    let mut out = Edited {
        changed: false,
        reset: false,
    };
    let name = format!("{entry}.{}", p.name);
    let handle = |r: egui::Response, out: &mut Edited| {
        // (`interact` answers a new response: read the edit off the widget's own first.)
        out.changed |= r.changed();
        let r = r.interact(egui::Sense::click()).on_hover_text(&tip);
        crate::script::place("param", name.clone(), &r);
        if r.double_clicked() {
            out.reset = true;
        }
        r.context_menu(|ui| {
            if ui.button("Reset to default").clicked() {
                out.reset = true;
                ui.close();
            }
        });
    };
    // About 300 pixels of drag across the soft range.
    let speed = (p.soft_max - p.soft_min) / 300.0;
    match p.kind {
        ParamKind::Scalar | ParamKind::Int => {
            let mut s = egui::Slider::new(&mut v[0], p.soft_min..=p.soft_max)
                .text(p.name)
                .clamping(egui::SliderClamping::Never)
                .logarithmic(p.soft_is_logarithmic());
            if p.kind == ParamKind::Int {
                s = s.integer();
            }
            let r = ui.add(s);
            handle(r, &mut out);
        }
        ParamKind::Vec3 => {
            ui.horizontal(|ui| {
                for c in v.iter_mut() {
                    let r = ui.add(egui::DragValue::new(c).speed(speed).max_decimals(4));
                    handle(r, &mut out);
                }
                ui.label(p.name).on_hover_text(&tip);
            });
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use fathom_core::primitives::Primitive;

    #[test]
    fn tooltips_name_the_range_and_default() {
        let def = Primitive::Sphere.def();
        let t = param_tooltip(&def.params[0]);
        assert!(
            t.contains("default 1") && t.contains("slider [0, 4], typed values [0, 1e6]"),
            "{t}"
        );
    }
}
