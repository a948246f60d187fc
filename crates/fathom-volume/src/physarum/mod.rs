//! The 3D physarum simulation (Jones 2010, extended to 3D as in the seed document): agents
//! with a position and an orthonormal basis read the trail grid at one forward and three
//! flanking sensors, turn toward the strongest reading (a random choice among ties), move,
//! and deposit; then the grid diffuses and decays. The network they grow is the density the
//! volume path tracer renders.
//!
//! One step runs in three phases, each over rayon and each independent of the thread count:
//! every agent senses the previous grid, turns and moves, drawing only from its own random
//! stream (phase 1 reads the grid, writes only agents); the deposits are summed into the grid
//! in z slabs, each slab scanning every agent's voxel (integer sums: the order does not
//! matter); diffusion and decay compute each voxel from the previous grid alone. The same
//! seed therefore gives the same bytes on any number of threads.

pub mod diffuse;
pub mod params;
pub mod presets;

use crate::error::VolumeError;
use crate::grid::{DensityGrid, Grid, TrailGrid, WorldBox, check_size};
use crate::sampling::{Stream, basis, uniform_sphere};
use glam::Vec3;
pub use params::{Boundary, Params, Spawn};
use rayon::prelude::*;
use std::time::Instant;

/// One agent: where it is, where it faces (`forward`, with `up` completing the sensor ring's
/// frame; right is `forward x up`), and its own random stream.
#[derive(Clone, Debug)]
pub struct Agent {
    pub pos: Vec3,
    pub forward: Vec3,
    pub up: Vec3,
    rng: Stream,
}

impl PartialEq for Agent {
    fn eq(&self, o: &Agent) -> bool {
        let bits = |v: Vec3| v.to_array().map(f32::to_bits);
        bits(self.pos) == bits(o.pos)
            && bits(self.forward) == bits(o.forward)
            && bits(self.up) == bits(o.up)
    }
}

/// Wall time of one step's phases, in milliseconds.
#[derive(Clone, Copy, Debug, Default, serde::Serialize)]
pub struct StepTimes {
    /// Re-order the agents along a Morton curve (every few steps).
    pub sort_ms: f64,
    /// Sense, turn and move every agent.
    pub move_ms: f64,
    /// Add the deposits to the grid.
    pub deposit_ms: f64,
    /// Diffuse and decay the grid.
    pub diffuse_ms: f64,
}

/// Angles of the three flanking sensors around the forward axis.
const RING: [f32; 3] = [0.0, 120.0, 240.0];

/// Per-step constants derived from the parameters.
#[derive(Clone)]
struct Steering {
    sensor_cos: f32,
    sensor_sin: f32,
    turn_cos: f32,
    turn_sin: f32,
    ring: [(f32, f32); 3],
    /// (cos, sin) of roll angles evenly spaced over [-roll, roll] (empty: no roll).
    roll: Vec<(f32, f32)>,
}

/// Roll angles an agent chooses from each step.
const ROLL_STEPS: usize = 256;

/// A running simulation.
pub struct Simulation {
    params: Params,
    res: [u32; 3],
    agents: Vec<Agent>,
    /// Each agent's voxel after its last move (the deposit phase reads it).
    cells: Vec<u32>,
    trail: Vec<u32>,
    scratch: Vec<u32>,
    steps: u64,
}

/// Bytes one agent costs (its state and its voxel index).
const AGENT_BYTES: u64 = std::mem::size_of::<Agent>() as u64 + 4;

impl Simulation {
    /// Spawns the agents in an empty `res` grid. Refuses bad parameters, and grids or agent
    /// counts whose memory exceeds `limit` bytes, before allocating.
    pub fn new(params: Params, res: [u32; 3], seed: u64, limit: u64) -> Result<Self, VolumeError> {
        params.validate()?;
        let voxels = check_size("physarum grid", res.map(u64::from), 8, limit)?;
        let need = voxels as u64 * 8 + params.agents as u64 * AGENT_BYTES;
        if need > limit {
            return Err(VolumeError::TooLarge {
                what: format!("physarum with {} agents", params.agents),
                res_x: res[0] as u64,
                res_y: res[1] as u64,
                res_z: res[2] as u64,
                bytes: need,
                limit,
            });
        }
        let size = Vec3::new(res[0] as f32, res[1] as f32, res[2] as f32);
        let agents: Vec<Agent> = (0..params.agents as u64)
            .into_par_iter()
            .map(|i| spawn(&params, size, Stream::new(seed, i, 0x000a_6e17)))
            .collect();
        let cells = agents.iter().map(|a| cell_of(a.pos, res)).collect();
        Ok(Simulation {
            params,
            res,
            agents,
            cells,
            trail: vec![0; voxels],
            scratch: vec![0; voxels],
            steps: 0,
        })
    }

