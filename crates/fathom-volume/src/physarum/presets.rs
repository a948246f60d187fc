//! Named simulation presets, each growing a visibly different structure (found by growing
//! 128^3 grids for 200 steps and looking at projections; see docs/volume.md).
//!
//! The parameters are given for a [`REFERENCE_RES`]^3 grid, and [`find`] scales them to the
//! grid asked for so that a finer grid grows the same structure in finer detail rather than a
//! different one: lengths (sensor distance, step size) scale with the grid's side, so the
//! network spreads over the same fraction of the box in the same number of steps, and the agent
//! count with the side squared (enough agents to keep the strands continuous without paying
//! for a volume's worth). Kept in voxels, a 256^3 grid's agents sense and move half as far
//! relative to the box, and 300 steps only grow the central clump (a tiny lit blob in the
//! picture; docs/log/volume-defaults.md).

use super::params::{Boundary, Params, Spawn};
use crate::error::VolumeError;

/// A named parameter set.
pub struct Preset {
    pub name: &'static str,
    pub description: &'static str,
    /// The parameters for a [`REFERENCE_RES`]^3 grid.
    pub params: Params,
}

/// The grid side the presets' lengths and agent counts are given for.
pub const REFERENCE_RES: u32 = 128;

const BASE: Params = Params {
    agents: 1 << 17,
    sensor_angle: 45.0,
    sensor_distance: 9.0,
    turn_angle: 45.0,
    step_size: 1.0,
    deposit: 1024,
    decay: 0.9,
    diffusion: 0.3,
    roll: 0.0,
    boundary: Boundary::Wrap,
    spawn: Spawn::Uniform,
};

/// Every preset, in the order `fathom volume --help` lists them.
pub const PRESETS: &[Preset] = &[
    Preset {
        name: "tendrils",
        description: "branching tendrils reaching out from a ball at the centre",
        params: Params {
            sensor_angle: 30.0,
            sensor_distance: 16.0,
            turn_angle: 30.0,
            decay: 0.8,
            roll: 45.0,
            boundary: Boundary::Walls,
            spawn: Spawn::Ball(0.5),
            ..BASE
        },
    },
    Preset {
        name: "sheets",
        description: "thin curved membranes walling off cells",
        params: Params {
            sensor_distance: 20.0,
            turn_angle: 60.0,
            step_size: 2.0,
            decay: 0.85,
            diffusion: 0.2,
            ..BASE
        },
    },
    Preset {
        name: "lattice",
        description: "a space-filling network of smooth struts",
        params: Params {
            sensor_angle: 60.0,
            sensor_distance: 12.0,
            step_size: 1.5,
            decay: 0.95,
            diffusion: 0.6,
            roll: 30.0,
            ..BASE
        },
    },
    Preset {
        name: "cage",
        description: "a spherical cage of strands around an empty centre",
        params: Params {
            turn_angle: 22.5,
            decay: 0.92,
            roll: 20.0,
            boundary: Boundary::Walls,
            spawn: Spawn::Ball(0.5),
            ..BASE
        },
    },
];

/// The preset called `name`, scaled to a grid of `res` (lengths with the longest side, agents
/// with the side squared; see the module doc) and its deposit lowered if the agents would
/// overflow a voxel; unknown names list the valid ones.
pub fn find(name: &str, res: [u32; 3]) -> Result<Params, VolumeError> {
    let p = PRESETS.iter().find(|p| p.name == name).ok_or_else(|| {
        let names: Vec<&str> = PRESETS.iter().map(|p| p.name).collect();
        VolumeError::Invalid(format!(
            "unknown physarum preset `{name}` (valid presets: {})",
            names.join(", ")
        ))
    })?;
    let side = res.iter().copied().max().unwrap_or(1) as f32 / REFERENCE_RES as f32;
    let voxels = res.iter().map(|&r| r as f64).product::<f64>();
    let area = (voxels / (REFERENCE_RES as f64).powi(3)).powf(2.0 / 3.0);
    let agents = (p.params.agents as f64 * area)
        .round()
        .clamp(1.0, super::params::MAX_AGENTS as f64) as u32;
    // Big grids get many agents: keep one step's deposits within the overflow bound.
    let deposit = p
        .params
        .deposit
        .min((super::params::MAX_STEP_DEPOSIT / agents as u64) as u32)
        .max(1);
    Ok(Params {
        agents,
        deposit,
        sensor_distance: (p.params.sensor_distance * side).min(MAX_SENSOR_DISTANCE),
        step_size: (p.params.step_size * side).min(MAX_STEP_SIZE),
        ..p.params.clone()
    })
}

/// The largest sensor distance and step size [`Params::validate`] accepts, in voxels.
const MAX_SENSOR_DISTANCE: f32 = 256.0;
const MAX_STEP_SIZE: f32 = 32.0;
