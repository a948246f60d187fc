//! The simulation's parameters with their ranges, and where the agents start.

use crate::error::{VolumeError, check_range};
use serde::Serialize;

/// What happens at the grid's faces.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub enum Boundary {
    /// Opposite faces meet: agents leaving one side enter the other; diffusion wraps.
    Wrap,
    /// Agents reflect off the faces; diffusion replicates the border voxels.
    Walls,
}

/// Where the agents start (positions uniform in the region, directions uniform).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub enum Spawn {
    /// Anywhere in the grid.
    Uniform,
    /// In a ball of this radius (a fraction of the half side) at the centre.
    Ball(f32),
    /// On a spherical shell of this radius (a fraction of the half side), facing inward.
    Shell(f32),
}

/// The parameters of a 3D physarum simulation. Lengths are in voxels, angles in degrees.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Params {
    pub agents: u32,
    /// Angle between the forward sensor and each of the three flanking sensors.
    pub sensor_angle: f32,
    /// How far ahead the sensors read.
    pub sensor_distance: f32,
    /// How far an agent turns towards the strongest flanking reading per step.
    pub turn_angle: f32,
    /// How far an agent moves per step.
    pub step_size: f32,
    /// Trail count each agent adds to its voxel per step.
    pub deposit: u32,
    /// Fraction of the trail kept per step, [0, 1].
    pub decay: f32,
    /// How far each voxel moves toward the mean of its 3x3x3 neighbourhood per step, [0, 1].
    pub diffusion: f32,
    /// Largest random roll about the forward axis per step (turns the sensor ring).
    pub roll: f32,
    pub boundary: Boundary,
    pub spawn: Spawn,
}

/// Most agents.
pub const MAX_AGENTS: u32 = 1 << 24;
/// Largest sum of one step's deposits: trail voxels are capped at 2^31 - 1 after diffusion,
/// so one step's deposits can never overflow a u32.
pub const MAX_STEP_DEPOSIT: u64 = 1 << 31;

impl Params {
    /// Checks every range, and that one step's deposits cannot overflow a voxel.
    pub fn validate(&self) -> Result<(), VolumeError> {
        if self.agents == 0 || self.agents > MAX_AGENTS {
            return Err(VolumeError::param(
                "agents",
                self.agents,
                format!("1..={MAX_AGENTS}"),
            ));
        }
        check_range("sensor angle", self.sensor_angle as f64, 0.0, 180.0)?;
        check_range("sensor distance", self.sensor_distance as f64, 0.0, 256.0)?;
        check_range("turn angle", self.turn_angle as f64, 0.0, 180.0)?;
        if !(self.step_size.is_finite() && self.step_size > 0.0 && self.step_size <= 32.0) {
            return Err(VolumeError::param(
                "step size",
                self.step_size,
                "(0, 32] voxels",
            ));
        }
        if !(1..=65535).contains(&self.deposit) {
            return Err(VolumeError::param("deposit", self.deposit, "1..=65535"));
        }
        if self.agents as u64 * self.deposit as u64 > MAX_STEP_DEPOSIT {
            return Err(VolumeError::param(
                "deposit",
                self.deposit,
                format!(
                    "1..={} with {} agents (agents x deposit must stay <= 2^31 so trail counts cannot overflow)",
                    MAX_STEP_DEPOSIT / self.agents as u64,
                    self.agents
                ),
            ));
        }
        check_range("decay", self.decay as f64, 0.0, 1.0)?;
        check_range("diffusion", self.diffusion as f64, 0.0, 1.0)?;
        check_range("roll", self.roll as f64, 0.0, 180.0)?;
        match self.spawn {
            Spawn::Uniform => {}
            Spawn::Ball(r) | Spawn::Shell(r) => check_range("spawn radius", r as f64, 0.0, 1.0)?,
        }
        Ok(())
    }
}