    /// The parameters.
    pub fn params(&self) -> &Params {
        &self.params
    }

    /// Steps run so far.
    pub fn steps(&self) -> u64 {
        self.steps
    }

    /// The agents.
    pub fn agents(&self) -> &[Agent] {
        &self.agents
    }

    /// The trail counts, x fastest.
    pub fn trail_counts(&self) -> &[u32] {
        &self.trail
    }

    /// One step: sense, turn, move; deposit; diffuse and decay. Returns how long each phase
    /// took.
    pub fn step(&mut self) -> StepTimes {
        let t0 = Instant::now();
        if self.steps.is_multiple_of(RESORT_EVERY) {
            self.sort_agents();
        }
        let ts = Instant::now();
        let p = &self.params;
        let rad = |deg: f32| deg.to_radians();
        let steer = Steering {
            sensor_cos: rad(p.sensor_angle).cos(),
            sensor_sin: rad(p.sensor_angle).sin(),
            turn_cos: rad(p.turn_angle).cos(),
            turn_sin: rad(p.turn_angle).sin(),
            ring: RING.map(|a| (rad(a).cos(), rad(a).sin())),
            roll: roll_table(rad(p.roll)),
        };
        let (res, trail) = (self.res, &self.trail);
        let (sd, step, boundary) = (p.sensor_distance, p.step_size, p.boundary);
        self.agents
            .par_iter_mut()
            .zip(self.cells.par_iter_mut())
            .with_min_len(4096)
            .for_each(|(a, cell)| {
                move_agent(a, &steer, sd, step, boundary, res, trail);
                *cell = cell_of(a.pos, res);
            });
        let (diffusion, decay) = (p.diffusion, p.decay);
        let t1 = Instant::now();
        self.deposit();
        let t2 = Instant::now();
        diffuse::diffuse(
            &self.trail,
            &mut self.scratch,
            self.res,
            diffusion,
            decay,
            boundary,
        );
        std::mem::swap(&mut self.trail, &mut self.scratch);
        self.steps += 1;
        let ms = |a: Instant, b: Instant| (b - a).as_secs_f64() * 1e3;
        let t3 = Instant::now();
        StepTimes {
            sort_ms: ms(t0, ts),
            move_ms: ms(ts, t1),
            deposit_ms: ms(t1, t2),
            diffuse_ms: ms(t2, t3),
        }
    }

    /// Re-orders the agents by the block of voxels they are in (a stable counting sort), so
    /// that agents next to each other in memory read nearby voxels: the grid does not fit in
    /// cache. The order of the agents changes nothing else (each carries its own random
    /// stream; the deposits are integer sums), and a stable sort of the same agents gives the
    /// same order on any thread count.
    fn sort_agents(&mut self) {
        let blocks = self.res.map(|r| r.div_ceil(SORT_BLOCK));
        let key = |a: &Agent| {
            let b = |k: usize| (a.pos[k] as u32 / SORT_BLOCK).min(blocks[k] - 1);
            (b(0) + blocks[0] * (b(1) + blocks[1] * b(2))) as usize
        };
        let keys: Vec<u32> = self.agents.par_iter().map(|a| key(a) as u32).collect();
        let mut start = vec![0usize; (blocks[0] * blocks[1] * blocks[2]) as usize + 1];
        for &k in &keys {
            start[k as usize + 1] += 1;
        }
        for i in 1..start.len() {
            start[i] += start[i - 1];
        }
        let mut order = vec![0u32; keys.len()];
        for (i, &k) in keys.iter().enumerate() {
            order[start[k as usize]] = i as u32;
            start[k as usize] += 1;
        }
        self.agents = order
            .par_iter()
            .map(|&i| self.agents[i as usize].clone())
            .collect();
        self.cells = self
            .agents
            .par_iter()
            .map(|a| cell_of(a.pos, self.res))
            .collect();
    }

