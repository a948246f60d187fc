//! One unit normal per welded position: the average of the file's corner normals where it has
//! them, else the angle-weighted average of the adjacent face normals (Thürmer and Wüthrich
//! 1998), which does not depend on how a face is split into triangles.

use glam::DVec3;

/// Vertex normals for `positions` and whether any had to be computed from the faces.
pub fn vertex_normals(
    positions: &[DVec3],
    tris: &[[u32; 3]],
    corner: Option<&[[DVec3; 3]]>,
) -> (Vec<DVec3>, bool) {
    let mut from_file = vec![DVec3::ZERO; positions.len()];
    if let Some(c) = corner {
        for (t, cn) in tris.iter().zip(c) {
            for k in 0..3 {
                let n = cn[k];
                if n.is_finite() && n.length_squared() > 0.0 {
                    from_file[t[k] as usize] += n.normalize();
                }
            }
        }
    }
    let faces = angle_weighted(positions, tris);
    let mut computed = corner.is_none();
    let normals = from_file
        .iter()
        .zip(&faces)
        .map(|(&f, &g)| match f.try_normalize() {
            // A file normal opposite to the winding-based one would turn the shell inside out
            // at that vertex; the winding wins.
            Some(n) if g == DVec3::ZERO || n.dot(g) > -0.5 => n,
            _ => {
                computed = true;
                g.try_normalize().unwrap_or(DVec3::Y)
            }
        })
        .collect();
    (normals, computed)
}

/// Sum over each vertex's triangles of the face normal times the corner angle (not normalised).
pub fn angle_weighted(positions: &[DVec3], tris: &[[u32; 3]]) -> Vec<DVec3> {
    let mut acc = vec![DVec3::ZERO; positions.len()];
    for t in tris {
        let p = t.map(|i| positions[i as usize]);
        let n = (p[1] - p[0]).cross(p[2] - p[0]).normalize_or_zero();
        for k in 0..3 {
            let e1 = p[(k + 1) % 3] - p[k];
            let e2 = p[(k + 2) % 3] - p[k];
            let ang = e1.angle_between(e2);
            if ang.is_finite() {
                acc[t[k] as usize] += n * ang;
            }
        }
    }
    acc
}
