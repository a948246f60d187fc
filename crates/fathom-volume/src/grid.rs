//! Dense 3D grids placed in a world-space box: u32 trail counts from the simulation and f32
//! densities for rendering, with nearest and trilinear lookup.
//!
//! The conventions are Mitsuba 3's (so a grid written as `.vol` renders the same there): voxel
//! (i, j, k) is stored at `i + res_x (j + res_y k)` (x fastest, then y, then z); in the box's
//! local coordinates `[0, 1]^3` its centre is at `((i + 0.5) / res_x, ...)`; trilinear lookup
//! clamps at the border (points outside the centres of the outer voxels take the outer values).

use crate::error::VolumeError;
use glam::Vec3;

/// Largest resolution along one axis.
pub const MAX_RES: u32 = 8192;

/// Default memory limit for one grid, in bytes (4 GiB).
pub const DEFAULT_MEMORY_LIMIT: u64 = 4 << 30;

/// An axis-aligned box in world space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WorldBox {
    pub min: Vec3,
    pub max: Vec3,
}

impl WorldBox {
    /// The unit cube `[0, 1]^3`: where a Mitsuba grid sits unless transformed.
    pub const UNIT: WorldBox = WorldBox {
        min: Vec3::ZERO,
        max: Vec3::ONE,
    };

    /// A box from its corners; refuses non-finite or empty boxes.
    pub fn new(min: Vec3, max: Vec3) -> Result<Self, VolumeError> {
        if !(min.is_finite() && max.is_finite()) || min.cmpge(max).any() {
            return Err(VolumeError::param(
                "box",
                format!("{min} .. {max}"),
                "finite corners with min < max on every axis",
            ));
        }
        Ok(WorldBox { min, max })
    }

    /// Edge lengths.
    pub fn extent(&self) -> Vec3 {
        self.max - self.min
    }

    /// The centre.
    pub fn centre(&self) -> Vec3 {
        0.5 * (self.min + self.max)
    }

    /// World point to the box's local coordinates (`[0, 1]^3` inside).
    #[inline]
    pub fn to_local(&self, p: Vec3) -> Vec3 {
        (p - self.min) / self.extent()
    }

    /// Whether `p` lies inside or on the box.
    pub fn contains(&self, p: Vec3) -> bool {
        p.cmpge(self.min).all() && p.cmple(self.max).all()
    }

    /// The parametric interval `[t0, t1]` (t0 >= 0) in which the ray `o + t d` is inside the
    /// box, or `None` if it misses (or only touches it). Axes where `d` is zero are handled
    /// (the ray is inside that slab or misses).
    #[inline]
    pub fn intersect(&self, o: Vec3, d: Vec3) -> Option<(f32, f32)> {
        let inv = d.recip();
        let mut t0 = 0.0f32;
        let mut t1 = f32::INFINITY;
        for a in 0..3 {
            if d[a] == 0.0 {
                if o[a] < self.min[a] || o[a] > self.max[a] {
                    return None;
                }
                continue;
            }
            let ta = (self.min[a] - o[a]) * inv[a];
            let tb = (self.max[a] - o[a]) * inv[a];
            t0 = t0.max(ta.min(tb));
            t1 = t1.min(ta.max(tb));
        }
        (t0 < t1).then_some((t0, t1))
    }
}

/// Checks that a grid of `res` voxels of `elem_bytes` each fits the memory limit; returns the
/// voxel count. Called before anything is allocated for the grid.
pub fn check_size(
    what: &str,
    res: [u64; 3],
    elem_bytes: u64,
    limit: u64,
) -> Result<usize, VolumeError> {
    if res.iter().any(|&r| r == 0 || r > MAX_RES as u64) {
        return Err(VolumeError::param(
            "grid resolution",
            format!("{}x{}x{} ({what})", res[0], res[1], res[2]),
            format!("1..={MAX_RES} voxels per axis"),
        ));
    }
    let voxels = res[0] * res[1] * res[2];
    let bytes = voxels * elem_bytes;
    if bytes > limit {
        return Err(VolumeError::TooLarge {
            what: what.into(),
            res_x: res[0],
            res_y: res[1],
            res_z: res[2],
            bytes,
            limit,
        });
    }
    usize::try_from(voxels).map_err(|_| VolumeError::Invalid(format!("{what}: grid too large")))
}

/// A dense grid of `T` over a world box.
#[derive(Clone, Debug, PartialEq)]
pub struct Grid<T> {
    res: [u32; 3],
    data: Vec<T>,
    /// Where the grid sits in world space.
    pub bbox: WorldBox,
}

/// Densities (extinction per unit length before `density_scale`).
pub type DensityGrid = Grid<f32>;
/// Trail counts of the physarum simulation.
pub type TrailGrid = Grid<u32>;

