//! Live modulation and flight paths in the window: the state the window keeps for them (a
//! [`Modulator`] running the scene's bindings, the timeline's position on a flight path) and
//! the two panels that show them (bindings, timeline).
//!
//! The document (`ExplorerApp::scene`, what undo and save see) is never modulated: every frame
//! the window derives the *live scene* from it (the timeline's parameter keys via
//! `Flight::apply`, then the bindings via `Modulator::apply`) and sends that to the render
//! worker when its numbers changed. Only numbers change, so the session re-bakes its parameter
//! buffer and never recompiles.

use fathom_core::binding::{Binding, Source, Wave};
use fathom_core::flight::{Flight, FlightPath, Keyframe};
use fathom_core::{Camera, Scene, Tape};
use fathom_live::{Applied, LiveError, Modulator, OscCounters};
use std::net::SocketAddr;
use std::time::Instant;

/// Starts the modulator for `scene`'s bindings, and its OSC listener on `osc_bind` when given.
/// A port in use (or any address that cannot be bound) is an error naming the address.
pub fn start_modulator(
    scene: &Scene,
    osc_bind: Option<SocketAddr>,
) -> Result<Modulator, LiveError> {
    let mut m = Modulator::new(scene)?;
    if let Some(addr) = osc_bind {
        m.listen(addr)?;
    }
    Ok(m)
}

/// One bound parameter's figures for the frame log.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct BoundValue {
    /// The parameter path.
    pub param: String,
    /// The source's level in [0, 1] (`None`: an OSC binding that has received nothing).
    pub level: Option<f64>,
    /// The value written to the parameter.
    pub value: Option<f64>,
}

/// The window's live layer: the modulator, its clock and the timeline.
pub struct Live {
    /// The bindings' runtime (LFOs, OSC, smoothing).
    pub modulator: Modulator,
    clock: Instant,
    /// What the last [`Live::derive`] did.
    pub applied: Applied,
    /// The flight-path timeline.
    pub timeline: Timeline,
    /// The last error from taking the document's bindings (shown once).
    rebind_error: Option<String>,
}

/// The timeline's state: which path, where on it, playing or not.
pub struct Timeline {
    /// Index of the path in `scene.paths`.
    pub path: usize,
    /// Seconds from the path's start.
    pub t: f64,
    /// Whether the time advances with the clock.
    pub playing: bool,
    /// Whether the path drives the view (after play or a scrub, until "Leave path").
    pub engaged: bool,
    /// The time moved (play, scrub): the camera is set from the pose on the next frame.
    moved: bool,
    /// The prepared path and the document generation and path it was prepared for.
    flight: Option<(u64, usize, Result<Flight, String>)>,
}

impl Live {
    /// A live layer over `modulator`, its clock started, no path engaged.
    pub fn new(modulator: Modulator) -> Live {
        Live {
            modulator,
            clock: Instant::now(),
            applied: Applied::default(),
            timeline: Timeline {
                path: 0,
                t: 0.0,
                playing: false,
                engaged: false,
                moved: false,
                flight: None,
            },
            rebind_error: None,
        }
    }

    /// Takes the document's bindings after an edit; returns an error to show (once per
    /// distinct error; the previous bindings keep running).
    pub fn rebind(&mut self, scene: &Scene) -> Option<String> {
        match self.modulator.rebind(scene) {
            Ok(()) => {
                self.rebind_error = None;
                None
            }
            Err(e) => {
                let e = format!("bindings not taken: {e}");
                if self.rebind_error.as_ref() == Some(&e) {
                    None
                } else {
                    self.rebind_error = Some(e.clone());
                    Some(e)
                }
            }
        }
    }

    /// Seconds on the modulation clock (since the window opened).
    pub fn clock(&self) -> f64 {
        self.clock.elapsed().as_secs_f64()
    }

    /// The prepared flight of the selected path (prepared again after a document edit:
    /// `generation` counts document edits, not live changes).
    pub fn flight(
        &mut self,
        doc: &Scene,
        generation: u64,
        tape: &Tape,
    ) -> Option<&Result<Flight, String>> {
        let tl = &mut self.timeline;
        if doc.paths.is_empty() {
            tl.flight = None;
            return None;
        }
        if tl.path >= doc.paths.len() {
            tl.path = 0;
        }
        let fresh = matches!(&tl.flight, Some((g, p, _)) if *g == generation && *p == tl.path);
        if !fresh {
            let f = doc.paths[tl.path]
                .prepare(doc, Some(tape))
                .map_err(|e| format!("path `{}`: {e}", doc.paths[tl.path].name));
            tl.flight = Some((generation, tl.path, f));
        }
        tl.flight.as_ref().map(|(_, _, f)| f)
    }