    /// Adds every agent's deposit to its voxel: slabs of z planes in parallel, each scanning
    /// all agents' voxels and adding those inside it.
    fn deposit(&mut self) {
        let plane = (self.res[0] * self.res[1]) as usize;
        // One slab per thread: each scans every agent's voxel once.
        let slabs = rayon::current_num_threads().min(self.res[2] as usize);
        let per = (self.res[2] as usize).div_ceil(slabs) * plane;
        let (cells, dep) = (&self.cells, self.params.deposit);
        self.trail
            .par_chunks_mut(per)
            .enumerate()
            .for_each(|(k, slab)| {
                let (lo, hi) = ((k * per) as u32, (k * per + slab.len()) as u32);
                for &c in cells {
                    if c >= lo && c < hi {
                        let v = &mut slab[(c - lo) as usize];
                        *v = v.saturating_add(dep);
                    }
                }
            });
    }

    /// The trail counts as a grid over a box centred at the origin whose longest side is 2.
    pub fn trail(&self) -> TrailGrid {
        Grid::from_data(self.res, self.trail.clone(), default_box(self.res)).expect("sizes match")
    }

    /// Densities for rendering: trail counts divided by the 99.9th percentile of the non-zero
    /// counts, so the dense strands have density about 1 whatever the deposit and decay.
    pub fn density(&self) -> DensityGrid {
        density_of(&self.trail(), 0.999)
    }
}

/// The box a simulation grid occupies: centred at the origin, longest side 2.
pub fn default_box(res: [u32; 3]) -> WorldBox {
    let r = Vec3::new(res[0] as f32, res[1] as f32, res[2] as f32);
    let half = r / r.max_element();
    WorldBox::new(-half, half).expect("a valid box")
}

/// Trail counts to densities, normalised by the `q` quantile of the non-zero counts.
pub fn density_of(trail: &TrailGrid, q: f64) -> DensityGrid {
    let mut nz: Vec<u32> = trail
        .data()
        .par_iter()
        .copied()
        .filter(|&v| v > 0)
        .collect();
    let norm = if nz.is_empty() {
        1.0
    } else {
        let k = (((nz.len() - 1) as f64) * q) as usize;
        *nz.select_nth_unstable(k).1 as f32
    };
    let data = trail.data().par_iter().map(|&v| v as f32 / norm).collect();
    Grid::from_data(trail.res(), data, trail.bbox).expect("sizes match")
}

/// Steps between re-orderings of the agents.
const RESORT_EVERY: u64 = 8;

/// Side of the voxel blocks the agents are sorted by.
const SORT_BLOCK: u32 = 8;

/// The storage index of the voxel holding `pos` (which is inside the grid).
#[inline(always)]
fn cell_of(pos: Vec3, res: [u32; 3]) -> u32 {
    let c = |a: usize| (pos[a] as u32).min(res[a] - 1);
    c(0) + res[0] * (c(1) + res[1] * c(2))
}

/// The voxel coordinate of `v` along an axis of `r` voxels, wrapped or clamped.
#[inline(always)]
fn axis_index(v: f32, r: i32, b: Boundary) -> i32 {
    let i = v.floor() as i32;
    match b {
        // Sensors reach less than a grid side past it in all but tiny grids: one add or
        // subtract instead of a division.
        Boundary::Wrap if i < 0 => {
            if i + r >= 0 {
                i + r
            } else {
                i.rem_euclid(r)
            }
        }
        Boundary::Wrap if i >= r => {
            if i - r < r {
                i - r
            } else {
                i.rem_euclid(r)
            }
        }
        Boundary::Wrap => i,
        Boundary::Walls => i.clamp(0, r - 1),
    }
}

/// The trail count at `p` (nearest voxel), outside the grid wrapped or clamped.
#[inline(always)]
fn sense(trail: &[u32], res: [u32; 3], p: Vec3, b: Boundary) -> u32 {
    let x = axis_index(p.x, res[0] as i32, b);
    let y = axis_index(p.y, res[1] as i32, b);
    let z = axis_index(p.z, res[2] as i32, b);
    trail[(x + res[0] as i32 * (y + res[1] as i32 * z)) as usize]
}

/// (cos, sin) of [`ROLL_STEPS`] angles evenly spaced over [-roll, roll]; empty for no roll.
fn roll_table(roll: f32) -> Vec<(f32, f32)> {
    if roll <= 0.0 {
        return Vec::new();
    }
    (0..ROLL_STEPS)
        .map(|i| {
            let psi = roll * (2.0 * (i as f32 + 0.5) / ROLL_STEPS as f32 - 1.0);
            (psi.cos(), psi.sin())
        })
        .collect()
}

