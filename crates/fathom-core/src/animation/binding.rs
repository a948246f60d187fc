//! Modulation bindings, as the scene file keeps them: a parameter (by its path, see
//! [`crate::param_path`]) driven by a source, an LFO or an OSC address, through a mapping onto
//! a range of the parameter, with optional smoothing.
//!
//! A source gives a level in [0, 1]: an LFO `0.5 + 0.5 * depth * wave(rate * t + phase)`, an
//! OSC value `(x - from.0) / (from.1 - from.0)` clamped to [0, 1]. The parameter gets
//! `to.0 + level * (to.1 - to.0)`, clamped to its declared range. This module holds the data,
//! its checks and the waveforms; the runtime (OSC listener, smoothing, per-frame apply) lives
//! in the `fathom-live` crate.

use crate::param_path::{ParamPath, ParamPathError};
use serde::{Deserialize, Serialize};
use thiserror::Error;

/// Most bindings in one scene.
pub const MAX_BINDINGS: usize = 256;
/// Fastest LFO, Hz.
pub const MAX_LFO_RATE: f64 = 1000.0;
/// Longest smoothing time constant, seconds.
pub const MAX_SMOOTHING: f64 = 60.0;
/// Highest OSC argument index a binding may read.
pub const MAX_OSC_ARG: usize = 63;
/// Longest OSC address pattern, bytes.
pub const MAX_OSC_ADDRESS: usize = 256;

/// One parameter driven by one source.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Binding {
    /// The parameter path (`root.shape.power`, `lights[0].intensity`, `camera.fov`).
    pub param: String,
    /// Where the value comes from.
    pub source: Source,
    /// The parameter values the source's level 0 and 1 map to (may be reversed); must lie in
    /// the parameter's declared range.
    pub to: (f64, f64),
    /// Time constant of exponential smoothing, seconds (0: none), [0, 60].
    #[serde(default, skip_serializing_if = "is_zero")]
    pub smoothing: f64,
}

fn is_zero(x: &f64) -> bool {
    *x == 0.0
}

/// A modulation source. Written `Lfo(wave: Sine, rate: 0.5)` or `Osc(address: "/a")` in scene
/// files (see [`SourceText`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(from = "SourceText", into = "SourceText")]
pub enum Source {
    /// A low-frequency oscillator.
    Lfo(Lfo),
    /// The value of an OSC message arriving over UDP.
    Osc(OscInput),
}

/// How a [`Source`] is written: struct variants, so a file says `Lfo(wave: Sine, rate: 0.5)`
/// rather than `Lfo((wave: Sine, rate: 0.5))`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum SourceText {
    /// An LFO: see [`Lfo`] for the fields.
    Lfo {
        /// The waveform.
        wave: Wave,
        /// Cycles per second, [0, 1000].
        rate: f64,
        /// Offset in cycles.
        #[serde(default, skip_serializing_if = "is_zero")]
        phase: f64,
        /// Share of the `to` range the swing covers, [0, 1]; 1 when left out.
        #[serde(default = "one")]
        depth: f64,
        /// Seed of the noise wave.
        #[serde(default, skip_serializing_if = "is_zero_u32")]
        seed: u32,
    },
    /// An OSC input: see [`OscInput`] for the fields.
    Osc {
        /// OSC address pattern matched against incoming addresses.
        address: String,
        /// Which argument carries the value, [0, 63].
        #[serde(default, skip_serializing_if = "is_zero_usize")]
        arg: usize,
        /// The input values mapped to level 0 and 1; (0, 1) when left out.
        #[serde(default = "unit_range")]
        from: (f64, f64),
    },
}

impl From<SourceText> for Source {
    fn from(t: SourceText) -> Source {
        match t {
            SourceText::Lfo {
                wave,
                rate,
                phase,
                depth,
                seed,
            } => Source::Lfo(Lfo {
                wave,
                rate,
                phase,
                depth,
                seed,
            }),
            SourceText::Osc { address, arg, from } => Source::Osc(OscInput { address, arg, from }),
        }
    }
}

