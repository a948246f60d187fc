//! fathom-live: scene parameters driven live, by LFOs and by OSC over UDP.
//!
//! A scene's bindings (`fathom_core::binding`) name a parameter, a source and a mapping. The
//! [`Modulator`] runs them: LFOs from the frame's time, OSC from a listener thread
//! ([`Modulator::listen`], 127.0.0.1 unless told otherwise) that decodes, matches and counts
//! every packet and hands the latest level per binding to the frame loop through atomics.
//! Once per frame a window (or `fathom render --path`) calls
//!
//! ```text
//! let applied = modulator.apply(&mut scene, t);   // numbers only
//! if applied.changed { session.set_scene(scene.clone())?; }   // re-bakes, never recompiles
//! ```
//!
//! and shows `applied.counters` (packets received, rejected) and [`Modulator::live`] (each
//! binding's level and value). [`send`] sends OSC (`fathom osc-send`). MIDI is not supported:
//! `midir` needs the ALSA development headers (`libasound2-dev`) to build on Linux.

#![warn(missing_docs)]

pub mod error;
pub mod modulator;
pub mod osc;
pub mod send;

pub use error::LiveError;
pub use modulator::{Applied, Edit, LiveValue, Modulator};
pub use osc::OscCounters;
pub use send::Sender;

/// The address the listener binds by default: this machine only.
pub const DEFAULT_OSC_BIND: &str = "127.0.0.1:9000";

#[cfg(test)]
mod tests;