/// A new agent, placed and oriented by the spawn rule.
fn spawn(p: &Params, size: Vec3, mut rng: Stream) -> Agent {
    let centre = 0.5 * size;
    let half = 0.5 * size.min_element();
    let dir = uniform_sphere(rng.f32(), rng.f32());
    let (pos, forward) = match p.spawn {
        Spawn::Uniform => (Vec3::new(rng.f32(), rng.f32(), rng.f32()) * size, dir),
        Spawn::Ball(r) => {
            let rr = r * half * rng.f32().cbrt();
            (centre + uniform_sphere(rng.f32(), rng.f32()) * rr, dir)
        }
        Spawn::Shell(r) => {
            let n = uniform_sphere(rng.f32(), rng.f32());
            (centre + n * (r * half), -n)
        }
    };
    let pos = pos.clamp(Vec3::ZERO, size - 1e-3);
    let up = basis(forward).0;
    Agent {
        pos,
        forward,
        up,
        rng,
    }
}

/// Sense, turn, roll, move (with the boundary rule) for one agent.
#[inline(always)]
fn move_agent(
    a: &mut Agent,
    s: &Steering,
    sd: f32,
    step: f32,
    b: Boundary,
    res: [u32; 3],
    trail: &[u32],
) {
    let right = a.forward.cross(a.up);
    let ring_dir = |k: usize| a.up * s.ring[k].0 + right * s.ring[k].1;
    let mut best = sense(trail, res, a.pos + a.forward * sd, b);
    let mut ties = [0usize; 4];
    let mut n = 1;
    for k in 0..3 {
        let d = a.forward * s.sensor_cos + ring_dir(k) * s.sensor_sin;
        let v = sense(trail, res, a.pos + d * sd, b);
        if v > best {
            best = v;
            n = 0;
        }
        if v == best {
            ties[n] = k + 1;
            n += 1;
        }
    }
    let choice = if n == 1 {
        ties[0]
    } else {
        ties[a.rng.below(n as u32) as usize]
    };
    if choice > 0 {
        // Rotate the frame in the plane of forward and the chosen ring direction
        // d = cos(phi) up + sin(phi) right: forward turns toward d, d turns to d2, and
        // e = forward x d stays. Since up = cos(phi) d - sin(phi) e, the new up is
        // cos(phi) d2 - sin(phi) e.
        let (c, sn) = s.ring[choice - 1];
        let d = ring_dir(choice - 1);
        let e = a.forward.cross(d);
        let d2 = d * s.turn_cos - a.forward * s.turn_sin;
        a.forward = a.forward * s.turn_cos + d * s.turn_sin;
        a.up = d2 * c - e * sn;
    }
    if !s.roll.is_empty() {
        let (pc, ps) = s.roll[a.rng.below(ROLL_STEPS as u32) as usize];
        let right = a.forward.cross(a.up);
        a.up = a.up * pc + right * ps;
    }
    // The rotations keep the frame orthonormal up to rounding: one Newton step of 1 / sqrt
    // (from 1) per vector holds it there without a square root or a division.
    a.forward *= 1.5 - 0.5 * a.forward.length_squared();
    a.up -= a.forward * a.forward.dot(a.up);
    a.up *= 1.5 - 0.5 * a.up.length_squared();
    a.pos += a.forward * step;
    let size = Vec3::new(res[0] as f32, res[1] as f32, res[2] as f32);
    for k in 0..3 {
        match b {
            Boundary::Wrap => {
                // A step is shorter than the grid side in all but tiny grids.
                if a.pos[k] < 0.0 {
                    a.pos[k] += size[k];
                } else if a.pos[k] >= size[k] {
                    a.pos[k] -= size[k];
                }
                if !(a.pos[k] >= 0.0 && a.pos[k] < size[k]) {
                    a.pos[k] = a.pos[k].rem_euclid(size[k]);
                    if a.pos[k] >= size[k] {
                        a.pos[k] = 0.0;
                    }
                }
            }
            Boundary::Walls => {
                if a.pos[k] < 0.0 || a.pos[k] >= size[k] {
                    a.pos[k] = if a.pos[k] < 0.0 {
                        -a.pos[k]
                    } else {
                        2.0 * size[k] - a.pos[k]
                    };
                    a.pos[k] = a.pos[k].clamp(0.0, size[k] - 1e-3);
                    a.forward[k] = -a.forward[k];
                    a.up[k] = -a.up[k];
                }
            }
        }
    }
}

#[cfg(test)]
mod tests;