impl From<Source> for SourceText {
    fn from(s: Source) -> SourceText {
        match s {
            Source::Lfo(l) => SourceText::Lfo {
                wave: l.wave,
                rate: l.rate,
                phase: l.phase,
                depth: l.depth,
                seed: l.seed,
            },
            Source::Osc(o) => SourceText::Osc {
                address: o.address,
                arg: o.arg,
                from: o.from,
            },
        }
    }
}

/// LFO waveforms. Each starts at its middle at phase 0 and rises (the noise aside).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Wave {
    /// A sine, rising from the middle at phase 0.
    Sine,
    /// A triangle, rising from the middle at phase 0.
    Triangle,
    /// Rises from the middle to the top, jumps to the bottom, rises again.
    Saw,
    /// Smoothed value noise: a random level per cycle, eased between cycles.
    Noise,
}

/// A low-frequency oscillator.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Lfo {
    /// The waveform.
    pub wave: Wave,
    /// Cycles per second, [0, 1000].
    pub rate: f64,
    /// Offset in cycles (0.25 starts a sine at its top).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub phase: f64,
    /// How much of the `to` range the swing covers, [0, 1] (1: all of it).
    #[serde(default = "one")]
    pub depth: f64,
    /// Seed of the noise wave (two noise LFOs with different seeds differ).
    #[serde(default, skip_serializing_if = "is_zero_u32")]
    pub seed: u32,
}

fn one() -> f64 {
    1.0
}
fn is_zero_u32(x: &u32) -> bool {
    *x == 0
}

/// Which OSC messages feed a binding and how their values are read.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OscInput {
    /// OSC address pattern matched against incoming addresses (`/muse/elements/alpha_absolute`,
    /// `/audio/band/*`; `?`, `*`, `[a-z]` and `{a,b}` as in OSC 1.0).
    pub address: String,
    /// Which argument of the message carries the value (0: the first), [0, 63].
    #[serde(default, skip_serializing_if = "is_zero_usize")]
    pub arg: usize,
    /// The input values mapped to level 0 and 1 (values outside are clamped and counted).
    #[serde(default = "unit_range")]
    pub from: (f64, f64),
}

fn is_zero_usize(x: &usize) -> bool {
    *x == 0
}
fn unit_range() -> (f64, f64) {
    (0.0, 1.0)
}

impl Wave {
    /// The waveform at `x` cycles, in [-1, 1].
    pub fn at(self, x: f64, seed: u32) -> f64 {
        let frac = |v: f64| v - v.floor();
        match self {
            Wave::Sine => (std::f64::consts::TAU * x).sin(),
            Wave::Triangle => 4.0 * (frac(x - 0.25) - 0.5).abs() - 1.0,
            Wave::Saw => 2.0 * frac(x + 0.5) - 1.0,
            Wave::Noise => {
                let k = x.floor();
                let f = x - k;
                let (a, b) = (noise_level(seed, k as i64), noise_level(seed, k as i64 + 1));
                a + (b - a) * (f * f * (3.0 - 2.0 * f))
            }
        }
    }
}

/// A random level in [-1, 1] for cycle `k` (splitmix64 of the seed and cycle).
fn noise_level(seed: u32, k: i64) -> f64 {
    let mut z = (k as u64) ^ ((seed as u64) << 32) ^ 0x9e37_79b9_7f4a_7c15;
    z = z.wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^= z >> 31;
    (z >> 11) as f64 / (1u64 << 52) as f64 - 1.0
}

impl Lfo {
    /// The level in [0, 1] at `t` seconds.
    pub fn level(&self, t: f64) -> f64 {
        let w = self.wave.at(self.rate * t + self.phase, self.seed);
        (0.5 + 0.5 * self.depth * w).clamp(0.0, 1.0)
    }
}

impl OscInput {
    /// The level in [0, 1] of an input value, and whether it had to be clamped; `None` for a
    /// value that is not finite.
    pub fn level(&self, x: f64) -> Option<(f64, bool)> {
        if !x.is_finite() {
            return None;
        }
        let (lo, hi) = self.from;
        let l = (x - lo) / (hi - lo);
        Some((l.clamp(0.0, 1.0), !(0.0..=1.0).contains(&l)))
    }
}