impl<T: Copy + Default> Grid<T> {
    /// A grid of `T::default()`, refused before allocation if it exceeds `limit` bytes.
    pub fn new(res: [u32; 3], bbox: WorldBox, limit: u64) -> Result<Self, VolumeError> {
        let n = check_size(
            "grid",
            res.map(u64::from),
            std::mem::size_of::<T>() as u64,
            limit,
        )?;
        Ok(Grid {
            res,
            data: vec![T::default(); n],
            bbox,
        })
    }

    /// A grid from its voxels in storage order (x fastest).
    pub fn from_data(res: [u32; 3], data: Vec<T>, bbox: WorldBox) -> Result<Self, VolumeError> {
        let n = check_size(
            "grid",
            res.map(u64::from),
            std::mem::size_of::<T>() as u64,
            u64::MAX,
        )?;
        if data.len() != n {
            return Err(VolumeError::Invalid(format!(
                "grid {}x{}x{} needs {n} voxels, got {}",
                res[0],
                res[1],
                res[2],
                data.len()
            )));
        }
        Ok(Grid { res, data, bbox })
    }

    /// Voxels per axis.
    pub fn res(&self) -> [u32; 3] {
        self.res
    }

    /// Voxels in storage order.
    pub fn data(&self) -> &[T] {
        &self.data
    }

    /// Voxels in storage order, writable.
    pub fn data_mut(&mut self) -> &mut [T] {
        &mut self.data
    }

    /// Storage index of voxel (x, y, z).
    #[inline(always)]
    pub fn index(&self, x: u32, y: u32, z: u32) -> usize {
        x as usize + self.res[0] as usize * (y as usize + self.res[1] as usize * z as usize)
    }

    /// Voxel (x, y, z).
    #[inline(always)]
    pub fn get(&self, x: u32, y: u32, z: u32) -> T {
        self.data[self.index(x, y, z)]
    }

    /// The voxel containing local point `l` (clamped to the grid).
    #[inline]
    pub fn nearest_local(&self, l: Vec3) -> T {
        let c =
            |a: usize| ((l[a] * self.res[a] as f32) as i64).clamp(0, self.res[a] as i64 - 1) as u32;
        self.get(c(0), c(1), c(2))
    }

    /// The voxel containing world point `p` (clamped to the grid).
    pub fn nearest(&self, p: Vec3) -> T {
        self.nearest_local(self.bbox.to_local(p))
    }

    /// The world-space centre of voxel (x, y, z).
    pub fn voxel_centre(&self, x: u32, y: u32, z: u32) -> Vec3 {
        let l = Vec3::new(
            (x as f32 + 0.5) / self.res[0] as f32,
            (y as f32 + 0.5) / self.res[1] as f32,
            (z as f32 + 0.5) / self.res[2] as f32,
        );
        self.bbox.min + l * self.bbox.extent()
    }

    /// The (x, y, z) of storage index `i`.
    pub fn coords(&self, i: usize) -> [u32; 3] {
        let (rx, ry) = (self.res[0] as usize, self.res[1] as usize);
        [
            (i % rx) as u32,
            (i / rx % ry) as u32,
            (i / (rx * ry)) as u32,
        ]
    }
}

impl Grid<f32> {
    /// Trilinear interpolation at local point `l`, clamped at the border.
    #[inline]
    pub fn trilinear_local(&self, l: Vec3) -> f32 {
        let q = l * Vec3::new(self.res[0] as f32, self.res[1] as f32, self.res[2] as f32)
            - Vec3::splat(0.5);
        self.trilinear_voxel(q)
    }

    /// Trilinear interpolation at `q` in voxel-centre coordinates (voxel i's centre at i).
    #[inline(always)]
    pub fn trilinear_voxel(&self, q: Vec3) -> f32 {
        let f = q.floor();
        let t = q - f;
        let (rx, ry, rz) = (self.res[0] as i32, self.res[1] as i32, self.res[2] as i32);
        let (x0, y0, z0) = (f.x as i32, f.y as i32, f.z as i32);
        let cx = |x: i32| x.clamp(0, rx - 1) as usize;
        let cy = |y: i32| y.clamp(0, ry - 1) as usize;
        let cz = |z: i32| z.clamp(0, rz - 1) as usize;
        let (xa, xb) = (cx(x0), cx(x0 + 1));
        let sy = rx as usize;
        let sz = sy * ry as usize;
        let (ya, yb) = (cy(y0) * sy, cy(y0 + 1) * sy);
        let (za, zb) = (cz(z0) * sz, cz(z0 + 1) * sz);
        let d = &self.data;
        let lerp = |a: f32, b: f32, t: f32| a + (b - a) * t;
        let row = |yz: usize| lerp(d[yz + xa], d[yz + xb], t.x);
        let c0 = lerp(row(ya + za), row(yb + za), t.y);
        let c1 = lerp(row(ya + zb), row(yb + zb), t.y);
        lerp(c0, c1, t.z)
    }