    /// One frame: advances the timeline by `dt` seconds when playing, then derives the live
    /// scene from the document: the path's pose (parameter keys; the camera is returned when
    /// the time moved), then the bindings at the modulation clock, with `view` as the camera
    /// the bindings may drive. Returns (live scene, the camera to set from the path, the
    /// camera the bindings drive).
    pub fn derive(
        &mut self,
        doc: &Scene,
        generation: u64,
        tape: &Tape,
        view: &Camera,
        dt: f64,
    ) -> (Scene, Option<Camera>, Option<Camera>) {
        let mut live = doc.clone();
        let mut path_camera = None;
        let playing = self.timeline.playing;
        let engaged = self.timeline.engaged;
        let t0 = self.timeline.t;
        let flight = match self.flight(doc, generation, tape) {
            Some(Ok(f)) => Some(f.clone()),
            _ => None,
        };
        match flight {
            Some(f) if engaged => {
                let tl = &mut self.timeline;
                if playing {
                    tl.t = (t0 + dt).min(f.duration());
                    tl.moved = true;
                    if tl.t >= f.duration() {
                        tl.playing = false;
                    }
                }
                tl.t = tl.t.clamp(0.0, f.duration());
                let pose = f.apply(tl.t, &mut live);
                if tl.moved {
                    path_camera = Some(pose.camera);
                    tl.moved = false;
                }
            }
            _ => {
                self.timeline.playing = false;
                self.timeline.engaged = false;
            }
        }
        // The bindings drive the camera the view shows; the worker's scene keeps the
        // document's camera (frames carry their own).
        live.camera = path_camera.clone().unwrap_or_else(|| view.clone());
        let t = self.clock();
        self.applied = self.modulator.apply(&mut live, t);
        let bound_camera = self.applied.camera.then(|| live.camera.clone());
        live.camera = doc.camera.clone();
        (live, path_camera, bound_camera)
    }

    /// The OSC counters (all zero without a listener).
    pub fn counters(&self) -> OscCounters {
        self.modulator.counters()
    }

    /// Each binding's parameter, level and value, for the frame log.
    pub fn bound_values(&self, doc: &Scene) -> Vec<BoundValue> {
        doc.bindings
            .iter()
            .zip(self.modulator.live())
            .map(|(b, l)| BoundValue {
                param: b.param.clone(),
                level: l.level,
                value: l.value,
            })
            .collect()
    }

    /// Moves the timeline to `t` seconds (a scrub): the path drives the view from the next
    /// frame.
    pub fn scrub(&mut self, t: f64) {
        let tl = &mut self.timeline;
        tl.t = t.max(0.0);
        tl.engaged = true;
        tl.moved = true;
    }

    /// Plays from the current time (from the start when at the end).
    pub fn play(&mut self, duration: f64) {
        let tl = &mut self.timeline;
        if tl.t >= duration {
            tl.t = 0.0;
        }
        tl.playing = true;
        tl.engaged = true;
        tl.moved = true;
    }
}

/// The path clock (before easing) at wall time `t`: `Keyframe::time` pins are on this clock
/// (`Flight`'s own easing, `fathom_core::flight::path_clock`).
pub fn path_clock(p: &FlightPath, t: f64) -> f64 {
    fathom_core::flight::path_clock(p.duration, p.ease_in, p.ease_out, t)
}

/// Adds a key at `camera` to path `index` of `scene` at wall time `t` (a document edit; the
/// caller records it): at the start or the end when `t` is there, otherwise after the keys
/// before `t`, pinned to `t` when the other pinned keys allow it. Returns the new key's index
/// and a note when it could not be pinned.
pub fn add_key(
    scene: &mut Scene,
    index: usize,
    flight: &Flight,
    t: f64,
    camera: &Camera,
) -> (usize, Option<String>) {
    let key = Keyframe::from_camera(camera);
    let path = &scene.paths[index];
    let d = path.duration;
    if t <= 0.0 {
        scene.paths[index].keys.insert(0, key);
        return (0, None);
    }
    if t >= d {
        scene.paths[index].keys.push(key);
        return (scene.paths[index].keys.len() - 1, None);
    }
    let at = flight.insert_index(t);
    let tau = path_clock(path, t);
    let doc = scene.clone();
    let p = &mut scene.paths[index];
    p.keys.insert(at, key);
    let note = p
        .pin(at, Some(tau), &doc)
        .err()
        .map(|e| format!("the new key is not pinned to {t:.2} s: {e}"));
    (at, note)
}