impl Binding {
    /// The parameter value for a source level in [0, 1] (before clamping to the declared
    /// range, which [`crate::param_resolve::Resolved::set`] does).
    pub fn map(&self, level: f64) -> f64 {
        self.to.0 + level * (self.to.1 - self.to.0)
    }
}

/// What is wrong with a binding. The scene's error adds where (`bindings[2].to`).
#[derive(Clone, Debug, PartialEq, Error)]
pub enum BindingError {
    /// The scene has more than [`MAX_BINDINGS`] bindings.
    #[error("{count} bindings; the limit is {MAX_BINDINGS}")]
    TooMany {
        /// How many bindings the scene has.
        count: usize,
    },
    /// The parameter path does not parse.
    #[error("{0}")]
    Param(ParamPathError),
    /// The `to` range is not finite or leaves the parameter's declared range.
    #[error("to = ({lo}, {hi}) must lie in `{param}`'s range {range}, with finite values")]
    To {
        /// The parameter path.
        param: String,
        /// The value level 0 maps to.
        lo: f64,
        /// The value level 1 maps to.
        hi: f64,
        /// The parameter's declared range, as text.
        range: String,
    },
    /// The smoothing time is negative, not finite or above [`MAX_SMOOTHING`].
    #[error("smoothing = {value} s is out of range [0, {MAX_SMOOTHING}]")]
    Smoothing {
        /// The smoothing given, seconds.
        value: f64,
    },
    /// The LFO rate is negative, not finite or above [`MAX_LFO_RATE`].
    #[error("rate = {value} Hz is out of range [0, {MAX_LFO_RATE}]")]
    Rate {
        /// The rate given, Hz.
        value: f64,
    },
    /// The LFO depth is outside [0, 1].
    #[error("depth = {value} is out of range [0, 1]")]
    Depth {
        /// The depth given.
        value: f64,
    },
    /// The LFO phase is not finite.
    #[error("phase = {value} must be a finite number of cycles")]
    Phase {
        /// The phase given, cycles.
        value: f64,
    },
    /// The OSC address fails [`plausible_osc_address`].
    #[error(
        "address `{address}` is not an OSC address pattern: it must start with `/`, be at most \
         {MAX_OSC_ADDRESS} bytes of printable ASCII without spaces or `#`"
    )]
    Address {
        /// The address given.
        address: String,
    },
    /// The OSC argument index is above [`MAX_OSC_ARG`].
    #[error("arg = {value} is out of range [0, {MAX_OSC_ARG}]")]
    Arg {
        /// The index given.
        value: usize,
    },
    /// The OSC `from` range is not two different finite numbers.
    #[error("from = ({lo}, {hi}) must be two different finite numbers")]
    From {
        /// The input value mapped to level 0.
        lo: f64,
        /// The input value mapped to level 1.
        hi: f64,
    },
}

/// Whether `a` may be an OSC address pattern (the OSC runtime checks the pattern syntax in
/// full when it builds its matcher).
pub fn plausible_osc_address(a: &str) -> bool {
    a.starts_with('/')
        && a.len() >= 2
        && a.len() <= MAX_OSC_ADDRESS
        && a.bytes().all(|b| b.is_ascii_graphic() && b != b'#')
}

