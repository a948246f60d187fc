//! Named simulation presets, each growing a visibly different structure. Agent counts are
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

/// Every preset, in the order `fathom volume --help` lists them.
pub fn presets() -> Vec<Preset> {
    vec![
        Preset {
            name: "tendrils",
            description: "branching tendrils grown from a ball at the centre",
            params: Params {
                agents: 1 << 20,
                sensor_angle: 30.0,
                sensor_distance: 8.0,
                turn_angle: 20.0,
                step_size: 1.0,
                deposit: 1024,
                decay: 0.92,
                diffusion: 0.3,
                roll: 10.0,
                boundary: Boundary::Walls,
                spawn: Spawn::Ball(0.5),
            },
        },
        Preset {
            name: "sheets",
            description: "curved membranes between cavities",
            params: Params {
                agents: 1 << 20,
                sensor_angle: 60.0,
                sensor_distance: 12.0,
                turn_angle: 45.0,
                step_size: 1.5,
                deposit: 1024,
                decay: 0.95,
                diffusion: 0.6,
                roll: 30.0,
                boundary: Boundary::Wrap,
                spawn: Spawn::Uniform,
            },
        },
        Preset {
            name: "lattice",
            description: "a space-filling cellular network of thin struts",
            params: Params {
                agents: 1 << 20,
                sensor_angle: 45.0,
                sensor_distance: 20.0,
                turn_angle: 60.0,
                step_size: 2.0,
                deposit: 1024,
                decay: 0.85,
                diffusion: 0.2,
                roll: 0.0,
                boundary: Boundary::Wrap,
                spawn: Spawn::Uniform,
            },
        },
    ]
}

/// The preset called `name`, its agent count scaled to a grid of `res`; unknown names list
/// the valid ones.
pub fn find(name: &str, res: [u32; 3]) -> Result<Params, VolumeError> {
    let all = presets();
    let names: Vec<&str> = all.iter().map(|p| p.name).collect();
    let p = all.into_iter().find(|p| p.name == name).ok_or_else(|| {
        VolumeError::Invalid(format!("unknown physarum preset `{name}` (valid presets: {})", names.join(", ")))
    })?;
    let voxels = res.iter().map(|&r| r as f64).product::<f64>();
    let agents = (p.params.agents as f64 * voxels / (256f64.powi(3))).round().clamp(1.0, super::params::MAX_AGENTS as f64) as u32;
    Ok(Params { agents, ..p.params })
}
