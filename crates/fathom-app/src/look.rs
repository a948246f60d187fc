//! Lights and the scene's render settings (sky, ambient, occlusion, shadows, fog, the tracer's
//! step limit and hit threshold, the orbit-trap palette), with the ranges the scene validation
//! checks.

use fathom_core::limits;
use fathom_core::scene::{Light, RenderSettings};

fn rgb(ui: &mut egui::Ui, label: &str, c: &mut [f64; 3], max: f64) -> bool {
    let mut f = c.map(|v| (v / max) as f32);
    let mut changed = false;
    ui.horizontal(|ui| {
        if ui.color_edit_button_rgb(&mut f).changed() {
            *c = f.map(|v| (v as f64 * max).clamp(0.0, max));
            changed = true;
        }
        ui.label(label);
    });
    changed
}

/// The lights: direction, colour, intensity, shadows; add and remove.
pub fn lights_editor(ui: &mut egui::Ui, lights: &mut Vec<Light>) -> bool {
    let mut changed = false;
    let mut remove = None;
    for (i, l) in lights.iter_mut().enumerate() {
        ui.push_id(("light", i), |ui| {
            ui.horizontal(|ui| {
                ui.strong(format!("light {}", i + 1));
                if ui.small_button("x").on_hover_text("remove").clicked() {
                    remove = Some(i);
                }
            });
            ui.horizontal(|ui| {
                for c in [&mut l.direction.x, &mut l.direction.y, &mut l.direction.z] {
                    changed |= ui
                        .add(egui::DragValue::new(c).speed(0.01).range(-1.0..=1.0))
                        .changed();
                }
                ui.label("direction");
            });
            if l.direction.length_squared() == 0.0 {
                l.direction.y = 1.0;
            }
            changed |= rgb(ui, "colour", &mut l.colour, 1.0);
            changed |= ui
                .add(egui::Slider::new(&mut l.intensity, 0.0..=4.0).text("intensity"))
                .changed();
            changed |= ui.checkbox(&mut l.shadows, "shadows").changed();
        });
    }
    if let Some(i) = remove {
        lights.remove(i);
        changed = true;
    }
    if lights.len() < limits::MAX_LIGHTS && ui.button("Add light").clicked() {
        lights.push(Light::default());
        changed = true;
    }
    changed
}

/// The scene's render settings.
pub fn render_settings_editor(ui: &mut egui::Ui, r: &mut RenderSettings) -> bool {
    let mut changed = false;
    changed |= rgb(ui, "sky top", &mut r.sky_top, 1.0);
    changed |= rgb(ui, "sky bottom (and fog)", &mut r.sky_bottom, 1.0);
    changed |= ui
        .add(egui::Slider::new(&mut r.ambient, 0.0..=1.0).text("ambient"))
        .changed();
    changed |= ui
        .add(egui::Slider::new(&mut r.ao, 0.0..=4.0).text("occlusion"))
        .on_hover_text("distance-field ambient occlusion")
        .changed();
    changed |= ui
        .add(
            egui::Slider::new(&mut r.shadow_softness, 1.0..=256.0)
                .logarithmic(true)
                .text("shadow hardness"),
        )
        .changed();
    changed |= ui
        .add(
            egui::Slider::new(&mut r.fog, 0.0..=10.0)
                .clamping(egui::SliderClamping::Never)
                .text("fog"),
        )
        .on_hover_text("fog density per world unit, [0, 1e6]")
        .changed();
    r.fog = r.fog.clamp(0.0, 1e6);
    changed |= ui
        .add(
            egui::Slider::new(&mut r.max_steps, 1..=limits::MAX_STEPS)
                .logarithmic(true)
                .text("max steps"),
        )
        .changed();
    changed |= ui
        .add(
            egui::Slider::new(&mut r.max_distance, 1e-3..=1e6)
                .logarithmic(true)
                .text("max distance"),
        )
        .changed();
    changed |= ui
        .add(
            egui::Slider::new(&mut r.pixel_epsilon, 0.01..=16.0)
                .logarithmic(true)
                .text("epsilon (pixels)"),
        )
        .on_hover_text("hit threshold as a multiple of the pixel footprint")
        .changed();
    ui.collapsing("orbit-trap palette  a + b cos(2 pi (c t + d))", |ui| {
        for (row, name) in r.palette.iter_mut().zip(["a", "b", "c", "d"]) {
            ui.horizontal(|ui| {
                for v in row.iter_mut() {
                    changed |= ui
                        .add(egui::DragValue::new(v).speed(0.01).range(-10.0..=10.0))
                        .changed();
                }
                ui.label(name);
            });
        }
    });
    changed
}
