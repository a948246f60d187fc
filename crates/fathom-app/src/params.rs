//! Widgets generated from the registry: a picker over any family's entries and an editor for a
//! call's parameters, with each parameter's declared range, default and documentation (as the
//! tooltip). A new primitive, fractal or operator appears here with no GUI code.
//!
//! Editing rules: sliders cover the declared range (logarithmic when it spans three orders of
//! magnitude); a typed value outside it is clamped into it and a note says so; double-click
//! (or the context menu) resets a parameter to its default.

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
        "{}\ndefault {d}; range [{}, {}]\ndouble-click resets",
        p.doc,
        fmt_num(p.min),
        fmt_num(p.max)
    )
}

/// A combo box choosing an entry of family `K`; returns whether it changed. Changing the entry
/// resets its parameters to the new entry's defaults.
pub fn entry_picker<K: Family>(
    ui: &mut egui::Ui,
    id: impl egui::AsIdSalt,
    label: &str,
    call: &mut Call<K>,
) -> bool {
    let mut changed = false;
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
                    changed = true;
                }
            }
        });
    changed
}

/// Editors for every parameter of `call`. Clamped values add a line to `notes`. Returns
/// whether anything changed.
pub fn call_params<K: Family>(
    ui: &mut egui::Ui,
    call: &mut Call<K>,
    notes: &mut Vec<String>,
) -> bool {
    let def = call.kind.def();
    let mut changed = false;
    let mut off = 0;
    for p in def.params {
        let w = p.kind.width();
        let values = &mut call.params[off..off + w];
        let r = param_editor(ui, p, values);
        if r.changed {
            changed = true;
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
            changed = true;
        }
        off += w;
    }
    changed
}

struct Edited {
    changed: bool,
    reset: bool,
}

/// One parameter's widget(s).
fn param_editor(ui: &mut egui::Ui, p: &ParamSpec, v: &mut [f64]) -> Edited {
    let tip = param_tooltip(p);
    let span = p.max - p.min;
    let log = p.min > 0.0 && p.max / p.min >= 1e3;
    let mut out = Edited {
        changed: false,
        reset: false,
    };
    let handle = |r: egui::Response, out: &mut Edited| {
        let r = r.on_hover_text(&tip);
        out.changed |= r.changed();
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
    match p.kind {
        ParamKind::Scalar | ParamKind::Int if span.is_finite() && span <= 1e6 => {
            let mut s = egui::Slider::new(&mut v[0], p.min..=p.max)
                .text(p.name)
                .clamping(egui::SliderClamping::Never)
                .logarithmic(log);
            if p.kind == ParamKind::Int {
                s = s.integer();
            }
            let r = ui.add(s);
            handle(r, &mut out);
        }
        ParamKind::Scalar | ParamKind::Int => {
            ui.horizontal(|ui| {
                let speed = (v[0].abs() * 0.01).max(1e-3);
                let r = ui.add(egui::DragValue::new(&mut v[0]).speed(speed));
                handle(r, &mut out);
                ui.label(p.name);
            });
        }
        ParamKind::Vec3 => {
            ui.horizontal(|ui| {
                for c in v.iter_mut() {
                    let speed = if span.is_finite() && span <= 100.0 {
                        0.01
                    } else {
                        (c.abs() * 0.01).max(1e-3)
                    };
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
        assert!(t.contains("default 1") && t.contains("range ["), "{t}");
    }
}
