//! Texture coordinates for meshes that have none: planar (along the bounding box's thinnest
//! axis), box (each triangle along its dominant axis) and spherical (longitude and latitude
//! about the bounding box's centre, with the seam unwrapped per triangle). Planar and box UVs
//! measure in units of the box's largest side, so tiles are square in the world.

use glam::{DVec2, DVec3};

/// A UV projection.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum UvProjection {
    /// Along the mesh's thinnest axis.
    Planar,
    /// Each triangle along the axis its normal points most along.
    Box,
    /// Longitude and latitude around the mesh's centre.
    Spherical,
}

/// Every projection with its name, for parsing and help.
pub const PROJECTIONS: &[(UvProjection, &str)] = &[
    (UvProjection::Planar, "planar"),
    (UvProjection::Box, "box"),
    (UvProjection::Spherical, "spherical"),
];

impl UvProjection {
    /// The name `--uv` takes.
    pub fn name(self) -> &'static str {
        PROJECTIONS
            .iter()
            .find(|p| p.0 == self)
            .map_or("?", |p| p.1)
    }

    /// Parses a projection name; unknown names list the valid ones.
    pub fn parse(s: &str) -> Result<UvProjection, String> {
        PROJECTIONS
            .iter()
            .find(|p| p.1 == s)
            .map(|p| p.0)
            .ok_or_else(|| {
                format!(
                    "unknown UV projection `{s}`; expected one of: {}",
                    PROJECTIONS
                        .iter()
                        .map(|p| p.1)
                        .collect::<Vec<_>>()
                        .join(", ")
                )
            })
    }
}

/// Drops axis `axis` of `p`: the two remaining coordinates in order.
fn drop_axis(p: DVec3, axis: usize) -> DVec2 {
    match axis {
        0 => DVec2::new(p.z, p.y),
        1 => DVec2::new(p.x, p.z),
        _ => DVec2::new(p.x, p.y),
    }
}

/// Per-corner UVs of `tris` by `proj`; (`lo`, `hi`) is the bounding box.
pub fn project(
    proj: UvProjection,
    positions: &[DVec3],
    tris: &[[u32; 3]],
    lo: DVec3,
    hi: DVec3,
) -> Vec<[DVec2; 3]> {
    let size = (hi - lo).max_element().max(1e-300);
    let centre = 0.5 * (lo + hi);
    let thinnest = (hi - lo).min_position();
    tris.iter()
        .map(|t| {
            let p = t.map(|i| positions[i as usize]);
            match proj {
                UvProjection::Planar => p.map(|q| drop_axis(q - lo, thinnest) / size),
                UvProjection::Box => {
                    let n = (p[1] - p[0]).cross(p[2] - p[0]).abs();
                    p.map(|q| drop_axis(q - lo, n.max_position()) / size)
                }
                UvProjection::Spherical => {
                    let mut uv = p.map(|q| {
                        let d = (q - centre).normalize_or_zero();
                        DVec2::new(
                            d.z.atan2(d.x) / std::f64::consts::TAU + 0.5,
                            d.y.clamp(-1.0, 1.0).acos() / std::f64::consts::PI,
                        )
                    });
                    // Unwrap the seam: corners more than half a turn apart meet across it.
                    let max_u = uv.iter().map(|c| c.x).fold(f64::MIN, f64::max);
                    for c in &mut uv {
                        if max_u - c.x > 0.5 {
                            c.x += 1.0;
                        }
                    }
                    uv
                }
            }
        })
        .collect()
}
