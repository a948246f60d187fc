//! The modulator: a scene's bindings at run time. Once per frame, [`Modulator::apply`] reads
//! each binding's source (an LFO at time `t`, or the latest OSC level from the listener's
//! atomic slots), maps it onto the binding's range, smooths it, and writes it into the scene
//! through the binding's parameter path, clamped to the declared range. Only numbers change,
//! never the scene's structure, so `Session::set_scene` re-bakes the parameter buffer (or only
//! the camera or settings) and never recompiles.

use crate::error::LiveError;
use crate::osc::{LevelSlot, Listener, OscCounters, Route, Routes, Shared};
use fathom_core::binding::{Binding, Source};
use fathom_core::param_path::ParamPath;
use fathom_core::scene::Scene;
use fathom_core::validate::validate_bindings;
use rosc::address::Matcher;
use serde::Serialize;
use std::net::SocketAddr;
use std::sync::Arc;

/// One binding's run-time state.
struct Bound {
    binding: Binding,
    path: ParamPath,
    /// The OSC slot, for OSC bindings.
    slot: Option<Arc<LevelSlot>>,
    /// The smoothed value last written, if any.
    value: Option<f64>,
    /// The source's latest level in [0, 1], if it has one yet.
    level: Option<f64>,
    /// OSC values received so far.
    received: u64,
}

/// A number written by [`Modulator::apply`].
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Edit {
    /// Index of the binding in `scene.bindings`.
    pub binding: usize,
    /// The value written (after smoothing and clamping to the declared range).
    pub value: f64,
}

/// What one [`Modulator::apply`] did.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Applied {
    /// The numbers written, one per binding that has a value.
    pub edits: Vec<Edit>,
    /// Whether any number of the scene changed (skip `Session::set_scene` when not).
    pub changed: bool,
    /// Whether a camera number changed: a window that flies its own camera should take the
    /// scene's camera fields that the bindings drive.
    pub camera: bool,
    /// Bindings whose parameter the scene no longer has (the tree was edited); skipped.
    pub stale: Vec<usize>,
    /// The OSC listener's counters (all zero without a listener).
    pub counters: OscCounters,
}

/// What a bindings panel shows for one binding.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct LiveValue {
    /// The source's latest level in [0, 1] (`None`: an OSC binding that has received nothing).
    pub level: Option<f64>,
    /// The value last written to the parameter.
    pub value: Option<f64>,
    /// OSC values received by this binding (0 for LFOs).
    pub received: u64,
}

/// A scene's bindings at run time, with an optional OSC listener thread.
pub struct Modulator {
    bound: Vec<Bound>,
    shared: Arc<Shared>,
    listener: Option<Listener>,
    last_t: Option<f64>,
}

impl Modulator {
    /// The modulator for `scene.bindings` (checked against the scene), without a listener:
    /// LFOs run, OSC bindings hold until [`Modulator::listen`] starts one.
    pub fn new(scene: &Scene) -> Result<Modulator, LiveError> {
        let mut m = Modulator {
            bound: Vec::new(),
            shared: Arc::new(Shared::default()),
            listener: None,
            last_t: None,
        };
        m.rebind(scene)?;
        Ok(m)
    }

    /// Starts the OSC listener on `addr` (port 0 picks a free port) and returns the address it
    /// listens on. The default `127.0.0.1` accepts packets from this machine only; binding
    /// `0.0.0.0` lets anyone who can reach the port drive the scene (see docs/live.md).
    /// A listener already running is stopped first.
    pub fn listen(&mut self, addr: SocketAddr) -> Result<SocketAddr, LiveError> {
        self.listener = None;
        let l = Listener::start(addr, self.shared.clone())
            .map_err(|source| LiveError::Bind { addr, source })?;
        let local = l.local;
        self.listener = Some(l);
        Ok(local)
    }

    /// The address the listener is bound to, if it runs.
    pub fn osc_addr(&self) -> Option<SocketAddr> {
        self.listener.as_ref().map(|l| l.local)
    }