    /// Trilinear interpolation at world point `p`.
    pub fn trilinear(&self, p: Vec3) -> f32 {
        self.trilinear_local(self.bbox.to_local(p))
    }

    /// The largest voxel value (0 for an all-zero grid).
    pub fn max_value(&self) -> f32 {
        self.data.iter().copied().fold(0.0, f32::max)
    }

    /// Checks every voxel is a valid density (finite, >= 0); the error names the first bad
    /// voxel and `origin`.
    pub fn validate_densities(&self, origin: &str) -> Result<(), VolumeError> {
        match self.data.iter().position(|v| !(v.is_finite() && *v >= 0.0)) {
            None => Ok(()),
            Some(i) => {
                let [x, y, z] = self.coords(i);
                Err(VolumeError::BadDensity {
                    origin: origin.into(),
                    x,
                    y,
                    z,
                    value: self.data[i],
                })
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ramp() -> DensityGrid {
        // 4 x 1 x 1 with values 0, 1, 3, 7: Mitsuba 3's gridvolume gives 0, 0, 0.5, 1, 2, 7, 7
        // at x = 0, 0.125, 0.25, 0.375, 0.5, 0.875, 1 (checked against mitsuba 3.9).
        Grid::from_data([4, 1, 1], vec![0.0, 1.0, 3.0, 7.0], WorldBox::UNIT).unwrap()
    }

    #[test]
    fn trilinear_follows_mitsuba_conventions() {
        let g = ramp();
        let want = [
            (0.0, 0.0),
            (0.125, 0.0),
            (0.25, 0.5),
            (0.375, 1.0),
            (0.5, 2.0),
            (0.875, 7.0),
            (1.0, 7.0),
            (3.5, 7.0),
            (-2.0, 0.0),
        ];
        for (x, v) in want {
            let got = g.trilinear(Vec3::new(x, 0.5, 0.5));
            assert!((got - v).abs() < 1e-6, "x = {x}: {got}, want {v}");
        }
        assert_eq!(g.nearest(Vec3::new(0.3, 0.5, 0.5)), 1.0);
        assert_eq!(g.nearest(Vec3::new(9.0, -3.0, 0.5)), 7.0);
    }

    #[test]
    fn storage_order_is_x_fastest_then_y_then_z() {
        let data: Vec<f32> = (0..24).map(|v| v as f32).collect();
        let g = Grid::from_data([2, 3, 4], data, WorldBox::UNIT).unwrap();
        assert_eq!(g.get(1, 0, 0), 1.0);
        assert_eq!(g.get(0, 1, 0), 2.0);
        assert_eq!(g.get(0, 0, 1), 6.0);
        assert_eq!(g.coords(g.index(1, 2, 3)), [1, 2, 3]);
        // The centre of voxel (1, 2, 3) interpolates to exactly its value.
        let c = g.voxel_centre(1, 2, 3);
        assert!((g.trilinear(c) - g.get(1, 2, 3)).abs() < 1e-5);
    }

    #[test]
    fn oversized_and_empty_grids_are_refused_before_allocation() {
        let e = Grid::<f32>::new([4096, 4096, 4096], WorldBox::UNIT, 1 << 30).unwrap_err();
        assert!(e.to_string().contains("memory limit"), "{e}");
        let e = Grid::<u32>::new([0, 4, 4], WorldBox::UNIT, 1 << 30).unwrap_err();
        assert!(e.to_string().contains("1..=8192"), "{e}");
        assert!(WorldBox::new(Vec3::ONE, Vec3::ZERO).is_err());
        assert!(WorldBox::new(Vec3::ZERO, Vec3::new(1.0, f32::NAN, 1.0)).is_err());
    }

    #[test]
    fn bad_densities_name_their_voxel() {
        let mut g = ramp();
        g.data_mut()[2] = -1.0;
        let e = g.validate_densities("t.vol").unwrap_err().to_string();
        assert!(e.contains("(2, 0, 0)") && e.contains("-1"), "{e}");
        g.data_mut()[2] = f32::NAN;
        assert!(g.validate_densities("t.vol").is_err());
    }

    #[test]
    fn box_intersection_handles_inside_and_axis_parallel_rays() {
        let b = WorldBox::UNIT;
        let (t0, t1) = b.intersect(Vec3::new(-1.0, 0.5, 0.5), Vec3::X).unwrap();
        assert!((t0 - 1.0).abs() < 1e-6 && (t1 - 2.0).abs() < 1e-6);
        let (t0, t1) = b.intersect(Vec3::splat(0.5), Vec3::Y).unwrap();
        assert!(t0 == 0.0 && (t1 - 0.5).abs() < 1e-6);
        assert!(b.intersect(Vec3::new(-1.0, 2.0, 0.5), Vec3::X).is_none());
        assert!(b.intersect(Vec3::new(2.0, 0.5, 0.5), Vec3::X).is_none());
    }
}