/// How a binding's source reads in the panel.
pub fn source_text(b: &Binding) -> String {
    match &b.source {
        Source::Lfo(l) => {
            let wave = match l.wave {
                Wave::Sine => "sine",
                Wave::Triangle => "triangle",
                Wave::Saw => "saw",
                Wave::Noise => "noise",
            };
            let mut s = format!("LFO {wave} {} Hz", fmt(l.rate));
            if l.phase != 0.0 {
                s += &format!(", phase {}", fmt(l.phase));
            }
            if l.depth != 1.0 {
                s += &format!(", depth {}", fmt(l.depth));
            }
            s
        }
        Source::Osc(o) => {
            let mut s = format!("OSC {}", o.address);
            if o.arg != 0 {
                s += &format!(" arg {}", o.arg);
            }
            s + &format!(" from [{}, {}]", fmt(o.from.0), fmt(o.from.1))
        }
    }
}

/// How a binding's mapping reads in the panel.
pub fn mapping_text(b: &Binding) -> String {
    let mut s = format!("0..1 -> [{}, {}]", fmt(b.to.0), fmt(b.to.1));
    if b.smoothing > 0.0 {
        s += &format!(", smoothing {} s", fmt(b.smoothing));
    }
    s
}

/// A number in a short form (no trailing zeros).
fn fmt(x: f64) -> String {
    let s = format!("{x:.4}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s.is_empty() || s == "-" {
        "0".into()
    } else {
        s.to_string()
    }
}

/// The OSC line of the bindings panel and the overlay.
pub fn osc_text(addr: Option<SocketAddr>, c: &OscCounters) -> String {
    match addr {
        Some(a) => format!(
            "OSC on {a}: {} packets, {} rejected ({} malformed, {} bad values), {} clamped, {} unmatched",
            c.packets, c.rejected, c.malformed, c.bad_values, c.clamped, c.unmatched
        ),
        None => "OSC: not listening (start with --osc-port PORT)".into(),
    }
}

/// The bindings panel: the OSC counters, then each binding's parameter, live level and value,
/// source and mapping.
pub fn bindings_ui(ui: &mut egui::Ui, live: &Live, doc: &Scene) {
    ui.label(osc_text(live.modulator.osc_addr(), &live.counters()));
    if doc.bindings.is_empty() {
        ui.label("This scene has no bindings (see docs/live.md).");
        return;
    }
    let values = live.modulator.live();
    egui::Grid::new("bindings")
        .striped(true)
        .num_columns(4)
        .show(ui, |ui| {
            ui.strong("parameter");
            ui.strong("live");
            ui.strong("source");
            ui.strong("mapping");
            ui.end_row();
            for (i, (b, v)) in doc.bindings.iter().zip(values).enumerate() {
                ui.label(&b.param);
                let stale = live.applied.stale.contains(&i);
                let text = match (stale, v.value) {
                    (true, _) => "parameter gone".to_string(),
                    (false, Some(x)) => fmt(x),
                    (false, None) => "waiting for OSC".to_string(),
                };
                let text = if matches!(b.source, Source::Osc(_)) {
                    format!("{text} ({} received)", v.received)
                } else {
                    text
                };
                ui.add(
                    egui::ProgressBar::new(v.level.unwrap_or(0.0) as f32)
                        .desired_width(140.0)
                        .text(text),
                )
                .on_hover_text("the source's level in [0, 1], and the value written");
                ui.label(source_text(b));
                ui.label(mapping_text(b));
                ui.end_row();
            }
        });
}

/// What the timeline panel asks the window to do.
#[derive(Debug, PartialEq)]
pub enum TimelineAction {
    /// Add a key at the current view at the timeline's time.
    AddKey,
    /// Change the selected path's duration to this many seconds.
    Retime(f64),
}