impl Binding {
    /// Checks what can be checked without a scene: the path's syntax, the smoothing and the
    /// source. The error's first part says where inside the binding (`.param`, `.source`).
    /// That the path names a number of a scene and `to` lies in its range is checked with
    /// the scene ([`crate::validate::validate_bindings`]).
    pub fn check(&self) -> Result<(), (&'static str, BindingError)> {
        ParamPath::parse(&self.param).map_err(|e| (".param", BindingError::Param(e)))?;
        let s = self.smoothing;
        if !(s.is_finite() && (0.0..=MAX_SMOOTHING).contains(&s)) {
            return Err((".smoothing", BindingError::Smoothing { value: s }));
        }
        match &self.source {
            Source::Lfo(l) => {
                if !(l.rate.is_finite() && (0.0..=MAX_LFO_RATE).contains(&l.rate)) {
                    return Err((".source", BindingError::Rate { value: l.rate }));
                }
                if !(l.depth.is_finite() && (0.0..=1.0).contains(&l.depth)) {
                    return Err((".source", BindingError::Depth { value: l.depth }));
                }
                if !l.phase.is_finite() {
                    return Err((".source", BindingError::Phase { value: l.phase }));
                }
            }
            Source::Osc(o) => {
                if !plausible_osc_address(&o.address) {
                    return Err((
                        ".source",
                        BindingError::Address {
                            address: o.address.clone(),
                        },
                    ));
                }
                if o.arg > MAX_OSC_ARG {
                    return Err((".source", BindingError::Arg { value: o.arg }));
                }
                let (lo, hi) = o.from;
                if !(lo.is_finite() && hi.is_finite() && lo != hi) {
                    return Err((".source", BindingError::From { lo, hi }));
                }
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lfo(wave: Wave) -> Lfo {
        Lfo {
            wave,
            rate: 2.0,
            phase: 0.0,
            depth: 1.0,
            seed: 0,
        }
    }

    #[test]
    fn lfo_values_at_given_times() {
        let close = |a: f64, b: f64| (a - b).abs() < 1e-12;
        // 2 Hz: a cycle every 0.5 s.
        let s = lfo(Wave::Sine);
        for (t, want) in [
            (0.0, 0.5),
            (0.125, 1.0),
            (0.25, 0.5),
            (0.375, 0.0),
            (0.5, 0.5),
        ] {
            assert!(close(s.level(t), want), "sine at {t}: {}", s.level(t));
        }
        let tri = lfo(Wave::Triangle);
        for (t, want) in [
            (0.0, 0.5),
            (0.0625, 0.75),
            (0.125, 1.0),
            (0.25, 0.5),
            (0.375, 0.0),
        ] {
            assert!(
                close(tri.level(t), want),
                "triangle at {t}: {}",
                tri.level(t)
            );
        }
        let saw = lfo(Wave::Saw);
        for (t, want) in [
            (0.0, 0.5),
            (0.125, 0.75),
            (0.2499, 0.9998),
            (0.25, 0.0),
            (0.375, 0.25),
        ] {
            assert!(
                (saw.level(t) - want).abs() < 1e-9,
                "saw at {t}: {}",
                saw.level(t)
            );
        }
        // Depth scales the swing about the middle; phase shifts it (a quarter cycle: the top).
        let half = Lfo {
            depth: 0.5,
            ..s.clone()
        };
        assert!(close(half.level(0.125), 0.75));
        let shifted = Lfo { phase: 0.25, ..s };
        assert!(close(shifted.level(0.0), 1.0));
        // Noise: deterministic, in range, continuous, equal to its cycle level at whole cycles,
        // and different for another seed.
        let n = lfo(Wave::Noise);
        let n2 = Lfo {
            seed: 7,
            ..n.clone()
        };
        let mut differs = false;
        let mut prev = n.level(0.0);
        for i in 1..=2000 {
            let t = i as f64 * 0.001;
            let v = n.level(t);
            assert!((0.0..=1.0).contains(&v));
            assert!((v - prev).abs() < 0.01, "jump at {t}");
            assert_eq!(v, n.level(t));
            differs |= (v - n2.level(t)).abs() > 0.05;
            prev = v;
        }
        assert!(differs);
        assert!(close(n.level(0.5), 0.5 + 0.5 * noise_level(0, 1)));
    }

    #[test]
    fn osc_levels_clamp_and_refuse_nan() {
        let o = OscInput {
            address: "/a".into(),
            arg: 0,
            from: (-1.0, 3.0),
        };
        assert_eq!(o.level(1.0), Some((0.5, false)));
        assert_eq!(o.level(7.0), Some((1.0, true)));
        assert_eq!(o.level(-9.0), Some((0.0, true)));
        assert_eq!(o.level(f64::NAN), None);
        assert_eq!(o.level(f64::INFINITY), None);
        let reversed = OscInput {
            from: (1.0, 0.0),
            ..o
        };
        assert_eq!(reversed.level(0.25), Some((0.75, false)));
    }
}
