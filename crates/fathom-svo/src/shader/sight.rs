//! A voxel's line of sight: the surface point a pixel through the voxel's centre would show,
//! found by sphere tracing from the eye's side of the voxel, four lines at a time.

use super::{Probe, Shader};
use glam::DVec3;

impl Shader {
    /// The surface point a pixel showing the voxel at world centre `c` (half side `h`) would
    /// see: sphere tracing from where the line of sight from [`Shader::view`]'s eye through
    /// the centre enters the voxel's bounding sphere, until the distance is below a quarter
    /// of the side or the point is inside. Shading there rather than at the centre is what
    /// the sphere tracer does: voxels of a face with sub-pixel holes behind it take the
    /// face's normal, not a hole wall's.
    ///
    /// When the line passes the voxel without meeting the surface (a leaf the conservative
    /// full test keeps in front of an underestimated surface, most of the Mandelbulb zoom's
    /// visible leaves before zoom 1e6), on scenes whose distance is an estimate the trace
    /// goes on, up to [`SIGHT_REACH`] half-diagonals ([`Shader::sight_limits`]), to the
    /// surface a pixel through the centre shows behind it: while such a leaf is drawn, it
    /// shows that surface's colour, as the tracer's pixel does. `None` when the line escapes
    /// or the steps run out, and then [`Shader::surface`] takes [`Shader::newton_point`].
    pub(crate) fn sight_point(&self, ev: &mut Probe, c: DVec3, h: f64) -> Option<SightHit> {
        let hd = h * 3f64.sqrt();
        let (reach, steps) = self.sight_limits();
        let dir = (c - self.view.eye).normalize_or_zero();
        if dir == DVec3::ZERO {
            return None;
        }
        let reach = hd * reach;
        let mut t = -hd;
        for _ in 0..steps {
            let p = c + dir * t;
            let v = self.eval(ev, p);
            if !v.d.is_finite() {
                return None;
            }
            if v.d < 0.5 * h {
                return Some(SightHit::traced(p, v, dir, t, hd));
            }
            t += v.d;
            if t > reach {
                return None;
            }
        }
        None
    }

    /// [`Shader::sight_point`] of four voxels of half side `h` at once (lanes whose `traced`
    /// is false give `None`): [`Shader::sight_lines`] traced to the full reach by
    /// [`Shader::trace4`].
    #[cfg(test)]
    pub(crate) fn sight_points(
        &self,
        ev: &mut Probe,
        c: [DVec3; 4],
        traced: [bool; 4],
        h: f64,
    ) -> [Option<SightHit>; 4] {
        let reach = h * 3f64.sqrt() * self.sight_limits().0;
        let lines = self.sight_lines(c, traced, h);
        self.trace4(ev, lines, h, reach, false).map(Sight::hit)
    }

    /// [`Shader::sight_line`] of four voxels (`None` where `traced` is false).
    #[cfg(test)]
    pub(crate) fn sight_lines(
        &self,
        c: [DVec3; 4],
        traced: [bool; 4],
        h: f64,
    ) -> [Option<SightLine>; 4] {
        std::array::from_fn(|i| traced[i].then(|| self.sight_line(c[i], h)).flatten())
    }

    /// The line of sight of the voxel of half side `h` with centre `c`, not yet traced: from
    /// the eye through the centre, starting where the line enters the voxel's bounding sphere
    /// (`None` when the eye is at the centre).
    pub(crate) fn sight_line(&self, c: DVec3, h: f64) -> Option<SightLine> {
        let dir = (c - self.view.eye).normalize_or_zero();
        (dir != DVec3::ZERO).then_some(SightLine {
            c,
            dir,
            t: -h * 3f64.sqrt(),
            steps: 0,
        })
    }

    /// Traces four lines of sight of voxels of half side `h` (`None` lanes stay
    /// [`Sight::Lost`]) until each meets the surface (its distance below a quarter of the
    /// side), gets a NaN or an infinite distance, runs out of [`Shader::sight_limits`]' steps
    /// (counted over every stretch of its trace), or goes beyond `until` (world units along
    /// the line from the centre): that ends it [`Sight::Passed`] with `pass`, to be traced on
    /// by a later call, and [`Sight::Lost`] without. Each step is one four-lane evaluation
    /// ([`Shader::eval4`]); a lane that has stopped repeats the point of one still tracing, so
    /// the packet costs what its slowest line does (traced one at a time, these traces were a
    /// quarter of a Mandelbulb zoom's subdivision time). Lanes are evaluated independently, so
    /// a line reaches the same points whatever lanes and packets carry it, also when traced
    /// on in other packets than the one it began in (within a few ulps of the scalar trace,
    /// [`Shader::sight_point`]).
    pub(crate) fn trace4(
        &self,
        ev: &mut Probe,
        mut lines: [Option<SightLine>; 4],
        h: f64,
        until: f64,
        pass: bool,
    ) -> [Sight; 4] {
        let hd = h * 3f64.sqrt();
        let max_steps = self.sight_limits().1;
        let mut out = [Sight::Lost; 4];
        loop {
            for (line, out) in lines.iter_mut().zip(&mut out) {
                if let Some(l) = *line
                    && (l.t > until || l.steps >= max_steps)
                {
                    if l.t > until && pass {
                        *out = Sight::Passed(l);
                    }
                    *line = None;
                }
            }
            let Some(first) = lines.iter().flatten().next().copied() else {
                break;
            };
            let p: [DVec3; 4] = std::array::from_fn(|i| {
                let l = lines[i].unwrap_or(first);
                l.c + l.dir * l.t
            });
            let v = self.eval4(ev, p);
            for i in 0..4 {
                let Some(l) = &mut lines[i] else {
                    continue;
                };
                l.steps += 1;
                let d = v[i].d;
                if !d.is_finite() {
                    lines[i] = None;
                } else if d < 0.5 * h {
                    out[i] = Sight::Hit(SightHit::traced(p[i], v[i], l.dir, l.t, hd));
                    lines[i] = None;
                } else {
                    l.t += d;
                }
            }
        }
        out
    }