/// The timeline panel: pick a path, play, pause, scrub, add a key at the view, retime.
pub fn timeline_ui(
    ui: &mut egui::Ui,
    live: &mut Live,
    doc: &Scene,
    generation: u64,
    tape: &Tape,
) -> Option<TimelineAction> {
    if doc.paths.is_empty() {
        ui.label("This scene has no flight paths (see docs/live.md).");
        return None;
    }
    let mut action = None;
    let mut pick = live.timeline.path.min(doc.paths.len() - 1);
    egui::ComboBox::new("flight path", "path")
        .selected_text(&doc.paths[pick].name)
        .show_ui(ui, |ui| {
            for (i, p) in doc.paths.iter().enumerate() {
                ui.selectable_value(&mut pick, i, &p.name);
            }
        });
    if pick != live.timeline.path {
        live.timeline.path = pick;
        live.timeline.t = 0.0;
        live.timeline.playing = false;
    }
    let flight = match live.flight(doc, generation, tape) {
        Some(Ok(f)) => f.clone(),
        Some(Err(e)) => {
            ui.colored_label(egui::Color32::from_rgb(255, 120, 110), e);
            return None;
        }
        None => return None,
    };
    let duration = flight.duration();
    ui.horizontal(|ui| {
        if live.timeline.playing {
            if ui.button("Pause").clicked() {
                live.timeline.playing = false;
            }
        } else if ui.button("Play").clicked() {
            live.play(duration);
        }
        if ui
            .button("Add key at view")
            .on_hover_text("a keyframe at the current view, at the timeline's time")
            .clicked()
        {
            action = Some(TimelineAction::AddKey);
        }
        if live.timeline.engaged
            && ui
                .button("Leave path")
                .on_hover_text("the path stops driving the view and its parameters")
                .clicked()
        {
            live.timeline.engaged = false;
            live.timeline.playing = false;
        }
    });
    let mut t = live.timeline.t;
    if ui
        .add(
            egui::Slider::new(&mut t, 0.0..=duration)
                .text("path time")
                .suffix(" s"),
        )
        .changed()
    {
        live.scrub(t);
        live.timeline.playing = false;
    }
    let keys: Vec<String> = flight
        .key_times()
        .iter()
        .map(|k| format!("{k:.2}"))
        .collect();
    ui.label(format!("{} keys at {} s", keys.len(), keys.join(", ")));
    let mut d = duration;
    if ui
        .add(
            egui::DragValue::new(&mut d)
                .range(0.1..=fathom_core::flight::MAX_DURATION)
                .speed(0.1)
                .prefix("duration ")
                .suffix(" s"),
        )
        .changed()
        && d != duration
    {
        action = Some(TimelineAction::Retime(d));
    }
    action
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn path_clock_matches_the_flights_key_times_with_easing() {
        let mut scene = fathom_core::presets::load("sierpinski").unwrap();
        let c = scene.camera.clone();
        let mut c2 = c.clone();
        c2.eye *= 0.5;
        let mut c3 = c.clone();
        c3.eye *= 0.25;
        let mut p = FlightPath::new(
            "p",
            10.0,
            vec![
                Keyframe::from_camera(&c),
                Keyframe::from_camera(&c2),
                Keyframe::from_camera(&c3),
            ],
        );
        p.ease_in = 2.0;
        p.ease_out = 1.0;
        scene.paths.push(p.clone());
        let f = p.prepare(&scene, None).unwrap();
        let mid = f.key_times()[1];
        // Pinning the middle key to the path clock at its own wall time keeps it there.
        scene.paths[0].keys[1].time = Some(path_clock(&p, mid));
        let f2 = scene.paths[0].prepare(&scene, None).unwrap();
        assert!(
            (f2.key_times()[1] - mid).abs() < 1e-9,
            "{:?}",
            f2.key_times()
        );
        // And a key added at a wall time lands at that time.
        let (at, note) = add_key(&mut scene, 0, &f2, 7.5, &c3);
        assert_eq!(note, None);
        let f3 = scene.paths[0].prepare(&scene, None).unwrap();
        assert!(
            (f3.key_times()[at] - 7.5).abs() < 1e-9,
            "{:?}",
            f3.key_times()
        );
    }

    #[test]
    fn the_panel_texts_say_source_and_mapping() {
        let b: Binding = ron::from_str(
            r#"Binding(param: "lights[0].intensity", source: Osc(address: "/a/b", arg: 2, from: (-0.5, 1.5)), to: (0.3, 1.6), smoothing: 0.25)"#,
        )
        .unwrap();
        assert_eq!(source_text(&b), "OSC /a/b arg 2 from [-0.5, 1.5]");
        assert_eq!(mapping_text(&b), "0..1 -> [0.3, 1.6], smoothing 0.25 s");
        let b: Binding = ron::from_str(
            r#"Binding(param: "root.shape.power", source: Lfo(wave: Triangle, rate: 0.1, phase: 0.25), to: (6.0, 10.0))"#,
        )
        .unwrap();
        assert_eq!(source_text(&b), "LFO triangle 0.1 Hz, phase 0.25");
    }
}
