//! Keyboard and mouse to [`Controls`]: W/S forward and back, A/D left and right, Q/E down and
//! up, Z/C roll, Shift four times faster; dragging in the viewport looks around (or orbits the
//! picked point); the wheel moves towards the surface (or the pivot); Ctrl+wheel or +/- change
//! the field of view. Keys count only when no text field has the keyboard.

use crate::camera::Controls;
use egui::Key;
use glam::DVec2;

/// The controls asked for this frame, from the viewport's response and the input state.
///
/// Every method of `viewport` and `ctx` is called outside `ctx.input`'s closure: a
/// [`egui::Response`] reads the input state itself, and taking egui's lock again while the
/// closure holds it deadlocks the window as soon as another thread (the render worker asking
/// for a repaint) waits for the lock in between.
pub fn controls(ctx: &egui::Context, viewport: &egui::Response) -> Controls {
    let keys = !ctx.egui_wants_keyboard_input();
    let look = viewport.dragged().then(|| viewport.drag_delta());
    let hovered = viewport.hovered();
    ctx.input(|i| {
        let axis = |neg: Key, pos: Key| {
            if !keys {
                return 0.0;
            }
            (i.key_down(pos) as i32 - i.key_down(neg) as i32) as f64
        };
        let mut c = Controls {
            forward: axis(Key::S, Key::W),
            right: axis(Key::A, Key::D),
            up: axis(Key::Q, Key::E),
            roll: axis(Key::Z, Key::C),
            boost: i.modifiers.shift,
            ..Controls::default()
        };
        if let Some(d) = look {
            c.look = DVec2::new(d.x as f64, d.y as f64);
        }
        if hovered {
            c.wheel = i.smooth_scroll_delta.y as f64 / 50.0;
            // Ctrl+wheel arrives as a zoom factor; one notch is about 10 %.
            let z = i.zoom_delta() as f64;
            if z != 1.0 && z > 0.0 {
                c.fov = z.ln() / 0.105;
            }
        }
        if keys {
            if i.key_pressed(Key::Plus) || i.key_pressed(Key::Equals) {
                c.fov += 1.0;
            }
            if i.key_pressed(Key::Minus) {
                c.fov -= 1.0;
            }
        }
        c
    })
}

/// The key help shown in the Help menu.
pub const KEY_HELP: &str = "\
W / S         forward / back            A / D        left / right
Q / E         down / up                 Z / C        roll
Shift         4x faster                 + / -        field of view
drag          look around (orbit around the picked point)
click         orbit the surface point under the cursor (click the sky to fly)
wheel         towards the surface or the pivot (Ctrl+wheel: field of view)
Ctrl+Z        undo                      Ctrl+Y       redo
Ctrl+S        save                      Ctrl+O       open
Ctrl+Q        quit (asks about unsaved edits)
F12           screenshot of the view    Ctrl+F12     screenshot...
F2            side panels on / off      F3           stats overlay on / off
F4            timeline and bindings     1..9         jump to bookmark
Ctrl+1..9     store a bookmark
Speeds follow the distance to the surface: a dive feels the same at every depth.";