    /// How far lines of sight are traced, in half-diagonals, and in how many steps:
    /// [`SIGHT_REACH`] and [`SIGHT_STEPS`] where the distance is an estimate (the scenes with
    /// a shell of leaves in front of their surface), the bounding sphere and
    /// [`SIGHT_STEPS_BOUND`] where it is a bound: there no leaves stand in front of the
    /// surface, and tracing on past the voxel gained nothing.
    pub(crate) fn sight_limits(&self) -> (f64, usize) {
        if self.corner_test {
            (SIGHT_REACH, SIGHT_STEPS)
        } else {
            (1.0, SIGHT_STEPS_BOUND)
        }
    }

    /// The surface point of a voxel whose line of sight found none: the centre `c` moved
    /// along the gradient by its distance (one Newton step, at most the half-diagonal).
    pub(crate) fn newton_point(&self, ev: &mut Probe, c: DVec3, h: f64) -> Option<SightHit> {
        let hd = h * 3f64.sqrt();
        let g = self.gradient(ev, c, h);
        let v = self.eval(ev, c);
        let len = g.length();
        let step = (v.d / len.max(1e-300)).clamp(-hd, hd);
        if len > 0.0 && step.is_finite() {
            let p = c - g / len * step;
            Some(SightHit {
                p,
                v: self.eval(ev, p),
                behind: None,
            })
        } else {
            None
        }
    }
}

/// A voxel's line of sight while it is traced ([`Shader::trace4`]): through centre `c` in
/// direction `dir`, at `t` along it from the centre (world units), after `steps` evaluations.
#[derive(Clone, Copy, Debug)]
pub(crate) struct SightLine {
    pub(crate) c: DVec3,
    pub(crate) dir: DVec3,
    pub(crate) t: f64,
    pub(crate) steps: usize,
}

/// Where a line of sight stands after a stretch of tracing ([`Shader::trace4`]).
#[derive(Clone, Copy, Debug)]
pub(crate) enum Sight {
    /// It met the surface.
    Hit(SightHit),
    /// It went past the end of the stretch without meeting the surface, or is not traced yet:
    /// to be traced on.
    Passed(SightLine),
    /// It escaped (went past the end of a stretch that does not pass lines on), met a NaN
    /// or an infinite distance, ran out of steps, or was never traced.
    Lost,
}

impl Sight {
    /// The surface point, if the line met the surface.
    pub(crate) fn hit(self) -> Option<SightHit> {
        match self {
            Sight::Hit(x) => Some(x),
            _ => None,
        }
    }
}

/// A surface point found for a voxel: by its line of sight ([`Shader::sight_point`]) or,
/// when that found none, by a Newton step from its centre ([`Shader::newton_point`]).
#[derive(Clone, Copy, Debug)]
pub(crate) struct SightHit {
    /// The point (world units relative to the origin).
    pub(crate) p: DVec3,
    /// The tape's value there.
    pub(crate) v: fathom_core::Value<f64>,
    /// The line of sight's direction when the point lies past the voxel's bounding sphere, on
    /// the far side from the eye: the line passed the voxel (a Newton point never does: its
    /// step is at most the half-diagonal).
    pub(crate) behind: Option<DVec3>,
}

impl SightHit {
    /// The hit of a line of sight in direction `dir` from the voxel's centre, `t` along it,
    /// for a voxel of half-diagonal `hd`.
    pub(crate) fn traced(
        p: DVec3,
        v: fathom_core::Value<f64>,
        dir: DVec3,
        t: f64,
        hd: f64,
    ) -> SightHit {
        SightHit {
            p,
            v,
            behind: (t > hd).then_some(dir),
        }
    }
}

/// Steps of a voxel's line-of-sight trace on scenes whose distance is an estimate
/// ([`Shader::sight_limits`]): 48 (24 before lines went past the voxel), so that a trace
/// that has passed the voxel can still cover a few times the voxel in the estimate's short
/// steps near a surface.
const SIGHT_STEPS: usize = 48;

/// Steps of a voxel's line-of-sight trace on scenes whose distance is a bound, where it
/// ends at the voxel's bounding sphere.
const SIGHT_STEPS_BOUND: usize = 24;

/// How far a voxel's line of sight is traced, in half-diagonals from its centre: on past
/// the voxel, to what a pixel through its centre would show behind it (see
/// [`Shader::sight_point`]). 64 gave the same pictures as 1000 on the Mandelbulb zoom.
const SIGHT_REACH: f64 = 64.0;
