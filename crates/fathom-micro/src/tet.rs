//! One tetrahedron of a shell and the affine maps that live on it: world point to barycentric
//! coordinates, barycentric to shell coordinates (u, h, v in tile units), and the Jacobian of
//! world to texture-scene space with its spectral norm, the Lipschitz factor that turns a
//! texture distance into a safe world distance.

use glam::{DMat3, DVec3};

/// No tetrahedron (a boundary face's neighbour).
pub const NONE: u32 = u32::MAX;

/// One tetrahedron of a prism.
#[derive(Clone, Debug)]
pub struct Tet {
    /// World positions.
    pub verts: [DVec3; 4],
    /// Shell coordinates of each vertex: (u * tiles, h, v * tiles), h = 0 on the base triangle
    /// and 1 on the offset one.
    pub tex: [DVec3; 4],
    /// The vertex normal of each vertex's triangle corner (the same below and above).
    pub normals: [DVec3; 4],
    /// Barycentric planes: `lambda_k(p) = planes[k].xyz . p + planes[k].w`.
    pub planes: [[f64; 4]; 4],
    /// Which triangle corner (0..3) each vertex belongs to.
    pub corner: [u8; 4],
    /// Which vertices lie on the offset (top) triangle.
    pub top: [bool; 4],
    /// The base triangle.
    pub tri: u32,
    /// The face (index of the opposite vertex) lying on the base triangle, or 4.
    pub bottom_face: u8,
    /// d(texture-scene point) / d(world point): constant on the tetrahedron.
    pub jac: DMat3,
    /// The prism's Lipschitz factor: the largest spectral norm of `jac` over its three
    /// tetrahedra.
    pub lipschitz: f64,
}

/// A segment of a ray inside a tetrahedron: entry and exit distances and faces.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Span {
    /// Distance along the ray where it enters.
    pub t_in: f64,
    /// Distance along the ray where it leaves.
    pub t_out: f64,
    /// The face it enters through (index of the opposite vertex), or 4 when none bounds it.
    pub face_in: u8,
    /// The face it leaves through, or 4 when none bounds it.
    pub face_out: u8,
}

impl Tet {
    /// Barycentric planes of a tetrahedron, or `None` when it is flat.
    pub fn planes_of(v: &[DVec3; 4]) -> Option<[[f64; 4]; 4]> {
        let m = DMat3::from_cols(v[1] - v[0], v[2] - v[0], v[3] - v[0]);
        let det = m.determinant();
        let scale = (v[1] - v[0]).length() * (v[2] - v[0]).length() * (v[3] - v[0]).length();
        if det.abs().partial_cmp(&(1e-12 * scale)) != Some(std::cmp::Ordering::Greater) {
            return None;
        }
        let inv = m.inverse().transpose(); // rows of the inverse as columns
        let mut planes = [[0.0; 4]; 4];
        let mut sum = DVec3::ZERO;
        for k in 0..3 {
            let r = inv.col(k);
            sum += r;
            planes[k + 1] = [r.x, r.y, r.z, -r.dot(v[0])];
        }
        planes[0] = [-sum.x, -sum.y, -sum.z, 1.0 + sum.dot(v[0])];
        Some(planes)
    }

    /// Barycentric coordinates of `p`.
    #[inline]
    pub fn bary(&self, p: DVec3) -> [f64; 4] {
        self.planes
            .map(|w| w[0] * p.x + w[1] * p.y + w[2] * p.z + w[3])
    }

    /// Shell coordinates (u, h, v in tile units) at barycentric `b`.
    #[inline]
    pub fn shell_at(&self, b: &[f64; 4]) -> DVec3 {
        self.tex[0] * b[0] + self.tex[1] * b[1] + self.tex[2] * b[2] + self.tex[3] * b[3]
    }

    /// The interpolated vertex normal at barycentric `b`.
    pub fn vertex_normal_at(&self, b: &[f64; 4]) -> DVec3 {
        (self.normals[0] * b[0]
            + self.normals[1] * b[1]
            + self.normals[2] * b[2]
            + self.normals[3] * b[3])
            .normalize_or_zero()
    }

    /// Where the ray `o + t d` is inside, if anywhere.
    pub fn clip(&self, o: DVec3, d: DVec3) -> Option<Span> {
        let mut s = Span {
            t_in: f64::NEG_INFINITY,
            t_out: f64::INFINITY,
            face_in: 4,
            face_out: 4,
        };
        for (k, w) in self.planes.iter().enumerate() {
            let b0 = w[0] * o.x + w[1] * o.y + w[2] * o.z + w[3];
            let db = w[0] * d.x + w[1] * d.y + w[2] * d.z;
            if db > 0.0 {
                let t = -b0 / db;
                if t > s.t_in {
                    s.t_in = t;
                    s.face_in = k as u8;
                }
            } else if db < 0.0 {
                let t = -b0 / db;
                if t < s.t_out {
                    s.t_out = t;
                    s.face_out = k as u8;
                }
            } else if b0 < 0.0 {
                return None;
            }
        }
        (s.t_in < s.t_out).then_some(s)
    }

    /// The three vertices of face `k` (opposite vertex `k`), wound so that their normal points
    /// out of the tetrahedron.
    pub fn face_outward(&self, k: usize) -> [usize; 3] {
        let mut f: Vec<usize> = (0..4).filter(|&i| i != k).collect();
        let v = &self.verts;
        let n = (v[f[1]] - v[f[0]]).cross(v[f[2]] - v[f[0]]);
        if n.dot(v[k] - v[f[0]]) > 0.0 {
            f.swap(1, 2);
        }
        [f[0], f[1], f[2]]
    }
}

/// d(scene point)/d(world point) of the affine map sending each vertex to `scene[k]`.
pub fn jacobian(planes: &[[f64; 4]; 4], scene: &[DVec3; 4]) -> DMat3 {
    let mut cols = [DVec3::ZERO; 3];
    for (w, s) in planes.iter().zip(scene) {
        for (j, c) in cols.iter_mut().enumerate() {
            *c += *s * w[j];
        }
    }
    DMat3::from_cols(cols[0], cols[1], cols[2])
}

/// The spectral norm (largest singular value) of `a`, from the largest eigenvalue of the
/// symmetric `a^T a` (closed form, Smith 1961), rounded up slightly so it is never below the
/// true value.
pub fn spectral_norm(a: &DMat3) -> f64 {
    let m = a.transpose() * *a;
    let (p1, q) = (
        m.x_axis.y.powi(2) + m.x_axis.z.powi(2) + m.y_axis.z.powi(2),
        (m.x_axis.x + m.y_axis.y + m.z_axis.z) / 3.0,
    );
    let diag = [m.x_axis.x, m.y_axis.y, m.z_axis.z];
    let lmax = if p1 <= 1e-30 * (q * q).max(1e-300) {
        diag.iter().copied().fold(0.0, f64::max)
    } else {
        let p2 = diag.iter().map(|d| (d - q).powi(2)).sum::<f64>() + 2.0 * p1;
        let p = (p2 / 6.0).sqrt();
        let b = (m - DMat3::from_diagonal(DVec3::splat(q))) * (1.0 / p);
        let r = (b.determinant() / 2.0).clamp(-1.0, 1.0);
        let phi = r.acos() / 3.0;
        q + 2.0 * p * phi.cos()
    };
    // The closed form is accurate to a few ulps of the largest entry; pad by more than that.
    let pad = 1e-9 * (m.x_axis.length() + m.y_axis.length() + m.z_axis.length());
    (lmax.max(0.0) + pad).sqrt() * (1.0 + 1e-12)
}
