//! Named simulation presets, each growing a visibly different structure (found by growing
//! 128^3 grids for 200 steps and looking at projections; see docs/volume.md). Agent counts are
//! given for a 256^3 grid and scale with the grid's volume.

use super::params::{Boundary, Params, Spawn};
use crate::error::VolumeError;

/// A named parameter set.
pub struct Preset {
    pub name: &'static str,
    pub description: &'static str,
    /// The parameters, with the agent count for a 256^3 grid.
    pub params: Params,
}

const BASE: Params = Params {
    agents: 1 << 20,
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

/// The preset called `name`, its agent count scaled to a grid of `res` (and its deposit
/// lowered if the agents would overflow a voxel); unknown names list the valid ones.
pub fn find(name: &str, res: [u32; 3]) -> Result<Params, VolumeError> {
    let p = PRESETS.iter().find(|p| p.name == name).ok_or_else(|| {
        let names: Vec<&str> = PRESETS.iter().map(|p| p.name).collect();
        VolumeError::Invalid(format!(
            "unknown physarum preset `{name}` (valid presets: {})",
            names.join(", ")
        ))
    })?;
    let voxels = res.iter().map(|&r| r as f64).product::<f64>();
    let agents = (p.params.agents as f64 * voxels / 256f64.powi(3))
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
        ..p.params.clone()
    })
}