    /// Takes the bindings of `scene` (after a panel edits them or the tree changes): checks
    /// them, keeps the state of bindings that did not change, and reroutes the listener
    /// without stopping it. On error nothing changes.
    pub fn rebind(&mut self, scene: &Scene) -> Result<(), LiveError> {
        validate_bindings(scene).map_err(|(at, error)| LiveError::Binding {
            at,
            msg: error.to_string(),
        })?;
        let mut bound = Vec::with_capacity(scene.bindings.len());
        let mut routes = Routes::default();
        for (i, b) in scene.bindings.iter().enumerate() {
            let path = ParamPath::parse(&b.param).map_err(|e| LiveError::Binding {
                at: format!("bindings[{i}].param"),
                msg: e.to_string(),
            })?;
            let old = self.bound.get(i).filter(|o| o.binding == *b);
            let slot = match &b.source {
                Source::Osc(input) => {
                    let matcher = Matcher::new(&input.address).map_err(|e| LiveError::Binding {
                        at: format!("bindings[{i}].source"),
                        msg: format!(
                            "`{}` is not a valid OSC address pattern: {e}",
                            input.address
                        ),
                    })?;
                    let slot = old
                        .and_then(|o| o.slot.clone())
                        .unwrap_or_else(|| Arc::new(LevelSlot::default()));
                    routes.routes.push(Route {
                        matcher,
                        input: input.clone(),
                        slot: slot.clone(),
                    });
                    Some(slot)
                }
                Source::Lfo(_) => None,
            };
            bound.push(Bound {
                binding: b.clone(),
                path,
                slot,
                value: old.and_then(|o| o.value),
                level: old.and_then(|o| o.level),
                received: old.map_or(0, |o| o.received),
            });
        }
        self.bound = bound;
        self.shared.set_routes(Arc::new(routes));
        Ok(())
    }

    /// Writes every binding's current value into `scene` at time `t` seconds (any clock that
    /// moves forward; a jump back, as when a timeline is scrubbed, resets smoothing). Never
    /// blocks on the listener. Only numbers change, so `Session::set_scene` afterwards
    /// re-bakes parameters and never recompiles.
    pub fn apply(&mut self, scene: &mut Scene, t: f64) -> Applied {
        let dt = match self.last_t {
            Some(last) if t >= last => Some(t - last),
            _ => None,
        };
        self.last_t = Some(t);
        let mut out = Applied {
            counters: self.shared.counters(),
            ..Applied::default()
        };
        for (i, b) in self.bound.iter_mut().enumerate() {
            let level = match (&b.binding.source, &b.slot) {
                (Source::Lfo(lfo), _) => Some(lfo.level(t)),
                (Source::Osc(_), Some(slot)) => {
                    let (level, count) = slot.read();
                    b.received = count;
                    (count > 0).then_some(level)
                }
                (Source::Osc(_), None) => None,
            };
            b.level = level;
            let Some(level) = level else { continue };
            let target = b.binding.map(level);
            let tau = b.binding.smoothing;
            let value = match (b.value, dt) {
                (Some(v), Some(dt)) if tau > 0.0 => v + (target - v) * (1.0 - (-dt / tau).exp()),
                _ => target,
            };
            let Ok(r) = b.path.resolve(scene) else {
                out.stale.push(i);
                continue;
            };
            let before = r.get(scene);
            match r.set(scene, value) {
                Some(written) => {
                    b.value = Some(written);
                    if before != Some(written) {
                        out.changed = true;
                        out.camera |= r.is_camera();
                    }
                    out.edits.push(Edit {
                        binding: i,
                        value: written,
                    });
                }
                None => out.stale.push(i),
            }
        }
        out
    }

    /// The listener's counters so far.
    pub fn counters(&self) -> OscCounters {
        self.shared.counters()
    }

    /// Each binding's latest level and value, in the order of `scene.bindings`.
    pub fn live(&self) -> Vec<LiveValue> {
        self.bound
            .iter()
            .map(|b| LiveValue {
                level: b.level,
                value: b.value,
                received: b.received,
            })
            .collect()
    }

    /// Feeds one datagram to the router as if it had arrived on the socket (for tests and
    /// benchmarks that want no network in the way).
    pub fn feed(&self, datagram: &[u8]) {
        self.shared.handle(datagram);
    }
}
